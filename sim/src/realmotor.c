/* SPDX-License-Identifier: Apache-2.0 */
/* Real-motor effects: main-flux saturation, iron loss, double-cage rotor (sim/README.md,
 * Real-motor effects). The machine in flux-linkage form, stationary frame, power invariant:
 *   d psi_S/dt  = u - R_S i_S,                       psi_S  = L_ls i_S  + psi_m
 *   d psi_Rk/dt = -R_Rk i_Rk + j n_p w psi_Rk,       psi_Rk = L_Rk i_Rk + psi_m   (k = 1, 2)
 *   i_S + sum_k i_Rk = i_m(psi_m) + i_fe,            i_m = psi_m / L_m(|psi_m|),
 *   i_fe = (d psi_m/dt) / R_fe,                      T_e = n_p (i_R x psi_m)
 * Without R_fe, psi_m follows from the fluxes (scalar Newton on |psi_m|, its direction is that
 * of sum psi_j / L_j); with R_fe it is a state: d psi_m/dt = R_fe (i_S + sum i_Rk - i_m).
 * The static curve i_m(|psi_m|) along psi_m is all the model needs: the incremental
 * (dynamic) inductance and the cross-saturation follow from it through the flux states. */
#include <stdio.h>
#include <string.h>

#include "imsim_internal.h"

#define SAT_EXP 6    /* i_m = psi/L_m0 (1 + a (psi/psi_n)^6): a polynomial a1 psi + a7 psi^7 */
#define CAGE_C  0.05 /* double cage: outer-cage leakage / inner-cage leakage                 */
#define FE_HMAX 1.5  /* RK4 step x fastest (iron-loss) eigenvalue, well inside RK4's 2.78     */
#define EL_HMAX 0.05 /* RK4 step x the fastest other electrical rate                          */
#define H_CAP_S 20e-6

bool ims_rm_wanted(const imsim_config_t *c)
{
  return c->sat_fraction != 0.0 || c->iron_loss_fraction != 0.0 || c->rotor_cage_ratio != 0.0;
}

static double pow6(double x)
{
  const double x2 = x * x;
  return x2 * x2 * x2;
}

double ims_rm_lm_static(const imsim_real_t *rm, double x)
{
  return rm->lm0_h / (1.0 + rm->sat_a * pow6(x / rm->psi_n_wb));
}

/* magnetic field energy of the main flux, int_0^x i_m dpsi */
static double wm_of(const imsim_real_t *rm, double x)
{
  return 0.5 * x * x / rm->lm0_h * (1.0 + 0.25 * rm->sat_a * pow6(x / rm->psi_n_wb));
}

/* Rotor impedance of the cage at slip angular frequency wsl (kr: thermal factor of R_R). */
static cpx cage_z(const imsim_real_t *rm, double kr, double wsl)
{
  const cpx z1 = cx(kr * rm->r1_ohm, wsl * rm->l1_h);
  if (!rm->dc) return z1;
  const cpx z2 = cx(kr * rm->r2_ohm, wsl * rm->l2_h);
  const cpx num = cmul(z1, z2), den = cadd(z1, z2);
  const double dd = cabs2(den);
  return cx((num.re * den.re + num.im * den.im) / dd, (num.im * den.re - num.re * den.im) / dd);
}

/* Branches of the double cage for the DC resistance r, DC leakage l and outer share g. */
static void cage_design(double r, double l, double g, imsim_real_t *rm)
{
  rm->r1_ohm = r / g;
  rm->r2_ohm = r / (1.0 - g);
  rm->l2_h = l / ((1.0 - g) * (1.0 - g) + CAGE_C * g * g);
  rm->l1_h = CAGE_C * rm->l2_h;
}

static double cage_ratio(double r, double l, double g, double w, imsim_real_t *rm)
{
  cage_design(r, l, g, rm);
  return cage_z(rm, 1.0, w).re / r;
}

