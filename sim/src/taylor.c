/* SPDX-License-Identifier: Apache-2.0 */
/* Fast propagator: x(h) = sum_k A^k [h^k/k! x0 + m_k B] by Horner, A frozen over the step:
 * the exact (to a Taylor tolerance) solution of the linear electrical part of eq. (1). */
#include "imsim_internal.h"

const double IMS_INV_FACT[34] = {1.0,
                                 1.0,
                                 0.5,
                                 1.0 / 6,
                                 1.0 / 24,
                                 1.0 / 120,
                                 1.0 / 720,
                                 1.0 / 5040,
                                 1.0 / 40320,
                                 1.0 / 362880,
                                 1.0 / 3628800,
                                 1.0 / 39916800,
                                 1.0 / 479001600,
                                 1.0 / 6227020800.0,
                                 1.0 / 87178291200.0,
                                 1.0 / 1307674368000.0,
                                 1.0 / 20922789888000.0,
                                 1.0 / 355687428096000.0,
                                 1.0 / 6402373705728000.0,
                                 1.0 / 121645100408832000.0,
                                 1.0 / 2432902008176640000.0,
                                 1.0 / 51090942171709440000.0,
                                 1.0 / 1124000727777607680000.0,
                                 1.0 / 25852016738884976640000.0,
                                 1.0 / 620448401733239439360000.0,
                                 1.0 / 15511210043330985984000000.0,
                                 1.0 / 403291461126605635584000000.0,
                                 1.0 / 10888869450418352160768000000.0,
                                 1.0 / 304888344611713860501504000000.0,
                                 1.0 / 8841761993739701954543616000000.0,
                                 1.0 / 265252859812191058636308480000000.0,
                                 1.0 / 8222838654177922817725562880000000.0,
                                 1.0 / 263130836933693530167218012160000000.0,
                                 1.0 / 8683317618811886495518194401280000000.0};

const double IMS_INV_K[33] = {0.0,      1.0,      1.0 / 2,  1.0 / 3,  1.0 / 4,  1.0 / 5,  1.0 / 6,
                              1.0 / 7,  1.0 / 8,  1.0 / 9,  1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13,
                              1.0 / 14, 1.0 / 15, 1.0 / 16, 1.0 / 17, 1.0 / 18, 1.0 / 19, 1.0 / 20,
                              1.0 / 21, 1.0 / 22, 1.0 / 23, 1.0 / 24, 1.0 / 25, 1.0 / 26, 1.0 / 27,
                              1.0 / 28, 1.0 / 29, 1.0 / 30, 1.0 / 31, 1.0 / 32};

/* Smallest Taylor order p with ||A h||^(p+1)/(p+1)! e^||A h|| < 1e-14 (balanced norm bound);
   the system is stable, so this local truncation error stays bounded (order 1e-11 globally). */
int ims_taylor_order_rho(double rho)
{
  double term = 1.0;
  const double er = rho < 1.0 ? 2.72 : exp(rho);
  int p = 0;
  while (p < 30) {
    term *= rho * IMS_INV_K[p + 1];
    if (term * er < 1e-14 && p >= 2) break;
    ++p;
  }
  return p;
}

/* Norm bound of the augmented A (per second). */
double ims_a_norm(const imsim_t *s, double w, const step_input_t *in)
{
  const imsim_config_t *c = &s->c;
  const double nw = fabs((double)c->pole_pairs * w);
  double norm = s->gamma + s->beta * s->m_h / s->tr + 2.0 * (1.0 / s->tr + nw);
  if (in->aa) norm += (2.0 + SQRT2) * 2.0 * PI * c->aa_hz;
  if (in->src) norm += fabs(in->we);
  return norm;
}

int ims_taylor_order(const imsim_t *s, double w, const step_input_t *in)
{
  return ims_taylor_order_rho(ims_a_norm(s, w, in) * s->h_s);
}

typedef struct {
  double bi, a11, a21, wc, swc;
  cpx a12, a22, jwe;
  bool aa, src;
} amat;

/* z = A y (augmented, frozen omega). */
static inline void apply_a(const amat *m, const cpx *y, cpx *z)
{
  z[0] = cadd(cscale(y[0], m->a11), cmul(m->a12, y[1]));
  if (m->src) z[0] = cadd(z[0], cscale(y[6], m->bi));
  z[1] = cadd(cscale(y[0], m->a21), cmul(m->a22, y[1]));
  if (m->aa) {
    const double wc = m->wc, swc = m->swc;
    const cpx uin = m->src ? y[6] : cx(0.0, 0.0);
    z[2] = cscale(y[3], wc);
    z[3] = cx(wc * (y[0].re - y[2].re) - swc * y[3].re, wc * (y[0].im - y[2].im) - swc * y[3].im);
    z[4] = cscale(y[5], wc);
    z[5] = cx(wc * (uin.re - y[4].re) - swc * y[5].re, wc * (uin.im - y[4].im) - swc * y[5].im);
  } else {
    z[2] = z[3] = z[4] = z[5] = cx(0.0, 0.0);
  }
  z[6] = m->src ? cmul(m->jwe, y[6]) : cx(0.0, 0.0);
}

