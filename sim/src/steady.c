/* SPDX-License-Identifier: Apache-2.0 */
/* Phasor steady state of eq. (1) under a balanced sinusoidal supply: the operating point of
 * --start steady, the IFOC rated flux, and the presets' checks. */
#include "imsim_internal.h"

static void steady_at(const imsim_config_t *c, double m, double tr, double w, double vll, double we, cpx *i,
                      cpx *psi, double *te)
{
  const double sl = c->sigma * c->ls_h;
  const double gamma = c->rs_ohm / sl + (1.0 - c->sigma) / (c->sigma * tr);
  const double beta = m / (c->sigma * c->ls_h * c->lr_h);
  const double nw = (double)c->pole_pairs * w;
  /* (j we - A) z = b U */
  const cpx m11 = cx(gamma, we);
  const cpx m12 = cx(-beta / tr, beta * nw);
  const cpx m21 = cx(-m / tr, 0.0);
  const cpx m22 = cx(1.0 / tr, we - nw);
  const cpx det = cadd(cmul(m11, m22), cscale(cmul(m12, m21), -1.0));
  const double dd = cabs2(det);
  const cpx inv = cx(det.re / dd, -det.im / dd);
  const double bu = vll / sl;
  *i = cmul(cscale(m22, bu), inv);
  *psi = cmul(cscale(m21, -bu), inv);
  *te = (double)c->pole_pairs * m / c->lr_h * (i->im * psi->re - i->re * psi->im);
}

int ims_speed_root(double (*surplus)(const void *ctx, double w), const void *ctx, double wsync, double *w)
{
  double hi = wsync, lo = wsync;
  if (surplus(ctx, hi) < 0.0) {
    int k = 0;
    for (k = 1; k <= 4000; ++k) {
      lo = wsync * (1.0 - (double)k / 4000.0);
      if (surplus(ctx, lo) > 0.0) break;
      hi = lo;
    }
    if (k > 4000) return -1;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (surplus(ctx, mid) > 0.0)
        lo = mid;
      else
        hi = mid;
    }
  }
  /* no load and no friction: synchronous speed */
  *w = 0.5 * (lo + hi);
  return 0;
}

/* The linear machine's torque surplus at speed w (ims_speed_root). */
typedef struct {
  const imsim_config_t *c;
  double m, vll_v, we, load_nm;
} lin_ctx_t;

static double lin_torque_surplus(const void *ctx, double w)
{
  const lin_ctx_t *x = (const lin_ctx_t *)ctx;
  cpx i, psi;
  double te;
  steady_at(x->c, x->m, x->c->tr_s, w, x->vll_v, x->we, &i, &psi, &te);
  return te - x->load_nm - x->c->b_nms * w;
}

int imsim_steady_state(const imsim_config_t *c, double vll_v, double freq_hz, double load_nm,
                       imsim_steady_t *out)
{
  if (ims_rm_wanted(c)) {
    imsim_real_t rm;
    char err[8];
    if (ims_rm_derive(c, &rm, err, sizeof err) != 0) return -1;
    return ims_rm_steady(c, &rm, vll_v, freq_hz, load_nm, out, NULL);
  }
  const double m = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
  const double we = 2.0 * PI * freq_hz;
  const double wsync = we / (double)c->pole_pairs;
  const lin_ctx_t x = {c, m, vll_v, we, load_nm};
  double w;
  if (ims_speed_root(lin_torque_surplus, &x, wsync, &w) != 0) return -1;
  ims_steady_at(c, NULL, vll_v, we, w, out, NULL);
  return 0;
}

void ims_steady_at(const imsim_config_t *c, const imsim_real_t *rm, double vll_v, double we, double w,
                   imsim_steady_t *out, cpx fl[4])
{
  if (rm != NULL && rm->on) {
    ims_rm_steady_at(c, rm, vll_v, we, w, out, fl);
    return;
  }
  const double m = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
  const double wsync = we / (double)c->pole_pairs;
  cpx i, psi;
  double te;
  steady_at(c, m, c->tr_s, w, vll_v, we, &i, &psi, &te);
  out->speed_rad_s = w;
  out->speed_rpm = w * 60.0 / (2.0 * PI);
  out->slip = wsync > 0.0 ? (wsync - w) / wsync : 0.0;
  out->i_rms_phase = sqrt(cabs2(i)) / sqrt(3.0);
  out->torque_nm = te;
  out->psi_r_wb = sqrt(cabs2(psi));
  out->i_ab[0] = i.re;
  out->i_ab[1] = i.im;
  out->psi_ab[0] = psi.re;
  out->psi_ab[1] = psi.im;
  out->psi_m_wb = out->lm_h = out->p_fe_w = 0.0;
}
