/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: one window's ISR sums to the float64 8x8 form the solve
 * takes, the window's statistics, and the centring vector the ISR uses for
 * the next windows (docs/METHOD.md §2, §10). Internal: not part of the public
 * API. */
#ifndef IMEST_BG_WINDOW_H
#define IMEST_BG_WINDOW_H

#include "bg_solve.h"
#include "common/imest_math.h"

/* What the judge needs from a window besides the solve. float32: every
 * user (the judge, the noise model, the steadiness test, the magnetising
 * curve's stage) compares or scales with them in float32; each is a ratio of
 * the window's sums, rounded once (relative 6e-8), and i_rms_a goes out as
 * that float32 value (the ISR's sums carry no more). */
typedef struct {
  float i_rms_a;   /* rms |i| (alpha/beta amplitude) */
  float w_mean;    /* mean mechanical speed [rad/s] */
  float slip_rate; /* mean rotation rate of the rotor-frame current [rad/s]:
                      the slip frequency in steady state */
  float u_ms;      /* mean square of u_alpha [V^2] */
  float dw_rad_s;  /* the speed's change inside the window through the angle observer [rad/s]
                      (bg_transient.c; set by the task) */
} bg_window_stats_t;

/* One window's ISR sums -> full 8x8 float64 sums (undoes the centring and
 * rebuilds column 3), and the window's statistics. */
void imest__bg_window_sums(const imest_window_t *w, double m, double fs, bg_sums_t *out,
                           bg_window_stats_t *st);

/* c0 (7-column centring vector) from K1, K2. */
void imest__bg_centre_from_k(imest_real_t c0[7], imest_real_t k1, imest_real_t k2, imest_real_t m);

#endif /* IMEST_BG_WINDOW_H */
