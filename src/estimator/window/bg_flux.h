/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: L_S at the window's flux from the configured magnetising
 * curve (main-flux saturation), and the estimate moved to it (docs/METHOD.md
 * §18.5). Runs after the solve, before the verdict. Internal: not part of the
 * public API. */
#ifndef IMEST_BG_FLUX_H
#define IMEST_BG_FLUX_H

#include "bg_window.h"

/* Built in unless the build defines IMEST_WITH_FLUX=0 (CMake: -DIMEST_FLUX=OFF),
 * for a firmware short of flash: the stage's code is then not linked, a
 * config with a curve is refused (imest_config_check(): ls_curve_points) and
 * L_S is flux-independent, as without a curve. */
#ifndef IMEST_WITH_FLUX
#define IMEST_WITH_FLUX 1
#endif

/* What the curve hands to the verdict's bounds (bg_validity.c). */
typedef struct {
  float tr_b, rs_b; /* the curve's share of T_R's and R_S's relative bounds (0: no curve, not applied) */
} bg_flux_t;

/* L_S of the magnetising curve at the magnetising current i_a [A] (alpha/beta
 * amplitude): piecewise linear between the points, clamped outside them.
 * *err_h receives the curve's uncertainty there [H]: between points,
 * t (1 - t) h D at the fraction t of a segment of width h, D the largest
 * change of slope at the segment's ends (to the neighbouring segments'; two
 * points: the slope itself), i.e. what the chord misses of a curve whose
 * slope changes by D along the segment, twice the parabola's (a saturation
 * curve bends more towards high flux than its points show: 4 kW, points at
 * 0.6 .. 1.05 x rated voltage, the chord 0.6 % above the curve at rated load,
 * this rule 0.4 %). Outside the points, a bound from what saturation allows:
 * the static L_S does not rise with the current, and the flux L_S i does not
 * fall with it. Below the first point (x_0, y_0) L_S is then at least y_0,
 * and, the curve concave there (a saturation curve is below about 0.85 of
 * rated flux; commissioning's first point is at 0.45 of it, the flux of field
 * weakening to twice base speed), at most the first segment's straight
 * continuation: *err_h =
 * |s_0| (x_0 - i_a), s_0 that segment's slope. Above the last point (x_n, y_n)
 * L_S is at most y_n and at least y_n x_n / i_a (the flux no lower than at
 * x_n): *err_h = y_n (1 - x_n / i_a), which a curve that bends down beyond its
 * last point, as saturation does, can reach and the last segment's slope
 * need not. Without a curve: ls_h, *err_h 0. */
float imest__bg_flux_ls(const imest_t *s, float i_a, float *err_h);

/* With a curve and where the steady-state picture holds (an estimate, the
 * slip frequency x T_R x sigma below 1: the condition of tr_uncertain): T_R
 * and R_S moved to L_S at the window's flux, r->ls_window_h set, *fx the
 * curve's share of the bounds. Elsewhere r is left as it is (ls_window_h NaN,
 * *fx 0). Where the curve and the window disagree (no motor with the curve's
 * L_S has the window's impedance, or the curve is too steep at this flux for
 * one secant step) r is left too, and *fx is infinite. Bounded: three
 * closed-form solves and four curve look-ups, no iteration that depends on
 * the data. */
void imest__bg_flux(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                    imest_result_t *r, bg_flux_t *fx);

#endif /* IMEST_BG_FLUX_H */
