/* The ISR path: one call per sample, fixed instruction count, float32 only.
 * Stages: plausibility -> 3-2 transform -> rotation -> filters and
 * derivatives -> regressor -> accumulation -> hand-off at the window end. */
#include "isr_accumulate.h"
#include "isr_regressor.h"
#include "isr_transform.h"

/* Zero every filter state and restart the warm-up: a fault must not leave
 * NaN or a spike in a filter memory. */
static void isr_restart_filters(imest_t *s)
{
  for (unsigned int c = 0; c < 5u; ++c) {
    s->ch[c].s1 = RL(0);
    s->ch[c].s2a = RL(0);
    s->ch[c].s2b = RL(0);
    s->ch[c].y1 = RL(0);
    s->ch[c].y2 = RL(0);
  }
  s->aa_s1 = RL(0);
  s->aa_s2 = RL(0);
  s->warm = s->warmup_n;
}

/* Reset a window buffer for a new window (the background clears the sums of
 * a buffer it releases; after an overrun the ISR reuses its own buffer). */
static void isr_open_window(imest_t *s, imest_window_t *w, uint32_t pending_flags)
{
  w->seq = s->seq;
  w->samples = 0;
  w->used = 0;
  w->flags = pending_flags | (s->warm ? IMEST_FLAG_WARMUP : 0u);
  w->rot = RL(0);
  s->k = 0;
}

/* Window complete: hand it over if the background has released the other
 * buffer, else drop it (counted, never torn). Returns 1 if handed over. */
static int isr_close_window(imest_t *s)
{
  imest_window_t *w = &s->win[s->published & 1u];
  w->samples = s->k;
  s->seq++;
  if (s->published == s->released) {
    IMEST_BARRIER();                  /* window contents before the index */
    s->published = s->published + 1u; /* the ISR now fills the other buffer */
    isr_open_window(s, &s->win[s->published & 1u], 0u);
    return 1;
  }
  /* overrun: the background still owns the other buffer */
  s->overruns = s->overruns + 1u;
  for (unsigned int p = 0; p < IMEST_NACC; ++p) {
    w->sum[p] = RL(0);
    w->blk[p] = RL(0);
  }
  isr_open_window(s, w, IMEST_FLAG_OVERRUN);
  return 0;
}

/* Common part once alpha/beta are known. in_range: every electrical input
 * was strictly inside its ADC limit (the absurd-value limit when no ADC limit
 * is configured); NaN fails that test too. */
