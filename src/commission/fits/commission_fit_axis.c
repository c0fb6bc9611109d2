/* SPDX-License-Identifier: Apache-2.0 */
/* Background: one axis of the standstill part (commission_staircase.c, commission_pulses.c).
 *
 * DC blocks: the mean axis voltage of block b (plateau p, pattern q) is modelled as
 *
 *   v_b = R i_b + t_d x_td,b + V_th x_th,b + dr x_dr,b + A_p g_b(tau)
 *
 * with i_b the mean axis current, x_* the mean regressors of the inverter model summed by the
 * ISR (imest__cm_dc_accumulate: per leg s(i) * switching * f_pwm * V_dc for the dead time, s(i) for the
 * threshold voltage (V_sw0 + V_d0)/2, i (d_c - 1/2) for r_sw - r_d, weighted by the leg's
 * projection on the axis), and A_p g_b the flux tail of plateau p (g_b: the block's mean of
 * exp(-(t - t_p)/tau)). R holds R_S plus the mean slope resistance (r_sw + r_d)/2. For a given
 * tau the 4 + 5 parameters are linear (weighted least squares, weights = samples); tau is
 * found by golden section on ln tau around the probe's value.
 *
 * Tail amplitudes -> (1 - sigma) L_S: each plateau's tail is L_m (I_p - i_m(t_p)) / tau with
 * i_m the magnetising current lagging the axis current by tau, so consecutive plateaus give
 * L_m = tau (A_p e^{-d_p/tau} - A_{p-1} e^{-d_{p-1}/tau - (t_p - t_{p-1})/tau}) / (I_p - I_{p-1}),
 * d_p the measured delay of the current step.
 *
 * Pulse position: in one clamped pattern (lower-clamped when the upper on-time is centred on
 * the sample, pwm_on_centred) the sample instant lies inside the active pulse, which the dead
 * time moves by t_d/2 off the sample: the sample reads the current low by
 * delta = sqrt(2/3) V_dc t_d / (2 sigma L_S) (the rise over t_d/2). The mean current in that
 * pattern is the sample plus delta, and as the true current steps by delta at each switch to
 * and from it, the rotor flux follows with T_R: a tail L_m delta F'(t) (F the pattern's
 * indicator lagged by T_R). Both are known once t_d, sigma L_S and L_m are, so the fit is
 * repeated with them until t_d settles (a few passes).
 *
 * Square-wave blocks: the current step per period y = a v + b i + c (v the voltage applied
 * over the period, i its mean current): sigma L_S = T / a, and -b/a the resistance at that
 * frequency (R_S, R_R' and the devices).
 *
 * Sensor gains: the three measured currents sum to (g_k - mean g) 1.5 i_k on this axis (the
 * true currents sum to zero); the slope against the axis leg's current gives g_k - mean g.
 * float64, fixed iteration counts. */
#include <math.h>
#include <stddef.h>

#include "commission_fit.h"

enum { COL_R = 0, COL_TD = 1, COL_VTH = 2, COL_DR = 3, COL_TAIL = 4 };
#define NPAR (4u + CM_PLATEAUS)
_Static_assert(IMEST_COMM_NBLK <= 64, "the skip mask has 64 bits");

typedef struct {
  imest_comm_t *c;
  uint32_t axis, nb;
  uint64_t skip;             /* blocks left out (clamped patterns with pulses too short) */
  int lumped;                /* no clamped block: dead time and thresholds in one column, no dr column */
  uint32_t shifted;          /* the pattern whose current sample lies inside its active pulse */
  double ishift;             /* its mean minus sampled axis current [A] */
  double dyn;                /* L_m * ishift: the flux's answer to the pattern switches [V s] */
  uint32_t kp[CM_PLATEAUS];  /* plateau start samples */
  double tau0;               /* the probe's tau: the search runs in u, tau = tau0 e^u */
  double h[IMEST_COMM_NBLK]; /* block means of F' for the present tau [1/s] */
  double g[IMEST_COMM_NBLK]; /* block means of exp(-(t - t_p)/tau), plateau p's tail */
  double beta[CM_LSQ_MAX], dinv[CM_LSQ_MAX], sse;
  unsigned int npar;
  int ok;
} axis_ctx_t;

