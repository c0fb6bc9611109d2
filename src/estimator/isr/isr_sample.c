/* SPDX-License-Identifier: Apache-2.0 */
/* The ISR path: one call per sample, fixed instruction count, float32 only.
 * Stages: (duty cycles -> phase voltage) -> plausibility -> 3-2 transform ->
 * offsets -> alignment -> angle observer -> rotation -> filters and
 * derivatives -> regressor -> accumulation -> hand-off at the window end. */
#include "common/imest_handoff.h"
#include "isr_accumulate.h"
#include "isr_angle.h"
#include "isr_duty.h"
#include "isr_regressor.h"
#include "isr_transform.h"

/* How the entry points describe a sample to isr_step(). */
#define ISR_IN_RANGE 1u /* every electrical input strictly inside its ADC limit (NaN fails) */
#define ISR_U_NOISY  2u /* the voltage is measured (its noise is evidence), not formed from duties */

/* One sample as the entry points hand it to isr_step(). */
typedef struct {
  imest_real_t ua, ub, ia, ib; /* alpha/beta (the stages update them in place) */
  imest_real_t i0;             /* zero sequence i_a + i_b + i_c (0 where the caller gives alpha/beta) */
  imest_real_t th;             /* mechanical angle as given */
  imest_real_t ia_now, ib_now; /* the currents offset-free, before any delay */
  unsigned int how;            /* ISR_* bits */
} isr_in_t;

static void isr_chan_reset(imest_chan_t *c)
{
  c->s1 = RL(0);
  c->s2a = RL(0);
  c->s2b = RL(0);
  c->y1 = RL(0);
  c->y2 = RL(0);
}

/* Zero every filter state and restart the warm-up: a fault must not leave
 * NaN or a spike in a filter memory. */
static void isr_restart_filters(imest_t *s)
{
  isr_chan_reset(&s->f_ux);
  isr_chan_reset(&s->f_uy);
  isr_chan_reset(&s->f_ix);
  isr_chan_reset(&s->f_iy);
  isr_chan_reset(&s->f_w);
  s->aa_s1 = RL(0);
  s->aa_s2 = RL(0);
  s->warm = s->warmup_fault_n; /* also after a start at rest: the filters restart mid-run */
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
  w->nreg = 0;
  s->k = 0;
}

/* The angle observer smooths only at a steady speed (isr_angle.h): engaged
 * when the window before had the mean speed of the one before that. The ISR
 * decides it from its own sums (the test of the background's noise model,
 * bg_task.c, in float32), so the decision is the same whenever the
 * background runs. It takes effect from the sample after the next window's
 * first used even sample (the observer follows from there on), and is made
 * just before that sample's angle step (OBS_DECIDE), not on the window's
 * last sample, the ISR's longest, nor on the even sample, the heavier of a
 * pair (it forms the regressor): the odd one only completes its sums. Not
 * inlined: the other samples pay only the test of obs_pending. */
#define OBS_WINDOW_ENDED 1u /* obs_pending: a window ended; at its first used even sample: */
#define OBS_DECIDE       2u /* decide before the next angle step (isr_step, or a window's end) */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static void
isr_engage_observer(imest_t *s)
{
  const imest_real_t n_used = s->obs_used > 0u ? (imest_real_t)s->obs_used : RL(1);
  const imest_real_t w_mean = s->obs_rot * s->fs / n_used, w_before = s->w_win_prev;
  const imest_real_t a = imest__abs(w_mean), b = imest__abs(w_before);
  const int steady_mean = s->obs_used > 0u && s->w_win_prev_ok &&
                          imest__abs(w_mean - w_before) <=
                              RL(IMEST_STEADY_REL_LIT) * (a > b ? a : b) + RL(IMEST_STEADY_ABS_RAD_S_LIT);
  const uint32_t st = s->obs.state;
  const int steady = steady_mean && (st & IMEST_ANG_OVER_LAST) == 0u;
  const int engaged = (st & IMEST_ANG_ENABLED) && steady;
  s->w_win_prev = w_mean;
  s->w_win_prev_ok = s->obs_used > 0u;
  s->obs.state = (st & ~(IMEST_ANG_ENGAGED | IMEST_ANG_STEADY)) | (engaged ? IMEST_ANG_ENGAGED : 0u) |
                 (steady_mean ? IMEST_ANG_STEADY : 0u);
  if (engaged) s->win[s->published & 1u].flags |= IMEST_WFLAG_OBSERVER; /* the background's judge */
  s->obs_pending = 0u;
}

/* The second half of a pending regressor sample's sums (isr_accumulate.h):
 * a window's sums always hold whole samples. */