int ims_rm_derive(const imsim_config_t *c, imsim_real_t *rm, char *err, size_t errlen)
{
  memset(rm, 0, sizeof *rm);
  if (!ims_rm_wanted(c)) return 0;
  if (!(c->sat_fraction >= 0.0 && c->sat_fraction < 0.6)) {
    snprintf(err, errlen, "saturation fraction must be in [0, 0.6)");
    return -1;
  }
  if (!(c->iron_loss_fraction >= 0.0 && c->iron_loss_fraction < 0.2)) {
    snprintf(err, errlen, "iron-loss fraction must be in [0, 0.2)");
    return -1;
  }
  if (!(c->rotor_cage_ratio == 0.0 || (c->rotor_cage_ratio > 1.0 && c->rotor_cage_ratio <= 4.0))) {
    snprintf(err, errlen, "double-cage ratio must be in (1, 4] (0 = single cage)");
    return -1;
  }
  const double m = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
  rm->lls_h = c->ls_h - m;
  rm->llr_h = c->lr_h - m;
  if (!(rm->lls_h > 0.0) || !(rm->llr_h > 0.0)) {
    snprintf(err, errlen, "real-motor effects need leakage inductances L_S - M and L_R - M > 0");
    return -1;
  }
  /* rated point of the linear machine */
  imsim_config_t lin = *c;
  lin.sat_fraction = lin.iron_loss_fraction = lin.rotor_cage_ratio = 0.0;
  const double vn = c->rated_voltage_v > 0.0 ? c->rated_voltage_v : c->vll_v;
  const double fn = c->rated_freq_hz > 0.0 ? c->rated_freq_hz : c->freq_hz;
  const double tn = c->rated_torque_nm > 0.0 ? c->rated_torque_nm : c->load_nm;
  imsim_steady_t st;
  if (!(vn > 0.0 && fn > 0.0) || imsim_steady_state(&lin, vn, fn, tn, &st) != 0) {
    snprintf(err, errlen,
             "real-motor effects need a rated point (rated or supply voltage and frequency "
             "> 0, load below breakdown)");
    return -1;
  }
  const cpx i = cx(st.i_ab[0], st.i_ab[1]), psir = cx(st.psi_ab[0], st.psi_ab[1]);
  const cpx ir = cscale(cadd(psir, cscale(i, -m)), 1.0 / c->lr_h);
  rm->psi_n_wb = m * sqrt(cabs2(cadd(i, ir)));
  rm->f_n_hz = fn;
  rm->sat_a = c->sat_fraction / (1.0 - c->sat_fraction);
  rm->lm0_h = m / (1.0 - c->sat_fraction);
  const double wn = 2.0 * PI * fn;
  if (c->iron_loss_fraction > 0.0) {
    const double pn = c->rated_power_w > 0.0 ? c->rated_power_w : tn * st.speed_rad_s;
    if (!(pn > 0.0)) {
      snprintf(err, errlen, "iron loss needs rated_power_w or a load at the rated point");
      return -1;
    }
    const double en = wn * rm->psi_n_wb;
    rm->fe = true;
    rm->rfe_ohm = en * en / (c->iron_loss_fraction * pn);
  }
  const double rr = c->lr_h / c->tr_s;
  rm->r1_ohm = rr;
  rm->l1_h = rm->llr_h;
  if (c->rotor_cage_ratio > 0.0) {
    rm->dc = true;
    double gpk = 0.0, kpk = 1.0;
    for (int q = 1; q < 190; ++q) {
      const double g = 0.005 * (double)q, k = cage_ratio(rr, rm->llr_h, g, wn, rm);
      if (k > kpk) {
        kpk = k;
        gpk = g;
      }
    }
    if (c->rotor_cage_ratio > kpk) {
      snprintf(err, errlen,
               "double-cage ratio %.3g not reachable with this rotor's leakage (R_R %.4g ohm, L_lr %.4g H "
               "at %.4g Hz): at most %.3g",
               c->rotor_cage_ratio, rr, rm->llr_h, fn, kpk);
      return -1;
    }
    double lo = 0.0, hi = gpk;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (cage_ratio(rr, rm->llr_h, mid, wn, rm) < c->rotor_cage_ratio)
        lo = mid;
      else
        hi = mid;
    }
    cage_design(rr, rm->llr_h, 0.5 * (lo + hi), rm);
  }
  /* RK4 step bound: the iron-loss mode (R_fe over the parallel of the leakages and the
     incremental L_m up to 1.3 psi_n) and the other electrical rates (rotor 1.6x hot) */
  double g = 1.0 / rm->lls_h + 1.0 / rm->l1_h + (rm->dc ? 1.0 / rm->l2_h : 0.0);
  double lam = c->rs_ohm / rm->lls_h;
  lam = fmax(lam, 1.6 * rm->r1_ohm / rm->l1_h);
  if (rm->dc) lam = fmax(lam, 1.6 * rm->r2_ohm / rm->l2_h);
  lam = fmax(lam, 2.0 * wn);
  rm->h_max_s = fmin(H_CAP_S, EL_HMAX / lam);
  if (rm->fe) {
    g += (1.0 + 7.0 * rm->sat_a * pow6(1.3)) / rm->lm0_h;
    rm->h_max_s = fmin(rm->h_max_s, FE_HMAX / (rm->rfe_ohm * g));
  }
  rm->inv_lls = 1.0 / rm->lls_h;
  rm->inv_l1 = 1.0 / rm->l1_h;
  rm->inv_l2 = rm->dc ? 1.0 / rm->l2_h : 0.0;
  rm->inv_lm0 = 1.0 / rm->lm0_h;
  rm->inv_psi_n = 1.0 / rm->psi_n_wb;
  rm->g_node = rm->inv_lls + rm->inv_l1 + rm->inv_l2 + rm->inv_lm0;
  rm->sat_k = rm->sat_a * rm->inv_lm0 * pow6(rm->inv_psi_n);
  rm->on = true;
  return 0;
}