/* (The DC blocks hold means, not sums, once imest__cm_fit_axis has begun.) */
static double axis_current(const imest_comm_block_t *b, uint32_t axis)
{
  const double ma = (double)b->s[CM_S_MA + axis];
  const double mb = (double)b->s[CM_S_MA + (axis + 1u) % 3u];
  const double mc = (double)b->s[CM_S_MA + (axis + 2u) % 3u];
  return IMEST_SQRT2_3_LIT * (ma - 0.5 * (mb + mc));
}

static int dc_block(const imest_comm_block_t *b)
{
  return CM_TAG_KIND(b->tag) == CM_KIND_DC && b->n > 0u && CM_TAG_PLATEAU(b->tag) < CM_PLATEAUS;
}

static int dc_used(const axis_ctx_t *x, uint32_t bi)
{
  return dc_block(&x->c->blk[bi]) && !((x->skip >> bi) & 1u);
}

/* For the present tau: g_b, the block's mean of exp(-(t - t_p) / tau) (its plateau's tail), and
   h_b, the shifted pattern's indicator lagged by tau, its derivative averaged over the block's
   summed samples. Blocks are contiguous in time (each began `discard` samples before k0). */
static void block_decays(axis_ctx_t *x, double tau)
{
  const imest_comm_t *c = x->c;
  cm_decay_t dec;
  imest__cm_decay_init(&dec, (double)c->ts_s, tau);
  double f = 0.0;
  uint32_t k_end = 0u;
  for (uint32_t bi = 0; bi < x->nb; ++bi) {
    const imest_comm_block_t *b = &c->blk[bi];
    x->h[bi] = x->g[bi] = 0.0;
    if (!dc_block(b)) continue;
    const double mean = imest__cm_decay_mean(&dec, b->n);
    x->g[bi] = imest__cm_decay_pow(&dec, b->k0 - x->kp[CM_TAG_PLATEAU(b->tag)]) * mean;
    const uint32_t k_start = k_end > 0u && k_end < b->k0 ? k_end : b->k0;
    const double ind = CM_TAG_PATTERN(b->tag) == x->shifted ? 1.0 : 0.0;
    const double f0 = ind + (f - ind) * imest__cm_decay_pow(&dec, b->k0 - k_start); /* at k0 */
    x->h[bi] = (ind - f0) / tau * mean;
    f = ind + (f0 - ind) * imest__cm_decay_pow(&dec, b->n);
    k_end = b->k0 + b->n;
  }
}

/* One row: R, t_d (not when lumped), V_th, dr (not when lumped), the plateaus' tails. */
static unsigned int dc_row(const axis_ctx_t *x, uint32_t bi, double row[CM_LSQ_MAX], double *y)
{
  const imest_comm_block_t *b = &x->c->blk[bi];
  const uint32_t p = CM_TAG_PLATEAU(b->tag);
  const int shifted = CM_TAG_PATTERN(b->tag) == x->shifted;
  unsigned int j = 0;
  row[j++] = axis_current(b, x->axis) + (shifted ? x->ishift : 0.0);
  if (!x->lumped) row[j++] = (double)b->s[CM_S_TD];
  row[j++] = (double)b->s[CM_S_VTH];
  if (!x->lumped) row[j++] = (double)b->s[CM_S_DR];
  for (uint32_t q = 0; q < CM_PLATEAUS; ++q) row[j + q] = 0.0;
  row[j + p] = x->g[bi];
  *y = (double)b->s[CM_S_V] - x->dyn * x->h[bi];
  return j + CM_PLATEAUS;
}

