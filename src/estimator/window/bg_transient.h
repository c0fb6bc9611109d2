/* SPDX-License-Identifier: Apache-2.0 */
/* Background: a speed transient inside a window seen through the angle
 * observer (docs/METHOD.md §13.1). Internal: not part of the public API. */
#ifndef IMEST_BG_TRANSIENT_H
#define IMEST_BG_TRANSIENT_H

#include "bg_impedance.h"
#include "common/imest_math.h"
#include "imest/imest.h"

/* integral |e_w| dt / dw x w_o of the triple-pole tracker (imest_init.c,
 * design_angle) after a speed step: 1.655 at 25 Hz and 8 kHz, 1.630 at 4 kHz
 * (the sampled loop, its response summed), for any f_n/fs the design allows;
 * the larger is kept. */
#define IMEST_OBS_LAG_WO       1.66f
/* the first-order share's factor (the measured move over the first order: bg_transient.c) */
#define IMEST_TRANSIENT_MARGIN 2.0f

/* T_R's share of the bound per rad/s of speed change over rad/s of slip:
 * 2 n_p t_lag / T_window, t_lag the angle observer's lag after a speed step
 * (the integral of its speed error) at natural frequency fn_hz (0: none). At
 * init. */
static inline float imest__bg_transient_k(float fn_hz, float pole_pairs, float window_s)
{
  /* t_lag = IMEST_OBS_LAG_WO / (2 pi fn_hz) */
  return fn_hz > 0.0f ? (IMEST_TRANSIENT_MARGIN * IMEST_OBS_LAG_WO / (2.0f * IMEST_PI_F)) * pole_pairs /
                            (fn_hz * window_s)
                      : 0.0f;
}

/* The window's change of speed [rad/s, mechanical] while the angle observer
 * was engaged (0 when it was not): its end speed minus its start speed (the
 * previous window's end; twice the end minus the mean when that is not known:
 * the first window, after an overrun). Keeps the end speed for the next
 * window. Call once per window, before s->w_prev_valid is updated. */
float imest__bg_transient_dw(imest_t *s, const imest_window_t *w, float w_mean_rad_s);

/* A share below this fraction of both tolerances is not counted: the bounds
 * are first-order figures, and a steady window (the observer's own speed noise
 * from the encoder's counts) keeps its bounds exactly. */
#define IMEST_TRANSIENT_DEADBAND 0.1f

/* What that change can move T_R and R_S by (relative), or 0 and 0 below a
 * tenth of both tolerances: T_R by eps = k dw / |w_s| (no slip: without
 * bound), R_S by |dZ/dT_R| T_R eps / R_S. z: the window's impedance at the
 * estimate tr_s, rs_ohm; ws_rad_s: the slip frequency; dw_rad_s: the change. */
static inline void imest__bg_transient_share(const imest_t *s, const bg_impedance_t *z, float dw_rad_s,
                                             float ws_rad_s, float tr_s, float rs_ohm, float *tr_rel,
                                             float *rs_rel)
{
  const float t = dw_rad_s > 0.0f ? s->transient_k * dw_rad_s / fabsf(ws_rad_s) : 0.0f;
  const float r = sqrtf(z->dr * z->dr + z->di * z->di) * tr_s * t / rs_ohm;
  const int counted =
      t > IMEST_TRANSIENT_DEADBAND * s->tr_tolerance || r > IMEST_TRANSIENT_DEADBAND * s->rs_tolerance;
  *tr_rel = counted ? t : 0.0f;
  *rs_rel = counted ? r : 0.0f;
}

#endif /* IMEST_BG_TRANSIENT_H */