/* ---- currents from the fluxes ----------------------------------------------------------- */

typedef struct {
  cpx is, i1, i2, psim, ife;
} rm_cur_t;

static void currents(const imsim_real_t *rm, const cpx fl[4], rm_cur_t *o)
{
  cpx psim;
  if (rm->fe) {
    psim = fl[3];
  } else {
    cpx sum = cadd(cscale(fl[0], rm->inv_lls), cscale(fl[1], rm->inv_l1));
    if (rm->dc) sum = cadd(sum, cscale(fl[2], rm->inv_l2));
    /* g_node x + sat_k x^7 = |sum|: from above the root (the linear solution) Newton descends
       monotonically, the curve being convex. Its error after a step dx is below
       3 dx^2 / x (f''/2f' <= 3/x for this curve), so a step of 1e-9 x leaves < 1e-17 x */
    const double sa = sqrt(cabs2(sum));
    double x = sa / rm->g_node;
    if (rm->sat_a > 0.0) {
      for (int it = 0; it < 60; ++it) {
        const double k6 = rm->sat_k * pow6(x);
        const double dx = (x * (rm->g_node + k6) - sa) / (rm->g_node + 7.0 * k6);
        x -= dx;
        if (fabs(dx) <= 1e-9 * x) break;
      }
    }
    psim = sa > 0.0 ? cscale(sum, x / sa) : cx(0.0, 0.0);
  }
  o->psim = psim;
  const cpx mpsim = cscale(psim, -1.0);
  o->is = cscale(cadd(fl[0], mpsim), rm->inv_lls);
  o->i1 = cscale(cadd(fl[1], mpsim), rm->inv_l1);
  o->i2 = rm->dc ? cscale(cadd(fl[2], mpsim), rm->inv_l2) : cx(0.0, 0.0);
  if (rm->fe) {
    /* i_m / |psi_m| from |psi_m|^2: no square root */
    const double u2 = cabs2(psim) * rm->inv_psi_n * rm->inv_psi_n;
    const double ks = rm->inv_lm0 * (1.0 + rm->sat_a * u2 * u2 * u2);
    o->ife = cadd(cadd(o->is, o->i1), cadd(o->i2, cscale(psim, -ks)));
  } else {
    o->ife = cx(0.0, 0.0);
  }
}