/* The linear fit for one tau: fills beta, dinv and sse; returns sse (huge if singular). */
static double axis_solve(axis_ctx_t *x, double tau)
{
  double a[CM_LSQ_MAX][CM_LSQ_MAX] = {{0}}, r[CM_LSQ_MAX] = {0}, row[CM_LSQ_MAX], y;
  unsigned int np = 0u;
  block_decays(x, tau);
  for (uint32_t bi = 0; bi < x->nb; ++bi) {
    if (!dc_used(x, bi)) continue;
    np = dc_row(x, bi, row, &y);
    const double w = (double)x->c->blk[bi].n;
    for (unsigned int i = 0; i < np; ++i) {
      const double wi = w * row[i];
      r[i] += wi * y;
      for (unsigned int j = i; j < np; ++j) a[i][j] += wi * row[j];
    }
  }
  for (unsigned int i = 1; i < np; ++i)
    for (unsigned int j = 0; j < i; ++j) a[i][j] = a[j][i];
  x->npar = np;
  x->ok = np > 0u && imest__cm_chol_solve(a, r, np, x->dinv) == 0;
  if (!x->ok) return 1e30;
  double sse = 0.0;
  for (unsigned int i = 0; i < np; ++i) x->beta[i] = r[i];
  for (uint32_t bi = 0; bi < x->nb; ++bi) {
    if (!dc_used(x, bi)) continue;
    (void)dc_row(x, bi, row, &y);
    double e = y;
    for (unsigned int i = 0; i < np; ++i) e -= row[i] * r[i];
    sse += (double)x->c->blk[bi].n * e * e;
  }
  x->sse = sse;
  return sse;
}

static double axis_cost(void *ctx, double u)
{
  axis_ctx_t *x = (axis_ctx_t *)ctx;
  return axis_solve(x, x->tau0 * imest__cm_exp(u));
}

/* (1 - sigma) L_S from the tails of consecutive plateaus (weighted by their current steps). */
static double tail_lm(const axis_ctx_t *x, double tau, const double d_p[CM_PLATEAUS],
                      const double i_p[CM_PLATEAUS])
{
  const double ts = (double)x->c->ts_s;
  const unsigned int j = x->lumped ? 2u : 4u; /* first tail column */
  double num = 0.0, den = 0.0;
  for (uint32_t p = 1; p < CM_PLATEAUS; ++p) {
    const double dt = ((double)x->kp[p] + d_p[p] - (double)x->kp[p - 1u] - d_p[p - 1u]) * ts;
    const double a_now = x->beta[j + p] * imest__cm_exp(-d_p[p] * ts / tau);
    const double a_before = x->beta[j + p - 1u] * imest__cm_exp(-d_p[p - 1u] * ts / tau - dt / tau);
    const double di = i_p[p] - i_p[p - 1u];
    if (di == 0.0) continue;
    num += fabs(di) * tau * (a_now - a_before) / di;
    den += fabs(di);
  }
  return den > 0.0 ? num / den : (double)NAN;
}

