/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning, ISR entry: input checks and protection, the duty pipeline (what is applied
 * now was returned one call ago), the axis current controller, the three modulation patterns
 * and the block sums handed to the background. float32 only; no data-dependent loop. */
#include <stddef.h>

#include "commission_internal.h"

void imest__cm_fail(imest_comm_t *c, int reason)
{
  if (c->state != IMEST_COMM_RUNNING && c->state != IMEST_COMM_IDLE) return;
  c->reason = reason;
  c->res.stage = (int)c->stage;
  c->state = reason == IMEST_COMM_REASON_ABORTED ? IMEST_COMM_ABORTED : IMEST_COMM_FAILED;
}

int imest__cm_job_done(const imest_comm_t *c)
{
  return c->done == c->job;
}

void imest__cm_post(imest_comm_t *c, uint32_t kind, uint32_t nblk)
{
  c->job_kind = kind;
  c->job_nblk = nblk;
  IMEST_BARRIER(); /* the job's data before its counter */
  c->job = c->job + 1u;
}

void imest__cm_set_gains(imest_comm_t *c, float sl_h)
{
  c->sl_rough = sl_h;
  c->kp = sl_h * c->wc;
  c->ki = c->kp * c->wc * 0.25f * c->ts_s; /* per sample; PI zero at wc/4 */
}

/* PI on the axis current with one integrator per pattern: each pattern needs its own voltage
   for the same current (different inverter error), so a pattern switch starts from the right
   value instead of a step of several volts. Anti-windup: the integrator stops at the limit. */
float imest__cm_pi(imest_comm_t *c, uint32_t pat, float err, int with_p)
{
  const float i_new = c->integ[pat] + c->ki * err;
  float u = i_new + (with_p ? c->kp * err : 0.0f);
  if (u > c->v_lim) {
    u = c->v_lim;
    c->lim_cnt++;
  } else if (u < -c->v_lim) {
    u = -c->v_lim;
    c->lim_cnt++;
  } else {
    c->integ[pat] = i_new;
    c->lim_cnt = 0u;
  }
  return u;
}

/* The duties that put u_n (alpha/beta units, along the axis) on the motor, into c->d_next.
   The perpendicular voltage is zero: the motor is symmetric and legs b and c carry equal
   currents, so the perpendicular current stays zero by itself, whatever the sensors' gains say
   (a loop on the measured perpendicular current would hold a true one of gain-mismatch size,
   and its torque turns a free rotor). Patterns: centred, every leg around 0.5; low, the two
   return legs clamped to 0 (lower switches on); high, the axis leg clamped to 1. */
void imest__cm_command(imest_comm_t *c, uint32_t pat, float u_n, float vdc)
{
  const uint32_t k0 = c->axis, k1 = (c->axis + 1u) % 3u, k2 = (c->axis + 2u) % 3u;
  const float inv = 1.0f / vdc;
  float a, b;
  if (pat == CM_PAT_LOW) {
    a = IMEST_SQRT3_2_F * u_n * inv;
    b = 0.0f;
  } else if (pat == CM_PAT_HIGH) {
    a = 1.0f;
    b = 1.0f - IMEST_SQRT3_2_F * u_n * inv;
  } else {
    const float vn = IMEST_SQRT2_3_F * u_n * inv;
    a = 0.5f + vn;
    b = 0.5f - 0.5f * vn;
  }
  a = a < 0.0f ? 0.0f : (a > 1.0f ? 1.0f : a);
  b = b < 0.0f ? 0.0f : (b > 1.0f ? 1.0f : b);
  c->d_next[k0] = a;
  c->d_next[k1] = b;
  c->d_next[k2] = b;
}

/* The axis current loop for one sample: PI, the pattern's duties. 0, or -1 after stopping the
   run because the voltage limit held for 0.2 s (the current cannot be reached). */
int imest__cm_current_loop(imest_comm_t *c, uint32_t pat, float err, float vdc)
{
  imest__cm_command(c, pat, imest__cm_pi(c, pat, err, 1), vdc);
  if (c->lim_cnt > (uint32_t)(0.2f * c->cfg.fs_hz)) {
    imest__cm_fail(c, IMEST_COMM_REASON_CURRENT_NOT_REACHED);
    return -1;
  }
  return 0;
}

/* A block starts with the next sample (the caller sums from its next call on). */
void imest__cm_block_start(imest_comm_t *c, uint32_t tag)
{
  c->cur.k0 = c->k + 1u;
  c->cur.n = 0u;
  c->cur.tag = tag;
  imest__zero_f32(c->cur.s, IMEST_COMM_NSUM);
}

