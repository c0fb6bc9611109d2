/* SPDX-License-Identifier: Apache-2.0 */
/* Reference integrator: classic RK4 of the full nonlinear model (electrical and mechanical
 * states together), one constant-input piece at a time. Slow; used to measure the fast path. */
#include "imsim_internal.h"

static void full_deriv(const imsim_t *s, const ims_full_state_t *X, cpx u_pwm, const step_input_t *in,
                       double tl, ims_full_state_t *d)
{
  const imsim_config_t *c = &s->c;
  const double bi = 1.0 / (c->sigma * c->ls_h);
  const double nw = (double)c->pole_pairs * X->w;
  const cpx u = in->src ? X->x[6] : u_pwm;
  const cpx i = X->x[0], psi = X->x[1];
  const cpx a12 = cx(s->beta / s->tr, -s->beta * nw);
  const cpx a22 = cx(-1.0 / s->tr, nw);
  d->x[0] = cadd(cadd(cscale(u, bi), cscale(i, -s->gamma)), cmul(a12, psi));
  d->x[1] = cadd(cscale(i, s->m_h / s->tr), cmul(a22, psi));
  const double wc = in->aa ? 2.0 * PI * c->aa_hz : 0.0;
  const double swc = SQRT2 * wc;
  d->x[2] = cscale(X->x[3], wc);
  d->x[3] = cx(wc * (i.re - X->x[2].re) - swc * X->x[3].re, wc * (i.im - X->x[2].im) - swc * X->x[3].im);
  d->x[4] = cscale(X->x[5], wc);
  d->x[5] = cx(wc * (u.re - X->x[4].re) - swc * X->x[5].re, wc * (u.im - X->x[4].im) - swc * X->x[5].im);
  d->x[6] = in->src ? cmul(cx(0.0, in->we), X->x[6]) : cx(0.0, 0.0);
  const double te = ims_torque_of(s, i, psi);
  d->w = (te - tl - c->b_nms * X->w) / c->j_kgm2;
  d->th = X->w;
}

static void full_axpy(ims_full_state_t *out, const ims_full_state_t *a, double k, const ims_full_state_t *b)
{
  for (int q = 0; q < 7; ++q) out->x[q] = cx(a->x[q].re + k * b->x[q].re, a->x[q].im + k * b->x[q].im);
  out->w = a->w + k * b->w;
  out->th = a->th + k * b->th;
}

void ims_rk4_piece(const imsim_t *s, ims_full_state_t *X, double len, cpx u_pwm, const step_input_t *in,
                   double tl)
{
  const int n = s->c.rk4_substeps;
  const double hh = len / (double)n;
  for (int it = 0; it < n; ++it) {
    ims_full_state_t k1, k2, k3, k4, tmp;
    full_deriv(s, X, u_pwm, in, tl, &k1);
    full_axpy(&tmp, X, 0.5 * hh, &k1);
    full_deriv(s, &tmp, u_pwm, in, tl, &k2);
    full_axpy(&tmp, X, 0.5 * hh, &k2);
    full_deriv(s, &tmp, u_pwm, in, tl, &k3);
    full_axpy(&tmp, X, hh, &k3);
    full_deriv(s, &tmp, u_pwm, in, tl, &k4);
    for (int q = 0; q < 7; ++q) {
      X->x[q].re += hh / 6.0 * (k1.x[q].re + 2.0 * k2.x[q].re + 2.0 * k3.x[q].re + k4.x[q].re);
      X->x[q].im += hh / 6.0 * (k1.x[q].im + 2.0 * k2.x[q].im + 2.0 * k3.x[q].im + k4.x[q].im);
    }
    X->w += hh / 6.0 * (k1.w + 2.0 * k2.w + 2.0 * k3.w + k4.w);
    X->th += hh / 6.0 * (k1.th + 2.0 * k2.th + 2.0 * k3.th + k4.th);
  }
}
