/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: the bias that white sensor noise puts into the window
 * sums, and its removal (bias-compensated least squares, docs/METHOD.md §16).
 *
 * Noise inside the regressor (the derivatives of the currents above all) adds
 * its covariance to R_W, R_Wy and R_y: E(K) gains K' Sigma K, which is least
 * for a small T_R, so the minimum moves (paper motor, 25 % load, 1 LSB of
 * noise: T_R +2 %, R_S -5 %). The covariance follows from the noise level and
 * the front end's known transfer functions: white noise of variance v per
 * alpha/beta axis stays white of variance v per rotor-frame axis after the
 * rotation, and the filter and the central differences give (x, dx, d2x) the
 * covariance v G (imest__bg_noise_gains). Each regressor column is a linear function
 * of that noise with coefficients in n_p w (acceleration neglected: the
 * compensation is for steady operation, where the bias matters). The noise
 * level itself comes from the window: the squared third differences of
 * i_alpha and u_alpha that the ISR sums. The bias matrix is formed in float32
 * (a 1e-7 error of a correction is nothing); the subtraction in float64. */
#include <math.h>

#include "bg_noise.h"
#include "isr_accumulate.h"
#include "estimator/solve/bg_float.h" /* BG_FMAXF...: no libm fmaxf on a core without VMAXNM */

/* x_f[n] of the Butterworth-3 (as isr_bw3) for an input x. */
typedef struct {
  float s1, s2a, s2b;
} bw3_state_t;

static float bw3_step(const imest_bw3_t *f, bw3_state_t *c, float x)
{
  const float t = (float)(f->b0 * x), v = t + c->s1;
  c->s1 = (float)(t - f->a1 * v);
  const float t2 = (float)(f->c0 * v), y = t2 + c->s2a;
  c->s2a = (float)((t2 + t2) - f->d1 * y + c->s2b);
  c->s2b = (float)(t2 - f->d2 * y);
  return y;
}

