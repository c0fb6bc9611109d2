/* SPDX-License-Identifier: Apache-2.0 */
/* Background: the rotating run (commission_rotate.c) -> L_S, sigma, n_p, the encoder's direction
 * and counts, the phase-order check.
 *
 * The current and the commanded voltage, demodulated at the field angle, give the impedance
 * Z = U / I at w_e (U scaled by the zero-order hold's sinc(w_e T / 2)). At slip frequency w_sl,
 * Im Z = w_e L_S (1 + sigma x^2) / (1 + x^2), x = w_sl T_R: at no load x ~ 1e-3 and the
 * correction is negligible, but it is applied. A voltage error in phase with the current (the
 * residual inverter error, friction losses) moves Re Z, not Im Z.
 *
 * The ratio w_e / w_measured = dir n_p cpr_assumed / cpr_true (1 - slip). The nameplate's rated
 * speed, if given, fixes n_p = floor(60 f_rated / n_rated) and the ratio gives the counts;
 * otherwise the counts are assumed right and n_p is the ratio rounded, which must be within
 * 2 % of an integer.
 *
 * The run has several levels of magnetising current (commission_rotate.c); each is one job.
 * L_S depends on the current on a saturating motor (its static L_m at rated flux is 15-25 %
 * below the unsaturated one), so the first level, set with the standstill L_S, is generally not
 * at the rated flux psi = V_rated / w_rated. The next levels search the current i* at which the
 * no-load stator flux L_S(i) i is psi: the first step i = psi / L_S (fixed point), then secant
 * steps on the measured flux L_S i against i, at most CM_ROT_SEARCH levels, until a step changes
 * the current by less than 1 % (the current within 80 % of the staircase's top level: at that
 * limit the run stays below the rated flux). L_S at rated flux is then interpolated between
 * the two levels nearest it in flux. Two more levels, 0.85 and 0.7 i*, complete the magnetising
 * curve (with the rated point and the first level if it ran above 1.05 i*). float64. */
#include <math.h>
#include <stddef.h>

#include "commission_fit.h"

/* The demodulated means: Z = U / I at w_e (zr, zi), the current's amplitude and negative
   sequence. IMEST_COMM_REASON_NONE, or why it failed. */
static int impedance(imest_comm_t *c, double *zr_out, double *zi_out)
{
  imest_comm_result_t *r = &c->res;
  const float *s = c->rot_sum;
  const double n = (double)s[CM_R_N], ts = (double)c->ts_s, we = (double)s[CM_R_WE];
  const double id = (double)s[CM_R_ID] / n, iq = (double)s[CM_R_IQ] / n;
  const double nd = (double)s[CM_R_ND] / n, nq = (double)s[CM_R_NQ] / n;
  const double hx = 0.5 * we * ts; /* below 0.1 rad: sin(x)/x by its series */
  const double hold = 1.0 - hx * hx / 6.0 * (1.0 - hx * hx / 20.0);
  const double ud = (double)s[CM_R_UD] / n * hold, uq = (double)s[CM_R_UQ] / n * hold;
  const double i2 = id * id + iq * iq;
  r->rotating_f_hz = (float)(we / (2.0 * IMEST_PI_D));
  r->rotating_i_a = (float)sqrt(i2);
  r->neg_seq_rel = i2 > 0.0 ? (float)sqrt((nd * nd + nq * nq) / i2) : (float)NAN;
  if (!(i2 > 0.0)) return IMEST_COMM_REASON_FIT;
  /* Z = U / I */
  const double zr = (ud * id + uq * iq) / i2, zi = (uq * id - ud * iq) / i2;
  r->rotating_r_ohm = (float)zr;
  if (r->neg_seq_rel > 0.5f) return IMEST_COMM_REASON_PHASE_ORDER;
  *zr_out = zr;
  *zi_out = zi;
  return IMEST_COMM_REASON_NONE;
}

/* n_p and the encoder's counts from the speed ratio at zero slip (arho = |rho| (1 - slip)):
   from the nameplate's rated speed if given, else the counts assumed right.
   IMEST_COMM_REASON_NONE, or why it failed. */