static double torque(const imsim_t *s, const rm_cur_t *k)
{
  const cpx ir = cadd(k->i1, k->i2);
  return (double)s->c.pole_pairs * (ir.re * k->psim.im - ir.im * k->psim.re);
}

/* ---- RK4 of the flux-linkage model -------------------------------------------------------- */

typedef struct {
  cpx fl[4], aa[4], src;
  double w, th;
  double efe; /* iron-loss energy: integrated alongside, read by nothing of the model */
} rm_state_t;

static void deriv(const imsim_t *s, const rm_state_t *X, cpx u_pwm, const step_input_t *in, double tl,
                  rm_state_t *d)
{
  const imsim_config_t *c = &s->c;
  const imsim_real_t *rm = &s->rm;
  const double kr = s->rr / s->rr0_ohm;
  const double nw = (double)c->pole_pairs * X->w;
  rm_cur_t k;
  currents(rm, X->fl, &k);
  const cpx u = in->src ? X->src : u_pwm;
  d->fl[0] = cadd(u, cscale(k.is, -s->rs));
  d->fl[1] = cadd(cscale(k.i1, -kr * rm->r1_ohm), cmul(cx(0.0, nw), X->fl[1]));
  d->fl[2] = rm->dc ? cadd(cscale(k.i2, -kr * rm->r2_ohm), cmul(cx(0.0, nw), X->fl[2])) : cx(0.0, 0.0);
  d->fl[3] = rm->fe ? cscale(k.ife, rm->rfe_ohm) : cx(0.0, 0.0);
  d->efe = rm->fe ? rm->rfe_ohm * cabs2(k.ife) : 0.0;
  const double wc = in->aa ? 2.0 * PI * c->aa_hz : 0.0;
  const double swc = SQRT2 * wc;
  const cpx i = k.is;
  d->aa[0] = cscale(X->aa[1], wc);
  d->aa[1] = cx(wc * (i.re - X->aa[0].re) - swc * X->aa[1].re, wc * (i.im - X->aa[0].im) - swc * X->aa[1].im);
  d->aa[2] = cscale(X->aa[3], wc);
  d->aa[3] = cx(wc * (u.re - X->aa[2].re) - swc * X->aa[3].re, wc * (u.im - X->aa[2].im) - swc * X->aa[3].im);
  d->src = in->src ? cmul(cx(0.0, in->we), X->src) : cx(0.0, 0.0);
  d->w = (torque(s, &k) - tl - c->b_nms * X->w) / c->j_kgm2;
  d->th = X->w;
}

static void axpy(rm_state_t *out, const rm_state_t *a, double k, const rm_state_t *b)
{
  for (int q = 0; q < 4; ++q) {
    out->fl[q] = cadd(a->fl[q], cscale(b->fl[q], k));
    out->aa[q] = cadd(a->aa[q], cscale(b->aa[q], k));
  }
  out->src = cadd(a->src, cscale(b->src, k));
  out->w = a->w + k * b->w;
  out->th = a->th + k * b->th;
  out->efe = a->efe + k * b->efe;
}

void ims_rm_piece(imsim_t *s, double len, cpx u_pwm, const step_input_t *in, double tl)
{
  rm_state_t X;
  for (int q = 0; q < 4; ++q) {
    X.fl[q] = s->rm.fl[q];
    X.aa[q] = s->x[2 + q];
  }
  X.src = s->x[6];
  X.w = s->w;
  X.th = s->th;
  X.efe = s->rm.e_fe_j;
  int n = (int)ceil(len / s->rm.h_max_s);
  if (n < s->c.rk4_substeps) n = s->c.rk4_substeps;
  const double hh = len / (double)n;
  for (int it = 0; it < n; ++it) {
    rm_state_t k1, k2, k3, k4, tmp;
    deriv(s, &X, u_pwm, in, tl, &k1);
    axpy(&tmp, &X, 0.5 * hh, &k1);
    deriv(s, &tmp, u_pwm, in, tl, &k2);
    axpy(&tmp, &X, 0.5 * hh, &k2);
    deriv(s, &tmp, u_pwm, in, tl, &k3);
    axpy(&tmp, &X, hh, &k3);
    deriv(s, &tmp, u_pwm, in, tl, &k4);
    axpy(&tmp, &k1, 2.0, &k2);
    axpy(&tmp, &tmp, 2.0, &k3);
    axpy(&tmp, &tmp, 1.0, &k4);
    axpy(&X, &X, hh / 6.0, &tmp);
  }
  for (int q = 0; q < 4; ++q) {
    s->rm.fl[q] = X.fl[q];
    s->x[2 + q] = X.aa[q];
  }
  s->x[6] = X.src;
  s->w = X.w;
  s->th = X.th;
  s->rm.e_fe_j = X.efe;
  ims_rm_sync(s, tl);
}

