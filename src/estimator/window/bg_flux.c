/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: L_S at the window's flux (main-flux saturation) from the
 * configured magnetising curve, and T_R and R_S moved to it (docs/METHOD.md
 * §18.2). Saturation moves the main inductance, not the leakage: the window's
 * motor has L_w = L_S(i_d) and sigma_w = sigma ls_h / L_w (sigma L_S held),
 * where the solve assumed ls_h and sigma. In steady state the fit matches the
 * window's impedance Z (bg_impedance.h) with the configured constants, so Z
 * follows from the estimate, and the estimate with L_w, sigma_w is the one
 * that gives the same Z: solved in closed form (no linearisation), twice,
 * because i_d = |i| / sqrt(1 + a^2) depends on a = slip frequency x T_R.
 * float32: every figure is relative, as in bg_validity.c. */
#include <math.h>

#include "bg_flux.h"
#include "bg_impedance.h"

/* Passes of the fixed point i_d(T_R) -> L_w -> T_R: the first takes i_d at
 * the fit's T_R, the second at the first's. The second's change, scaled by
 * the contraction the two passes show (k = change 2 / change 1), bounds what
 * further passes would change: k / (1 - k) x change 2 (4 kW at rated load:
 * the first moves T_R by +4.5 %, the second by +1 %). */
#define FLUX_PASSES        2
/* The steady-state picture against the estimator: moved to L_w, the estimate
 * is the one re-estimating with L_S = L_w gives to within this share of the
 * move (measured: tools/studies/saturation, 4 and 11 kW motors, 25-100 % load
 * and field weakening; docs/METHOD.md §18.2). */
#define FLUX_PICTURE_SHARE 0.02f

static float seg_slope(const float *x, const float *y, unsigned int k)
{
  return (y[k + 1u] - y[k]) / (x[k + 1u] - x[k]);
}

/* The curvature the slopes show at inner point j (1 .. n-2), second divided difference x 2. */
static float node_curvature(const float *x, const float *y, unsigned int j)
{
  return 2.0f * fabsf(seg_slope(x, y, j) - seg_slope(x, y, j - 1u)) / (x[j + 1u] - x[j - 1u]);
}

float imest__bg_flux_ls(const imest_t *s, float i_a, float *err_h)
{
  const unsigned int n = s->ls_curve_points;
  const float *x = s->ls_curve_i_a, *y = s->ls_curve_h;
  *err_h = 0.0f;
  if (n < 2u) return s->ls_h;
  unsigned int k = 0u; /* the segment [x_k, x_k+1]: the first, the last, or the one holding i_a */
  while (k + 2u < n && i_a > x[k + 1u]) ++k;
  const float h = x[k + 1u] - x[k], slope = seg_slope(x, y, k);
  if (!(i_a > x[0])) {
    *err_h = fabsf(slope) * (x[0] - i_a);
    return y[0];
  }
  if (!(i_a < x[n - 1u])) {
    *err_h = fabsf(slope) * (i_a - x[n - 1u]);
    return y[n - 1u];
  }
  const float t = (i_a - x[k]) / h;
  float c = 0.0f;
  if (k >= 1u) c = node_curvature(x, y, k);
  if (k + 2u < n) c = fmaxf(c, node_curvature(x, y, k + 1u));
  if (n == 2u) c = 2.0f * fabsf(y[1] - y[0]) / (h * h);
  *err_h = t * (1.0f - t) * h * h * c * 0.5f;
  return y[k] + t * (y[k + 1u] - y[k]);
}

/* The T_R and R_S that give the impedance z with the constants ls, sg:
 * Im Z / (we ls) = (1 + sg a^2) / (1 + a^2) gives a^2, Re Z gives R_S.
 * 0 if no such motor exists (Im Z outside (sg, 1) x we ls). */
