/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning: config defaults and checks, instance set-up, abort, progress and names.
 * Runs outside the ISR (init) or reads only. float32: sample counts to the nearest sample,
 * below 2^24 for any configured time and rate but time_max_s (where a few samples do not
 * matter), and rates that are floats already. */
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "commission_internal.h"
#include "common/imest_range.h" /* imest__in_range, as the tracker's and temperatures' checks */

/* Copies n chars (src NULL: zeroes): a struct assignment would call memcpy, which nothing else
   in the library links (0.3 KB on a Cortex-M4F); no <string.h> in the core. */
void imest__cm_copy(void *dst, const void *src, size_t n)
{
  unsigned char *d = (unsigned char *)dst;
  const unsigned char *s = (const unsigned char *)src;
  if (s == NULL)
    for (size_t b = 0; b < n; ++b) d[b] = 0u;
  else
    for (size_t b = 0; b < n; ++b) d[b] = s[b];
}

void imest_comm_config_default(imest_comm_config_t *cc)
{
  if (cc == NULL) return;
  /* every field defined, those not named below 0 */
  imest__cm_copy(cc, NULL, sizeof *cc);
  cc->fs_hz = 8000.0f;
  cc->pwm_hz = 0.0f;
  cc->i_max_a = 0.0f; /* required */
  cc->level_frac = 0.8f;
  cc->v_max_v = 0.0f;
  cc->time_max_s = 300.0f;
  cc->tr_max_s = 3.0f;
  cc->n_sensors = 3u;
  cc->encoder_cpr = 0.0f;
  cc->r_series_ohm = 0.0f;
  cc->pwm_on_centred = 1;
  cc->allow_rotation = 0;
  cc->rated_voltage_v = 0.0f;
  cc->rated_freq_hz = 0.0f;
  cc->rated_speed_rpm = 0.0f;
  cc->speed_frac = 0.4f;
  cc->ramp_s = 2.0f;
}

/* The config's fields and their ranges, checked in order by one loop (a table takes a fraction
   of the flash of a comparison chain, as the estimator's config check says): finite and
   lo <= x <= hi, with the flags' open ends, hi times fs_hz (checked first) where CK_HI_FS, only
   with allow_rotation where CK_ROT; n_sensors (unsigned) as a float, exact for 2 and 3. */
enum { CK_LO_OPEN = 1, CK_HI_OPEN = 2, CK_HI_FS = 4, CK_ROT = 8, CK_UINT = 16 };
typedef struct {
  unsigned short offset, flags;
  float lo, hi;
  const char *name;
} cm_check_t;
#define CM_NO_HI FLT_MAX /* finite is the only upper bound */
#define CK(f, flags, lo, hi)                                                                                 \
  {                                                                                                          \
    (unsigned short)offsetof(imest_comm_config_t, f), flags, lo, hi, #f                                      \
  }
static const cm_check_t k_checks[] = {
    CK(fs_hz, 0, 1000.0f, 1.0e5f),
    CK(pwm_hz, CK_HI_FS, 0.0f, 64.0f), /* and 0 or at least fs_hz (below) */
    CK(i_max_a, CK_LO_OPEN, 0.0f, 1.0e5f),
    CK(level_frac, 0, 0.1f, 0.95f),
    CK(v_max_v, 0, 0.0f, CM_NO_HI),
    CK(time_max_s, CK_LO_OPEN, 0.0f, 3600.0f),
    CK(tr_max_s, 0, 0.01f, 20.0f),
    CK(n_sensors, CK_UINT, 2.0f, 3.0f),
    CK(encoder_cpr, CK_HI_OPEN, 0.0f, 1.0e9f),
    CK(r_series_ohm, 0, 0.0f, CM_NO_HI),
    CK(rated_voltage_v, CK_ROT | CK_LO_OPEN, 0.0f, CM_NO_HI),
    CK(rated_freq_hz, CK_ROT | CK_LO_OPEN | CK_HI_OPEN | CK_HI_FS, 0.0f, 0.1f),
    CK(rated_speed_rpm, 0, 0.0f, CM_NO_HI), /* and below 60 rated_freq_hz if both known (below) */
    CK(speed_frac, 0, 0.05f, 1.0f),
    CK(ramp_s, 0, 0.1f, 60.0f),
};
#undef CK

static int check_ok(const imest_comm_config_t *cc, const cm_check_t *k)
{
  const void *p = (const char *)cc + k->offset;
  const float x = (k->flags & CK_UINT) ? (float)*(const unsigned int *)p : *(const float *)p;
  const float hi = (k->flags & CK_HI_FS) ? k->hi * cc->fs_hz : k->hi;
  if ((k->flags & CK_ROT) && !cc->allow_rotation) return 1;
  if (!imest__in_range(x, k->lo, (k->flags & CK_LO_OPEN) != 0, hi)) return 0;
  if ((k->flags & CK_HI_OPEN) && !(x < hi)) return 0;
  /* the two bounds that involve another field */
  if (k->offset == offsetof(imest_comm_config_t, pwm_hz)) return !(x > 0.0f && x < cc->fs_hz);
  if (k->offset == offsetof(imest_comm_config_t, rated_speed_rpm))
    return !(x > 0.0f && imest__in_range(cc->rated_freq_hz, 0.0f, 1, CM_NO_HI) &&
             x >= 60.0f * cc->rated_freq_hz);
  return 1;
}