/* Exact (to the Taylor tolerance) propagation over h of the linear electrical system with
   omega frozen at w_mid, plus the leading Magnus correction for omega varying linearly over
   the step: dx = n omega' h^3/12 [A1, A] x_mid, A1 = dA/d(n omega) = [[0, -j beta], [0, j]].
   The input does not enter the correction because A1 B = 0, so it holds for PWM too. */
void ims_fast_step(imsim_t *s, const double *hkv, double w_mid, double nwdot, const step_input_t *in)
{
  const imsim_config_t *c = &s->c;
  const double nw = (double)c->pole_pairs * w_mid;
  amat m;
  m.bi = 1.0 / (c->sigma * c->ls_h);
  m.a11 = -s->gamma;
  m.a12 = cx(s->beta / s->tr, -s->beta * nw);
  m.a21 = s->m_h / s->tr;
  m.a22 = cx(-1.0 / s->tr, nw);
  m.wc = in->aa ? 2.0 * PI * c->aa_hz : 0.0;
  m.swc = SQRT2 * m.wc;
  m.jwe = cx(0.0, in->we);
  m.aa = in->aa;
  m.src = in->src;
  const int p = in->p;
  enum { NS = 7 };
  cpx y[NS];
  const cpx x00 = s->x[0], x01 = s->x[1], x06 = s->x[6];
  if (!in->aa) {
    /* motor block only (+ source state): the common, fast path */
    cpx y0 = cscale(x00, hkv[p]), y1 = cscale(x01, hkv[p]), y6 = cscale(x06, hkv[p]);
    if (in->pwm) y0 = cadd(y0, cscale(in->mom[p], m.bi));
    for (int k = p - 1; k >= 0; --k) {
      const double hk = hkv[k];
      cpx z0 = cadd(cscale(y0, m.a11), cmul(m.a12, y1));
      const cpx z1 = cadd(cscale(y0, m.a21), cmul(m.a22, y1));
      if (in->src) {
        z0 = cadd(z0, cscale(y6, m.bi));
        y6 = cadd(cmul(m.jwe, y6), cscale(x06, hk));
      } else {
        z0 = cadd(z0, cscale(in->mom[k], m.bi));
      }
      y0 = cadd(z0, cscale(x00, hk));
      y1 = cadd(z1, cscale(x01, hk));
    }
    y[0] = y0;
    y[1] = y1;
    for (int q = 2; q < NS; ++q) y[q] = s->x[q];
    y[6] = y6;
  } else {
    cpx x0[NS], z[NS];
    for (int k = 0; k < NS; ++k) x0[k] = s->x[k];
    /* y = hk[p] x0 + m_p B;  then y = A y + hk[k] x0 + m_k B for k = p-1 .. 0 */
    for (int k = 0; k < NS; ++k) y[k] = cscale(x0[k], hkv[p]);
    if (in->pwm) {
      y[0] = cadd(y[0], cscale(in->mom[p], m.bi));
      y[5] = cadd(y[5], cscale(in->mom[p], m.wc));
    }
    for (int k = p - 1; k >= 0; --k) {
      apply_a(&m, y, z);
      const double hk = hkv[k];
      for (int q = 0; q < NS; ++q) y[q] = cx(z[q].re + hk * x0[q].re, z[q].im + hk * x0[q].im);
      if (in->pwm) {
        y[0] = cadd(y[0], cscale(in->mom[k], m.bi));
        y[5] = cadd(y[5], cscale(in->mom[k], m.wc));
      }
    }
  }
  if (nwdot != 0.0) {
    /* [A1, A] xm = A1 (A xm) - A (A1 xm); only i, psi and (with AA) the 2nd current-filter
       state are affected, because A1 has a single non-zero column (psi). */
    const double k3 = nwdot * hkv[3] * 0.5; /* h^3/12 = (h^3/6) / 2 */
    const cpx xm0 = cscale(cadd(x00, y[0]), 0.5), xm1 = cscale(cadd(x01, y[1]), 0.5);
    const cpx axm1 = cadd(cscale(xm0, m.a21), cmul(m.a22, xm1));
    const cpx v0 = cx(s->beta * xm1.im, -s->beta * xm1.re); /* -j beta xm1 */
    const cpx v1 = cx(-xm1.im, xm1.re);                     /*  j xm1      */
    const cpx av0 = cadd(cscale(v0, m.a11), cmul(m.a12, v1));
    const cpx av1 = cadd(cscale(v0, m.a21), cmul(m.a22, v1));
    const cpx c0 = cx(s->beta * axm1.im, -s->beta * axm1.re);
    const cpx c1 = cx(-axm1.im, axm1.re);
    y[0] = cadd(y[0], cscale(cadd(c0, cscale(av0, -1.0)), k3));
    y[1] = cadd(y[1], cscale(cadd(c1, cscale(av1, -1.0)), k3));
    if (in->aa) y[3] = cadd(y[3], cscale(v0, -k3 * m.wc));
  }
  for (int k = 0; k < NS; ++k) s->x[k] = y[k];
}
