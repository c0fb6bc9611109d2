/* SPDX-License-Identifier: Apache-2.0 */
/* The background task: once per finished window, take the buffer from the
 * ISR, solve, judge, and release the buffer with the centring for a later
 * window. Telemetry is the caller's (imest_can_publish()). imest_background()
 * is the sequence of the steps below, each named for what it does. */
#include <math.h>
#include <stddef.h>

#include "bg_combine.h"
#include "bg_flux.h"
#include "common/imest_handoff.h"
#include "bg_noise.h"
#include "bg_transient.h"
#include "bg_validity.h"
#include "estimator/solve/bg_float.h" /* BG_FMAXF...: no libm fmaxf on a core without VMAXNM */

/* Fewer used samples than this: the sums cannot determine the 7 columns. */
#define MIN_USED_SAMPLES 16u

/* What one window's steps hand on to the next step. */
typedef struct {
  bg_sums_t sums;       /* the window's (or the combination's) sums, noise taken out */
  bg_window_stats_t st; /* the window's statistics */
  bg_noise_t nz;        /* the window's noise and its bias */
  double ry_raw;        /* R_y of this window before the noise compensation */
  double e_c0;          /* the noise's E at the centring (the combination's when combined) */
  double noise_share;   /* the combination's samples over this window's (1 alone) */
  int steady, dirty, fits, combined;
} bg_step_t;

static void result_clear(imest_result_t *r)
{
  unsigned char *raw = (unsigned char *)r;
  for (size_t b = 0; b < sizeof *r; ++b) raw[b] = 0u;
}

/* The result's header: what the window is, before anything is estimated. */
static void result_header(const imest_t *s, const imest_window_t *w, imest_result_t *out)
{
  result_clear(out);
  out->seq = w->seq;
  out->samples = w->samples;
  out->used_samples = w->used;
  out->overruns = IMEST_LOAD_RELAXED(&s->overruns);
  out->flags = (unsigned int)(w->flags & 0xFFFFu); /* every IMEST_FLAG_ fits 16 bits (int may be 16) */
  /* every window before this one was complete (a flushed one ends a run) */
  out->t_end_s = BG_DIV((double)w->seq * (double)s->window_n + (double)w->samples - 1.0, (double)s->fs);
  out->span_s = BG_DIV((double)w->samples, (double)s->fs);
  out->windows = 1u;
  out->tr_bound_rel = (double)NAN;
  out->rs_bound_rel = (double)NAN;
}

/* The window's sums and statistics; is the speed steady; the white noise's
 * bias out of the sums (bg_noise.c). */
static void window_sums(imest_t *s, const imest_window_t *w, double m, bg_step_t *x, imest_result_t *out)
{
  imest__bg_window_sums(w, m, (double)s->fs, &x->sums, &x->st);
  /* float32, as the ISR's own test (isr_engage_observer): a 2 % tolerance on
   * speeds of at most speed_limit_rad_s; the mean rounded to float32
   * (relative 6e-8) moves the verdict only at the tolerance's edge */
  const float w_now = x->st.w_mean, w_before = s->w_prev_rad_s;
  x->steady =
      w->used > 0u && s->w_prev_valid &&
      fabsf(w_now - w_before) <= (float)IMEST_STEADY_REL_LIT * BG_FMAXF(fabsf(w_now), fabsf(w_before)) +
                                     (float)IMEST_STEADY_ABS_RAD_S_LIT;
  x->st.dw_rad_s = imest__bg_transient_dw(s, w, w_now); /* before w_prev_valid moves on */
  s->w_prev_rad_s = w_now;
  s->w_prev_valid = w->used > 0u;
  imest__bg_noise_estimate(s, w, &x->st, &x->sums, x->steady, &x->nz);
  x->ry_raw = x->sums.ry;
  imest__bg_noise_subtract(&x->sums, &x->nz, m);
  x->sums.noise = &x->nz;
  x->sums.noise_f = x->nz.scale;
  x->sums.noise_m = m;
  out->noise_i_a = (double)sqrtf(x->nz.var_i);
  out->noise_u_v = (double)sqrtf(x->nz.var_u);
}

