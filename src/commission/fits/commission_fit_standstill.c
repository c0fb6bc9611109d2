/* SPDX-License-Identifier: Apache-2.0 */
/* Background: the three axes combined into the standstill result. Sensor gains first (each
 * axis gives its sensor's gain relative to the mean of the three), then every per-axis value
 * corrected for them (an axis current read high by dev/2 makes R and the inductances read low
 * by as much), then means and spreads. R_S: the fitted R less the half-difference of the slope
 * resistances (the common part min(r_sw, r_d) stays in R_S: no terminal measurement separates
 * it) and less the user's known series resistance. sigma*L_S at slip frequency from each axis's
 * two-tone sums (commission_slip.c) with that axis's R (their own magnetising branch: no T_R).
 * float32: the per-axis fits (float64) are done; what is left are means, spreads and sums of
 * squares of three values each, with no cancellation (float32's 6e-8 against the fits' 1e-4
 * standard errors), and every result is a float. */
#include <math.h>
#include <stddef.h>

#include "commission_fit.h"

static void mean_spread(const float v[3], float *mean, float *spread)
{
  float lo = v[0], hi = v[0], s = 0.0f;
  for (int k = 0; k < 3; ++k) {
    s += v[k];
    if (v[k] < lo) lo = v[k];
    if (v[k] > hi) hi = v[k];
  }
  *mean = s / 3.0f;
  *spread = *mean != 0.0f ? (hi - lo) / imest__abs(*mean) : NAN;
}

static void set_value(imest_comm_value_t *out, float value, float std_rel, float spread)
{
  out->value = value;
  out->std_rel = std_rel;
  out->spread_rel = spread;
}

/* Z - r at tone t of slip-frequency block sums s (commission_slip.c): Z = U / I, U moved back
   by the zero-order hold's half period and scaled by its sinc, less the axis's DC resistance r.
   NaN without a current (0 / 0). */
static void slip_z(const float s[IMEST_COMM_NSUM], uint32_t t, float w, float ts, float r, float *zr,
                   float *zi)
{
  const float *st = s + (size_t)t * (size_t)CM_L_TONE;
  /* the phasor of x_k = Re(X e^{j theta_k}) is X = (2 / n) sum x_k e^{-j theta_k}, and the ISR
     summed x cos and x sin */
  const float ic = st[CM_L_IC], is = -st[CM_L_IS], vc = st[CM_L_VC], vs = -st[CM_L_VS];
  const float h = 0.5f * w * ts, h2 = h * h; /* below 0.04 rad: the series */
  const float ch = 1.0f - 0.5f * h2, sh = h * (1.0f - h2 / 6.0f), sinc = 1.0f - h2 / 6.0f;
  /* U e^{-j h} sinc */
  const float ur = (vc * ch + vs * sh) * sinc, ui = (vs * ch - vc * sh) * sinc;
  const float i2 = ic * ic + is * is;
  *zr = (ur * ic + ui * is) / i2 - r;
  *zi = (ui * ic - ur * is) / i2;
}

/* One axis's slip-frequency sigma*L_S from its two tones, w1 and w2 = CM_SLIP_M w1, with the
   axis's DC resistance r (imest_commission.h, "What is measured"). In the inverse-Gamma circuit
   Z_k - r - j w_k S = 1 / (1 / R'_k + 1 / (j w_k L_M)): the magnetising branch L_M (the
   incremental one at the test's DC current, which no standstill T_R gives on a saturating
   motor) is the same at both tones, the rotor's R'_k may differ (deep bars), so S is the root
   of w_1 Im y_1(S) = w_2 Im y_2(S) = -1 / L_M, y_k = 1 / (Z_k - r - j w_k S). Newton's steps
   from the root with R'_1 = R'_2 (closed form); the root has its error from the leakage's own
   frequency dependence only. rp[k]: R'_k, *lm: L_M; returns S, NaN without the tones. float32: Im y_k is
   a difference of terms up to 15:1 (the upper tone), 1e-6 against the blocks' 1e-3 scatter. */