void imest__cm_block_flush(imest_comm_t *c)
{
  if (c->nblk < IMEST_COMM_NBLK) {
    c->blk[c->nblk] = c->cur;
    IMEST_BARRIER();
    c->nblk = c->nblk + 1u;
  }
}

/* One sample of a DC block: the axis voltage applied over this period, the currents at its
   start, and the regressors of the inverter model (commission_fit_axis.c) from the duties that
   apply now: per leg the sign of its current, whether it switches (dead time) and the share of
   the period its switch (not its diode) conducts. */
void imest__cm_dc_accumulate(imest_comm_t *c, const float m[3], float v_n, float vdc)
{
  static const float w[3] = {IMEST_SQRT2_3_F, -0.5f * IMEST_SQRT2_3_F, -0.5f * IMEST_SQRT2_3_F};
  float td = 0.0f, vth = 0.0f, dr = 0.0f, pulse = 0.5f;
  for (uint32_t j = 0u; j < 3u; ++j) {
    const uint32_t x = (c->axis + j) % 3u;
    const float d = c->d_app[x];
    const float s = m[x] > 0.0f ? 1.0f : -1.0f;
    const float sw = (d > 0.0f && d < 1.0f) ? 1.0f : 0.0f;
    const float dc = m[x] > 0.0f ? d : 1.0f - d;
    const float p = d < 0.5f ? d : 1.0f - d;
    if (sw > 0.0f && p < pulse) pulse = p;
    td += w[j] * s * sw;
    vth += w[j] * s;
    dr += w[j] * m[x] * (dc - 0.5f);
  }
  imest_comm_block_t *b = &c->cur;
  b->n++;
  b->s[CM_S_V] += v_n;
  b->s[CM_S_MA] += m[0];
  b->s[CM_S_MA + 1] += m[1];
  b->s[CM_S_MA + 2] += m[2];
  b->s[CM_S_TD] += td * c->fpwm * vdc;
  b->s[CM_S_VTH] += vth;
  b->s[CM_S_DR] += dr;
  b->s[CM_S_PULSE] += pulse;
}

/* Axis voltage of the duties d over a bus vdc (alpha/beta units, zero sequence cancels). */
static float axis_voltage(uint32_t axis, const float d[3], float vdc)
{
  return vdc * cm_axis_component(d, axis);
}

static int finite_f(float x)
{
  return (x == x) && imest__abs(x) <= 3.0e38f;
}

/* The run's start (first call), whether it runs, abort, input faults, the time limit. 1 if this
   sample is to be processed. (static inline, as the helpers below: one call each, inlined into
   the ISR entry.) */
static inline int sample_admitted(imest_comm_t *c, const float i_abc_a[3], float vdc_v, float theta_rad)
{
  if (c->state == IMEST_COMM_IDLE) {
    c->state = IMEST_COMM_RUNNING;
    c->th0 = c->th_prev = theta_rad;
  }
  if (c->state != IMEST_COMM_RUNNING) return 0;
  if (c->abort_req) {
    imest__cm_fail(c, IMEST_COMM_REASON_ABORTED);
    return 0;
  }
  if (!finite_f(i_abc_a[0]) || !finite_f(i_abc_a[1]) || !finite_f(i_abc_a[2]) || !finite_f(vdc_v) ||
      !finite_f(theta_rad) || vdc_v <= 0.0f) {
    imest__cm_fail(c, IMEST_COMM_REASON_INPUT_FAULT);
    return 0;
  }
  c->k++;
  if (c->k > c->n_max) {
    imest__cm_fail(c, IMEST_COMM_REASON_TIMEOUT);
    return 0;
  }
  return 1;
}

/* currents: offsets off (once known), relative gains corrected (once known); the peak and the
   bus checked. 1 if within limits. */
static inline int currents(imest_comm_t *c, const float i_abc_a[3], float vdc_v, float m[3])
{
  for (int x = 0; x < 3; ++x) {
    m[x] = (i_abc_a[x] - c->off[x]) * c->ginv[x];
    const float a = imest__abs(m[x]);
    if (a > c->i_peak) c->i_peak = a;
  }
  if (c->i_peak > c->i_trip) {
    imest__cm_fail(c, IMEST_COMM_REASON_OVERCURRENT);
    return 0;
  }
  if (c->vdc0 > 0.0f && (vdc_v < 0.7f * c->vdc0 || vdc_v > 1.3f * c->vdc0)) {
    imest__cm_fail(c, IMEST_COMM_REASON_INPUT_FAULT);
    return 0;
  }
  return 1;
}