static int isr_step(imest_t *s, imest_real_t ua, imest_real_t ub, imest_real_t ia, imest_real_t ib,
                    imest_real_t th, int in_range)
{
  imest_window_t *w = &s->win[s->published & 1u];
  uint32_t fault = 0;

  /* Only an out-of-range sample pays for telling saturation from garbage:
   * NaN and Inf fail every comparison. */
  if (!in_range) {
    const int plausible = isr_within(ua, s->u_abs) & isr_within(ub, s->u_abs) & isr_within(ia, s->i_abs) &
                          isr_within(ib, s->i_abs);
    fault = plausible ? IMEST_FLAG_ADC_SAT : IMEST_FLAG_INPUT_FAULT;
  }
  if (!isr_within(th, RL(1.0e8))) fault |= IMEST_FLAG_INPUT_FAULT;
  if (fault & IMEST_FLAG_INPUT_FAULT) {
    th = s->th_prev; /* keep the last good angle */
  }
  const uint32_t first = !s->started;
  const imest_real_t dth = first ? RL(0) : isr_wrap_pi(th - s->th_prev);
  s->started = 1u;
  s->th_prev = th;
  if (!isr_within(dth, s->dth_max)) {
    fault |= IMEST_FLAG_ENCODER_FAULT;
  }

  if (fault) {
    /* the sample is not used and the filters restart from rest */
    w->flags |= fault | IMEST_FLAG_WARMUP;
    isr_restart_filters(s);
  } else {
    /* Sensor offsets: the same high-pass on all four electrical channels, so
     * the motor's equations still hold for the filtered signals. A start at
     * rest (warmup_n is 0 only then) has no current yet: its first currents
     * are the offsets. */
    if (first && s->warmup_n == 0u) {
      s->dcb[2] = ia;
      s->dcb[3] = ib;
    }
    ua = isr_dc_block(s->dcb_a, &s->dcb[0], ua);
    ub = isr_dc_block(s->dcb_a, &s->dcb[1], ub);
    ia = isr_dc_block(s->dcb_a, &s->dcb[2], ia);
    ib = isr_dc_block(s->dcb_a, &s->dcb[3], ib);
    /* Optional stages branch on configuration only (the same path every
     * sample), so a drive that does not use them does not pay for them. */
    imest_real_t w_raw = dth * s->fs, th_r = th;
    if (s->dly != RL(0)) {
      /* align currents and angle with lagging voltage samples */
      const imest_real_t a = s->dly, ia_now = ia, ib_now = ib, w_now = w_raw;
      ia = ia_now - a * (ia_now - s->ia_prev);
      ib = ib_now - a * (ib_now - s->ib_prev);
      w_raw = w_now - a * (w_now - s->wr_prev);
      th_r = th - a * dth;
      s->ia_prev = ia_now;
      s->ib_prev = ib_now;
      s->wr_prev = w_now;
    }
    if (s->aa_on) {
      /* the angle through a model of the electrical channels' AA filter */
      w_raw = isr_aa(&s->aa, &s->aa_s1, &s->aa_s2, w_raw);
    }

    /* rotation into the rotor frame by n_p * theta */
    imest_real_t sn, cs;
    isr_sincos(isr_wrap_pi(s->n * th_r), &sn, &cs);
    imest_real_t ux, uy, ix, iy;
    isr_rotate(sn, cs, ua, ub, &ux, &uy);
    isr_rotate(sn, cs, ia, ib, &ix, &iy);

    isr_signals_t g;
    g.ux = isr_filter_deriv(s, &s->ch[0], ux);
    g.uy = isr_filter_deriv(s, &s->ch[1], uy);
    g.ix = isr_filter_deriv(s, &s->ch[2], ix);
    g.iy = isr_filter_deriv(s, &s->ch[3], iy);
    isr_filter_speed(s, &s->ch[4], w_raw, &g.w, &g.dw);

    if (s->warm) {
      s->warm--;
      w->flags |= IMEST_FLAG_WARMUP;
    } else {
      imest_real_t zx[8], zy[8];
      isr_regressor(s, &g, w->c0, zx, zy);
      /* i x di/dt: in steady state |i|^2 times the slip frequency */
      const imest_real_t cross = g.ix.x * g.iy.dx - g.iy.x * g.ix.dx;
      isr_accumulate(w, zx, zy, cross, s->k % IMEST_NACC);
      w->rot += dth;
      w->used++;
    }
  }

  s->k++;
  return (s->k >= s->window_n) ? isr_close_window(s) : 0;
}

int imest_isr_flush(imest_t *s)
{
  return (s->k > 0u) ? isr_close_window(s) : 0;
}

int imest_isr_ab(imest_t *s, float u_alpha_v, float u_beta_v, float i_alpha_a, float i_beta_a,
                 float theta_rad)
{
  const imest_real_t ua = (imest_real_t)u_alpha_v, ub = (imest_real_t)u_beta_v;
  const imest_real_t ia = (imest_real_t)i_alpha_a, ib = (imest_real_t)i_beta_a;
  /* the limits apply to whatever quantities the caller passes */
  const int in_range = (isr_abs(ia) < s->i_lim) & (isr_abs(ib) < s->i_lim) & (isr_abs(ua) < s->u_lim) &
                       (isr_abs(ub) < s->u_lim);
  return isr_step(s, ua, ub, ia, ib, (imest_real_t)theta_rad, in_range);
}

int imest_isr_abc(imest_t *s, const float u_abc_v[3], const float i_abc_a[3], float theta_rad)
{
  imest_real_t u[3], i[3];
  int in_range = 1;
  for (unsigned int p = 0; p < 3u; ++p) {
    u[p] = (imest_real_t)u_abc_v[p];
    i[p] = (imest_real_t)i_abc_a[p];
    /* a sample at (or beyond) the ADC limit: the true value is unknown */
    in_range &= (isr_abs(i[p]) < s->i_lim) & (isr_abs(u[p]) < s->u_lim);
  }
  imest_real_t ua, ub, ia, ib;
  isr_clarke(u, &ua, &ub);
  isr_clarke(i, &ia, &ib);
  return isr_step(s, ua, ub, ia, ib, (imest_real_t)theta_rad, in_range);
}
