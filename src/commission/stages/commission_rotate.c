/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 7 (with allow_rotation): a rotating field at no load. The field angle
 * advances by a unit phasor rotated every sample (no sin/cos calls). The current is controlled
 * in the field frame to the rated magnetising current on d and zero on q (a current-fed field:
 * voltage-fed V/f at no load oscillates on a low-inertia motor, a current-fed one is damped by
 * the rotor circuit); feed-forward (R_S + j w L_S) I_m with the standstill values, PI for the
 * rest. The command is turned to the centre of the period it will be applied in (1.5 samples
 * ahead) and modulated, on the curve's levels with one leg clamped to its rail (modulate());
 * the identified inverter model is added per leg, so the voltage applied is the one commanded.
 *
 * The run starts from a magnetised motor: the same current as DC on the a axis for 1 s + 3 T_R
 * (the field frame starts there). Then the frequency ramps to speed_frac of rated (held while a
 * phase current is above 90 % of i_max_a), settles (1 s + 3 T_R; each later level as long as
 * the background says, for its own T_R) and is measured over whole
 * electrical periods (>= 1 s): the current demodulated at the field angle (positive and negative
 * sequence), the commanded voltage, and the encoder's travel. Each measured level is handed to
 * the background (imest__cm_fit_rotation: L_S at that current, n_p, the encoder's direction and
 * counts, the phase-order check), which sets the next level's magnetising current: the search for
 * the current that gives the rated flux (L_S measured, not the standstill one, which a saturating
 * motor makes far too low), then the magnetising curve's lower levels. Meanwhile the ISR holds the
 * present level (CM_ROT_NEXT); the switch is one reference change, settled and measured as the
 * first. After the last level the frequency ramps down and the current goes to zero. ISR,
 * float32. */
#include "commission_internal.h"

/* cos and sin of a small angle |x| < 0.3 (series; error < 1e-9) */
static void cs_small(float x, float *co, float *si)
{
  const float x2 = x * x;
  *co = 1.0f - 0.5f * x2 * (1.0f - x2 * (1.0f / 12.0f) * (1.0f - x2 * (1.0f / 30.0f)));
  *si = x * (1.0f - x2 * (1.0f / 6.0f) * (1.0f - x2 * (1.0f / 20.0f)));
}

void imest__cm_rotate_begin(imest_comm_t *c)
{
  c->stage = IMEST_COMM_STAGE_ROTATE;
  c->step = CM_ROT_MAGNETISE;
  c->cnt = 0u;
  c->axis = 0u;
  c->we = 0.0f;
  c->we_test = IMEST_2PI_F * c->cfg.speed_frac * c->cfg.rated_freq_hz;
  /* The rated flux: the stator flux at rated voltage and frequency at no load, where
     V = (R_S + j w L_S) I and the flux is L_S I, so psi = V / (w sqrt(1 + (R_S / (w L_S))^2)):
     the R_S drop, in quadrature with the flux's voltage, taken off (0.1 % on the 0.4 kW motor,
     R_S / (w L_S) 0.05; with the standstill L_S, which a saturating motor makes low, the drop
     is overstated by at most 0.05 % of psi). */
  const float wn = IMEST_2PI_F * c->cfg.rated_freq_hz, x = c->res.rs_ohm.value / (wn * c->ls_ss);
  c->psi = c->cfg.rated_voltage_v / (wn * imest__sqrt(1.0f + x * x));
  /* The levels' limit: the staircase's top, the current the standstill part has driven through
     every phase already (alpha/beta amplitude level_a: a phase peak of level_frac i_max_a). The
     first level, the rated flux's current with the standstill L_S, starts below it
     (CM_ROT_FIRST_FRAC): on a saturating motor that L_S is low and the current high. */
  c->psi_im = c->level_a;
  float im = c->psi / c->ls_ss;
  if (im > CM_ROT_FIRST_FRAC * c->psi_im) im = CM_ROT_FIRST_FRAC * c->psi_im;
  c->i_ref = im;
  c->plateau = 0u; /* the level */
  c->ph_c = 1.0f;
  c->ph_s = 0.0f;
  c->lim_cnt = 0u;
  imest__zero_f32(c->rot_sum, CM_R_COUNT);
  c->blk[CM_ROT_LEVELS].s[CM_LB_NSEARCH] = 0.0f;
  c->blk[CM_ROT_LEVELS].s[CM_LB_I] = 0.0f;
  c->blk[CM_ROT_LEVELS].s[CM_LB_SETTLE] = 0.0f;
  /* measure over whole electrical periods, at least 1 s */
  const float f_e = c->we_test / IMEST_2PI_F;
  const float periods = (float)(uint32_t)(1.0f * f_e + 0.999f);
  c->n_meas = (uint32_t)(periods * c->cfg.fs_hz / f_e + 0.5f);
  c->n_ramp = (uint32_t)(c->cfg.ramp_s * c->cfg.fs_hz + 0.5f);
  c->n_settle = (uint32_t)((1.0f + 3.0f * c->tau) * c->cfg.fs_hz + 0.5f); /* also the magnetising */
}

