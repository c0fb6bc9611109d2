/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: L_S at the window's flux from the configured magnetising
 * curve (main-flux saturation), and the estimate moved to it (docs/METHOD.md
 * §18.2). Runs after the solve, before the verdict. Internal: not part of the
 * public API. */
#ifndef IMEST_BG_FLUX_H
#define IMEST_BG_FLUX_H

#include "bg_window.h"

/* What the curve hands to the verdict's bounds (bg_validity.c). */
typedef struct {
  float tr_b, rs_b; /* the curve's share of T_R's and R_S's relative bounds (0: no curve, not applied) */
} bg_flux_t;

/* L_S of the magnetising curve at the magnetising current i_a [A] (alpha/beta
 * amplitude): piecewise linear between the points, clamped outside them.
 * *err_h receives the curve's uncertainty there [H]: between points, the
 * linear interpolation's error t (1 - t) h^2 c / 2 on a segment of width h,
 * with c the largest curvature the neighbouring segments' slopes show at the
 * segment's ends (two points: none shows, |L_1 - L_0| / h^2 taken, i.e. the
 * chord missed by a quarter of the step at mid-segment); outside the points,
 * the whole difference between the clamped value and the end segment's
 * straight continuation. Without a curve: ls_h, *err_h 0. */
float imest__bg_flux_ls(const imest_t *s, float i_a, float *err_h);

/* With a curve and where the steady-state picture holds (an estimate, the
 * slip frequency x T_R x sigma below 1: the condition of tr_uncertain): T_R
 * and R_S moved to L_S at the window's flux, r->ls_window_h set, *fx the
 * curve's share of the bounds. Elsewhere r is left as it is (ls_window_h NaN,
 * *fx 0). Bounded: two passes, no iteration that depends on the data. */
void imest__bg_flux(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                    imest_result_t *r, bg_flux_t *fx);

#endif /* IMEST_BG_FLUX_H */
