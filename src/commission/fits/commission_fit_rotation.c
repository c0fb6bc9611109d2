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
 * the two levels nearest it in flux. CM_ROT_CURVE more levels complete the magnetising curve
 * with the rated point: their fluxes spread evenly from the rated point's down to
 * CM_ROT_FLUX_MIN of it (field weakening to twice base speed), each level's current that flux
 * over L_S predicted from the levels below which none was measured yet (curve_current).
 * float32: the ISR's sums are float32, and what is computed from them here are a few ratios and
 * products (no sums, no differences of near-equal terms but the slip's Re Z - R_S, whose
 * rounding, 1e-7 of R_S, is far below its noise); n_p and the counts are integers well
 * inside float32's 2^24. */
#include <math.h>
#include <stddef.h>

#include "commission_fit.h"

/* The demodulated means: Z = U / I at w_e (zr, zi), the current's amplitude and negative
   sequence. IMEST_COMM_REASON_NONE, or why it failed. */
static int impedance(imest_comm_t *c, float *zr_out, float *zi_out)
{
  imest_comm_result_t *r = &c->res;
  const float *s = c->rot_sum;
  const float n = s[CM_R_N], we = s[CM_R_WE];
  const float id = s[CM_R_ID] / n, iq = s[CM_R_IQ] / n;
  const float nd = s[CM_R_ND] / n, nq = s[CM_R_NQ] / n;
  const float hx = 0.5f * we * c->ts_s; /* below 0.1 rad: sin(x)/x by its series */
  const float hold = 1.0f - hx * hx / 6.0f * (1.0f - hx * hx / 20.0f);
  const float ud = s[CM_R_UD] / n * hold, uq = s[CM_R_UQ] / n * hold;
  const float i2 = id * id + iq * iq;
  r->rotating_f_hz = we * (float)IMEST_INV_2PI_LIT;
  r->rotating_i_a = imest__sqrt(i2);
  r->neg_seq_rel = i2 > 0.0f ? imest__sqrt((nd * nd + nq * nq) / i2) : NAN;
  if (!(i2 > 0.0f)) return IMEST_COMM_REASON_FIT;
  /* Z = U / I */
  const float zr = (ud * id + uq * iq) / i2, zi = (uq * id - ud * iq) / i2;
  r->rotating_r_ohm = zr;
  if (r->neg_seq_rel > 0.5f) return IMEST_COMM_REASON_PHASE_ORDER;
  *zr_out = zr;
  *zi_out = zi;
  return IMEST_COMM_REASON_NONE;
}

/* floor(v) for 0 <= v < 2^31 without libm (v itself otherwise: NaN stays NaN) */
static float floor_pos(float v)
{
  return v >= 0.0f && v < 2147483648.0f ? (float)(uint32_t)v : v;
}

/* n_p and the encoder's counts from the speed ratio at zero slip (arho = |rho| (1 - slip)):
   from the nameplate's rated speed if given, else the counts assumed right.
   IMEST_COMM_REASON_NONE, or why it failed. */
static int pole_pairs(imest_comm_t *c, float arho)
{
  imest_comm_result_t *r = &c->res;
  const float cpr_a = c->cfg.encoder_cpr;
  float np;
  if (c->cfg.rated_speed_rpm > 0.0f) {
    np = floor_pos(60.0f * c->cfg.rated_freq_hz / c->cfg.rated_speed_rpm);
    if (np < 1.0f) np = 1.0f;
    r->flags |= IMEST_COMM_FLAG_NP_NAMEPLATE;
    if (cpr_a > 0.0f) {
      const float cpr = floor_pos(np * cpr_a / arho + 0.5f);
      r->encoder_cpr = cpr;
      if (imest__abs(cpr - cpr_a) > 0.5f) r->flags |= IMEST_COMM_FLAG_CPR_MISMATCH;
    }
  } else {
    np = floor_pos(arho + 0.5f);
    if (!(np >= 1.0f) || !(imest__abs(arho / np - 1.0f) <= 0.02f))
      return IMEST_COMM_REASON_POLE_PAIRS_AMBIGUOUS;
    r->flags |= IMEST_COMM_FLAG_NP_ASSUMED_CPR;
    if (cpr_a > 0.0f) r->encoder_cpr = cpr_a;
  }
  r->pole_pairs = (unsigned int)np;
  return IMEST_COMM_REASON_NONE;
}

