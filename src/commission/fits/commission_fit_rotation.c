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
 * 2 % of an integer. float64. */
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

/* L_S from lx (its value at zero slip) corrected for the slip x = w_sl T_R, and sigma.
   IMEST_COMM_REASON_NONE, or IMPLAUSIBLE. */
static int report_inductance(imest_comm_t *c, double lx, double x, double sl)
{
  imest_comm_result_t *r = &c->res;
  double ls = lx;
  for (int it = 0; it < 3; ++it) {
    const double sig = sl / ls;
    ls = lx * (1.0 + x * x) / (1.0 + sig * x * x);
  }
  /* the two independent L_S (rotating, standstill) against each other: the quality figure */
  const double ls_ss = (double)r->ls_standstill_h.value;
  r->ls_h.value = (float)ls;
  r->ls_h.std_rel = (float)NAN;
  r->ls_h.spread_rel = (float)(ls_ss > 0.0 ? fabs(ls - ls_ss) / ls : (double)NAN);
  r->sigma.value = (float)(sl / ls);
  r->sigma.std_rel = r->sigma_ls_h.std_rel;
  r->sigma.spread_rel = r->sigma_ls_h.spread_rel;
  r->flags |= IMEST_COMM_FLAG_ROTATED;
  if (!(ls > 0.0 && ls < 100.0 && sl < ls)) return IMEST_COMM_REASON_IMPLAUSIBLE;
  return IMEST_COMM_REASON_NONE;
}

void imest__cm_fit_rotation(imest_comm_t *c)
{
  imest_comm_result_t *r = &c->res;
  const float *s = c->rot_sum;
  const double n = (double)s[CM_R_N], ts = (double)c->ts_s, we = (double)s[CM_R_WE];
  if (!(n > 0.0) || !(we > 0.0)) {
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
  if (fail == IMEST_COMM_REASON_NONE) fail = report_inductance(c, lx, x, sl);
  if (fail != IMEST_COMM_REASON_NONE) {
    c->final_fail = fail;
    return;
  }
  c->final_ready = 1;
}
