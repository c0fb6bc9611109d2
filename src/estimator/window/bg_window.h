/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: one window's ISR sums to the float64 8x8 form the solve
 * takes, the window's statistics, and the centring vector the ISR uses for
 * the next windows (docs/METHOD.md §2, §10). Internal: not part of the public
 * API. */
#ifndef IMEST_BG_WINDOW_H
#define IMEST_BG_WINDOW_H

#include "bg_solve.h"
#include "common/imest_math.h"

/* What the judge needs from a window besides the solve. */
typedef struct {
  double i_rms_a;   /* rms |i| (alpha/beta amplitude) */
  double w_mean;    /* mean mechanical speed [rad/s] */
  double slip_rate; /* mean rotation rate of the rotor-frame current [rad/s]:
                       the slip frequency in steady state */
  double u_ms;      /* mean square of u_alpha [V^2] */
  float dw_rad_s;   /* the speed's change inside the window through the angle observer [rad/s]
                       (bg_transient.c; set by the task) */
} bg_window_stats_t;

/* One window's ISR sums -> full 8x8 float64 sums (undoes the centring and
 * rebuilds column 3), and the window's statistics. */
void imest__bg_window_sums(const imest_window_t *w, double m, double fs, bg_sums_t *out,
                           bg_window_stats_t *st);

/* c0 (7-column centring vector) from K1, K2. */
void imest__bg_centre_from_k(imest_real_t c0[7], double k1, double k2, double m);

#endif /* IMEST_BG_WINDOW_H */