/* Too little information in the window before (poorly determined, nothing
 * else wrong) and this one steady and clean: solve the windows together
 * (bg_combine.c), the span grows by this window. A window joins only if it
 * fits the estimate it is centred on: its residual there, the noise's share
 * taken out, within the residual bound (a window with a plausible spike would
 * spoil every later combination). */
static void combine_join(imest_t *s, const imest_window_t *w, double m, bg_step_t *x, imest_result_t *out)
{
  x->dirty = (w->flags & (IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ADC_SAT | IMEST_FLAG_ENCODER_FAULT |
                          IMEST_FLAG_WARMUP | IMEST_FLAG_OVERRUN)) != 0u;
  x->e_c0 = x->nz.e_c0;
  x->noise_share = 1.0;
  x->fits = x->sums.centred && x->sums.ree <= (double)s->max_ei * (double)s->max_ei * x->ry_raw;
  x->combined = IMEST_WITH_COMBINE && s->combo.n > 0u && s->combo.n < BG_COMBINE_MAX && x->steady &&
                !x->dirty && x->fits;
  if (!x->combined) {
    s->combo.n = 0u;
    return;
  }
  imest__bg_combine_add(&s->combo, &x->sums, x->nz.e_c0, x->ry_raw, w->samples);
  imest__bg_combine_sums(&s->combo, m, &x->sums);
  x->e_c0 = s->combo.e_c0;
  x->noise_share = BG_DIV((double)s->combo.samples, (double)(w->samples ? w->samples : 1u));
  x->sums.noise_f = x->nz.scale * x->noise_share;
  out->span_s = BG_DIV((double)s->combo.samples, (double)s->fs);
  out->windows = (unsigned int)s->combo.n;
  out->flags |= IMEST_FLAG_COMBINED;
}

/* The solve (src/estimator/solve/): the sums to K, T_R, R_S and their quality. */
static void solve(const imest_t *s, const imest_window_t *w, bg_step_t *x, bg_solve_out_t *so)
{
  so->status = IMEST_REASON_NUMERIC;
  so->tr_s = (double)NAN;
  if (w->used < MIN_USED_SAMPLES) return;
  bg_solve_cfg_t cfg = {0}; /* fields added later default to 0 */
  cfg.sigma = (double)s->sigma;
  cfg.ls_h = (double)s->ls_h;
  cfg.tr_nominal_s = (double)s->tr_nominal_s;
  cfg.tr_min_s = (double)s->tr_min_s;
  cfg.tr_max_s = (double)s->tr_max_s;
  cfg.weight_c = imest__bg_solve_weight_c(&x->sums); /* speed-normalised cost (bg_solve.h) */
  cfg.e_noise = x->e_c0;
  (void)imest__bg_solve(&x->sums, &cfg, so);
}

/* The solve's figures into the result: E and E_I of the data as measured
 * (the noise's part added back), and the part the noise explains. */