/* encoder: wraps counted, so wrapped and unwrapped angles both work. 0 if the rotor moved at
   standstill. */
static inline int track_encoder(imest_comm_t *c, float theta_rad)
{
  const float d = theta_rad - c->th_prev;
  if (d > IMEST_PI_F) c->wraps--;
  if (d < -IMEST_PI_F) c->wraps++;
  c->th_prev = theta_rad;
  if (c->stage < IMEST_COMM_STAGE_ROTATE) {
    const float moved = imest__abs(theta_rad - c->th0 + IMEST_2PI_F * (float)c->wraps);
    if (moved > c->th_dev) c->th_dev = moved;
    if (moved > 1.0f) { /* a sixth of a turn: the rotor is driven, not creeping */
      imest__cm_fail(c, IMEST_COMM_REASON_ROTOR_MOVED);
      return 0;
    }
  }
  return 1;
}

/* The present stage's sample (each sets c->d_next). */
static inline void run_stage(imest_comm_t *c, const float i_abc_a[3], const float m[3], float vdc_v,
                             float i_n, float v_ended)
{
  switch (c->stage) {
  case IMEST_COMM_STAGE_OFFSETS: imest__cm_stage_offsets(c, i_abc_a, vdc_v); break;
  case IMEST_COMM_STAGE_WIRING: imest__cm_stage_wiring(c, m, vdc_v); break;
  case IMEST_COMM_STAGE_TIME_CONSTANT: imest__cm_stage_probe(c, m, vdc_v, i_n, c->v_app); break;
  case IMEST_COMM_STAGE_STAIRCASE: imest__cm_stage_staircase(c, m, vdc_v, i_n, c->v_app); break;
  case IMEST_COMM_STAGE_PULSES: imest__cm_stage_pulses(c, vdc_v, i_n, v_ended); break;
  case IMEST_COMM_STAGE_SLIP: imest__cm_stage_slip(c, vdc_v, i_n, c->v_app); break;
  case IMEST_COMM_STAGE_DEMAGNETISE: imest__cm_stage_demagnetise(c, vdc_v, i_n); break;
  case IMEST_COMM_STAGE_ROTATE: imest__cm_stage_rotate(c, m, vdc_v); break;
  case IMEST_COMM_STAGE_END:
  default:
    c->d_next[0] = c->d_next[1] = c->d_next[2] = 0.5f;
    if (c->state == IMEST_COMM_RUNNING) c->state = IMEST_COMM_COMPUTING;
    break;
  }
}

int imest_comm_isr(imest_comm_t *c, const float i_abc_a[3], float vdc_v, float theta_rad, float duty_abc[3])
{
  if (c == NULL || i_abc_a == NULL || duty_abc == NULL) return IMEST_ERR_NULL;
  duty_abc[0] = duty_abc[1] = duty_abc[2] = 0.5f;
  if (!sample_admitted(c, i_abc_a, vdc_v, theta_rad)) return 0;
  float m[3];
  if (!currents(c, i_abc_a, vdc_v, m)) return 0;
  if (!track_encoder(c, theta_rad)) return 0;
  /* the duty pipeline: what was returned last call applies from now on */
  for (int x = 0; x < 3; ++x) c->d_app[x] = c->d_next[x];
  const float v_ended = c->v_app; /* axis voltage of the period that just ended */
  c->v_app = axis_voltage(c->axis, c->d_app, vdc_v);

  /* alpha/beta and the axis frame */
  float ia, ib;
  imest__clarke(m, &ia, &ib);
  static const float cs[3][2] = {{1.0f, 0.0f}, {-0.5f, IMEST_HALF_SQRT3_F}, {-0.5f, -IMEST_HALF_SQRT3_F}};
  const float cn = cs[c->axis][0], sn = cs[c->axis][1];
  const float i_n = ia * cn + ib * sn;

  run_stage(c, i_abc_a, m, vdc_v, i_n, v_ended);
  c->i_prev = i_n;
  if (c->state != IMEST_COMM_RUNNING) return 0;
  duty_abc[0] = c->d_next[0];
  duty_abc[1] = c->d_next[1];
  duty_abc[2] = c->d_next[2];
  return 1;
}