int imest_comm_config_check(const imest_comm_config_t *cc, const char **field)
{
  const char *bad = NULL;
  if (cc == NULL) {
    if (field) *field = "cc";
    return IMEST_ERR_NULL;
  }
  for (size_t k = 0; bad == NULL && k < sizeof k_checks / sizeof k_checks[0]; ++k)
    if (!check_ok(cc, &k_checks[k])) bad = k_checks[k].name;
  if (field) *field = bad;
  return bad ? IMEST_ERR_CONFIG : IMEST_OK;
}

static uint32_t samples(float t_s, float fs)
{
  const float n = t_s * fs + 0.5f;
  return n < 1.0f ? 1u : (n > 4.0e9f ? 4000000000u : (uint32_t)n);
}

int imest_comm_init(imest_comm_t *c, const imest_comm_config_t *cc)
{
  if (c == NULL || cc == NULL) return IMEST_ERR_NULL;
  const int rc = imest_comm_config_check(cc, NULL);
  if (rc != IMEST_OK) return rc;
  imest__cm_copy(c, NULL, sizeof *c);
  imest__cm_copy(&c->cfg, cc, sizeof *cc);
  const float fs = cc->fs_hz;
  c->ts_s = 1.0f / fs;
  c->fpwm = cc->pwm_hz > 0.0f ? cc->pwm_hz : cc->fs_hz;
  c->i_trip = cc->i_max_a;
  /* phase current top level -> alpha/beta axis current: i_n = sqrt(3/2) i_phase */
  c->level_a = cc->level_frac * cc->i_max_a * IMEST_SQRT3_2_F;
  /* Current loop crossover fs/40 (1.5 samples of delay cost 13 degrees of phase there). */
  c->wc = IMEST_2PI_F * fs / 40.0f;
  c->n_off = samples(0.25f, fs);
  /* discards after a level step and after a pattern switch: the loop's settling (about 5 and
     4 closed-loop time constants of the slow PI zero at wc/4) */
  c->n_disc_level = samples(20.0f / c->wc, fs);
  c->n_disc_pattern = samples(12.0f / c->wc, fs);
  c->n_hf_half = 4u; /* square wave at fs/8 */
  c->n_hf_blk = samples(0.2f / (float)CM_HF_BLOCKS, fs);
  c->n_max = samples(cc->time_max_s, fs);
  for (int x = 0; x < 3; ++x) {
    c->ginv[x] = 1.0f;
    c->bg_ginv[x] = 1.0f;
    c->res.i_gain_rel[x] = 1.0f;
    c->res.wiring_map[x] = x + 1;
    c->d_app[x] = c->d_next[x] = 0.5f;
  }
  c->state = IMEST_COMM_IDLE;
  c->reason = IMEST_COMM_REASON_NONE;
  c->stage = IMEST_COMM_STAGE_OFFSETS;
  const float nanf_ = (float)NAN;
  imest_comm_value_t *vals[] = {&c->res.rs_ohm,        &c->res.sigma_ls_h,      &c->res.tr_s,
                                &c->res.rr_ohm,        &c->res.ls_standstill_h, &c->res.dead_time_s,
                                &c->res.v_threshold_v, &c->res.dr_ohm,          &c->res.ls_h,
                                &c->res.sigma,         &c->res.sigma_ls_hf_h,   &c->res.sigma_ls_slip_h,
                                &c->res.rr_hf_ohm,     &c->res.rr_slip_ohm};
  for (size_t v = 0; v < sizeof vals / sizeof vals[0]; ++v) {
    vals[v]->value = nanf_;
    vals[v]->std_rel = nanf_;
    vals[v]->spread_rel = nanf_;
  }
  c->res.encoder_cpr = nanf_;
  c->res.speed_ratio = nanf_;
  c->res.slip = nanf_;
  c->res.neg_seq_rel = nanf_;
  c->res.rotating_r_ohm = nanf_;
  c->res.rotating_i_a = nanf_;
  c->res.rotating_f_hz = nanf_;
  c->res.slip_test_hz = nanf_;
  c->res.ls_curve_points = 0u;
  for (int x = 0; x < 4; ++x) c->res.ls_curve_i_a[x] = c->res.ls_curve_h[x] = nanf_;
  c->res.dc_fit_rms_v = nanf_;
  for (int x = 0; x < 3; ++x) c->res.rs_axis_ohm[x] = nanf_;
  c->res.inverter.uncertainty = -1.0f;
  return IMEST_OK;
}

int imest_comm_abort(imest_comm_t *c)
{
  if (c == NULL) return IMEST_ERR_NULL;
  c->abort_req = 1u;
  return IMEST_OK;
}

