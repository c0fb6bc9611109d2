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

/* The rated point from the search levels 0..ns-1: the current i* where L_S(i) i = psi and L_S
   there, interpolated (linearly in the current) between the two levels nearest psi in flux; with
   one level, the fixed-point step i = psi / L_S from it (it was within 1 %). Within the current
   limit: there the flux stays below psi. Also the rated point's uncertainty: the interpolation's
   correction to the nearest level, at least the measurement's 0.1 %. */
static void rated_point(imest_comm_t *c, uint32_t ns, double psi, double *i_out, double *ls_out, double *std_out)
{
  const imest_comm_block_t *lv = c->blk;
  uint32_t a = 0u, b = 0u;
  double da = 1e30, db = 1e30;
  for (uint32_t k = 0u; k < ns; ++k) {
    const double d = fabs((double)lv[k].s[CM_LV_LS] * (double)lv[k].s[CM_LV_I] - psi);
    if (d < da) {
      b = a;
      db = da;
      a = k;
      da = d;
    } else if (d < db) {
      b = k;
      db = d;
    }
  }
  const double ia = (double)lv[a].s[CM_LV_I], la = (double)lv[a].s[CM_LV_LS];
  const double ib = (double)lv[b].s[CM_LV_I], lb = (double)lv[b].s[CM_LV_LS];
  const double pa = ia * la, pb = ib * lb;
  /* two levels whose flux increases with the current: L_S linear in the current between them */
  const int two = ns >= 2u && fabs(ib - ia) > 1e-6 * ia && (pb - pa) / (ib - ia) > 0.0;
  double is = psi / la;
  if (two) {
    is = ia + (psi - pa) * (ib - ia) / (pb - pa);
    /* no extrapolation beyond half the levels' distance */
    const double lo = fmin(ia, ib) - 0.5 * fabs(ib - ia), hi = fmax(ia, ib) + 0.5 * fabs(ib - ia);
    is = is < lo ? lo : (is > hi ? hi : is);
  }
  if (is > (double)c->psi_im) is = (double)c->psi_im;
  const double ls = two ? la + (is - ia) * (lb - la) / (ib - ia) : la;
  *i_out = is;
  *ls_out = ls;
  const double corr = fabs(ls - la) / ls;
  *std_out = corr > 1e-3 ? corr : 1e-3;
}

/* The next level's current after level k (0: the run is complete): the search's fixed-point or
   secant step, or the curve's lower levels once the rated point is known. */
static double next_level(imest_comm_t *c, uint32_t k)
{
  imest_comm_block_t *lv = c->blk;
  float *st = c->blk[CM_ROT_LEVELS].s;
  const uint32_t ns = (uint32_t)st[CM_LB_NSEARCH];
  const double psi = (double)c->psi, i_lim = (double)c->psi_im;
  if (k > ns) return 0.0; /* the second curve level: done */
  if (k == ns && st[CM_LB_I] > 0.0f && ns > 0u) return 0.7 * (double)st[CM_LB_I];
  /* a search level */
  const double ik = (double)lv[k].s[CM_LV_I], lk = (double)lv[k].s[CM_LV_LS];
  double in = psi / lk;
  if (k > 0u) {
    const double ip = (double)lv[k - 1u].s[CM_LV_I], lp = (double)lv[k - 1u].s[CM_LV_LS];
    const double slope = (ik * lk - ip * lp) / (ik - ip);
    if (fabs(ik - ip) > 1e-6 * ik && slope > 0.0) in = ik + (psi - ik * lk) / slope;
  }
  in = in < 0.5 * ik ? 0.5 * ik : (in > 1.5 * ik ? 1.5 * ik : in);
  if (in > i_lim) in = i_lim;
  st[CM_LB_NSEARCH] = (float)(k + 1u);
  const int at_limit = ik >= 0.999 * i_lim && in >= 0.999 * i_lim;
  if (fabs(in - ik) < 0.01 * ik || at_limit || k + 1u >= CM_ROT_SEARCH) {
    double is = 0.0, ls = 0.0, sd = 0.0;
    rated_point(c, k + 1u, psi, &is, &ls, &sd);
    st[CM_LB_I] = (float)is;
    st[CM_LB_LS] = (float)ls;
    st[CM_LB_STD] = (float)sd;
    return 0.85 * is;
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
  const double ls = (double)st[CM_LB_LS], is = (double)st[CM_LB_I], sl = (double)r->sigma_ls_h.value;
  /* the curve */
  unsigned int n = 0u;
  for (uint32_t k = last; k >= ns && k < CM_ROT_LEVELS && n < 2u; --k) {
    r->ls_curve_i_a[n] = lv[k].s[CM_LV_I];
    r->ls_curve_h[n] = lv[k].s[CM_LV_LS];
    n++;
  }
  r->ls_curve_i_a[n] = (float)is;
  r->ls_curve_h[n] = (float)ls;
  n++;
  uint32_t top = 0u, nearest = 0u;
  for (uint32_t k = 0u; k < ns; ++k) {
    if (lv[k].s[CM_LV_I] > lv[top].s[CM_LV_I]) top = k;
    if (fabs((double)lv[k].s[CM_LV_I] - is) < fabs((double)lv[nearest].s[CM_LV_I] - is)) nearest = k;
  }
  if ((double)lv[top].s[CM_LV_I] > 1.05 * is) {
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
  const double dep = (double)(hi - lo) / ls; /* L_S's change over the curve: its flux dependence */
  const double sd = (double)st[CM_LB_STD];
  r->ls_curve_std_rel = (float)sd;
  r->rotating_i_a = (float)is;
  r->rotating_r_ohm = lv[nearest].s[CM_LV_ZR];
  r->ls_h.value = (float)ls;
  r->ls_h.std_rel = (float)sd;
  r->ls_h.spread_rel = (float)dep;
  r->sigma.value = (float)(sl / ls);
  {
    const double s1 = (double)r->sigma_ls_h.std_rel, s2 = (double)r->sigma_ls_h.spread_rel;
    r->sigma.std_rel = (float)sqrt(s1 * s1 + sd * sd);
    r->sigma.spread_rel = (float)(s2 > dep ? s2 : dep);
  }
  /* T_R is the standstill flux tails' (at the staircase's currents): on a saturating motor the
     standstill L_S differs from the rated-flux one, and T_R at rated flux by a similar share */
  {
    const double ls_ss = (double)r->ls_standstill_h.value, d = fabs(ls - ls_ss) / ls;
    if (ls_ss > 0.0 && !(r->tr_s.spread_rel >= (float)d)) r->tr_s.spread_rel = (float)d;
  }
  r->flags |= IMEST_COMM_FLAG_ROTATED;
  if (!(ls > 0.0 && ls < 100.0 && sl < ls)) return IMEST_COMM_REASON_IMPLAUSIBLE;
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
  const double in = next_level(c, level);
  if (in > 0.0) {
    *next = (float)in;
    return;
  }
  fail = report(c, level);
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  c->final_ready = 1;
}