/* L_S from lx (its value at zero slip) corrected for the slip x = w_sl T_R */
static float slip_corrected(float lx, float x, float sl)
{
  float ls = lx;
  for (int it = 0; it < 3; ++it) {
    const float sig = sl / ls;
    ls = lx * (1.0f + x * x) / (1.0f + sig * x * x);
  }
  return ls;
}

/* The rated point from the search levels 0..ns-1: the current i* where L_S(i) i = psi and L_S
   there, interpolated (linearly in the current) between the last two levels (the search's
   nearest to psi); with one level, the fixed-point step i = psi / L_S from it (it was within
   1 %). Within the current limit: there the flux stays below psi. Into st[CM_LB_I], st[CM_LB_LS]
   and st[CM_LB_T], where i* is on the line: t = (i* - i_a) / (i_b - i_a), a the last level, b
   the one before (NaN: not interpolated, L_S is a's); its uncertainty: rated_std. */
static void rated_point(imest_comm_t *c, uint32_t ns, float psi, float *st)
{
  const float *a = c->blk[ns - 1u].s, *b = c->blk[ns >= 2u ? ns - 2u : 0u].s;
  const float ia = a[CM_LV_I], la = a[CM_LV_LS], ib = b[CM_LV_I], lb = b[CM_LV_LS];
  const float pa = ia * la, pb = ib * lb;
  float is = psi / la, ls = la, t = NAN;
  /* two levels whose flux increases with the current: L_S linear in the current between them,
     no further than half their distance beyond them */
  if (imest__abs(ib - ia) > 1e-6f * ia && (pb - pa) / (ib - ia) > 0.0f) {
    const float h = 0.5f * imest__abs(ib - ia);
    const float lo = (ia < ib ? ia : ib) - h, hi = (ia < ib ? ib : ia) + h;
    is = ia + (psi - pa) * (ib - ia) / (pb - pa);
    is = is < lo ? lo : (is > hi ? hi : is);
    if (is > c->psi_im) is = c->psi_im;
    t = (is - ia) / (ib - ia);
    ls = la + t * (lb - la);
  } else if (is > c->psi_im) {
    is = c->psi_im;
  }
  st[CM_LB_I] = is;
  st[CM_LB_LS] = ls;
  st[CM_LB_T] = t;
}

/* The slope of L_S between levels j and k [H/A]. */
static float level_slope(const imest_comm_t *c, uint32_t j, uint32_t k)
{
  const float *a = c->blk[j].s, *b = c->blk[k].s;
  return (b[CM_LV_LS] - a[CM_LV_LS]) / (b[CM_LV_I] - a[CM_LV_I]);
}

/* The rated point's standard error, relative, from the levels 0..last measured: the two
   levels' own, CM_ROT_LS_FLOOR each (weights 1 - t and t: independent errors at most 1.58 x
   with t down to -0.5; never below one level's, which errors common to both keep), plus a
   bound of what the line leaves of the curve there, counted as a CM_COVERAGE-th of it
   (imest_comm_apply's coverage makes it whole again). The correction L* - L_a is no error: the
   curve is measured there. The bound: the line's slope (the two levels'; not interpolated, one
   level or a flux not rising between the two: none) against the slopes to the nearest levels
   either side, the larger change (as bg_flux.c bounds its own interpolation), times
   |t (1 - t)| |i_b - i_a| (not interpolated: |i* - i_a|); with no neighbour L_S / i (the flux
   L_S i rises with the current while L_S does not: |dL_S/di| <= L_S / i). */
static float rated_std(const imest_comm_t *c, uint32_t last, uint32_t ns)
{
  const float *st = c->blk[CM_ROT_LEVELS].s;
  const float is = st[CM_LB_I], ls = st[CM_LB_LS], t = st[CM_LB_T];
  const int interp = isfinite(t);
  const uint32_t a = ns - 1u, b = interp ? ns - 2u : a;
  const float ia = c->blk[a].s[CM_LV_I], ib = c->blk[b].s[CM_LV_I];
  const uint32_t lo = ia < ib ? a : b, hi = ia < ib ? b : a;
  const float s_ab = interp ? level_slope(c, a, b) : 0.0f;
  uint32_t kd = CM_ROT_LEVELS, ku = CM_ROT_LEVELS; /* the nearest levels below and above */
  for (uint32_t k = 0u; k <= last && k < CM_ROT_LEVELS; ++k) {
    const float ik = c->blk[k].s[CM_LV_I];
    if (ik < c->blk[lo].s[CM_LV_I] && (kd == CM_ROT_LEVELS || ik > c->blk[kd].s[CM_LV_I])) kd = k;
    if (ik > c->blk[hi].s[CM_LV_I] && (ku == CM_ROT_LEVELS || ik < c->blk[ku].s[CM_LV_I])) ku = k;
  }
  float ds = -1.0f; /* the larger slope change to a neighbour; none yet */
  if (kd < CM_ROT_LEVELS) ds = imest__abs(level_slope(c, kd, lo) - s_ab);
  if (ku < CM_ROT_LEVELS) ds = BG_FMAXF(ds, imest__abs(level_slope(c, hi, ku) - s_ab));
  if (ds < 0.0f) ds = ls / (is < ia ? is : ia);
  const float w2 = interp ? (1.0f - t) * (1.0f - t) + t * t : 1.0f;
  const float rem = (interp ? imest__abs(t * (1.0f - t) * (ib - ia)) : imest__abs(is - ia)) * ds;
  return CM_ROT_LS_FLOOR * (w2 > 1.0f ? imest__sqrt(w2) : 1.0f) + rem / (CM_COVERAGE * ls);
}

