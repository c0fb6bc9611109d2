/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: L_S at the window's flux (main-flux saturation) from the
 * configured magnetising curve, and T_R and R_S moved to it (docs/METHOD.md
 * §18.5). Saturation moves the main inductance, not the leakage: the window's
 * motor has L_w = L_S(i_d) and sigma_w = sigma ls_h / L_w (sigma L_S held),
 * where the solve assumed ls_h and sigma. In steady state the fit matches the
 * window's impedance Z (bg_impedance.h) with the configured constants, so Z
 * follows from the estimate, and the estimate with L_w, sigma_w is the one
 * that gives the same Z: solved in closed form (no linearisation), twice,
 * because the magnetising current |i_m| = |i| sqrt((1 + (a lambda)^2) /
 * (1 + a^2)) depends on a = slip frequency x T_R (a secant step on L_w,
 * FLUX_MAX_CONTRACTION).
 * float32: every figure is relative, as in bg_validity.c. */
#include <math.h>

#include "bg_flux.h"
#include "estimator/solve/bg_float.h" /* BG_FMAXF...: no libm fmaxf on a core without VMAXNM */

/* The fixed point L = curve(i_d(T_R(L))) is solved by one secant step: the
 * fit's T_R gives L_1 = curve(i_d), the estimate with L_1 gives L_2; the
 * fixed point of the straight line through (ls_h, L_1), (L_1, L_2) is L_w,
 * and the estimate with L_w is the result (two estimates in all). The step's
 * contraction k = (L_2 - L_1) / (L_1 - ls_h) must be below this (4 kW, rated
 * load: k about 0.3): beyond it the curve is too steep at this flux for the
 * step to be trusted, and the window's bounds say so. */
#define FLUX_MAX_CONTRACTION  0.5f
/* The steady-state picture against the estimator: moved to L_w, the estimate
 * is the one re-estimating with L_S = L_w gives to within these shares of the
 * move (measured, tools/studies/saturation: 4 and 11 kW motors, 25-100 % load
 * at 50 Hz and field weakening at 75 Hz; T_R within 5 % of its move (11 kW at
 * 25 % load: +0.50 % moved, +0.41 % re-estimated, from -1.34 % without), R_S
 * within 8 % (the same window); docs/METHOD.md §18.5). */
#define FLUX_PICTURE_SHARE_TR 0.05f
#define FLUX_PICTURE_SHARE_RS 0.1f

#if IMEST_WITH_FLUX
static float seg_slope(const float *x, const float *y, uint32_t k)
{
  return (y[k + 1u] - y[k]) / (x[k + 1u] - x[k]);
}

/* the bounds outside the points: bg_flux.h */
float imest__bg_flux_ls(const imest_t *s, float i_a, float *err_h)
{
  const uint32_t n = s->ls_curve_points;
  const float *x = s->ls_curve_i_a, *y = s->ls_curve_h;
  *err_h = 0.0f;
  if (n < 2u) return s->ls_h;
  uint32_t k = 0u; /* the segment [x_k, x_k+1]: the first, the last, or the one holding i_a */
  while (k + 2u < n && i_a > x[k + 1u]) ++k;
  const float h = x[k + 1u] - x[k], slope = seg_slope(x, y, k);
  if (!(i_a > x[0])) {
    *err_h = fabsf(slope) * (x[0] - i_a);
    return y[0];
  }
  if (!(i_a < x[n - 1u])) {
    *err_h = y[n - 1u] * (1.0f - x[n - 1u] / i_a);
    return y[n - 1u];
  }
  const float t = (i_a - x[k]) / h;
  float dslope = n == 2u ? fabsf(slope) : 0.0f; /* the slope's change at the segment's ends */
  if (k >= 1u) dslope = fabsf(slope - seg_slope(x, y, k - 1u));
  if (k + 2u < n) dslope = BG_FMAXF(dslope, fabsf(seg_slope(x, y, k + 1u) - slope));
  *err_h = t * (1.0f - t) * h * dslope;
  return y[k] + t * (y[k + 1u] - y[k]);
}

/* A window's impedance Z = zr + j zi [ohm]. */
typedef struct {
  float zr, zi;
} flux_z_t;

/* The T_R and R_S that give the impedance z with L_S = ls and sigma L_S =
 * sls: Im Z / (we ls) = (1 + sg a^2) / (1 + a^2) gives a^2, Re Z gives R_S.
 * 0 if no such motor exists (Im Z outside (sg, 1) x we ls). */
static int refit(const flux_z_t *z, float we, float ws, float ls, float sls, float *tr, float *rs)
{
  const float sg = sls / ls, q = z->zi / (we * ls);
  if (!(q > sg && q < 1.0f)) return 0;
  const float a2 = (1.0f - q) / (q - sg), a = copysignf(sqrtf(a2), ws);
  *tr = fabsf(a / ws);
  *rs = z->zr - we * ls * a * (1.0f - sg) / (1.0f + a2);
  return 1;
}