#if defined(__GNUC__)
__attribute__((noinline)) /* one copy of the 28 products for the odd call, a flush and a fault */
#endif
static void
isr_complete_pending(imest_t *s, imest_window_t *w)
{
  if (s->zpend) {
    isr_accumulate_b(w, s->zx, s->zy);
    s->zpend = 0u;
  }
}

/* Window complete: hand it over if the background has released the other
 * buffer, else drop it (counted, never torn). Returns 1 if handed over. */
static int isr_close_window(imest_t *s)
{
  imest_window_t *w = &s->win[s->published & 1u];
  isr_complete_pending(s, w); /* a flushed window can end on an even sample */
  w->samples = s->k;
  /* the ISR state the background judges the window by, as it is now */
  w->duty_input = s->duty_input;
  w->vdc_v = s->vdc_prev;
  w->off_ia = s->off_ia;
  w->off_ib = s->off_ib;
  w->dth_end_rad = s->obs.dth; /* the speed at the window's end (the tracker always runs) */
  /* a swing at a steady mean (hunting), not a run-up: the background's judge */
  const uint32_t swing = IMEST_ANG_OVER | IMEST_ANG_STEADY;
  if ((s->obs.state & swing) == swing) w->flags |= IMEST_WFLAG_SWING;
  s->seq++;
  if (s->obs_pending == OBS_DECIDE)
    isr_engage_observer(s); /* a fault closed the window: the one it decides */
  s->obs_rot = w->rot;      /* for the observer's decision (isr_engage_observer) */
  s->obs_used = w->used;
  /* the tracker lagged a motion: the next decision finds it not steady (isr_angle.h) */
  const uint32_t st = s->obs.state;
  s->obs.state = (st & ~(IMEST_ANG_OVER | IMEST_ANG_OVER_LAST)) | ((st & IMEST_ANG_OVER) << 1);
  s->obs_pending = OBS_WINDOW_ENDED;
  const uint32_t pub = s->published; /* the ISR's own index */
  if (pub == IMEST_LOAD_ACQUIRE(&s->released)) {
    /* the window's contents before the index; the ISR now fills the other buffer */
    IMEST_STORE_RELEASE(&s->published, pub + 1u);
    isr_open_window(s, &s->win[(pub + 1u) & 1u], 0u);
    return 1;
  }
  /* overrun: the background still owns the other buffer */
  IMEST_STORE_RELAXED(&s->overruns, s->overruns + 1u);
  imest__zero_real(w->sum, IMEST_NACC);
  imest__zero_real(w->blk, IMEST_NACC);
  isr_open_window(s, w, IMEST_FLAG_OVERRUN);
  return 0;
}

/* The plausibility of a sample: 0, or the fault bits it sets. Only an
 * out-of-range sample pays for telling saturation from garbage: NaN and Inf
 * fail every comparison. A faulty angle is replaced by the last good one;
 * *dth is the angle's step. */
static inline uint32_t isr_check(imest_t *s, const isr_in_t *in, imest_real_t *th, imest_real_t *dth)
{
  uint32_t fault = 0;
  if (!(in->how & ISR_IN_RANGE)) {
    const int plausible = imest__within(in->ua, s->u_abs) & imest__within(in->ub, s->u_abs) &
                          imest__within(in->ia, s->i_abs) & imest__within(in->ib, s->i_abs);
    fault = plausible ? IMEST_FLAG_ADC_SAT : IMEST_FLAG_INPUT_FAULT;
  }
  if (!imest__within(*th, RL(1.0e8))) fault |= IMEST_FLAG_INPUT_FAULT;
  if (fault & IMEST_FLAG_INPUT_FAULT) *th = s->th_prev; /* keep the last good angle */
  *dth = s->started ? imest__wrap_pi(*th - s->th_prev) : RL(0);
  if (!imest__within(*dth, s->dth_max)) fault |= IMEST_FLAG_ENCODER_FAULT;
  return fault;
}

/* A faulty sample is not used: the filters restart from rest and the angle
 * observer restarts from the encoder (a jump must not ring through it). */
static inline int isr_fault(imest_t *s, imest_window_t *w, uint32_t fault)
{
  w->flags |= fault | IMEST_FLAG_WARMUP;
  isr_complete_pending(s, w);
  isr_restart_filters(s);
  isr_angle_reset(&s->obs, s->obs.dth);
  s->k++;
  return (s->k >= s->window_n) ? isr_close_window(s) : 0;
}

/* Sensor offsets: the same high-pass on all four electrical channels, so the
 * motor's equations still hold for the filtered signals. A start at rest
 * (warmup_n is 0 only then) has no current yet: its first currents are the
 * offsets. */