void imest__cm_finish(imest_comm_t *c)
{
  c->stage = IMEST_COMM_STAGE_END;
  c->d_next[0] = c->d_next[1] = c->d_next[2] = 0.5f;
  c->res.stage = (int)c->stage;
  c->state = IMEST_COMM_COMPUTING;
}

/* The inverter's voltage error of one leg (imest.h, imest_inverter_t) from the identified
   model, for the feed-forward: the sign made linear over the ripple band. vdt: the dead time's
   volt-seconds per period (t_d f_pwm V_dc), 0 for a clamped leg (no edge). */
static float leg_error(const imest_comm_t *c, float i, float d, float vdt)
{
  float s = i / c->inv_band;
  if (s > 1.0f) s = 1.0f;
  if (s < -1.0f) s = -1.0f;
  const float ai = imest__abs(i);
  const float dc = i > 0.0f ? d : 1.0f - d;
  return s * (vdt + c->inv_v + c->inv_rd * ai + dc * (c->inv_rsw - c->inv_rd) * ai);
}

/* A level measured: it holds until the background has set the next level's current from this
   one's L_S (0: it was the last); then that level settles, or the run ramps down. 1 if the run
   stopped, 0 if the field control runs. */
static inline int next_level(imest_comm_t *c)
{
  if (!imest__cm_job_done(c)) {
    if (c->cnt <= (uint32_t)(10.0f * c->cfg.fs_hz)) return 0;
    imest__cm_fail(c, IMEST_COMM_REASON_BACKGROUND);
    return 1;
  }
  c->cnt = 0u;
  const float next = c->blk[CM_ROT_LEVELS].s[CM_LB_NEXT];
  const float settle = c->blk[CM_ROT_LEVELS].s[CM_LB_SETTLE]; /* the level's own (background) */
  if (next > 0.0f) {
    c->i_ref = next;
    if (settle > 0.0f && settle < (float)c->n_max) c->n_settle = (uint32_t)settle;
    c->plateau++;
    c->step = CM_ROT_SETTLE;
    imest__zero_f32(c->rot_sum, CM_R_COUNT);
  } else {
    c->step = CM_ROT_DOWN;
  }
  return 0;
}

/* The run's steps (magnetise, ramp, settle, measure, down, stop): their counters and
   transitions. 1 if the sample is done (the duties set or the run stopped), 0 if the field
   control runs. (static inline, as the helpers below: one call each, inlined into the stage.) */