static int pole_pairs(imest_comm_t *c, double arho)
{
  imest_comm_result_t *r = &c->res;
  const double cpr_a = (double)c->cfg.encoder_cpr;
  double np;
  if (c->cfg.rated_speed_rpm > 0.0f) {
    np = floor(60.0 * (double)c->cfg.rated_freq_hz / (double)c->cfg.rated_speed_rpm);
    if (np < 1.0) np = 1.0;
    r->flags |= IMEST_COMM_FLAG_NP_NAMEPLATE;
    if (cpr_a > 0.0) {
      const double cpr = floor(np * cpr_a / arho + 0.5);
      r->encoder_cpr = (float)cpr;
      if (fabs(cpr - cpr_a) > 0.5) r->flags |= IMEST_COMM_FLAG_CPR_MISMATCH;
    }
  } else {
    np = floor(arho + 0.5);
    if (np < 1.0 || fabs(arho / np - 1.0) > 0.02) return IMEST_COMM_REASON_POLE_PAIRS_AMBIGUOUS;
    r->flags |= IMEST_COMM_FLAG_NP_ASSUMED_CPR;
    if (cpr_a > 0.0) r->encoder_cpr = (float)cpr_a;
  }
  r->pole_pairs = (unsigned int)np;
  return IMEST_COMM_REASON_NONE;
}

/* L_S from lx (its value at zero slip) corrected for the slip x = w_sl T_R */
static double slip_corrected(double lx, double x, double sl)
{
  double ls = lx;
  for (int it = 0; it < 3; ++it) {
    const double sig = sl / ls;
    ls = lx * (1.0 + x * x) / (1.0 + sig * x * x);
  }
  return ls;
}

/* The levels' arithmetic is float32 (a few ratios of values measured to 0.1 %; float64 would
   cost the M4F's soft-double calls in flash). */
static float absf(float x)
{
  return x < 0.0f ? -x : x;
}

/* The rated point from the search levels 0..ns-1: the current i* where L_S(i) i = psi and L_S
   there, interpolated (linearly in the current) between the last two levels (the search's
   nearest to psi); with one level, the fixed-point step i = psi / L_S from it (it was within
   1 %). Within the current limit: there the flux stays below psi. Into st[CM_LB_I], st[CM_LB_LS]
   and st[CM_LB_STD], the rated point's uncertainty: the interpolation's correction to the last
   level, at least the measurement's 0.1 %. */
static void rated_point(imest_comm_t *c, uint32_t ns, float psi, float *st)
{
  const float *a = c->blk[ns - 1u].s, *b = c->blk[ns >= 2u ? ns - 2u : 0u].s;
  const float ia = a[CM_LV_I], la = a[CM_LV_LS], ib = b[CM_LV_I], lb = b[CM_LV_LS];
  const float pa = ia * la, pb = ib * lb;
  float is = psi / la, ls = la;
  /* two levels whose flux increases with the current: L_S linear in the current between them,
     no further than half their distance beyond them */
  if (absf(ib - ia) > 1e-6f * ia && (pb - pa) / (ib - ia) > 0.0f) {
    const float h = 0.5f * absf(ib - ia);
    const float lo = (ia < ib ? ia : ib) - h, hi = (ia < ib ? ib : ia) + h;
    is = ia + (psi - pa) * (ib - ia) / (pb - pa);
    is = is < lo ? lo : (is > hi ? hi : is);
    if (is > c->psi_im) is = c->psi_im;
    ls = la + (is - ia) * (lb - la) / (ib - ia);
  } else if (is > c->psi_im) {
    is = c->psi_im;
  }
  const float corr = absf(ls - la) / ls;
  st[CM_LB_I] = is;
  st[CM_LB_LS] = ls;
  st[CM_LB_STD] = corr > 1e-3f ? corr : 1e-3f;
}

/* The next level's current after level k (0: the run is complete): the search's fixed-point or
   secant step, or the curve's lower levels once the rated point is known. */