/* The current of the curve's level j (0: the highest) from the levels 0..n-1 measured: its flux,
   the rated point's less (j + 1) / CM_ROT_CURVE of (1 - CM_ROT_FLUX_MIN) of it, over L_S there
   predicted by the straight line through the two levels of lowest current (one level: its L_S).
   Below them L_S rises as the current falls (the iron less saturated), by less than that line's
   continuation where the curve is concave, as a saturation curve is below about 0.85 of rated
   flux (the simulator's: its inflection at 0.85-0.9): there the prediction errs high, and the
   level's flux is at or below its target, which the lowest level must reach. Above the
   inflection the curve is convex, and the first curve level's flux comes out a little above
   its target (0.84 for 0.82 on the saturating 4 and 11 kW motors). A fixed point
   i = flux / L(i), contracting by |dL/di| i / L (0.3 on the 4 kW motor), CURVE_STEPS steps. */
#define CURVE_STEPS       4
/* The prediction's largest rise above the lowest level's L_S: the unsaturated L_m is 1.2 to
   1.35 x the rated-flux one (15-25 % saturation); the cap holds only a secant that noise made
   steep on a nearly flat curve. */
#define CURVE_LS_RISE_MAX 2.0f
/* the flux of the curve's level j (0: the highest) */
static float curve_flux(const imest_comm_t *c, uint32_t j)
{
  const float *st = c->blk[CM_ROT_LEVELS].s;
  const float frac = 1.0f - (float)(j + 1u) * ((1.0f - CM_ROT_FLUX_MIN) / (float)CM_ROT_CURVE);
  return frac * st[CM_LB_I] * st[CM_LB_LS];
}

static float curve_current(const imest_comm_t *c, uint32_t n, uint32_t j)
{
  const float flux = curve_flux(c, j);
  uint32_t a = 0u, b = 0u; /* the lowest current, the next */
  for (uint32_t k = 1u; k < n; ++k) {
    const float ik = c->blk[k].s[CM_LV_I];
    if (ik < c->blk[a].s[CM_LV_I]) {
      b = a;
      a = k;
    } else if (b == a || ik < c->blk[b].s[CM_LV_I]) {
      b = k;
    }
  }
  const float ia = c->blk[a].s[CM_LV_I], la = c->blk[a].s[CM_LV_LS];
  const float ib = c->blk[b].s[CM_LV_I], lb = c->blk[b].s[CM_LV_LS];
  float slope = 0.0f; /* dL_S/di: not positive (saturation) */
  if (ib - ia > 1e-3f * ia) slope = (lb - la) / (ib - ia);
  if (slope > 0.0f) slope = 0.0f;
  float i = flux / la;
  for (int it = 0; it < CURVE_STEPS; ++it) {
    float l = la + slope * (i - ia);
    l = l < la ? la : (l > CURVE_LS_RISE_MAX * la ? CURVE_LS_RISE_MAX * la : l);
    i = flux / l;
  }
  return i;
}

/* How long the next level settles, into st[CM_LB_SETTLE] [samples]: 1 s (the speed) and
   enough of its rotor time constant that what is left of the flux's step from level k is
   below CM_ROT_SETTLE_RESID of its flux. Why per level: the rotor flux follows a change of the
   magnetising current with T_R = L_R / R_R at the new flux, and below rated flux the iron is
   less saturated, so L_R, and T_R, is up to 1.3 x the rated flux's and about 1.9 x the
   standstill flux tails' tau (11 and 37 kW motors: 0.61 and 0.68 s against 0.32 and 0.35 s).
   3 tau, the magnetising's settle, left 5 % of the step from 0.63 to 0.45 of rated flux (40 %
   of the new flux) at the start of the lowest level's measurement: L_S +0.67 % and +1.0 %
   high there. The tails measure tau = L_R/R_R at the staircase's L_S (ls_ss), so the level's
   T_R is tau L_S / ls_ss with L_S = flux / current predicted for it: above the true one (1.5 x
   on the 4 to 37 kW motors: ls_ss is the incremental L_S), so the residual stays below. */