static float slip_sigma_ls(const float s[IMEST_COMM_NSUM], float w1, float ts, float r, float rp[2],
                           float *lm)
{
  float a[2], b[2], w[2] = {w1, w1 * (float)CM_SLIP_M};
  for (uint32_t t = 0u; t < 2u; ++t) slip_z(s, t, w[t], ts, r, &a[t], &b[t]);
  /* Im Z_k - w_k S = Re Z_k / (w_k T): the same T at both tones */
  const float p1 = b[0] / w[0], p2 = b[1] / w[1], q1 = a[0] / (w[0] * w[0]), q2 = a[1] / (w[1] * w[1]);
  float S = p1 - q1 * (p1 - p2) / (q1 - q2);
  for (int it = 0; it < 4; ++it) {
    float g = 0.0f, dg = 0.0f;
    for (uint32_t t = 0u; t < 2u; ++t) {
      const float be = b[t] - w[t] * S, d = a[t] * a[t] + be * be, sg = t == 0u ? 1.0f : -1.0f;
      g += sg * w[t] * be / d;
      dg -= sg * w[t] * w[t] * (a[t] * a[t] - be * be) / (d * d);
    }
    S -= g / dg;
  }
  for (uint32_t t = 0u; t < 2u; ++t) {
    const float be = b[t] - w[t] * S;
    rp[t] = (a[t] * a[t] + be * be) / a[t];
    if (t == 0u) *lm = (a[t] * a[t] + be * be) / (w[t] * be); /* -1 / (w_1 Im y_1) */
  }
  return S;
}

/* The three axes' values (gain corrected): means, spreads, and the sums of the per-axis
   variances. */
typedef struct {
  float rm, rsp, slm, slsp, taum, tausp, lmm, lmsp, tdm, tdsp, vthm, vthsp, drm, drsp;
  float r_var, sl_var, td_var, vth_var, dr_var, tau_var, rms2;
  float sfm, sfsp, sf_d, sf_lm,
      sf_rr; /* R_R' at the lower tone; slip-frequency sigma*L_S: mean, spread, mean correction; L_M */
} axes_t;

/* Sensor gains relative to their mean (three sensors only), and the correction factor each
   axis's values take for its sensor. */
static void sensor_gains(imest_comm_t *c, float corr[3])
{
  imest_comm_result_t *r = &c->res;
  const imest_comm_axis_fit_t *f = c->fit;
  float dev[3] = {0, 0, 0};
  if (c->cfg.n_sensors != 3u) return;
  const float mean = (f[0].gain_dev + f[1].gain_dev + f[2].gain_dev) / 3.0f;
  float worst = 0.0f;
  for (int k = 0; k < 3; ++k) {
    dev[k] = f[k].gain_dev - mean;
    corr[k] = 1.0f + 0.5f * dev[k];
    r->i_gain_rel[k] = 1.0f + dev[k];
    c->bg_ginv[k] = 1.0f / (1.0f + dev[k]);
    if (imest__abs(dev[k]) > worst) worst = imest__abs(dev[k]);
  }
  r->flags |= IMEST_COMM_FLAG_GAINS;
  if (worst > 0.005f) r->flags |= IMEST_COMM_FLAG_GAIN_MISMATCH;
}

/* Every per-axis value corrected for its sensor's gain, then means and spreads. */
static void combine_axes(imest_comm_t *c, const float corr[3], axes_t *a)
{
  imest_comm_result_t *r = &c->res;
  const imest_comm_axis_fit_t *f = c->fit;
  float rk[3], slk[3], tauk[3], lmk[3], tdk[3], vthk[3], drk[3], sfk[3];
  a->r_var = a->sl_var = a->td_var = a->vth_var = a->dr_var = a->tau_var = a->rms2 = 0.0f;
  a->sf_d = a->sf_lm = a->sf_rr = 0.0f;
  for (int k = 0; k < 3; ++k) {
    rk[k] = f[k].r_ohm * corr[k];
    slk[k] = f[k].slsig_h * corr[k];
    lmk[k] = f[k].lm_h * corr[k];
    tauk[k] = f[k].tau_s;
    tdk[k] = f[k].td_s;
    vthk[k] = f[k].vth_v;
    drk[k] = f[k].dr_ohm * corr[k];
    /* slip-frequency sigma*L_S with this axis's R; the leakage's frequency dependence from a
       double cage's one pole: the leakage falls by tau x the resistance's rise, tau = the
       square wave's leakage drop over its resistance rise (both the rotor's high-frequency
       limits against the tones'), and the resistance rises as w^2: from 0 to f1 by
       (R'_2 - R'_1) / (M^2 - 1). The root above is S(0) - (M^2 + 1) x that fall c (each tone's
       S(w_k) = S(0) - c (w_k / w1)^2 weighted by the Im condition); it is corrected, and c
       (M^2 + 1) stays as the frequency dependence */
    float rp[2], lm;
    const float sk =
        slip_sigma_ls(c->blk[CM_SLIP_BLK + (uint32_t)k].s, c->sl_w, c->ts_s, f[k].r_ohm, rp, &lm);
    a->sf_lm += lm * corr[k] / 3.0f;
    a->sf_rr += rp[0] * corr[k] / 3.0f;
    const float dl = sk - f[k].slsig_h, dr = f[k].rhf_ohm - f[k].r_ohm - rp[0];
    const float drise = (rp[1] - rp[0]) / (float)(CM_SLIP_M * CM_SLIP_M - 1u);
    const float fall = dl > 0.0f && dr > 0.0f && drise > 0.0f ? dl / dr * drise : 0.0f;
    const float kap = (float)(CM_SLIP_M * CM_SLIP_M + 1u);
    sfk[k] = (sk + kap * fall) * corr[k];
    a->sf_d += kap * fall * corr[k] / 3.0f;
    a->r_var += f[k].r_std * f[k].r_std;
    a->sl_var += (f[k].slsig_std * f[k].slsig_h) * (f[k].slsig_std * f[k].slsig_h);
    a->td_var += f[k].td_std * f[k].td_std;
    a->vth_var += f[k].vth_std * f[k].vth_std;
    a->dr_var += f[k].dr_std * f[k].dr_std;
    a->tau_var += f[k].tau_std * f[k].tau_std;
    a->rms2 += f[k].rms_v * f[k].rms_v;
    r->rs_axis_ohm[k] = rk[k] - c->cfg.r_series_ohm;
  }
  mean_spread(rk, &a->rm, &a->rsp);
  mean_spread(slk, &a->slm, &a->slsp);
  mean_spread(tauk, &a->taum, &a->tausp);
  mean_spread(lmk, &a->lmm, &a->lmsp);
  mean_spread(tdk, &a->tdm, &a->tdsp);
  mean_spread(vthk, &a->vthm, &a->vthsp);
  mean_spread(drk, &a->drm, &a->drsp);
  mean_spread(sfk, &a->sfm, &a->sfsp);
}

