/* SPDX-License-Identifier: Apache-2.0 */
/* Background: the three axes combined into the standstill result. Sensor gains first (each
 * axis gives its sensor's gain relative to the mean of the three), then every per-axis value
 * corrected for them (an axis current read high by dev/2 makes R and the inductances read low
 * by as much), then means and spreads. R_S: the fitted R less the half-difference of the slope
 * resistances (the common part min(r_sw, r_d) stays in R_S: no terminal measurement separates
 * it) and less the user's known series resistance. sigma*L_S at slip frequency from each axis's
 * two-tone sums (commission_slip.c) with that axis's R and T_R.
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

/* sigma*L_S at tone t of slip-frequency block sums s (commission_slip.c): Z = U / I, U moved
   back by the zero-order hold's half period and scaled by its sinc, less the axis's DC
   resistance r; then (Im Z - Re Z / (w tau)) / w (imest_commission.h, "What is measured").
   NaN without a current (0 / 0). float32: the sums are float32, and what follows are a ratio and a
   difference of terms 3:1 (Im Z against Re Z / x at x = 6), 1e-7 against the blocks' 1e-3
   scatter. */
static float slip_sigma_ls(const float s[IMEST_COMM_NSUM], uint32_t t, float w, float ts, float r, float tau)
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
  const float zr = (ur * ic + ui * is) / i2 - r, zi = (ui * ic - ur * is) / i2;
  return (zi - zr / (w * tau)) / w;
}

/* The three axes' values (gain corrected): means, spreads, and the sums of the per-axis
   variances. */
typedef struct {
  float rm, rsp, slm, slsp, taum, tausp, lmm, lmsp, tdm, tdsp, vthm, vthsp, drm, drsp;
  float r_var, sl_var, td_var, vth_var, dr_var, tau_var, rms2;
  float sfm, sfsp, sf_d; /* slip-frequency sigma*L_S: mean, spread, mean D */
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
  a->sf_d = 0.0f;
  for (int k = 0; k < 3; ++k) {
    rk[k] = f[k].r_ohm * corr[k];
    slk[k] = f[k].slsig_h * corr[k];
    lmk[k] = f[k].lm_h * corr[k];
    tauk[k] = f[k].tau_s;
    tdk[k] = f[k].td_s;
    vthk[k] = f[k].vth_v;
    drk[k] = f[k].dr_ohm * corr[k];
    /* slip-frequency sigma*L_S at f1 and 2 f1 with this axis's R and T_R: the middle of its
       range over 0..f1, sigma*L_S(f1) - D / 6, and D = sigma*L_S(2 f1) - sigma*L_S(f1) */
    float v[2];
    for (uint32_t t = 0; t < 2u; ++t)
      v[t] = slip_sigma_ls(c->blk[CM_SLIP_BLK + (uint32_t)k].s, t, c->sl_w * (float)(t + 1u), c->ts_s,
                           f[k].r_ohm, f[k].tau_s) *
             corr[k];
    sfk[k] = v[0] - (v[1] - v[0]) / 6.0f;
    a->sf_d += (v[1] - v[0]) / 3.0f;
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
  /* the frequency dependence left over rotor frequencies 0..f1: |D| / 6 */
  const float dep = imest__abs(a->sf_d) / 6.0f / a->sfm;
  set_value(&r->sigma_ls_slip_h, a->sfm, NAN, a->sfsp > dep ? a->sfsp : dep);
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
  inv->i_band_a = slm > 0.0f ? vdc / (8.0f * slm * fpwm) : 0.0f;
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
  c->inv_band = inv->i_band_a > 0.0f ? inv->i_band_a : 1e-3f;
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
  if ((f[0].rhf_ohm + f[1].rhf_ohm + f[2].rhf_ohm) / 3.0f - a.rm > 3.0f * a.lmm / a.taum)
    r->flags |= IMEST_COMM_FLAG_ROTOR_HF;
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