static void fit_square_wave(imest_comm_t *c, uint32_t nb, imest_comm_axis_fit_t *f)
{
  double s[IMEST_COMM_NSUM] = {0}, n = 0.0;
  for (uint32_t bi = 0; bi < nb; ++bi) {
    const imest_comm_block_t *b = &c->blk[bi];
    if (CM_TAG_KIND(b->tag) != CM_KIND_HF) continue;
    n += (double)b->n;
    for (int j = 0; j < IMEST_COMM_NSUM; ++j) s[j] += (double)b->s[j];
  }
  double a[CM_LSQ_MAX][CM_LSQ_MAX] = {{0}}, r[CM_LSQ_MAX] = {0}, dinv[CM_LSQ_MAX];
  a[0][0] = s[CM_H_X11];
  a[0][1] = a[1][0] = s[CM_H_X12];
  a[0][2] = a[2][0] = s[CM_H_X1];
  a[1][1] = s[CM_H_X22];
  a[1][2] = a[2][1] = s[CM_H_X2];
  a[2][2] = n;
  r[0] = s[CM_H_YX1];
  r[1] = s[CM_H_YX2];
  r[2] = s[CM_H_Y];
  const double rhs[3] = {r[0], r[1], r[2]};
  if (n < 16.0 || imest__cm_chol_solve(a, r, 3u, dinv) != 0 || !(r[0] > 0.0)) {
    f->slsig_h = NAN;
    f->slsig_std = NAN;
    f->rhf_ohm = NAN;
    return;
  }
  const double sse = s[CM_H_YY] - (r[0] * rhs[0] + r[1] * rhs[1] + r[2] * rhs[2]);
  const double s2 = sse > 0.0 ? sse / (n - 3.0) : 0.0;
  f->slsig_h = (float)((double)c->ts_s / r[0]);
  f->slsig_std = (float)(BG_SQRT(s2 * dinv[0]) / r[0]);
  f->rhf_ohm = (float)(-r[1] / r[0]);
}

/* The DC blocks' sums become means (the fits evaluate them many times); the buffer is the
   background's until the job is done. */
static void blocks_to_means(imest_comm_t *c, uint32_t nb)
{
  /* (cppcheck 2.10 takes nb for < 1 here: it is the job's block count, up to IMEST_COMM_NBLK.) */
  // cppcheck-suppress knownConditionTrueFalse
  for (uint32_t bi = 0; bi < nb; ++bi) {
    imest_comm_block_t *b = &c->blk[bi];
    if (!dc_block(b)) continue;
    const float inv = 1.0f / (float)b->n;
    for (int j = 0; j < IMEST_COMM_NSUM; ++j)
      if (j != CM_S_DELAY) b->s[j] *= inv;
  }
}

/* Each plateau's start sample (x->kp), current-step delay d_p and mean axis current i_p.
   0, or -1 if a plateau has no DC block. */
static int plateau_means(axis_ctx_t *x, double d_p[CM_PLATEAUS], double i_p[CM_PLATEAUS])
{
  const imest_comm_t *c = x->c;
  double w_p[CM_PLATEAUS] = {0};
  int seen[CM_PLATEAUS] = {0};
  for (uint32_t bi = 0; bi < x->nb; ++bi) {
    const imest_comm_block_t *b = &c->blk[bi];
    if (!dc_block(b)) continue;
    const uint32_t p = CM_TAG_PLATEAU(b->tag);
    if (!seen[p]) {
      seen[p] = 1;
      x->kp[p] = b->k0 - c->n_disc_level;
      d_p[p] = (double)b->s[CM_S_DELAY] - 0.5; /* left sum of the shortfall -> trapezoid */
    }
    const double w = (double)b->n;
    i_p[p] += w * axis_current(b, x->axis);
    w_p[p] += w;
  }
  for (uint32_t p = 0; p < CM_PLATEAUS; ++p) {
    if (!seen[p]) return -1;
    i_p[p] /= w_p[p];
  }
  return 0;
}

/* gains: zero sequence against the axis leg's current (weighted, with intercept) */
static double sensor_gain_dev(const axis_ctx_t *x)
{
  const imest_comm_t *c = x->c;
  cm_line_t line = {0};
  for (uint32_t bi = 0; bi < x->nb; ++bi) {
    const imest_comm_block_t *b = &c->blk[bi];
    if (!dc_block(b)) continue;
    const double z = (double)b->s[CM_S_MA] + (double)b->s[CM_S_MA + 1] + (double)b->s[CM_S_MA + 2];
    imest__cm_line_add(&line, (double)b->n, (double)b->s[CM_S_MA + x->axis], z);
  }
  double slope;
  (void)imest__cm_line_fit(&line, &slope);
  return c->cfg.n_sensors == 3u ? slope / 1.5 : 0.0;
}