/* The standstill values with their qualities; returns R_S. */
static float report_values(imest_comm_t *c, const axes_t *a)
{
  imest_comm_result_t *r = &c->res;
  const float rs = a->rm - 0.5f * imest__abs(a->drm) - c->cfg.r_series_ohm;
  for (int k = 0; k < 3; ++k) r->rs_axis_ohm[k] -= 0.5f * imest__abs(a->drm);
  set_value(&r->rs_ohm, rs, imest__sqrt(a->r_var) / 3.0f / rs, a->rsp * a->rm / rs);
  set_value(&r->sigma_ls_hf_h, a->slm, imest__sqrt(a->sl_var) / 3.0f / a->slm, a->slsp);
  r->slip_test_hz = c->sl_w * (float)IMEST_INV_2PI_LIT;
  /* the leakage's frequency dependence, the correction's size */
  const float dep = a->sf_d / a->sfm;
  set_value(&r->sigma_ls_slip_h, a->sfm, NAN, a->sfsp > dep ? a->sfsp : dep);
  c->sl_lm = a->sf_lm;
  /* a deep-bar rotor's sigma*L_S is the slip-frequency one; without it (NaN fails), the square
     wave's, marked as not the one needed */
  const int hf = (r->flags & IMEST_COMM_FLAG_ROTOR_HF) != 0u, slip = hf && a->sfm > 0.0f;
  imest__cm_copy(&r->sigma_ls_h, slip ? &r->sigma_ls_slip_h : &r->sigma_ls_hf_h, sizeof r->sigma_ls_h);
  if (slip) r->flags |= IMEST_COMM_FLAG_SIGMA_SLIP;
  if (hf && !slip && !(r->sigma_ls_h.spread_rel >= 0.5f)) r->sigma_ls_h.spread_rel = 0.5f;
  set_value(&r->tr_s, a->taum, imest__sqrt(a->tau_var) / 3.0f / a->taum, a->tausp);
  set_value(&r->dead_time_s, a->tdm, imest__sqrt(a->td_var) / 3.0f / imest__abs(a->tdm), a->tdsp);
  set_value(&r->v_threshold_v, a->vthm, imest__sqrt(a->vth_var) / 3.0f / imest__abs(a->vthm), a->vthsp);
  set_value(&r->dr_ohm, a->drm, imest__sqrt(a->dr_var) / 3.0f / imest__abs(a->drm), a->drsp);
  /* the flux tails' L_S: their (1 - sigma) L_S plus the sigma*L_S of the same (slow) rotor */
  const float ls_ss = r->sigma_ls_h.value + a->lmm;
  set_value(&r->ls_standstill_h, ls_ss, NAN, (a->lmsp * a->lmm) / ls_ss);
  set_value(&r->rr_ohm, a->lmm / a->taum, NAN, NAN);
  r->dc_fit_rms_v = imest__sqrt(a->rms2 / 3.0f);
  return rs;
}