static float next_level(imest_comm_t *c, uint32_t k)
{
  const imest_comm_block_t *lv = c->blk;
  float *st = c->blk[CM_ROT_LEVELS].s;
  const uint32_t ns = (uint32_t)st[CM_LB_NSEARCH];
  const float psi = c->psi, i_lim = c->psi_im;
  if (k > ns) return 0.0f; /* the second curve level: done */
  if (k == ns && st[CM_LB_I] > 0.0f && ns > 0u) return 0.7f * st[CM_LB_I];
  /* a search level */
  const float ik = lv[k].s[CM_LV_I], lk = lv[k].s[CM_LV_LS];
  float in = psi / lk;
  if (k > 0u) {
    const float ip = lv[k - 1u].s[CM_LV_I], lp = lv[k - 1u].s[CM_LV_LS];
    if (absf(ik - ip) > 1e-6f * ik) {
      const float slope = (ik * lk - ip * lp) / (ik - ip);
      if (slope > 0.0f) in = ik + (psi - ik * lk) / slope;
    }
  }
  in = in < 0.5f * ik ? 0.5f * ik : (in > 1.5f * ik ? 1.5f * ik : in);
  if (in > i_lim) in = i_lim;
  st[CM_LB_NSEARCH] = (float)(k + 1u);
  const int at_limit = ik >= 0.999f * i_lim && in >= 0.999f * i_lim;
  if (absf(in - ik) < 0.01f * ik || at_limit || k + 1u >= CM_ROT_SEARCH) {
    rated_point(c, k + 1u, psi, st);
    return 0.85f * st[CM_LB_I];
  }
  return in;
}

/* The result at the end of the run: L_S at rated flux, sigma, the magnetising curve (increasing
   current: 0.7 i*, 0.85 i*, the rated point, the first level if it ran above 1.05 i*), their
   uncertainty and flux dependence. IMEST_COMM_REASON_NONE, or IMPLAUSIBLE. */
static int report(imest_comm_t *c, uint32_t last)
{
  imest_comm_result_t *r = &c->res;
  const imest_comm_block_t *lv = c->blk;
  const float *st = c->blk[CM_ROT_LEVELS].s;
  const uint32_t ns = (uint32_t)st[CM_LB_NSEARCH];
  const float ls = st[CM_LB_LS], is = st[CM_LB_I], sl = r->sigma_ls_h.value, sd = st[CM_LB_STD];
  /* the curve: the two lower levels (measured last), the rated point, the top level */
  unsigned int n = 0u;
  for (uint32_t k = last; k >= ns && k < CM_ROT_LEVELS && n < 2u; --k) {
    r->ls_curve_i_a[n] = lv[k].s[CM_LV_I];
    r->ls_curve_h[n] = lv[k].s[CM_LV_LS];
    n++;
  }
  r->ls_curve_i_a[n] = is;
  r->ls_curve_h[n] = ls;
  n++;
  uint32_t top = 0u;
  for (uint32_t k = 1u; k < ns; ++k)
    if (lv[k].s[CM_LV_I] > lv[top].s[CM_LV_I]) top = k;
  if (lv[top].s[CM_LV_I] > 1.05f * is) {
    r->ls_curve_i_a[n] = lv[top].s[CM_LV_I];
    r->ls_curve_h[n] = lv[top].s[CM_LV_LS];
    n++;
  }
  r->ls_curve_points = n;
  float lo = r->ls_curve_h[0], hi = lo;
  for (unsigned int j = 1u; j < n; ++j) {
    if (r->ls_curve_h[j] < lo) lo = r->ls_curve_h[j];
    if (r->ls_curve_h[j] > hi) hi = r->ls_curve_h[j];
  }
  const float dep = (hi - lo) / ls; /* L_S's change over the curve: its flux dependence */
  r->rotating_i_a = is;
  r->rotating_r_ohm = lv[ns - 1u].s[CM_LV_ZR]; /* the level nearest rated flux */
  r->ls_h.value = ls;
  r->ls_h.std_rel = sd;
  r->ls_h.spread_rel = dep;
  r->sigma.value = sl / ls;
  {
    const float s1 = r->sigma_ls_h.std_rel, s2 = r->sigma_ls_h.spread_rel;
    r->sigma.std_rel = s1 + sd; /* at most sqrt(2) x their root sum of squares */
    r->sigma.spread_rel = s2 > dep ? s2 : dep;
  }
  /* T_R is the standstill flux tails' (at the staircase's currents): on a saturating motor the
     standstill L_S differs from the rated-flux one, and T_R at rated flux by a similar share */
  {
    const float ls_ss = r->ls_standstill_h.value, d = absf(ls - ls_ss) / ls;
    if (ls_ss > 0.0f && !(r->tr_s.spread_rel >= d)) r->tr_s.spread_rel = d;
  }
  r->flags |= IMEST_COMM_FLAG_ROTATED;
  if (!(ls > 0.0f && ls < 100.0f && sl < ls)) return IMEST_COMM_REASON_IMPLAUSIBLE;
  return IMEST_COMM_REASON_NONE;
}