static void result_from_solve(const bg_step_t *x, const imest_t *s, const bg_solve_out_t *so,
                              imest_result_t *out)
{
  if (so->status == IMEST_OK) {
    const double ry_all = x->combined ? s->combo.ry_raw : x->ry_raw;
    out->tr_s = so->tr_s;
    out->rs_ohm = so->rs_ohm;
    out->k1 = so->k1;
    out->k2 = so->k2;
    const double e_noise = BG_FMAX(0.0, so->noise_e_k) * x->noise_share; /* bg_solve's, at this K */
    out->e = so->e + x->nz.scale * e_noise;
    out->e_i = BG_SQRT(BG_DIV(out->e, ry_all));
    out->e_i_noise = BG_SQRT(BG_DIV(e_noise, ry_all));
    out->hessian[0][0] = so->hessian[0][0];
    out->hessian[0][1] = so->hessian[0][1];
    out->hessian[1][0] = so->hessian[1][0];
    out->hessian[1][1] = so->hessian[1][1];
    out->pe_k1 = so->pe_k1;
    out->pe_k2 = so->pe_k2;
    out->pe_k1_rel = BG_DIV(so->pe_k1, so->k1);
    out->pe_k2_rel = BG_DIV(so->pe_k2, so->k2);
    if (so->hessian_pd) out->flags |= IMEST_FLAG_HESSIAN_PD;
  } else {
    out->tr_s = (double)NAN;
    out->rs_ohm = (double)NAN;
    out->k1 = (double)NAN;
    out->k2 = (double)NAN;
    out->e = (double)NAN;
    out->e_i = (double)NAN;
    out->e_i_noise = (double)NAN;
    out->pe_k1 = (double)NAN;
    out->pe_k2 = (double)NAN;
    out->pe_k1_rel = (double)NAN;
    out->pe_k2_rel = (double)NAN;
  }
  out->n_roots = so->status == IMEST_REASON_NUMERIC ? 0u : so->n_roots;
  out->n_admissible = so->status == IMEST_REASON_NUMERIC ? 0u : so->n_admissible;
  for (unsigned int k = 0; k < out->n_roots && k < IMEST_MAX_ROOTS; ++k) out->roots_k2[k] = so->roots_k2[k];
}

/* A combination goes on while it is poorly determined, steady and clean,
 * up to BG_COMBINE_MAX windows; a window poorly determined alone starts one. */
static void combine_after(imest_t *s, const imest_window_t *w, const bg_step_t *x, const imest_result_t *out)
{
  if (!IMEST_WITH_COMBINE || out->tr_valid || !x->steady || x->dirty || !x->fits ||
      out->tr_reason != IMEST_REASON_POORLY_DETERMINED || s->combo.n >= BG_COMBINE_MAX)
    s->combo.n = 0u;
  else if (!x->combined)
    imest__bg_combine_add(&s->combo, &x->sums, x->nz.e_c0, x->ry_raw, w->samples);
}

/* Centre later windows on the latest trusted K (T_R valid: R_S may be
 * refused for its own bound while K1, K2 are well determined); clear the
 * buffer and release it to the ISR. */
static void release_window(imest_t *s, imest_window_t *w, const imest_result_t *out)
{
  if (out->tr_valid) {
    s->last_k1 = (float)out->k1;
    s->last_k2 = (float)out->k2;
  }
  if (s->last_k2 > 0.0f) imest__bg_centre_from_k(w->c0, s->last_k1, s->last_k2, s->m);
  for (unsigned int p = 0; p < IMEST_NACC; ++p) {
    w->sum[p] = 0;
    w->blk[p] = 0;
  }
  IMEST_STORE_RELEASE(&s->released, s->released + 1u); /* the buffer, cleared, back to the ISR */
}

int imest_background(imest_t *s, imest_result_t *out)
{
  if (s == NULL || out == NULL) return IMEST_ERR_NULL;
  const uint32_t rel = s->released;                       /* the background's own index */
  if (IMEST_LOAD_ACQUIRE(&s->published) == rel) return 0; /* the window only after its index */
  imest_window_t *w = &s->win[rel & 1u];
  const double m = (double)s->m;
  bg_step_t x;
  bg_solve_out_t so = {0};
  bg_flux_t fx;

  result_header(s, w, out);
  window_sums(s, w, m, &x, out);
  combine_join(s, w, m, &x, out);
  solve(s, w, &x, &so);
  result_from_solve(&x, s, &so, out);
  imest__bg_flux(s, &x.st, &x.sums, w->nreg, out, &fx); /* L_S at the window's flux (a curve given) */
  imest__bg_judge(s, w, &x.st, &x.sums, &so, &fx, x.steady, out);
  combine_after(s, w, &x, out);
  release_window(s, w, out);
  return 1;
}