/* the inverter model (imest_inverter_t) */
static void inverter_model(imest_comm_t *c, const axes_t *a)
{
  const float vdc = c->vdc0, fpwm = c->fpwm;
  const float tdm = a->tdm, vthm = a->vthm, drm = a->drm, slm = a->slm;
  imest_inverter_t *inv = &c->res.inverter;
  inv->dead_time_s = tdm;
  inv->v_switch_v = vthm;
  inv->v_diode_v = vthm;
  inv->r_switch_ohm = drm > 0.0f ? drm : 0.0f;
  inv->r_diode_ohm = drm < 0.0f ? -drm : 0.0f;
  /* 0: the estimator sets the smooth sign's band per leg and sample from its own duties (the
     ripple at the edges plus the dead time's transition), which follows the operating point; a
     fixed band cannot. Commissioning's own feed-forward uses the ripple's peak. */
  inv->i_band_a = 0.0f;
  c->inv_band = slm > 0.0f ? vdc / (8.0f * slm * fpwm) : 1e-3f;
  {
    /* relative uncertainty of the model's error: the fit (3 sigma), the spread between axes,
       and 0.1 V for the switch/diode threshold difference standstill cannot see */
    const float e_typ = imest__abs(tdm) * fpwm * vdc + imest__abs(vthm);
    const float e_td = (3.0f * imest__sqrt(a->td_var) / 3.0f + 0.5f * imest__abs(a->tdsp * tdm)) * fpwm * vdc;
    const float e_v = 3.0f * imest__sqrt(a->vth_var) / 3.0f + 0.5f * imest__abs(a->vthsp * vthm) + 0.1f;
    float u = e_typ > 0.0f ? imest__sqrt(e_td * e_td + e_v * e_v) / e_typ : 1.0f;
    if (u < 0.02f) u = 0.02f;
    inv->uncertainty = u;
  }
}

/* for the rotating part: the loop's resistance and the inverter feed-forward; without it, L_S
   and sigma from standstill and the result is ready */
static void prepare_rotation(imest_comm_t *c, const axes_t *a, float rs)
{
  imest_comm_result_t *r = &c->res;
  const imest_inverter_t *inv = &r->inverter;
  const float ls_ss = r->ls_standstill_h.value;
  c->rs_ff = rs + c->cfg.r_series_ohm;
  c->inv_td_f = a->tdm * c->fpwm;
  c->inv_v = a->vthm;
  c->inv_rsw = inv->r_switch_ohm;
  c->inv_rd = inv->r_diode_ohm;
  c->tau = a->taum;
  c->ls_ss = ls_ss;
  if (!c->cfg.allow_rotation) {
    set_value(&r->ls_h, ls_ss, NAN, NAN);
    set_value(&r->sigma, r->sigma_ls_h.value / ls_ss, NAN, r->sigma_ls_h.spread_rel);
    r->flags |= IMEST_COMM_FLAG_LS_STANDSTILL;
    c->final_ready = 1;
  }
}

void imest__cm_fit_standstill(imest_comm_t *c)
{
  imest_comm_result_t *r = &c->res;
  const imest_comm_axis_fit_t *f = c->fit;
  float corr[3] = {1, 1, 1};
  axes_t a;
  sensor_gains(c, corr);
  combine_axes(c, corr, &a);
  /* the rotor's resistance at the square wave's frequency against R_R' from the flux tails: far
     above it (deep bars, a double cage; single cages stay below 2.2 x, saturated or not), the
     square wave's sigma*L_S is the rotor's high-frequency leakage, below the slip-frequency one */
  const float rr_hf = (f[0].rhf_ohm + f[1].rhf_ohm + f[2].rhf_ohm) / 3.0f - a.rm;
  if (rr_hf > 3.0f * a.lmm / a.taum) r->flags |= IMEST_COMM_FLAG_ROTOR_HF;
  set_value(&r->rr_hf_ohm, rr_hf, NAN, NAN);
  set_value(&r->rr_slip_ohm, a.sf_rr > 0.0f ? a.sf_rr : NAN, NAN, NAN);
  const float rs = report_values(c, &a);
  inverter_model(c, &a);
  if (a.rsp > 0.03f || a.slsp > 0.03f) r->flags |= IMEST_COMM_FLAG_AXIS_SPREAD;
  if (!f[0].separable || !f[1].separable || !f[2].separable) r->flags |= IMEST_COMM_FLAG_INVERTER_LUMPED;
  r->flags |= IMEST_COMM_FLAG_STANDSTILL;

  /* plausibility */
  const int ok = rs > 0.0f && rs < 1e3f && a.slm > 0.0f && a.slm < 10.0f && a.taum > 1e-3f &&
                 a.taum < 30.0f && a.tdm > -0.5e-6f && a.tdm < 20e-6f && a.vthm > -0.5f && a.vthm < 5.0f &&
                 a.lmm > 0.0f;
  if (!ok) {
    c->bg_fail = IMEST_COMM_REASON_IMPLAUSIBLE;
    return;
  }
  prepare_rotation(c, &a, rs);
}