void ims_rm_sync(imsim_t *s, double tl)
{
  rm_cur_t k;
  currents(&s->rm, s->rm.fl, &k);
  s->x[0] = k.is;
  s->x[1] = cadd(k.psim, cscale(cadd(k.i1, k.i2), s->rm.llr_h));
  s->te = torque(s, &k);
  s->acc = (s->te - tl - s->c.b_nms * s->w) / s->c.j_kgm2;
}

double ims_rm_p_rotor(const imsim_t *s)
{
  rm_cur_t k;
  currents(&s->rm, s->rm.fl, &k);
  const double kr = s->rr / s->rr0_ohm;
  return kr * (s->rm.r1_ohm * cabs2(k.i1) + s->rm.r2_ohm * cabs2(k.i2));
}

/* The T_R an IFOC needs in the steady state: the one for which its slip relation
   omega_sl = i_q / (T_R i_d) holds, with i_d, i_q the stator current in the frame of the rotor
   flux psi_R = psi_m + L_lr,eff i_R (the frame in which the rotor current is in quadrature:
   i_R = -j omega_sl psi_R / R_R,eff). With psi_R real, psi_m = psi_R (1 + j a),
   a = omega_sl L_lr,eff / R_R,eff, and i_S = psi_m (1/L_m + j omega_e / R_fe) - i_R:
     i_d = psi_R (1/L_m - a omega_e / R_fe),
     i_q = psi_R (omega_sl (L_m + L_lr,eff) / (L_m R_R,eff) + omega_e / R_fe),
   so T_R,ifoc = ((L_m + L_lr,eff)/R_R,eff + L_m omega_e / (omega_sl R_fe)) /
                 (1 - a L_m omega_e / R_fe).
   Without iron loss (R_fe infinite) it is L_R,eff / R_R,eff; with it the iron-loss current,
   in phase with the EMF (in quadrature with the flux), adds to i_q a share that does not scale
   with the slip, and T_R,ifoc grows without bound as the slip goes to 0 (no load). Slip not yet
   known (the first sample): tr_s. */
static double tr_ifoc(const imsim_real_t *rm, double lm, double rr, double llr, double we, double wsl)
{
  const double tr = (lm + llr) / rr;
  if (!rm->fe) return tr;
  const double ws = fabs(wsl) > 1e-6 ? wsl : (wsl < 0.0 ? -1e-6 : 1e-6); /* as tr_s's 1e-6 */
  const double k = lm * we / rm->rfe_ohm;                                /* omega_e L_m / R_fe */
  return (tr + k / ws) / (1.0 - ws * llr / rr * k);
}