static inline int rotate_steps(imest_comm_t *c, int limited, float ia, float vdc)
{
  switch (c->step) {
  case CM_ROT_MAGNETISE: {
    if (imest__cm_current_loop(c, CM_PAT_CENTRED, c->i_ref - ia, vdc) != 0) return 1;
    if (c->cnt >= c->n_settle) {
      /* the field frame starts on the a axis: the integrators continue from the DC loop */
      c->step = CM_ROT_RAMP;
      c->cnt = 0u;
      c->integ[0] = c->integ[CM_PAT_CENTRED] - c->rs_ff * c->i_ref;
      c->integ[1] = 0.0f;
    }
    return 1;
  }
  case CM_ROT_RAMP:
    if (limited) {
      c->cnt--; /* hold the frequency while the current is high */
      if (++c->lim_cnt > (uint32_t)c->cfg.fs_hz) {
        imest__cm_fail(c, IMEST_COMM_REASON_CURRENT_LIMIT_ROTATING);
        return 1;
      }
    }
    c->we = c->we_test * (float)c->cnt / (float)c->n_ramp;
    if (c->cnt >= c->n_ramp) {
      c->we = c->we_test;
      c->step = CM_ROT_SETTLE;
      c->cnt = 0u;
    }
    break;
  case CM_ROT_SETTLE:
    if (c->cnt >= c->n_settle) {
      c->step = CM_ROT_MEASURE;
      c->cnt = 0u;
      c->rot_th0 = c->th_prev;
      c->rot_w0 = c->wraps;
    }
    break;
  case CM_ROT_MEASURE: break;
  case CM_ROT_NEXT: return next_level(c);
  case CM_ROT_DOWN:
    c->we = c->we_test * (1.0f - (float)c->cnt / (float)c->n_ramp);
    if (c->cnt >= c->n_ramp) {
      c->we = 0.0f;
      c->step = CM_ROT_STOP;
      c->cnt = 0u;
    }
    break;
  case CM_ROT_STOP:
  default:
    c->d_next[0] = c->d_next[1] = c->d_next[2] = 0.5f;
    if (c->cnt >= c->n_zero) imest__cm_finish(c);
    return 1;
  }
  return 0;
}

/* field angle: rotate the unit phasor, renormalise to first order */
static inline void advance_field(imest_comm_t *c, float ts)
{
  float co, si;
  cs_small(c->we * ts, &co, &si);
  float pc, ps;
  imest__rotate(-si, co, c->ph_c, c->ph_s, &pc, &ps);
  const float g = 1.5f - 0.5f * (pc * pc + ps * ps);
  c->ph_c = pc * g;
  c->ph_s = ps * g;
}

/* The measuring step's sums (current, negative sequence, voltage); at its end the encoder's
   travel, and the job for the background. */
static inline void measure(imest_comm_t *c, float ia, float ib, float id, float iq, float ud, float uq)
{
  float *r = c->rot_sum;
  r[CM_R_ID] += id;
  r[CM_R_IQ] += iq;
  float nd, nq; /* the negative sequence: the current turned the other way */
  imest__rotate(-c->ph_s, c->ph_c, ia, ib, &nd, &nq);
  r[CM_R_ND] += nd;
  r[CM_R_NQ] += nq;
  r[CM_R_UD] += ud;
  r[CM_R_UQ] += uq;
  r[CM_R_I2] += ia * ia + ib * ib;
  r[CM_R_N] += 1.0f;
  if (c->cnt >= c->n_meas) {
    c->rot_th1 = c->th_prev;
    c->rot_wraps = c->wraps - c->rot_w0;
    r[CM_R_WE] = c->we;
    imest__cm_post(c, CM_JOB_ROTATION | (c->plateau << 4), 0u);
    c->step = CM_ROT_NEXT;
    c->cnt = 0u;
  }
}

/* the voltage (field frame ud, uq) for the period after the next sample, at that period's
   centre angle, into c->d_next: each leg's model error added and, on the curve's levels, one leg
   clamped to its rail (discontinuous PWM; the others carry the zero sequence): of the leg with
   the highest voltage
   (clamped high) and the one with the lowest (low), the one whose current is nearer zero.
   Why: a leg that switches while its current is inside the ripple band makes a dead-time error
   the model's smooth sign does not follow (the current's sign at each edge, and the current
   held at zero within the dead time), and at no load that happens near the voltage's peak, 90
   degrees ahead of the current, so the error's fundamental lies along the voltage, in Im Z.
   Measured with every leg switching (min-max zero sequence): the curve's lowest level (a
   current 3 x the ripple band) +0.54 % high on the saturating 4 kW motor with 2 us dead time,
   +0.18 % with 1 us, -0.05 % with an ideal inverter. Clamped, each leg rests for the 60 degrees
   around its current's zero crossing (inside the 120 degrees it is the highest or lowest leg
   while the current lags the voltage by more than 30 degrees: at no load, whatever the slip
   and the iron loss), so a leg switches only with |i| >= I / 2, beyond the band at every
   level. The clamped leg's conduction drop is the model's without its dead time. */