#define CM_ROT_SETTLE_RESID (0.2f * CM_ROT_LS_FLOOR)
#define CM_ROT_SETTLE_TAUS  12u /* at most (a whole flux step to a fifth of 0.1 %: 9) */
static void set_settle(imest_comm_t *c, uint32_t k, float i_next, float flux_next)
{
  const float flux_k = c->blk[k].s[CM_LV_I] * c->blk[k].s[CM_LV_LS];
  const float t_r = c->tau * (flux_next / i_next) / c->ls_ss;
  float left = imest__abs(flux_next - flux_k) / flux_next;
  uint32_t n = 0u;
  while (left > CM_ROT_SETTLE_RESID && n < CM_ROT_SETTLE_TAUS) {
    left *= 0.36787944f; /* e^-1 */
    n++;
  }
  c->blk[CM_ROT_LEVELS].s[CM_LB_SETTLE] = (1.0f + (float)n * t_r) * c->cfg.fs_hz;
}

/* The next level's current after level k (0: the run is complete): the search's fixed-point or
   secant step, or the curve's lower levels once the rated point is known (levels ns on); and
   how long it settles. */
static float next_level(imest_comm_t *c, uint32_t k)
{
  const imest_comm_block_t *lv = c->blk;
  float *st = c->blk[CM_ROT_LEVELS].s;
  const uint32_t ns = (uint32_t)st[CM_LB_NSEARCH];
  const float psi = c->psi, i_lim = c->psi_im;
  uint32_t j = 0u; /* the next curve level, if the next is one */
  if (st[CM_LB_I] > 0.0f && ns > 0u && k >= ns) {
    j = k - ns + 1u;
    if (j >= CM_ROT_CURVE) return 0.0f;
  } else {
    /* a search level */
    const float ik = lv[k].s[CM_LV_I], lk = lv[k].s[CM_LV_LS];
    float in = psi / lk;
    if (k > 0u) {
      const float ip = lv[k - 1u].s[CM_LV_I], lp = lv[k - 1u].s[CM_LV_LS];
      if (imest__abs(ik - ip) > 1e-6f * ik) {
        const float slope = (ik * lk - ip * lp) / (ik - ip);
        if (slope > 0.0f) in = ik + (psi - ik * lk) / slope;
      }
    }
    in = in < 0.5f * ik ? 0.5f * ik : (in > 1.5f * ik ? 1.5f * ik : in);
    if (in > i_lim) in = i_lim;
    st[CM_LB_NSEARCH] = (float)(k + 1u);
    const int at_limit = ik >= 0.999f * i_lim && in >= 0.999f * i_lim;
    if (!(imest__abs(in - ik) < 0.01f * ik || at_limit || k + 1u >= CM_ROT_SEARCH)) {
      set_settle(c, k, in, psi);
      return in;
    }
    rated_point(c, k + 1u, psi, st);
  }
  const float i = curve_current(c, k + 1u, j);
  set_settle(c, k, i, curve_flux(c, j));
  return i;
}

/* The result at the end of the run: L_S at rated flux, sigma, the magnetising curve (increasing
   current: the curve's levels, measured last, lowest flux first, then the rated point), their
   uncertainty and flux dependence. IMEST_COMM_REASON_NONE, or IMPLAUSIBLE. */