void ims_rm_fill(imsim_t *s, imsim_sample_t *o)
{
  imsim_real_t *rm = &s->rm;
  rm_cur_t k;
  currents(rm, rm->fl, &k);
  const double kr = s->rr / s->rr0_ohm;
  const double x = sqrt(cabs2(k.psim));
  o->p_cu_rotor_w = kr * (rm->r1_ohm * cabs2(k.i1) + rm->r2_ohm * cabs2(k.i2));
  /* The iron loss over the sample period that just ended, not R_fe |i_fe|^2 at the sample
     instant: with PWM the EMF across R_fe carries the carrier's ripple, whose loss a
     carrier-synchronous sample misses: it always falls on a zero vector (4 kW, 8 kHz, 3.5 %
     iron loss, ideal inverter: 88 W at the instant, 144 W dissipated, 135 W at the fundamental).
     The first sample has no period behind it and takes the instant's value. */
  const double dt = s->t - rm->t_prev_s;
  o->p_fe_w = !rm->fe                    ? 0.0
              : rm->has_prev && dt > 0.0 ? (rm->e_fe_j - rm->e_fe_prev_j) / dt
                                         : rm->rfe_ohm * cabs2(k.ife);
  rm->e_fe_prev_j = rm->e_fe_j;
  rm->t_prev_s = s->t;
  o->psi_m_wb = x;
  o->lm_h = ims_rm_lm_static(rm, x);
  o->w_mag_j = 0.5 * rm->lls_h * cabs2(k.is) + 0.5 * rm->l1_h * cabs2(k.i1) + 0.5 * rm->l2_h * cabs2(k.i2) +
               wm_of(rm, x);
  /* slip frequency: the main flux's rotation over the last sample period, less n_p w */
  double wsl = 0.0;
  const bool slip_known = rm->has_prev && x > 0.0 && cabs2(rm->psi_m_prev) > 0.0;
  if (slip_known) {
    const cpx p = rm->psi_m_prev;
    const double dphi = atan2(p.re * k.psim.im - p.im * k.psim.re, p.re * k.psim.re + p.im * k.psim.im);
    wsl = dphi * s->c.fs_hz - (double)s->c.pole_pairs * s->w;
  }
  rm->psi_m_prev = k.psim;
  rm->has_prev = true;
  const double we = fmax(fabs(wsl), 1e-6);
  const cpx z = cage_z(rm, kr, we);
  o->rr_eff_ohm = z.re;
  o->lr_eff_h = o->lm_h + z.im / we;
  o->tr_s = o->lr_eff_h / o->rr_eff_ohm;
  o->tr_ifoc_s =
      slip_known ? tr_ifoc(rm, o->lm_h, z.re, z.im / we, wsl + (double)s->c.pole_pairs * s->w, wsl) : o->tr_s;
}

/* ---- phasor steady state ------------------------------------------------------------------ */

static cpx cinv(cpx a)
{
  const double d = cabs2(a);
  return cx(a.re / d, -a.im / d);
}

typedef struct {
  cpx is, i1, i2, psim, e;
  double te, lm;
} rm_phasor_t;

/* Phasors at speed w (u = vll + j0 at t = 0): |psi_m| by bisection of its fixed point. */
static void phasor_at(const imsim_config_t *c, const imsim_real_t *rm, double vll, double we, double w,
                      rm_phasor_t *o)
{
  const double wsl = we - (double)c->pole_pairs * w;
  /* Y_k = 1 / (R_k we / wsl + j we L_k) */
  const cpx y1 = cscale(cinv(cx(rm->r1_ohm * we, we * rm->l1_h * wsl)), wsl);
  const cpx y2 = rm->dc ? cscale(cinv(cx(rm->r2_ohm * we, we * rm->l2_h * wsl)), wsl) : cx(0.0, 0.0);
  const cpx yr = cadd(y1, y2);
  double lo = 0.0, hi = 0.0;
  for (int it = 0; it < 120; ++it) {
    const double x = it == 0 ? 0.0 : 0.5 * (lo + hi);
    const double lm = ims_rm_lm_static(rm, x);
    const cpx ym = cadd(cx(rm->fe ? 1.0 / rm->rfe_ohm : 0.0, 0.0), cinv(cx(0.0, we * lm)));
    const cpx zp = cinv(cadd(ym, yr));
    const cpx z = cadd(cx(c->rs_ohm, we * rm->lls_h), zp);
    o->is = cmul(cx(vll, 0.0), cinv(z));
    o->e = cmul(o->is, zp);
    o->psim = cmul(o->e, cx(0.0, -1.0 / we));
    o->lm = lm;
    const double ax = sqrt(cabs2(o->psim));
    if (it == 0) {
      hi = ax;
    } else if (ax > x) {
      lo = x;
    } else {
      hi = x;
    }
  }
  /* rotor currents into the magnetising node (the time-domain convention): i_Rk = -E Y_k */
  o->i1 = cscale(cmul(o->e, y1), -1.0);
  o->i2 = cscale(cmul(o->e, y2), -1.0);
  const cpx ir = cadd(o->i1, o->i2);
  o->te = (double)c->pole_pairs * (ir.re * o->psim.im - ir.im * o->psim.re);
}