static inline void isr_offsets(imest_t *s, isr_in_t *in, uint32_t first)
{
  if (first) {
    if (s->warmup_n == 0u) {
      s->off_ia = in->ia;
      s->off_ib = in->ib;
    }
    isr_angle_reset(&s->obs, RL(0));
  }
  in->ua = isr_dc_block(s->dcb_a, &s->off_ua, in->ua);
  in->ub = isr_dc_block(s->dcb_a, &s->off_ub, in->ub);
  in->ia = isr_dc_block(s->dcb_a, &s->off_ia, in->ia);
  in->ib = isr_dc_block(s->dcb_a, &s->off_ib, in->ib);
}

/* White-noise evidence for the background's bias compensation: the third
 * difference of the alpha input (beta carries the same noise). A smooth
 * signal's third difference is (w_e T)^3 of it (1e-4 at 30 Hz and 4 kHz),
 * white noise's sqrt(20) of it. Kept as the last value and its last two
 * differences; *ia_prev, *ua_prev: the last values (the delays use them). */
static inline void isr_noise(imest_t *s, const isr_in_t *in, imest_real_t *d3i_out, imest_real_t *noise_u,
                             imest_real_t *ia_prev, imest_real_t *ua_prev)
{
  *ia_prev = s->ia1;
  *ua_prev = s->ua1;
  const imest_real_t d1i = in->ia - *ia_prev, d2i = d1i - s->dia1, d3i = d2i - s->d2ia1;
  s->ia1 = in->ia;
  s->dia1 = d1i;
  s->d2ia1 = d2i;
  *d3i_out = d3i;
  *noise_u = RL(0);
  if (in->how & ISR_U_NOISY) { /* a voltage formed from duty cycles has no sensor noise */
    const imest_real_t d1u = in->ua - *ua_prev, d2u = d1u - s->dua1, d3u = d2u - s->d2ua1;
    s->dua1 = d1u;
    s->d2ua1 = d2u;
    *noise_u = d3u * d3u;
  }
  s->ua1 = in->ua;
}

/* Alignment of the channels in time. Optional stages branch on configuration
 * only (the same path every sample), so a drive that does not use them does
 * not pay for them. step: the observer's angle step; *th_r, *w_raw: the
 * angle and the raw speed, delayed where the currents are. */
static inline void isr_align(imest_t *s, isr_in_t *in, imest_real_t ia_prev, imest_real_t ua_prev,
                             imest_real_t step, imest_real_t *th_r, imest_real_t *w_raw)
{
  const uint32_t align = s->stages;
  if ((align & IMEST_STAGE_ALIGN) == 0u) return; /* one test for a drive that aligns nothing */
  if (align & IMEST_STAGE_DELAY_I) {
    /* the voltage lags: delay currents and angle to match */
    const imest_real_t a = s->dly_i, w_now = *w_raw;
    in->ia = in->ia - a * (in->ia - ia_prev);
    in->ib = in->ib - a * (in->ib - s->ib1);
    s->ib1 = in->ib_now;
    *w_raw = w_now - a * (w_now - s->wr_prev);
    *th_r = *th_r - a * step;
    s->wr_prev = w_now;
  }
  if (align & IMEST_STAGE_DELAY_U) {
    /* the voltage leads: delay it to match */
    const imest_real_t ub_now = in->ub;
    in->ua = in->ua - s->dly_u * (in->ua - ua_prev);
    in->ub = in->ub - s->dly_u * (in->ub - s->ub1);
    s->ub1 = ub_now;
  }
  if (align & IMEST_STAGE_AA) {
    /* the angle through a model of the electrical channels' AA filter */
    *w_raw = isr_aa(&s->aa, &s->aa_s1, &s->aa_s2, *w_raw);
  }
}

/* Rotation into the rotor frame by n_p * theta, then the filters and
 * derivatives of every channel. */
static inline void isr_rotor_frame(imest_t *s, const isr_in_t *in, imest_real_t th_r, imest_real_t w_raw,
                                   isr_signals_t *g)
{
  imest_real_t sn, cs;
  isr_sincos(imest__wrap_pi(s->n * th_r), &sn, &cs);
  imest_real_t ux, uy, ix, iy;
  imest__rotate(sn, cs, in->ua, in->ub, &ux, &uy);
  imest__rotate(sn, cs, in->ia, in->ib, &ix, &iy);
  g->ux = isr_filter_deriv(s, &s->f_ux, ux);
  g->uy = isr_filter_deriv(s, &s->f_uy, uy);
  g->ix = isr_filter_deriv(s, &s->f_ix, ix);
  g->iy = isr_filter_deriv(s, &s->f_iy, iy);
  isr_filter_speed(s, &s->f_w, w_raw, &g->w, &g->dw);
}