/* Adds to skip the clamped blocks whose switching leg's pulse is shorter than 2.1 dead times;
   returns how many clamped blocks remain. */
static uint32_t skip_short_pulses(const axis_ctx_t *x, double td, uint64_t *skip)
{
  const imest_comm_t *c = x->c;
  uint32_t clamped = 0u;
  for (uint32_t bi = 0; bi < x->nb; ++bi) {
    const imest_comm_block_t *b = &c->blk[bi];
    if (!dc_block(b) || CM_TAG_PATTERN(b->tag) == CM_PAT_CENTRED) continue;
    if ((double)b->s[CM_S_PULSE] < 2.1 * td * (double)c->fpwm) *skip |= (uint64_t)1u << bi;
    if (!((*skip >> bi) & 1u)) clamped++;
  }
  return clamped;
}

/* tau by golden section on ln tau within a factor e of the probe's; then, in passes, the
   clamped blocks whose switching leg's pulse is shorter than 2.1 dead times left out (a
   pulse split at the sample instant, as double-update PWM units and the simulator do, is
   partly eaten below 2 dead times) and the pulse-position correction updated. Returns u at
   the minimum (tau = tau0 e^u) and its sse. */
static double tau_passes(axis_ctx_t *x, double sl, const double d_p[CM_PLATEAUS],
                         const double i_p[CM_PLATEAUS], double *sse_out)
{
  const imest_comm_t *c = x->c;
  const double u0 = 0.0;
  double u = u0, sse = 0.0;
  for (int pass = 0; pass < 6; ++pass) {
    /* the first pass searches a factor e around the probe's tau, later ones close to the last */
    u = pass == 0 ? imest__cm_golden(axis_cost, x, u0 - 1.0, u0 + 1.0, 24u)
                  : imest__cm_golden(axis_cost, x, u - 0.05, u + 0.05, 16u);
    sse = axis_solve(x, x->tau0 * imest__cm_exp(u));
    if (!x->ok) break;
    const double td = x->lumped ? 0.0 : x->beta[COL_TD];
    uint64_t skip = x->skip;
    const uint32_t clamped = skip_short_pulses(x, td, &skip);
    const double lm = tail_lm(x, x->tau0 * imest__cm_exp(u), d_p, i_p);
    const double ishift =
        (!x->lumped && sl > 0.0) ? IMEST_SQRT2_3_LIT * (double)c->vdc0 * td / (2.0 * sl) : 0.0;
    const double dyn = lm > 0.0 ? lm * ishift : 0.0;
    const int lumped = clamped == 0u;
    const int settled = skip == x->skip && lumped == x->lumped &&
                        fabs(ishift - x->ishift) <= 1e-3 * fabs(ishift) &&
                        fabs(dyn - x->dyn) <= 1e-3 * fabs(dyn);
    x->skip = skip;
    x->lumped = lumped;
    x->ishift = lumped ? 0.0 : ishift;
    x->dyn = lumped ? 0.0 : dyn;
    if (settled) break;
  }
  *sse_out = sse;
  return u;
}

/* The inverter columns with their standard errors (s2: per-sample variance of the voltage). */
static void report_inverter(const axis_ctx_t *x, double s2, imest_comm_axis_fit_t *f)
{
  const double ktd = (double)x->c->fpwm * (double)x->c->vdc0;
  if (!x->lumped) {
    f->td_s = (float)x->beta[COL_TD];
    f->td_std = (float)BG_SQRT(s2 * x->dinv[COL_TD]);
    f->vth_v = (float)x->beta[COL_VTH];
    f->vth_std = (float)BG_SQRT(s2 * x->dinv[COL_VTH]);
    f->dr_ohm = (float)x->beta[COL_DR];
    f->dr_std = (float)BG_SQRT(s2 * x->dinv[COL_DR]);
  } else { /* all of it as dead time: it usually dominates, and scales with the bus */
    f->td_s = (float)(x->beta[1] / ktd);
    f->td_std = (float)(BG_SQRT(s2 * x->dinv[1]) / ktd);
    f->vth_v = 0.0f;
    f->vth_std = NAN;
    f->dr_ohm = 0.0f;
    f->dr_std = NAN;
  }
}