/* The real machine's torque surplus at speed w (ims_speed_root). */
typedef struct {
  const imsim_config_t *c;
  const imsim_real_t *rm;
  double vll_v, we, load_nm;
} rm_ctx_t;

static double rm_torque_surplus(const void *ctx, double w)
{
  const rm_ctx_t *x = (const rm_ctx_t *)ctx;
  rm_phasor_t ph;
  phasor_at(x->c, x->rm, x->vll_v, x->we, w, &ph);
  return ph.te - x->load_nm - x->c->b_nms * w;
}

int ims_rm_steady(const imsim_config_t *c, const imsim_real_t *rm, double vll_v, double freq_hz,
                  double load_nm, imsim_steady_t *out, cpx fl[4])
{
  if (!(freq_hz > 0.0)) return -1;
  const double we = 2.0 * PI * freq_hz;
  const double wsync = we / (double)c->pole_pairs;
  const rm_ctx_t x = {c, rm, vll_v, we, load_nm};
  double w;
  if (ims_speed_root(rm_torque_surplus, &x, wsync, &w) != 0) return -1;
  ims_rm_steady_at(c, rm, vll_v, we, w, out, fl);
  return 0;
}

void ims_rm_steady_at(const imsim_config_t *c, const imsim_real_t *rm, double vll_v, double we, double w,
                      imsim_steady_t *out, cpx fl[4])
{
  const double wsync = we / (double)c->pole_pairs;
  rm_phasor_t ph;
  phasor_at(c, rm, vll_v, we, w, &ph);
  const cpx ir = cadd(ph.i1, ph.i2);
  const cpx psir = cadd(ph.psim, cscale(ir, rm->llr_h));
  out->speed_rad_s = w;
  out->speed_rpm = w * 60.0 / (2.0 * PI);
  out->slip = (wsync - w) / wsync;
  out->i_rms_phase = sqrt(cabs2(ph.is)) / sqrt(3.0);
  out->torque_nm = ph.te;
  out->psi_r_wb = sqrt(cabs2(psir));
  out->i_ab[0] = ph.is.re;
  out->i_ab[1] = ph.is.im;
  out->psi_ab[0] = psir.re;
  out->psi_ab[1] = psir.im;
  out->psi_m_wb = sqrt(cabs2(ph.psim));
  out->lm_h = ph.lm;
  out->p_fe_w = rm->fe ? cabs2(ph.e) / rm->rfe_ohm : 0.0;
  if (fl != NULL) {
    fl[0] = cadd(ph.psim, cscale(ph.is, rm->lls_h));
    fl[1] = cadd(ph.psim, cscale(ph.i1, rm->l1_h));
    fl[2] = rm->dc ? cadd(ph.psim, cscale(ph.i2, rm->l2_h)) : cx(0.0, 0.0);
    fl[3] = ph.psim;
  }
}

int imsim_real_params(const imsim_config_t *c, imsim_real_params_t *out)
{
  imsim_real_t rm;
  char err[8];
  memset(out, 0, sizeof *out);
  if (ims_rm_derive(c, &rm, err, sizeof err) != 0) return -1;
  if (!rm.on) return 0;
  out->lm0_h = rm.lm0_h;
  out->psi_n_wb = rm.psi_n_wb;
  out->sat_a = rm.sat_a;
  out->lls_h = rm.lls_h;
  out->llr_h = rm.llr_h;
  out->rfe_ohm = rm.fe ? rm.rfe_ohm : 0.0;
  out->r1_ohm = rm.r1_ohm;
  out->l1_h = rm.l1_h;
  out->r2_ohm = rm.dc ? rm.r2_ohm : 0.0;
  out->l2_h = rm.dc ? rm.l2_h : 0.0;
  out->f_n_hz = rm.f_n_hz;
  out->h_max_s = rm.h_max_s;
  return 0;
}