static int report(imest_comm_t *c, uint32_t last)
{
  imest_comm_result_t *r = &c->res;
  const imest_comm_block_t *lv = c->blk;
  const float *st = c->blk[CM_ROT_LEVELS].s;
  const uint32_t ns = (uint32_t)st[CM_LB_NSEARCH];
  const float ls = st[CM_LB_LS], is = st[CM_LB_I], sl = r->sigma_ls_h.value, sd = rated_std(c, last, ns);
  /* the curve's levels in increasing current, each above the one before and below the rated
     point (the estimator takes increasing currents only) */
  unsigned int n = 0u;
  for (uint32_t k = last; k >= ns && k < CM_ROT_LEVELS && n < CM_ROT_CURVE; --k) {
    const float ik = lv[k].s[CM_LV_I];
    if (!(ik < is) || (n > 0u && !(ik > r->ls_curve_i_a[n - 1u]))) continue;
    r->ls_curve_i_a[n] = ik;
    r->ls_curve_h[n] = lv[k].s[CM_LV_LS];
    n++;
  }
  r->ls_curve_i_a[n] = is;
  r->ls_curve_h[n] = ls;
  n++;
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
  /* the slip-frequency test's S is the leakage with the incremental L_M at its DC current; at
     rated flux the static L_M is another: S = L_ls + L_m L_lr / (L_m + L_lr) moves by
     (L_lr / L_R)^2 dL_m, and L_lr L_m / L_R <= S bounds that by (S / L_M)^2 |dL_M| (the split
     of the leakage between stator and rotor is not observable: the bound takes all of it in
     the rotor) */
  {
    const float lm_r = ls - sl, u = sl * imest__abs(c->sl_lm - lm_r) / (lm_r * lm_r);
    if (lm_r > 0.0f && u > r->sigma_ls_slip_h.spread_rel) r->sigma_ls_slip_h.spread_rel = u;
    if ((r->flags & IMEST_COMM_FLAG_SIGMA_SLIP) && lm_r > 0.0f && u > r->sigma_ls_h.spread_rel)
      r->sigma_ls_h.spread_rel = u;
  }
  r->sigma.value = sl / ls;
  {
    const float s1 = r->sigma_ls_h.std_rel, s2 = r->sigma_ls_h.spread_rel;
    r->sigma.std_rel = s1 + sd; /* at most sqrt(2) x their root sum of squares */
    r->sigma.spread_rel = s2 > dep ? s2 : dep;
  }
  /* T_R is the standstill flux tails' (at the staircase's currents): on a saturating motor the
     standstill L_S differs from the rated-flux one, and T_R at rated flux by a similar share */
  {
    const float ls_ss = r->ls_standstill_h.value, d = imest__abs(ls - ls_ss) / ls;
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
  const float n = s[CM_R_N], we = s[CM_R_WE];
  if (!(n > 0.0f) || !(we > 0.0f) || level >= CM_ROT_LEVELS) {
    c->final_fail = IMEST_COMM_REASON_FIT;
    return;
  }
  float zr = 0.0f, zi = 0.0f;
  int fail = impedance(c, &zr, &zi);
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  const float sl = r->sigma_ls_h.value;
  /* the encoder: travel over the measurement */
  const float dth = c->rot_th1 - c->rot_th0 + IMEST_2PI_F * (float)c->rot_wraps;
  const float wm = dth / (n * c->ts_s);
  const float lx = zi / we; /* L_S at zero slip */
  if (!(lx > 3.0f * sl)) {
    c->final_fail = IMEST_COMM_REASON_ROTOR_BLOCKED; /* the impedance of a rotor that does not turn */
    return;
  }
  if (!(imest__abs(wm) > 1e-3f * we)) {
    c->final_fail = IMEST_COMM_REASON_ENCODER_STILL;
    return;
  }
  /* slip from the resistive part: Re Z - R_S = w_e L_S (1 - sigma) x / (1 + x^2), x = w_sl T_R
     (its noise: the residual inverter error in phase with the current, a few percent of x) */
  const float tr = r->tr_s.value;
  const float x = (zr - c->rs_ff) / (we * lx * (1.0f - sl / lx));
  const float slip = tr > 0.0f ? x / (we * tr) : 0.0f;
  r->slip = slip;
  if (imest__abs(x) > 0.05f) r->flags |= IMEST_COMM_FLAG_LOAD_ON_SHAFT;
  /* speed ratio at zero slip: dir n_p cpr_assumed / cpr_true */
  const float rho = we / wm;
  r->speed_ratio = rho;
  r->encoder_dir = rho > 0.0f ? 1 : -1;
  if (rho < 0.0f) r->flags |= IMEST_COMM_FLAG_ENCODER_REVERSED;
  /* n_p and the counts from the search's levels only: the curve's lower fluxes have up to 5 x
     the slip (friction over flux squared), whose noise moved the counts by one on the 4 kW motor */
  if (!(c->blk[CM_ROT_LEVELS].s[CM_LB_I] > 0.0f)) fail = pole_pairs(c, imest__abs(rho) * (1.0f - slip));
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  imest_comm_block_t *lv = &c->blk[level];
  lv->s[CM_LV_I] = r->rotating_i_a;
  lv->s[CM_LV_LS] = slip_corrected(lx, x, sl);
  lv->s[CM_LV_ZR] = zr;
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
