/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: a load or speed step inside a window (docs/METHOD.md
 * §13.1). The front end's model holds in a transient: every channel, the
 * encoder's speed included, goes through the same filters. The angle observer
 * does not (src/estimator/isr/isr_angle.h): a type-3 tracker follows a
 * constant speed and a constant acceleration without lag, but after a change
 * of speed faster than its bandwidth (a load step on a stiff V/f drive
 * settles in a few ms) its speed lags the rotor's, by the whole change at
 * first, decaying over a few 1/w_o. The rotor frame then turns at the wrong
 * slip: the rotor-flux equation gains -j n_p e_w psi, the slip w_s is off by
 * n_p e_w. The observer is engaged only after a window at steady speed, so a
 * step inside such a window goes through it. Measured on the 4 kW motor (V/f,
 * 12-bit, exact constants), load 50 -> 100 % at mid-window: T_R +0.6 %,
 * R_S +26 % and valid, where the same window through the encoder alone gave
 * T_R -0.05 %, R_S -1.6 % (the steady windows' -0.08 % and -2 %).
 *
 * The bound: over the window the slip's relative error weighs
 * eps = n_p |dw| t_lag / (|w_s| T_window), t_lag = integral |e_w| dt / dw of
 * the observer's response to a speed step. A slip error reads as a T_R error
 * of the impedance (Z depends on w_s T_R alone), so T_R moves by eps and Re Z
 * by |dZ/dT_R| T_R eps, all of which R_S may take. Twice that is kept: on the
 * simulator (4 kW, V/f load steps of 10 to 50 %, up and down, anywhere in the
 * window) first order gave T_R 0.8-1.3 x and R_S 0.4-0.5 x of the move measured. */
#include <math.h>

#include "bg_transient.h"
#include "common/imest_math.h"

/* a change of speed below this fraction of the speed is not a step: the
 * observer's end speed carries the encoder's quantisation (between steady
 * windows 0.003 to 0.03 rad/s, 0.002 to 0.03 % of the speed, with 4096 to
 * 16384 counts at 4 and 8 kHz) */
#define TRANSIENT_MIN_DW_REL 1e-3f

float imest__bg_transient_dw(imest_t *s, const imest_window_t *w, float w_mean_rad_s)
{
  const float w_end_rad_s = (float)w->dth_end_rad * (float)s->fs, w_mean = w_mean_rad_s;
  const int start_known = s->w_prev_valid && !(w->flags & IMEST_FLAG_OVERRUN);
  const float dw_rad_s = start_known ? w_end_rad_s - s->w_end_prev_rad_s : 2.0f * (w_end_rad_s - w_mean);
  s->w_end_prev_rad_s = w_end_rad_s;
  const int step = fabsf(dw_rad_s) > TRANSIENT_MIN_DW_REL * fabsf(w_mean);
  return (w->flags & IMEST_WFLAG_OBSERVER) && step ? fabsf(dw_rad_s) : 0.0f;
}