/* One level of the rotating run (its number in the job's kind): its impedance, the encoder, the
   next level's current for the ISR (blk[CM_ROT_LEVELS].s[CM_LB_NEXT], 0 when done); the result
   after the last. */
void imest__cm_fit_rotation(imest_comm_t *c)
{
  imest_comm_result_t *r = &c->res;
  const float *s = c->rot_sum;
  const uint32_t level = (c->job_kind >> 4) & 0xFu;
  float *next = &c->blk[CM_ROT_LEVELS].s[CM_LB_NEXT];
  *next = 0.0f;
  const double n = (double)s[CM_R_N], ts = (double)c->ts_s, we = (double)s[CM_R_WE];
  if (!(n > 0.0) || !(we > 0.0) || level >= CM_ROT_LEVELS) {
    c->final_fail = IMEST_COMM_REASON_FIT;
    return;
  }
  double zr = 0.0, zi = 0.0;
  int fail = impedance(c, &zr, &zi);
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  const double sl = (double)r->sigma_ls_h.value;
  /* the encoder: travel over the measurement */
  const double dth = (double)c->rot_th1 - (double)c->rot_th0 + 2.0 * IMEST_PI_D * (double)c->rot_wraps;
  const double wm = dth / (n * ts);
  const double lx = zi / we; /* L_S at zero slip */
  if (!(lx > 3.0 * sl)) {
    c->final_fail = IMEST_COMM_REASON_ROTOR_BLOCKED; /* the impedance of a rotor that does not turn */
    return;
  }
  if (!(fabs(wm) > 1e-3 * we)) {
    c->final_fail = IMEST_COMM_REASON_ENCODER_STILL;
    return;
  }
  /* slip from the resistive part: Re Z - R_S = w_e L_S (1 - sigma) x / (1 + x^2), x = w_sl T_R
     (its noise: the residual inverter error in phase with the current, a few percent of x) */
  const double tr = (double)r->tr_s.value;
  const double x = (zr - (double)c->rs_ff) / (we * lx * (1.0 - sl / lx));
  const double slip = tr > 0.0 ? x / (we * tr) : 0.0;
  r->slip = (float)slip;
  if (fabs(x) > 0.05) r->flags |= IMEST_COMM_FLAG_LOAD_ON_SHAFT;
  /* speed ratio at zero slip: dir n_p cpr_assumed / cpr_true */
  const double rho = we / wm;
  r->speed_ratio = (float)rho;
  r->encoder_dir = rho > 0.0 ? 1 : -1;
  if (rho < 0.0) r->flags |= IMEST_COMM_FLAG_ENCODER_REVERSED;
  fail = pole_pairs(c, fabs(rho) * (1.0 - slip));
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  imest_comm_block_t *lv = &c->blk[level];
  lv->s[CM_LV_I] = r->rotating_i_a;
  lv->s[CM_LV_LS] = (float)slip_corrected(lx, x, sl);
  lv->s[CM_LV_ZR] = (float)zr;
  const float in = next_level(c, level);
  if (in > 0.0f) {
    *next = in;
    return;
  }
  fail = report(c, level);
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  c->final_ready = 1;
}
