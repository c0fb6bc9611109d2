/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 3, the rotor time constant: a DC current (1/3 of the top level) on the
 * a axis under PI control. As the rotor flux builds, the voltage decays as V_inf + A e^(-t/T_R).
 * The voltage is summed in rounds of 6 blocks whose length doubles every round (2 ms, 4 ms ...),
 * so the record is log-spaced in time; after each round the background fits the exponential to
 * all blocks so far (imest__cm_fit_probe) and says when T_R is known (the record spans 2.5 T_R and the
 * fit is tight). T_R sets the plateau length of the staircase. ISR part float32. */
#include <math.h>

#include "commission_internal.h"

enum { P_DISCARD = 0u, P_RECORD = 1u };

static uint32_t block_len(const imest_comm_t *c, uint32_t round)
{
  uint32_t n = (uint32_t)(2.0e-3f * c->cfg.fs_hz + 0.5f);
  if (n < 4u) n = 4u;
  return n << round;
}

void imest__cm_probe_begin(imest_comm_t *c)
{
  c->stage = IMEST_COMM_STAGE_TIME_CONSTANT;
  c->axis = 0u;
  c->step = P_DISCARD;
  c->cnt = 0u;
  c->block = 0u;
  c->nblk = 0u;
  c->posted = 0u;
  c->i_ref_old = 0.0f;
  c->i_ref = c->level_a * cm_level(0u);
  c->probe_k0 = c->k + 1u; /* the reference applies from the next period */
  for (int p = 0; p < 3; ++p) c->integ[p] = 0.0f;
}

void imest__cm_stage_probe(imest_comm_t *c, const float m[3], float vdc, float i_n, float v_n)
{
  (void)m;
  if (imest__cm_current_loop(c, CM_PAT_CENTRED, c->i_ref - i_n, vdc) != 0) return;
  c->cnt++;
  if (c->step == P_DISCARD) {
    if (c->cnt >= c->n_disc_level) {
      c->step = P_RECORD;
      c->cnt = 0u;
      imest__cm_block_start(c, CM_TAG(CM_KIND_PROBE, 0u, 0u));
    }
    return;
  }
  if (c->nblk < CM_PROBE_ROUND * CM_PROBE_ROUNDS) {
    c->cur.n++;
    c->cur.s[0] += v_n;
    c->cur.s[1] += i_n;
    if (c->cur.n >= block_len(c, c->nblk / CM_PROBE_ROUND)) {
      imest__cm_block_flush(c);
      if (c->nblk < CM_PROBE_ROUND * CM_PROBE_ROUNDS) imest__cm_block_start(c, CM_TAG(CM_KIND_PROBE, 0u, 0u));
    }
  }
  /* hand complete rounds to the background, one job at a time */
  if (!imest__cm_job_done(c)) {
    if (++c->wait > (uint32_t)(10.0f * c->cfg.fs_hz)) imest__cm_fail(c, IMEST_COMM_REASON_BACKGROUND);
    return;
  }
  c->wait = 0u;
  if (c->posted > 0u && c->bg_tau_ok) {
    c->tau = c->bg_tau;
    imest__cm_staircase_begin(c, 0u);
    return;
  }
  const uint32_t complete = c->nblk - c->nblk % CM_PROBE_ROUND;
  if (complete > c->posted) {
    c->posted = complete;
    imest__cm_post(c, CM_JOB_PROBE, complete);
  } else if (c->nblk >= CM_PROBE_ROUND * CM_PROBE_ROUNDS) {
    imest__cm_fail(c, IMEST_COMM_REASON_FIT); /* no usable decay within the longest record */
  }
}