/* The sample into the window: after the warm-up, an even call forms the
 * regressor (stored for the odd call) and its first sums, the odd call the
 * rest. */
static inline void isr_window_sample(imest_t *s, imest_window_t *w, const isr_in_t *in,
                                     const isr_signals_t *g, imest_real_t d3i, imest_real_t noise_u,
                                     imest_real_t step)
{
  if (s->warm) {
    s->warm--;
    w->flags |= IMEST_FLAG_WARMUP;
    return;
  }
  if ((s->k & 1u) == 0u) {
    s->obs_pending <<= 1; /* OBS_WINDOW_ENDED -> OBS_DECIDE; 0 stays (OBS_DECIDE is done by now) */
    isr_regressor(s, g, w->c0, s->zx, s->zy);
    isr_extra_t x;
    /* i x di/dt: in steady state |i|^2 times the slip frequency */
    x.cross = g->ix.x * g->iy.dx - g->iy.x * g->ix.dx;
    x.noise_i = d3i * d3i;
    x.noise_u = noise_u;
    x.i0 = in->i0;
    x.ia = in->ia_now; /* offset-free, before any delay, like i0 */
    x.ib = in->ib_now;
    x.ua = in->ua;
    isr_accumulate_a(w, s->zx, s->zy, &x);
    s->zpend = 1u;
  } else {
    isr_complete_pending(s, w);
  }
  w->rot += step;
  w->used++;
}

/* Common part once alpha/beta are known: ua, ub, ia, ib alpha/beta, i0 the
 * zero sequence i_a + i_b + i_c of the phase currents (0 where the caller
 * gives alpha/beta), th the mechanical angle as given, how: ISR_* bits; the
 * stages of the file's opening comment in order. Scalar arguments: they
 * travel in FPU registers (the stages are inlined: in stays in registers). */
static int isr_step(imest_t *s, imest_real_t ua, imest_real_t ub, imest_real_t ia, imest_real_t ib,
                    imest_real_t i0, imest_real_t th_in, unsigned int how)
{
  isr_in_t in = {ua, ub, ia, ib, i0, th_in, RL(0), RL(0), how};
  imest_window_t *w = &s->win[s->published & 1u];
  imest_real_t th = in.th, dth;
  const uint32_t fault = isr_check(s, &in, &th, &dth);
  const uint32_t first = !s->started;
  s->started = 1u;
  s->th_prev = th;
  if (fault) return isr_fault(s, w, fault);

  isr_offsets(s, &in, first);
  in.ia_now = in.ia;
  in.ib_now = in.ib;
  imest_real_t d3i, noise_u, ia_prev, ua_prev;
  isr_noise(s, &in, &d3i, &noise_u, &ia_prev, &ua_prev);

  /* The encoder angle through the tracking observer (which keeps quantisation
   * steps out of the rotation and the speed alike); its step is the speed. */
  imest_real_t step;
  if (s->obs_pending == OBS_DECIDE) isr_engage_observer(s);
  imest_real_t th_r = th + isr_angle_update(&s->obs, dth, &step);
  imest_real_t w_raw = step * s->fs;
  isr_align(s, &in, ia_prev, ua_prev, step, &th_r, &w_raw);

  isr_signals_t g;
  isr_rotor_frame(s, &in, th_r, w_raw, &g);
  isr_window_sample(s, w, &in, &g, d3i, noise_u, step);
  isr_fold(w, s->k % IMEST_NACC);

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
  const int in_range = (imest__abs(ia) < s->i_lim) & (imest__abs(ib) < s->i_lim) &
                       (imest__abs(ua) < s->u_lim) & (imest__abs(ub) < s->u_lim);
  s->duty_input = 0u;
  return isr_step(s, ua, ub, ia, ib, RL(0), (imest_real_t)theta_rad,
                  (in_range ? ISR_IN_RANGE : 0u) | ISR_U_NOISY);
}

int imest_isr_abc(imest_t *s, const float u_abc_v[3], const float i_abc_a[3], float theta_rad)
{
  imest_real_t u[3], i[3];
  int in_range = 1;
  for (unsigned int p = 0; p < 3u; ++p) {
    u[p] = (imest_real_t)u_abc_v[p];
    i[p] = (imest_real_t)i_abc_a[p];
    /* a sample at (or beyond) the ADC limit: the true value is unknown */
    in_range &= (imest__abs(i[p]) < s->i_lim) & (imest__abs(u[p]) < s->u_lim);
  }
  imest_real_t ua, ub, ia, ib;
  imest__clarke(u, &ua, &ub);
  imest__clarke(i, &ia, &ib);
  s->duty_input = 0u;
  return isr_step(s, ua, ub, ia, ib, (i[0] + i[1]) + i[2], (imest_real_t)theta_rad,
                  (in_range ? ISR_IN_RANGE : 0u) | ISR_U_NOISY);
}