/* The rotor leakage's share of the rotor inductance, lambda = L_lr / L_R, of
 * the motor with sigma L_S = sls and L_S = ls, the leakage split equally (L_ls
 * = L_lr, so L_R = L_S and sigma_w = 1 - (1 - lambda)^2): lambda = 1 - sqrt(1
 * - sigma_w), sigma_w / 2 to within sigma_w / 4 of it (|i_m| within 0.03 %
 * at a = 2, sigma_w = 0.15). */
#define LR_SHARE(sls, ls) (0.5f * (sls) / (ls))

/* The split is not observable at the terminals. IEEE 112 puts the rotor's
 * share of the leakage at 0.5 (designs A, D, wound rotors), 0.6 (B) and 0.7
 * (C): the bound takes lambda up to this factor higher (lambda scales with
 * the share to first order), where the magnetising current is highest. */
#define FLUX_LR_SHARE_HI 1.4f

/* The magnetising current of the estimate with T_R tr, the curve's abscissa
 * (at no load the whole current): in the rotor-flux frame the stator current
 * is i_d (1 + j a), a = ws tr, and the main flux psi_m = psi_R - L_lr i_R
 * carries the rotor leakage's share of the torque current, i_m = i_d (1 + j a
 * lambda): |i_m| = |i| sqrt((1 + (a lambda)^2) / (1 + a^2)) (+0.18 % on the
 * 4 kW motor at rated load, a = 1.9, lambda = 0.032). */
static float im_at(float i2, float ws, float tr, float lam)
{
  const float a = ws * tr, al = a * lam;
  return sqrtf(i2 * (1.0f + al * al) / (1.0f + a * a));
}

/* The window's mean |i|^2 is of the currents past the ISR's linear stages,
 * while the curve's abscissa is the motor's current. At the field's
 * frequency, theta = we / fs per sample, they pass it with the gains: the
 * offset high-pass (isr_dc_block: y = x - m, m += a y, H(z) = (1 - z^-1) /
 * (1 - (1 - a) z^-1)), 1 / |H|^2 = (1 - a) + a^2 / (4 sin^2(theta / 2));
 * the alignment's delay of the currents by d of a sample (linear
 * interpolation), |G|^2 = 1 - d (1 - d) 4 sin^2(theta / 2). The amplitude
 * -0.28 % at 12.5 Hz, -0.04 % at 25 Hz and 0.00 % at 50 Hz (1 Hz cut-off,
 * half a sample, 8 kHz), what the 4 kW recordings show against the
 * simulator's currents. 1 / |G|^2 to first order (what is left is below
 * 4e-5 of |i|^2 up to 200 Hz at 8 kHz), 4 sin^2(theta / 2) as theta^2, to
 * within theta^2 / 12 of it (no sinf; a is 0 without the high-pass). */
static float i2_of_motor(const imest_t *s, float i2, float we)
{
  const float a = (float)s->dcb_a, d = (float)s->dly_i, th = we / (float)s->fs, s4 = th * th;
  return i2 * ((1.0f - a) + a * a / s4 + d * (1.0f - d) * s4);
}

/* L_S of the curve at the magnetising current of the estimate with T_R tr,
 * lambda lam. */
static float ls_at(const imest_t *s, float i2, float ws, float tr, float lam, float *err)
{
  return imest__bg_flux_ls(s, im_at(i2, ws, tr, lam), err);
}

/* The curve's points' own uncertainty beyond ls_uncertainty, relative, at the
 * flux ls i_d: each point is measured as ls_h is (no-load reactive impedance,
 * the same drive), so a voltage error that is ls_uncertainty of the last
 * point's reactive voltage is rated / flux times that share at a point of
 * lower flux (the voltage of a no-load test at one frequency is proportional
 * to its flux; commissioning: the dead time's and the devices' residual,
 * imest_commission.h). Its excess over ls_uncertainty, which the constants'
 * shift takes already, at ls_shift_e's coverage. */
static float low_flux_share(const imest_t *s, float ls, float i_d)
{
  const uint32_t n = s->ls_curve_points;
  const float last = s->ls_curve_i_a[n - 1u] * s->ls_curve_h[n - 1u], flux = ls * i_d;
  return flux > 0.0f && flux < last ? s->ls_shift_e * (last / flux - 1.0f) : 0.0f;
}

/* The secant step of FLUX_MAX_CONTRACTION: L_w from ls_h and the two curve
 * values; 0 if the step cannot be trusted. */
