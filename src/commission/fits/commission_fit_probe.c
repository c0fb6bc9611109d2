/* SPDX-License-Identifier: Apache-2.0 */
/* Background: the rotor time constant from the probe's voltage record (commission_probe.c).
 * Block means v_b over log-spaced blocks are fitted with c + A g_b(tau), g_b the block's mean
 * of exp(-(t - t_0)/tau); for each tau the two linear parameters are solved in closed form,
 * tau itself by a grid over ln tau (4 samples to 240 000) and a golden-section refinement
 * (fixed iteration counts).
 * T_R is known when the record spans 2.5 tau and the curvature of the residual gives
 * std(ln tau) < 0.1. float64. */
#include <math.h>
#include <stddef.h>

#include "commission_fit.h"

/* Weighted least squares of v_b = c + A g_b: returns the residual sum (weights n_b). */
static double probe_sse(const imest_comm_t *c, uint32_t nb, double tau, double *amp)
{
  cm_line_t line = {0};
  cm_decay_t dec;
  imest__cm_decay_init(&dec, (double)c->ts_s, tau);
  for (uint32_t b = 0; b < nb; ++b) {
    const imest_comm_block_t *k = &c->blk[b];
    if (k->n == 0u) continue;
    const double w = (double)k->n, v = (double)k->s[0] / w;
    const double g = imest__cm_decay_pow(&dec, k->k0 - c->probe_k0) * imest__cm_decay_mean(&dec, k->n);
    imest__cm_line_add(&line, w, g, v);
  }
  double a;
  const double sse = imest__cm_line_fit(&line, &a);
  if (amp) *amp = a;
  return sse;
}

double imest__cm_golden(double (*f)(void *, double), void *ctx, double lo, double hi, unsigned int iters)
{
  const double r = 0.6180339887498949;
  double a = lo, b = hi;
  double x1 = b - r * (b - a), x2 = a + r * (b - a);
  double f1 = f(ctx, x1), f2 = f(ctx, x2);
  for (unsigned int i = 0; i < iters; ++i) {
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - r * (b - a);
      f1 = f(ctx, x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + r * (b - a);
      f2 = f(ctx, x2);
    }
  }
  return f1 < f2 ? x1 : x2;
}

double imest__cm_curvature(double (*f)(void *, double), void *ctx, double u, double f_u, double h)
{
  return (f(ctx, u + h) - 2.0 * f_u + f(ctx, u - h)) / (h * h);
}

/* tau = tau_lo e^u: the search runs in u (no logarithm needed) */
typedef struct {
  const imest_comm_t *c;
  uint32_t nb;
  double tau_lo;
} probe_ctx_t;

static double probe_cost(void *ctx, double u)
{
  const probe_ctx_t *p = (const probe_ctx_t *)ctx;
  return probe_sse(p->c, p->nb, p->tau_lo * imest__cm_exp(u), NULL);
}

void imest__cm_fit_probe(imest_comm_t *c)
{
  const uint32_t nb = c->job_nblk;
  const double ts = (double)c->ts_s;
  probe_ctx_t ctx = {c, nb, 4.0 * ts};
  const double u_lo = 0.0, u_hi = 11.0; /* 4 samples .. 240 000 samples */
  enum { NGRID = 24 };
  double best = 0.0, fbest = 0.0;
  for (int g = 0; g < NGRID; ++g) {
    const double u = u_lo + (u_hi - u_lo) * (double)g / (double)(NGRID - 1);
    const double f = probe_cost(&ctx, u);
    if (g == 0 || f < fbest) {
      best = u;
      fbest = f;
    }
  }
  const double step = (u_hi - u_lo) / (double)(NGRID - 1);
  double lo = best - step, hi = best + step;
  if (lo < u_lo) lo = u_lo;
  if (hi > u_hi) hi = u_hi;
  const double u = imest__cm_golden(probe_cost, &ctx, lo, hi, 30u);
  double amp;
  const double sse = probe_sse(c, nb, ctx.tau_lo * imest__cm_exp(u), &amp);
  /* curvature of the residual in ln tau -> standard error of ln tau */
  const double d2 = imest__cm_curvature(probe_cost, &ctx, u, sse, 0.05);
  const double s2 = nb > 3u ? sse / (double)(nb - 3u) : 0.0;
  const double var_u = d2 > 0.0 ? 2.0 * s2 / d2 : 1e9;
  const imest_comm_block_t *last = &c->blk[nb - 1u];
  const double span = (double)(last->k0 + last->n - c->probe_k0) * ts;
  const double tau = ctx.tau_lo * imest__cm_exp(u);
  c->bg_tau = (float)tau;
  c->bg_tau_ok = (span >= 2.5 * tau && var_u < 0.01 && amp != 0.0) ? 1 : 0;
}