static inline void modulate(imest_comm_t *c, float ia, float ib, float ud, float uq, float vdc, float ts)
{
  float co, si;
  cs_small(1.5f * c->we * ts, &co, &si);
  float c2, s2, ua, ub;
  imest__rotate(-si, co, c->ph_c, c->ph_s, &c2, &s2);
  imest__rotate(-s2, c2, ud, uq, &ua, &ub);
  float v[3];
  cm_clarke_inv(ua, ub, v);
  /* the inverter model's error at the current expected in that period: the present current
     turned ahead with the field by 1.5 samples (a sign decided 1.5 samples early shifts the
     error's fundamental by w 1.5 T, across the current: into the reactive voltage) */
  float pa, pb;
  imest__rotate(-si, co, ia, ib, &pa, &pb);
  float ip[3];
  cm_clarke_inv(pa, pb, ip);
  uint32_t khi = 0u, klo = 0u;
  for (uint32_t x = 1u; x < 3u; ++x) {
    if (v[x] > v[khi]) khi = x;
    if (v[x] < v[klo]) klo = x;
  }
  /* the clamp on the curve's levels only (the rated point known): the search's levels keep
     every leg switching, with the min-max zero sequence (k = 3: no leg clamped), whose
     in-phase error the counts per revolution were measured with (the slip from Re Z) */
  const int clamp = c->blk[CM_ROT_LEVELS].s[CM_LB_I] > 0.0f;
  const int up = imest__abs(ip[khi]) <= imest__abs(ip[klo]);
  const uint32_t k = clamp ? (up ? khi : klo) : 3u;
  const float rail = up ? 0.5f * vdc : -0.5f * vdc;
  /* each leg's duty for its conduction shares from the uncompensated references */
  const float inv = 1.0f / vdc, vdt = c->inv_td_f * vdc;
  const float v0 = clamp ? rail - v[k] : -0.5f * (v[khi] + v[klo]);
  float u[3];
  for (uint32_t x = 0u; x < 3u; ++x)
    u[x] = v[x] + leg_error(c, ip[x], 0.5f + (v[x] + v0) * inv, x == k ? 0.0f : vdt);
  const float w0 = clamp ? rail - u[k] : v0;
  for (uint32_t x = 0u; x < 3u; ++x) {
    const float d = 0.5f + (u[x] + w0) * inv;
    c->d_next[x] = d < 0.0f ? 0.0f : (d > 1.0f ? 1.0f : d);
  }
  if (clamp) c->d_next[k] = up ? 1.0f : 0.0f; /* exactly: a duty a rounding off the rail has an edge */
}

void imest__cm_stage_rotate(imest_comm_t *c, const float m[3], float vdc)
{
  const float ts = c->ts_s;
  c->cnt++;
  const float i_hi = 0.9f * c->cfg.i_max_a;
  const int limited = imest__abs(m[0]) > i_hi || imest__abs(m[1]) > i_hi || imest__abs(m[2]) > i_hi;
  float ia, ib;
  imest__clarke(m, &ia, &ib);
  if (rotate_steps(c, limited, ia, vdc)) return;
  advance_field(c, ts);

  /* current in the field frame, its control (the rated magnetising current on d; ramping down,
     the current follows the frequency to zero) */
  float id, iq;
  imest__rotate(c->ph_s, c->ph_c, ia, ib, &id, &iq);
  const float ref = c->step == CM_ROT_DOWN ? c->i_ref * (1.0f - (float)c->cnt / (float)c->n_ramp) : c->i_ref;
  const float ed = ref - id, eq = -iq;
  const float fd = c->rs_ff * ref, fq = c->we * c->ls_ss * ref;
  c->integ[0] += c->ki * ed;
  c->integ[1] += c->ki * eq;
  const float ud = fd + c->integ[0] + c->kp * ed, uq = fq + c->integ[1] + c->kp * eq;

  if (c->step == CM_ROT_MEASURE) measure(c, ia, ib, id, iq, ud, uq);
  modulate(c, ia, ib, ud, uq, vdc, ts);
}
