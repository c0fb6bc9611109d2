/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 4, the DC current staircase on one axis, and stage 6, demagnetising:
 *
 * Five plateaus at 1/3, 2/3, 1, 2/3, 1/3 of the top level, each ~3 T_R long and cut into 9
 * blocks that cycle through the three modulation patterns (centred, lower-clamped,
 * upper-clamped; imest__cm_command). The flux tail is the same for every pattern, so interleaving
 * keeps the patterns' voltage differences (dead time, devices) free of it; the background fits
 * the tail itself (imest__cm_fit_axis). The first samples of each block are not summed while the
 * current loop settles after the switch; for the first block of a plateau, their shortfall
 * against the new reference is summed instead: it is the delay of the current step, which the
 * standstill L_S estimate needs.
 *
 * After the square wave (commission_pulses.c) the current returns to zero until the rotor flux
 * has decayed (3 T_R) and the background has fitted the axis; then the next axis, or the end of
 * the standstill part. ISR, float32. */
#include "commission_internal.h"

void imest__cm_staircase_begin(imest_comm_t *c, uint32_t axis)
{
  c->stage = IMEST_COMM_STAGE_STAIRCASE;
  c->axis = axis;
  c->nblk = 0u;
  c->plateau = 0u;
  c->block = 0u;
  c->cnt = 0u;
  c->step_area = 0.0f;
  c->i_ref_old = c->i_ref;
  c->i_ref = c->level_a * cm_level(0u);
  c->i_mag = c->i_ref_old; /* settled after the probe; ~0 after demagnetising */
  /* plateau length ~3 T_R in 9 blocks; at least 3 discards per block */
  float p = 3.0f * c->tau;
  if (p < 0.1f) p = 0.1f;
  if (p > 8.0f) p = 8.0f;
  uint32_t n = (uint32_t)(p * c->cfg.fs_hz / (float)CM_BLK_PLATEAU + 0.5f);
  if (n < 3u * c->n_disc_level) n = 3u * c->n_disc_level;
  c->n_blk = n;
  /* after demagnetising, zero current for 0.3 T_R, at least 20 ms */
  float z = 0.3f * c->tau;
  if (z < 0.02f) z = 0.02f;
  c->n_zero = (uint32_t)(z * c->cfg.fs_hz + 0.5f);
}

/* The patterns' order on the top plateau: each pattern's blocks have the same mean position
   (4), so a linear drift of the flux tail that the fit leaves over cancels between them. */
static uint32_t pattern_of(const imest_comm_t *c)
{
  static const uint32_t order[CM_BLK_PLATEAU] = {CM_PAT_CENTRED, CM_PAT_LOW,     CM_PAT_HIGH,
                                                 CM_PAT_HIGH,    CM_PAT_CENTRED, CM_PAT_LOW,
                                                 CM_PAT_LOW,     CM_PAT_HIGH,    CM_PAT_CENTRED};
  return c->plateau == CM_PLATEAU_PATTERNS ? order[c->block] : CM_PAT_CENTRED;
}

static uint32_t discard(const imest_comm_t *c)
{
  /* a level step, and the very first switch to each clamped pattern (its integrator has no
     value yet), settle longer than a pattern switch; no switch, no discard */
  if (c->block == 0u || (c->axis == 0u && c->plateau == CM_PLATEAU_PATTERNS && c->block < 3u))
    return c->n_disc_level;
  return c->plateau == CM_PLATEAU_PATTERNS ? c->n_disc_pattern : 1u;
}

void imest__cm_stage_staircase(imest_comm_t *c, const float m[3], float vdc, float i_n, float v_n)
{
  const uint32_t pat = pattern_of(c);
  const float e = c->i_ref - i_n;
  c->i_mag += (i_n - c->i_mag) * c->ts_s / c->tau;
  if (imest__cm_current_loop(c, pat, e, vdc) != 0) return;
  c->cnt++;
  const uint32_t disc = discard(c);
  if (c->cnt <= disc) {
    if (c->block == 0u) c->step_area += e;
    if (c->cnt == disc) {
      imest__cm_block_start(c, CM_TAG(CM_KIND_DC, c->plateau, pat));
      const float di = c->i_ref - c->i_ref_old;
      c->cur.s[CM_S_DELAY] = (c->block == 0u && imest__abs(di) > 0.0f) ? c->step_area / di : 0.0f;
    }
    return;
  }
  /* the sample of this call: the currents at t_k, the duties and voltage of [t_k, t_k+1) */
  imest__cm_dc_accumulate(c, m, v_n, vdc);
  if (c->cnt < c->n_blk) return;
  imest__cm_block_flush(c);
  c->cnt = 0u;
  if (++c->block < CM_BLK_PLATEAU) return;
  c->block = 0u;
  if (++c->plateau < CM_PLATEAUS) {
    c->i_ref_old = c->i_ref;
    c->i_ref = c->level_a * cm_level(c->plateau);
    c->step_area = 0.0f;
    return;
  }
  imest__cm_pulses_begin(c);
}

void imest__cm_stage_demagnetise(imest_comm_t *c, float vdc, float i_n)
{
  /* Active demagnetising: a current against the rotor flux along the same axis (no torque:
     flux and current stay collinear) takes the magnetising current i_m (a model: i_n lagged
     by T_R) to zero three times faster than zero current would; then zero current. Residual
     flux along one axis would otherwise push the rotor when the next axis is excited. */
  c->i_mag += (i_n - c->i_mag) * c->ts_s / c->tau;
  float ref = 0.0f;
  if (c->step == 0u && imest__abs(c->i_mag) > 0.005f * c->level_a && c->cnt < 10u * c->n_zero) {
    ref = -2.0f * c->i_mag;
    c->cnt_demag = c->cnt + 1u;
  }
  if (imest__cm_current_loop(c, CM_PAT_CENTRED, ref - i_n, vdc) != 0) return;
  c->cnt++;
  if (c->cnt < c->cnt_demag + c->n_zero) return;
  if (!imest__cm_job_done(c)) {
    if (c->cnt > c->cnt_demag + c->n_zero + (uint32_t)(10.0f * c->cfg.fs_hz))
      imest__cm_fail(c, IMEST_COMM_REASON_BACKGROUND);
    return;
  }
  if (c->bg_fail) {
    imest__cm_fail(c, c->bg_fail);
    return;
  }
  if (c->step == 0u) {
    /* an axis fitted: its sigma*L_S tunes the loop for the next one */
    if (c->bg_sl > 0.0f) imest__cm_set_gains(c, c->bg_sl);
    if (c->axis < 2u) {
      imest__cm_staircase_begin(c, c->axis + 1u);
      return;
    }
    c->step = 1u; /* all three axes: combine them */
    imest__cm_post(c, CM_JOB_STANDSTILL, 0u);
    return;
  }
  /* standstill result complete */
  for (int x = 0; x < 3; ++x) c->ginv[x] = c->bg_ginv[x];
  if (c->cfg.allow_rotation)
    imest__cm_rotate_begin(c);
  else
    imest__cm_finish(c);
}