int imest_isr_duty(imest_t *s, const float duty_abc[3], float vdc_v, const float i_abc_a[3], float theta_rad)
{
  const imest_duty_model_t *m = &s->duty;
  const imest_real_t vdc = (imest_real_t)vdc_v, vdc_prev = s->vdc_prev;
  s->vdc_prev = vdc;
  const imest_real_t wp = m->w_prev, wn = RL(1) - wp;
  /* per sample, shared by the legs: the weighted bus voltages, the dead
   * time's volt-seconds, the ripple's scale and the band's fixed part */
  isr_duty_k_t k;
  const imest_real_t kr = isr_duty_constants(m, vdc_prev, vdc, &k);
  const imest_real_t ia = (imest_real_t)i_abc_a[0], ib = (imest_real_t)i_abc_a[1],
                     ic = (imest_real_t)i_abc_a[2];
  const imest_real_t da = (imest_real_t)duty_abc[0], db = (imest_real_t)duty_abc[1],
                     dc = (imest_real_t)duty_abc[2];
  const imest_real_t pa = s->dleg[0], pb = s->dleg[1], pc = s->dleg[2];
  s->dleg[0] = da;
  s->dleg[1] = db;
  s->dleg[2] = dc;
  /* written out per leg: a compiler need not unroll a loop over three */
  const imest_real_t dbar[3] = {wp * pa + wn * da, wp * pb + wn * db, wp * pc + wn * dc};
  /* each leg's ripple at its edges: the edges' currents, or the smooth
   * sign's band (kr 0 with a fixed band: no ripple term) */
  imest_real_t r[3];
  isr_duty_ripple(kr, dbar, r);
  imest_real_t e[3];
  if (s->stages & IMEST_STAGE_DUTY_EDGES) { /* configuration only: the same path every sample */
    e[0] = isr_duty_error(m, &k, dbar[0], ia, r[0]);
    e[1] = isr_duty_error(m, &k, dbar[1], ib, r[1]);
    e[2] = isr_duty_error(m, &k, dbar[2], ic, r[2]);
  } else {
    e[0] = isr_duty_error_smooth(m, &k, dbar[0], ia, r[0]);
    e[1] = isr_duty_error_smooth(m, &k, dbar[1], ib, r[1]);
    e[2] = isr_duty_error_smooth(m, &k, dbar[2], ic, r[2]);
  }
  const imest_real_t u[3] = {(k.kp * pa + k.kn * da) - e[0], (k.kp * pb + k.kn * db) - e[1],
                             (k.kp * pc + k.kn * dc) - e[2]};
  /* the leg voltages' steps at the sample */
  const imest_real_t step[3] = {vdc * da - vdc_prev * pa, vdc * db - vdc_prev * pb, vdc * dc - vdc_prev * pc};
  const imest_real_t i[3] = {ia, ib, ic};
  /* the ADC limit applies to the currents; the duties and the bus voltage
   * only have to be numbers: one test catches NaN, Inf or absurd duties and
   * a bus voltage near u_absurd_v (both weighted into one sum of squares) */
  const int in_range = (imest__abs(ia) < s->i_lim) & (imest__abs(ib) < s->i_lim) &
                       (imest__abs(ic) < s->i_lim) &
                       (((da * da + db * db) + dc * dc) + m->vdc2_w * (vdc * vdc) < RL(12));
  imest_real_t ua, ub, ia_ab, ib_ab, sa, sb;
  imest__clarke(u, &ua, &ub); /* the zero sequence (the legs' common part) drops out */
  imest__clarke(i, &ia_ab, &ib_ab);
  /* The voltage is a staircase (one step per sample): the sampled current
   * carries the aliased images of its steps, -(T / 12 sigma L_S) times the
   * step at the sample (docs/METHOD.md §17; uncorrected, R_S -10 % on the
   * 4 kW motor at 4 kHz, -2.5 % at 8 kHz). */
  imest__clarke(step, &sa, &sb);
  ia_ab += m->zoh * sa;
  ib_ab += m->zoh * sb;
  s->duty_input = 1u;
  return isr_step(s, ua, ub, ia_ab, ib_ab, (ia + ib) + ic, (imest_real_t)theta_rad,
                  in_range ? ISR_IN_RANGE : 0u);
}