void imest__bg_noise_gains(const imest_bw3_t *bw, float fs, float g[6])
{
  /* float32: gains of a correction, summed over a few hundred samples
   * (0.5 fs and fs^2 are the float64 products rounded: a product of two
   * float32 numbers is exact in float64) */
  bw3_state_t c = {0.0f, 0.0f, 0.0f};
  const float f1 = 0.5f * fs, f2 = fs * fs;
  float y1 = 0.0f, y2 = 0.0f, peak = 0.0f;
  float acc[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  for (uint32_t n = 0; n < 65536u; ++n) {
    const float y0 = bw3_step(bw, &c, n == 0u ? 1.0f : 0.0f);
    const float x = y1, dx = (y0 - y2) * f1, d2x = ((y0 - y1) - (y1 - y2)) * f2;
    acc[0] += x * x;
    acc[1] += x * dx;
    acc[2] += x * d2x;
    acc[3] += dx * dx;
    acc[4] += dx * d2x;
    acc[5] += d2x * d2x;
    y2 = y1;
    y1 = y0;
    peak = BG_FMAXF(peak, fabsf(y0));
    /* the response has decayed far below the sums' resolution */
    if (n > 16u && fabsf(y0) + fabsf(y2) < 1e-7f * peak && fabsf(c.s1) + fabsf(c.s2a) < 1e-7f * peak) break;
  }
  for (unsigned int k = 0; k < 6u; ++k) g[k] = acc[k];
}

/* A regressor column's noise coefficients in one row (x): on the row's own
 * current (i, di, d2i), the other row's current, the own voltage/(sigma L_S)
 * (u, du). The other row gives the same quadratic form (isotropy). */
typedef struct {
  float own[3], cross[3], v[2];
} coef_t;

static float quad3(const float *g, const float *a, const float *b)
{
  /* a' G b with G symmetric, packed (xx, xd, xdd, dd, ddd, d2d2) */
  const float ga0 = g[0] * a[0] + g[1] * a[1] + g[2] * a[2];
  const float ga1 = g[1] * a[0] + g[3] * a[1] + g[4] * a[2];
  const float ga2 = g[2] * a[0] + g[4] * a[1] + g[5] * a[2];
  return ga0 * b[0] + ga1 * b[1] + ga2 * b[2];
}

void imest__bg_noise_estimate(const imest_t *s, const imest_window_t *w, const bg_window_stats_t *st,
                              const bg_sums_t *sums, int steady, bg_noise_t *nz)
{
  /* float32: the noise level is a statistic of the window (its own
   * scatter is ~1/sqrt(samples), >= 1e-3), a bias estimate that becomes a
   * correction; the float32 sums of the third differences carry no more
   * than float32's precision to begin with. Speeds up to speed_limit_rad_s,
   * variances 1e-12..1e10 A^2, V^2: inside float32's range. */
  const float n = w->nreg > 0u ? (float)w->nreg : 1.0f;
  const float np = (float)s->n, fs = (float)s->fs;
  /* the smooth signal's share of the third differences: a sinusoid at the
   * stator frequency, half of |i|^2 on the alpha axis */
  const float we = np * st->w_mean + st->slip_rate;
  /* 2 sin(x/2) by its series (|x| <= pi: error < 1e-3 of it; libm's sin
   * would cost 5 KB of flash on a soft-double core) */
  const float x = BG_FMINF(fabsf(we / fs), IMEST_PI_F), x2 = x * x;
  const float h =
      x * (1.0f - x2 * (1.0f / 24.0f) * (1.0f - x2 * (1.0f / 80.0f) * (1.0f - x2 * (1.0f / 168.0f))));
  const float h3 = h * h * h, h6 = h3 * h3;
  const float ni = (float)(w->sum[IMEST_ACC_NOISE_I] + w->blk[IMEST_ACC_NOISE_I]) / n;
  const float nu = (float)(w->sum[IMEST_ACC_NOISE_U] + w->blk[IMEST_ACC_NOISE_U]) / n;
  const float i2 = 0.5f * (float)sums->rw[3][3] / n;
  const float u2 = st->u_ms;
  /* two current sensors (the third computed: the zero sequence is exactly
   * zero) give beta 5/3 of alpha's noise: 4/3 per axis on average */
  const int two = w->sum[IMEST_ACC_I0A] == (imest_real_t)0 && w->sum[IMEST_ACC_I0B] == (imest_real_t)0;
  nz->var_i = BG_FMAXF(0.0f, ni - h6 * i2) / 20.0f * (two ? 4.0f / 3.0f : 1.0f);
  nz->var_u = BG_FMAXF(0.0f, nu - h6 * u2) / 20.0f;
  nz->scale = 1.0;
  nz->steady = steady;
  /* the columns W1 W2 W4 W5 W6 W7 W8 y in one row (docs/METHOD.md §2, b = n w' = 0) */
  const float a = np * st->w_mean, a2 = a * a, a3 = a2 * a;
  const float m = (float)s->m, m1 = 1.0f + m;
  static const coef_t zero = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f}};
  coef_t c[8];
  for (unsigned int k = 0; k < 8u; ++k) c[k] = zero;
  c[0].own[1] = -1.0f; /* W1 = -di */
  c[1].own[1] = -1.0f; /* W2 = -di + (1+m) a i_other + u/s */
  c[1].cross[0] = m1 * a;
  c[1].v[0] = 1.0f;
  c[2].own[0] = -1.0f; /* W4 = -i */
  c[3].own[1] = -a2;   /* W5 = -a^2 di + a^2 u/s + (1+m) a^3 i_other */
  c[3].cross[0] = m1 * a3;
  c[3].v[0] = a2;
  c[4].own[0] = -a2; /* W6 = -a^2 i */
  c[5].own[1] = -a2; /* W7 = -a^2 di */
  c[6].own[2] = -a2; /* W8 = -a^2 d2i + a^2 du/s + a^3 di_other */
  c[6].cross[1] = a3;
  c[6].v[1] = a2;
  c[7].own[0] = -m * a2; /* y = d2i - a di_other - m a^2 i - du/s */
  c[7].own[2] = 1.0f;
  c[7].cross[1] = -a;
  c[7].v[1] = -1.0f;

  const float inv_s = (float)s->inv_s;
  const float vi = nz->var_i, vv = nz->var_u * inv_s * inv_s;
  const float *g = s->noise_g;
  const float twice_n = 2.0f * n; /* two rows, every sample */
  unsigned int p = 0;
  for (unsigned int i = 0; i < 8u; ++i) {
    for (unsigned int j = i; j < 8u; ++j) {
      const float gi = quad3(g, c[i].own, c[j].own) + quad3(g, c[i].cross, c[j].cross);
      const float gv = g[0] * c[i].v[0] * c[j].v[0] + g[1] * (c[i].v[0] * c[j].v[1] + c[i].v[1] * c[j].v[0]) +
                       g[3] * c[i].v[1] * c[j].v[1];
      nz->bias[p++] = twice_n * (vi * gi + vv * gv);
    }
  }
}