/* The axis's result at the minimum u (sse there): parameters, standard errors (tau's from the
   cost's curvature), rms residual, L_m from the tails. 0, or -1 if the fit has no degrees of
   freedom left. */
static int report_axis(axis_ctx_t *x, double u, double sse, const double d_p[CM_PLATEAUS],
                       const double i_p[CM_PLATEAUS], imest_comm_axis_fit_t *f)
{
  const imest_comm_t *c = x->c;
  uint32_t n_dc = 0u;
  for (uint32_t bi = 0; bi < x->nb; ++bi) n_dc += dc_used(x, bi) ? 1u : 0u;
  if (!x->ok || n_dc <= x->npar) return -1;
  const double d2 = imest__cm_curvature(axis_cost, x, u, sse, 0.02);
  (void)axis_solve(x, x->tau0 * imest__cm_exp(u));  /* beta at the minimum again */
  const double s2 = sse / (double)(n_dc - x->npar); /* per-sample variance of the voltage */
  const double tau = x->tau0 * imest__cm_exp(u);
  f->separable = !x->lumped;
  f->r_ohm = (float)x->beta[COL_R];
  f->r_std = (float)BG_SQRT(s2 * x->dinv[COL_R]);
  report_inverter(x, s2, f);
  f->tau_s = (float)tau;
  f->tau_std = (float)(d2 > 0.0 ? tau * BG_SQRT(2.0 * s2 / d2) : (double)NAN);
  f->i_top_a = (float)i_p[2];
  {
    double wsum = 0.0;
    for (uint32_t bi = 0; bi < x->nb; ++bi)
      if (dc_used(x, bi)) wsum += (double)c->blk[bi].n;
    f->rms_v = (float)(wsum > 0.0 ? BG_SQRT(sse / wsum) : (double)NAN);
  }
  f->lm_h = (float)tail_lm(x, tau, d_p, i_p);
  return 0;
}

void imest__cm_fit_axis(imest_comm_t *c, uint32_t axis)
{
  imest_comm_axis_fit_t *f = &c->fit[axis];
  axis_ctx_t x = {.c = c, .axis = axis}; /* the rest zero until set (the steps take x whole) */
  const uint32_t nb_job = c->job_nblk;
  x.nb = nb_job < (uint32_t)IMEST_COMM_NBLK ? nb_job : (uint32_t)IMEST_COMM_NBLK;
  double d_p[CM_PLATEAUS] = {0}, i_p[CM_PLATEAUS] = {0};
  blocks_to_means(c, x.nb);
  f->ok = 0;
  if (plateau_means(&x, d_p, i_p) != 0) {
    c->bg_fail = IMEST_COMM_REASON_FIT;
    return;
  }
  f->gain_dev = (float)sensor_gain_dev(&x);
  fit_square_wave(c, x.nb, f);

  x.tau0 = (double)(c->tau > 0.0f ? c->tau : 0.1f);
  const double sl = (double)(f->slsig_h > 0.0f ? f->slsig_h : c->sl_rough);
  x.skip = 0u;
  x.lumped = 0;
  x.shifted = c->cfg.pwm_on_centred ? CM_PAT_LOW : CM_PAT_HIGH;
  x.ishift = 0.0;
  x.dyn = 0.0;
  double sse;
  const double u = tau_passes(&x, sl, d_p, i_p, &sse);
  if (report_axis(&x, u, sse, d_p, i_p, f) != 0) {
    c->bg_fail = IMEST_COMM_REASON_FIT;
    return;
  }
  f->ok = 1;
  if (f->slsig_h > 0.0f) c->bg_sl = f->slsig_h;
}