static int refit(const bg_impedance_t *z, float we, float ws, float ls, float sg, float *tr, float *rs)
{
  const float q = z->zi / (we * ls);
  if (!(q > sg && q < 1.0f)) return 0;
  const float a2 = (1.0f - q) / (q - sg), a = copysignf(sqrtf(a2), ws);
  *tr = fabsf(a / ws);
  *rs = z->zr - we * ls * a * (1.0f - sg) / (1.0f + a2);
  return 1;
}

/* What passes beyond the last would still change, from the last two
 * changes: k / (1 - k) x the last, k their ratio; infinite unless k < 1/2
 * (the fixed point then converges too slowly to be trusted after two). */
static float passes_left(const float d[FLUX_PASSES])
{
  const float last = d[FLUX_PASSES - 1], before = d[FLUX_PASSES - 2];
  if (!(last > 0.0f)) return 0.0f;
  const float k = last / before;
  return k < 0.5f ? last * k / (1.0f - k) : INFINITY;
}

void imest__bg_flux(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                    imest_result_t *r, bg_flux_t *fx)
{
  fx->tr_b = 0.0f;
  fx->rs_b = 0.0f;
  r->ls_window_h = (double)NAN;
  if (s->ls_curve_points == 0u) return;
  const float tr0 = (float)r->tr_s, rs0 = (float)r->rs_ohm, ws = (float)st->slip_rate;
  const float we = ws + s->n * (float)st->w_mean;
  const float i2 = nreg > 0u ? (float)sm->rw[3][3] / (float)nreg : 0.0f;
  /* The steady-state picture: an estimate, a field, a slip, below the
   * pull-out slip (tr_uncertain's condition). Elsewhere (a run-up, a
   * transient, no estimate) the dynamics determine T_R: the estimate stays
   * the fit's with ls_h, and nothing is added to its bounds. */
  if (!(tr0 > 0.0f && isfinite(tr0) && isfinite(rs0) && i2 > 0.0f && fabsf(we) > 0.0f && ws != 0.0f &&
        fabsf(ws * tr0) * s->sigma < 1.0f))
    return;
  const float sls = s->sigma * s->ls_h;
  bg_impedance_t z; /* the window's impedance, as the fit saw it */
  imest__bg_impedance(we, ws, s->ls_h, s->sigma, tr0, rs0, &z);
  float tr = tr0, rs = rs0, lw = s->ls_h, err = 0.0f;
  float d_tr[FLUX_PASSES], d_rs[FLUX_PASSES]; /* each pass's change */
  for (int p = 0; p < FLUX_PASSES; ++p) {
    const float a = ws * tr, tr_in = tr, rs_in = rs;
    lw = imest__bg_flux_ls(s, sqrtf(i2 / (1.0f + a * a)), &err);
    if (!refit(&z, we, ws, lw, sls / lw, &tr, &rs)) {
      /* no motor with L_w gives this impedance: the curve and the window
       * disagree; the estimate stays, and its bounds say it is not known */
      fx->tr_b = INFINITY;
      fx->rs_b = INFINITY;
      return;
    }
    d_tr[p] = fabsf(tr - tr_in);
    d_rs[p] = fabsf(rs - rs_in);
  }
  /* The bounds: the curve's uncertainty at i_d through the first-order move
   * of the estimate with L_S (sigma L_S held: sigma moves the other way), what
   * more passes would change, and the picture's share of the move. */
  const float sg = sls / lw, e = err / lw;
  bg_impedance_t zw;
  imest__bg_impedance(we, ws, lw, sg, tr, rs, &zw);
  float e_tr, e_rs;
  imest__bg_constants_shift(&zw, sg, e, -e, tr, rs, &e_tr, &e_rs);
  const float ars = fabsf(rs);
  fx->tr_b = fabsf(e_tr) + (passes_left(d_tr) + FLUX_PICTURE_SHARE * fabsf(tr0 - tr)) / tr;
  fx->rs_b = fabsf(e_rs) + (passes_left(d_rs) + FLUX_PICTURE_SHARE * fabsf(rs0 - rs)) / ars;
  r->tr_s = (double)tr;
  r->rs_ohm = (double)rs;
  r->ls_window_h = (double)lw;
}