int imest_comm_status(const imest_comm_t *c, imest_comm_status_t *st)
{
  if (c == NULL || st == NULL) return IMEST_ERR_NULL;
  st->state = c->state;
  st->stage = (int)c->stage;
  st->reason = c->reason;
  st->axis = (unsigned int)c->axis;
  st->time_s = (float)c->k * c->ts_s;
  /* rough shares of the run: the three axes take most of the standstill part; the rotating
     part, when allowed, about a third of the whole */
  const float ss = c->cfg.allow_rotation ? 0.65f : 0.97f;
  const float per_axis = (ss - 0.08f) / 3.0f;
  const float in_axis =
      ((float)c->plateau + (float)c->block / (float)CM_BLK_PLATEAU) / (float)(CM_PLATEAUS + 1u);
  float p;
  switch (c->stage) {
  case IMEST_COMM_STAGE_OFFSETS: p = 0.01f; break;
  case IMEST_COMM_STAGE_WIRING: p = 0.02f; break;
  case IMEST_COMM_STAGE_TIME_CONSTANT: p = 0.04f; break;
  case IMEST_COMM_STAGE_STAIRCASE: p = 0.08f + per_axis * ((float)c->axis + in_axis); break;
  case IMEST_COMM_STAGE_PULSES:
  case IMEST_COMM_STAGE_SLIP:
  case IMEST_COMM_STAGE_DEMAGNETISE: p = 0.08f + per_axis * ((float)c->axis + 0.9f); break;
  case IMEST_COMM_STAGE_ROTATE: {
    /* magnetise, ramp, the levels (settle, measure, next), down, stop */
    const float lv = c->plateau < CM_ROT_LEVELS ? (float)c->plateau : (float)(CM_ROT_LEVELS - 1u);
    const float s = (c->step == CM_ROT_SETTLE || c->step == CM_ROT_MEASURE || c->step == CM_ROT_NEXT)
                        ? 2.0f + 2.0f * (lv + 0.5f) / (float)CM_ROT_LEVELS
                        : (float)c->step;
    p = ss + (0.98f - ss) * s / 5.0f;
    break;
  }
  case IMEST_COMM_STAGE_END:
  default: p = c->state == IMEST_COMM_DONE ? 1.0f : 0.99f; break;
  }
  st->progress = p;
  return IMEST_OK;
}

const char *imest_comm_reason_name(int reason)
{
  switch (reason) {
  case IMEST_COMM_REASON_NONE: return "none";
  case IMEST_COMM_REASON_ABORTED: return "aborted";
  case IMEST_COMM_REASON_INPUT_FAULT: return "input_fault";
  case IMEST_COMM_REASON_OVERCURRENT: return "overcurrent";
  case IMEST_COMM_REASON_CURRENT_AT_REST: return "current_at_rest";
  case IMEST_COMM_REASON_OPEN_PHASE: return "open_phase";
  case IMEST_COMM_REASON_WIRING: return "wiring";
  case IMEST_COMM_REASON_CURRENT_NOT_REACHED: return "current_not_reached";
  case IMEST_COMM_REASON_ROTOR_MOVED: return "rotor_moved";
  case IMEST_COMM_REASON_TIMEOUT: return "timeout";
  case IMEST_COMM_REASON_BACKGROUND: return "background";
  case IMEST_COMM_REASON_FIT: return "fit";
  case IMEST_COMM_REASON_IMPLAUSIBLE: return "implausible";
  case IMEST_COMM_REASON_ENCODER_STILL: return "encoder_still";
  case IMEST_COMM_REASON_ROTOR_BLOCKED: return "rotor_blocked";
  case IMEST_COMM_REASON_PHASE_ORDER: return "phase_order";
  case IMEST_COMM_REASON_POLE_PAIRS_AMBIGUOUS: return "pole_pairs_ambiguous";
  case IMEST_COMM_REASON_CURRENT_LIMIT_ROTATING: return "current_limit_rotating";
  default: return "unknown";
  }
}

const char *imest_comm_stage_name(int stage)
{
  switch (stage) {
  case IMEST_COMM_STAGE_OFFSETS: return "offsets";
  case IMEST_COMM_STAGE_WIRING: return "wiring";
  case IMEST_COMM_STAGE_TIME_CONSTANT: return "time_constant";
  case IMEST_COMM_STAGE_STAIRCASE: return "staircase";
  case IMEST_COMM_STAGE_PULSES: return "pulses";
  case IMEST_COMM_STAGE_SLIP: return "slip";
  case IMEST_COMM_STAGE_DEMAGNETISE: return "demagnetise";
  case IMEST_COMM_STAGE_ROTATE: return "rotate";
  case IMEST_COMM_STAGE_END: return "end";
  default: return "unknown";
  }
}

const char *imest_comm_state_name(int state)
{
  switch (state) {
  case IMEST_COMM_IDLE: return "idle";
  case IMEST_COMM_RUNNING: return "running";
  case IMEST_COMM_COMPUTING: return "computing";
  case IMEST_COMM_DONE: return "done";
  case IMEST_COMM_FAILED: return "failed";
  case IMEST_COMM_ABORTED: return "aborted";
  default: return "unknown";
  }
}
