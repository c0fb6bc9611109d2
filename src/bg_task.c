/* The background task: once per finished window, take the buffer from the
 * ISR, solve, judge, and release the buffer with the centring for a later
 * window. Telemetry is the caller's (imest_can_publish()). */
#include <math.h>
#include <stddef.h>

#include "bg_combine.h"
#include "bg_noise.h"
#include "bg_validity.h"

static void result_clear(imest_result_t *r)
{
  unsigned char *raw = (unsigned char *)r;
  for (size_t b = 0; b < sizeof *r; ++b) raw[b] = 0u;
}

int imest_background(imest_t *s, imest_result_t *out)
{
  if (s == NULL || out == NULL) return IMEST_ERR_NULL;
  if (s->published == s->released) return 0;
  IMEST_BARRIER(); /* read the window only after seeing it published */
  imest_window_t *w = &s->win[s->released & 1u];

  result_clear(out);
  out->seq = w->seq;
  out->samples = w->samples;
  out->used_samples = w->used;
  out->overruns = s->overruns;
  out->flags = (unsigned int)(w->flags & 0xFFFFu); /* every IMEST_FLAG_ fits 16 bits (int may be 16) */
  /* every window before this one was complete (a flushed one ends a run) */
  out->t_end_s = ((double)w->seq * (double)s->window_n + (double)w->samples - 1.0) / (double)s->fs;
  out->span_s = (double)w->samples / (double)s->fs;
  out->windows = 1u;
  out->tr_bound_rel = (double)NAN;
  out->rs_bound_rel = (double)NAN;

  const double m = (double)s->m;
  bg_sums_t sums;
  bg_window_stats_t st;
  bg_window_sums(w, m, (double)s->fs, &sums, &st);
  /* the white noise's bias out of the sums (bg_noise.c) */
  /* Is the speed steady? The window's mean speed within 2 % (and 1 rad/s)
   * of the previous window's. The noise compensation and the angle observer
   * are models of steady operation. */
  const double w_before = (double)s->w_prev_rad_s;
  const int steady = w->used > 0u && s->w_prev_valid &&
                     fabs(st.w_mean - w_before) <= 0.02 * fmax(fabs(st.w_mean), fabs(w_before)) + 1.0;
  s->w_prev_rad_s = (float)st.w_mean;
  s->w_prev_valid = w->used > 0u;
  bg_noise_t nz;
  bg_noise_estimate(s, w, &st, &sums, steady, &nz);
  const double ry_raw = sums.ry;
  bg_noise_subtract(&sums, &nz, m);
  sums.noise = &nz;
  sums.noise_f = nz.scale;
  sums.noise_m = m;
  out->noise_i_a = sqrt(nz.var_i);
  out->noise_u_v = sqrt(nz.var_u);
  /* Too little information in the window before (poorly determined, nothing
   * else wrong) and this one steady and clean: solve the windows together
   * (bg_combine.c), the span grows by this window. */
  const unsigned int dirty = w->flags & (IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ADC_SAT |
                                         IMEST_FLAG_ENCODER_FAULT | IMEST_FLAG_WARMUP | IMEST_FLAG_OVERRUN);
  double e_c0 = nz.e_c0, noise_share = 1.0;
  /* A window joins only if it fits the estimate it is centred on: its
   * residual there, the noise's share taken out, within the residual bound
   * (a window with a plausible spike would spoil every later combination). */
  const int fits = sums.centred && sums.ree <= (double)s->max_ei * (double)s->max_ei * ry_raw;
  const int combined = s->combo.n > 0u && s->combo.n < BG_COMBINE_MAX && steady && !dirty && fits;
  if (combined) {
    bg_combine_add(&s->combo, &sums, nz.e_c0, ry_raw, w->samples);
    bg_combine_sums(&s->combo, m, &sums);
    e_c0 = s->combo.e_c0;
    noise_share = (double)s->combo.samples / (double)(w->samples ? w->samples : 1u);
    sums.noise_f = nz.scale * noise_share;
    out->span_s = (double)s->combo.samples / (double)s->fs;
    out->windows = (unsigned int)s->combo.n;
    out->flags |= IMEST_FLAG_COMBINED;
  } else {
    s->combo.n = 0u;
  }
  const double ry_all = combined ? s->combo.ry_raw : ry_raw;
  bg_solve_out_t so = {0};
  so.status = IMEST_REASON_NUMERIC;
  so.tr_s = (double)NAN;
  if (w->used >= 16u) {
    bg_solve_cfg_t cfg = {0}; /* fields added later default to 0 */
    cfg.sigma = (double)s->sigma;
    cfg.ls_h = (double)s->ls_h;
    cfg.tr_nominal_s = (double)s->tr_nominal_s;
    cfg.tr_min_s = (double)s->tr_min_s;
    cfg.tr_max_s = (double)s->tr_max_s;
    cfg.weight_c = bg_solve_weight_c(&sums); /* speed-normalised cost (bg_solve.h) */
    cfg.e_noise = e_c0;
    (void)bg_solve(&sums, &cfg, &so);
  }

  if (so.status == IMEST_OK) {
    out->tr_s = so.tr_s;
    out->rs_ohm = so.rs_ohm;
    out->k1 = so.k1;
    out->k2 = so.k2;
    /* E and E_I of the data as measured (the noise's part added back), and the
     * part the noise explains */
    const double e_noise = fmax(0.0, so.noise_e_k) * noise_share; /* bg_solve's, at this K */
    out->e = so.e + nz.scale * e_noise;
    out->e_i = sqrt(out->e / ry_all);
    out->e_i_noise = sqrt(e_noise / ry_all);
    out->hessian[0][0] = so.hessian[0][0];
    out->hessian[0][1] = so.hessian[0][1];
    out->hessian[1][0] = so.hessian[1][0];
    out->hessian[1][1] = so.hessian[1][1];
    out->pe_k1 = so.pe_k1;
    out->pe_k2 = so.pe_k2;
    out->pe_k1_rel = so.pe_k1 / so.k1;
    out->pe_k2_rel = so.pe_k2 / so.k2;
    if (so.hessian_pd) out->flags |= IMEST_FLAG_HESSIAN_PD;
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
  out->n_roots = so.status == IMEST_REASON_NUMERIC ? 0u : so.n_roots;
  out->n_admissible = so.status == IMEST_REASON_NUMERIC ? 0u : so.n_admissible;
  for (unsigned int k = 0; k < out->n_roots && k < IMEST_MAX_ROOTS; ++k) {
    out->roots_k2[k] = so.roots_k2[k];
  }
  bg_judge(s, w, &st, &sums, &so, steady, out);
  /* A combination goes on while it is poorly determined, steady and clean,
   * up to BG_COMBINE_MAX windows; a window poorly determined alone starts one. */
  if (out->tr_valid || !steady || dirty || !fits || out->tr_reason != IMEST_REASON_POORLY_DETERMINED ||
      s->combo.n >= BG_COMBINE_MAX)
    s->combo.n = 0u;
  else if (!combined)
    bg_combine_add(&s->combo, &sums, nz.e_c0, ry_raw, w->samples);

  /* Centre later windows on the latest trusted K (T_R valid: R_S may be
   * refused for its own bound while K1, K2 are well determined). */
  if (out->tr_valid) {
    s->last_k1 = (float)out->k1;
    s->last_k2 = (float)out->k2;
  }
  if (s->last_k2 > 0.0f) bg_centre_from_k(w->c0, (double)s->last_k1, (double)s->last_k2, m);
  /* The angle observer smooths only at a steady speed (src/isr_angle.h). */
  s->obs.engaged = (s->obs.enabled && steady) ? 1u : 0u;
  for (unsigned int p = 0; p < IMEST_NACC; ++p) {
    w->sum[p] = 0;
    w->blk[p] = 0;
  }
  IMEST_BARRIER(); /* buffer cleared before it is released */
  s->released = s->released + 1u;
  return 1;
}