static int secant(float l0, float l1, float l2, float *lw)
{
  const float f0 = l1 - l0, f1 = l2 - l1;
  *lw = l1;
  if (f0 == 0.0f || f1 == 0.0f) return 1; /* on the fixed point already */
  const float k = f1 / f0;
  if (!(fabsf(k) < FLUX_MAX_CONTRACTION)) return 0;
  *lw = l1 + f1 / (1.0f - k);
  return 1;
}

void imest__bg_flux(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                    imest_result_t *r, bg_flux_t *fx)
{
  fx->tr_b = 0.0f;
  fx->rs_b = 0.0f;
  r->ls_window_h = (double)NAN;
  if (s->ls_curve_points == 0u) return;
  const float tr0 = (float)r->tr_s, rs0 = (float)r->rs_ohm, ws = st->slip_rate;
  const float we = ws + (float)s->n * st->w_mean; /* s->n: float64 in the reference build */
  const float i2 = nreg > 0u ? (float)sm->rw[3][3] / (float)nreg : 0.0f;
  /* The steady-state picture: an estimate, a field, a slip, below the
   * pull-out slip (tr_uncertain's condition). Elsewhere (a run-up, a
   * transient, no estimate) the dynamics determine T_R: the estimate stays
   * the fit's with ls_h, and nothing is added to its bounds. */
  if (!(tr0 > 0.0f && isfinite(tr0) && isfinite(rs0) && i2 > 0.0f && fabsf(we) > 0.0f && ws != 0.0f &&
        fabsf(ws * tr0) * s->sigma < 1.0f))
    return;
  const float sls = s->sigma * s->ls_h;
  const float a0 = ws * tr0, x = we * s->ls_h / (1.0f + a0 * a0);
  /* the window's impedance, as the fit saw it (bg_impedance.h's Z) */
  const flux_z_t z = {rs0 + x * a0 * (1.0f - s->sigma), x * (1.0f + s->sigma * a0 * a0)};
  float tr = tr0, rs = rs0, err, lw = s->ls_h, tr_e, rs_e;
  const float im2 = i2_of_motor(s, i2, we); /* the motor's |i|^2 */
  const float l1 = ls_at(s, im2, ws, tr0, 0.5f * s->sigma, &err);
  int ok = refit(&z, we, ws, l1, sls, &tr, &rs) &&
           secant(s->ls_h, l1, ls_at(s, im2, ws, tr, LR_SHARE(sls, l1), &err), &lw) &&
           refit(&z, we, ws, lw, sls, &tr, &rs);
  /* The curve's share of the bounds: L_w's uncertainty, i.e. its distance
   * from the curve at the result's own magnetising current (the step's
   * remainder) plus the curve's uncertainty there (the interpolation's and,
   * below the last point's flux, its points'), plus the leakage split's (the
   * curve at lambda FLUX_LR_SHARE_HI times), taken through the same closed
   * form (the estimate with L_w that much higher); and the picture's share of
   * the move. */
  const float lam = LR_SHARE(sls, lw), im = im_at(im2, ws, tr, lam);
  float e_hi;
  const float l_im = imest__bg_flux_ls(s, im, &err); /* err set before it is read */
  const float split = fabsf(ls_at(s, im2, ws, tr, FLUX_LR_SHARE_HI * lam, &e_hi) - l_im);
  const float dl = fabsf(l_im - lw) + err + split + lw * low_flux_share(s, lw, im);
  ok = ok && refit(&z, we, ws, lw + dl, sls, &tr_e, &rs_e);
  if (!ok) {
    /* no motor with the curve's L_S gives this impedance, or the curve is too
     * steep here: the curve and the window disagree. The estimate stays the
     * fit's, and its bounds say that it is not known. */
    fx->tr_b = INFINITY;
    fx->rs_b = INFINITY;
    return;
  }
  fx->tr_b = (fabsf(tr_e - tr) + FLUX_PICTURE_SHARE_TR * fabsf(tr0 - tr)) / tr;
  fx->rs_b = (fabsf(rs_e - rs) + FLUX_PICTURE_SHARE_RS * fabsf(rs0 - rs)) / fabsf(rs);
  r->tr_s = (double)tr;
  r->rs_ohm = (double)rs;
  r->ls_window_h = (double)lw;
}
#else  /* IMEST_WITH_FLUX: left out of the build, no curve (imest_config_check() refuses one) */
float imest__bg_flux_ls(const imest_t *s, float i_a, float *err_h)
{
  (void)i_a;
  *err_h = 0.0f;
  return s->ls_h;
}

void imest__bg_flux(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                    imest_result_t *r, bg_flux_t *fx)
{
  (void)s;
  (void)st;
  (void)sm;
  (void)nreg;
  fx->tr_b = 0.0f;
  fx->rs_b = 0.0f;
  r->ls_window_h = (double)NAN;
}
#endif /* IMEST_WITH_FLUX */
