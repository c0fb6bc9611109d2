/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning, background call: runs the job the ISR handed over (one at a time: the ISR posts
 * the next only when this one is done), then, once the ISR has stopped commanding, completes the
 * result's state. The ISR never writes the state after COMPUTING, so the background may. */
#include <stddef.h>

#include "commission_fit.h"

int imest_comm_background(imest_comm_t *c)
{
  if (c == NULL) return IMEST_ERR_NULL;
  int did = 0;
  const uint32_t job = c->job;
  if (c->done != job) {
    IMEST_BARRIER(); /* the job's data after its counter */
    const uint32_t kind = c->job_kind;
    c->bg_fail = 0;
    switch (kind & 0xFu) {
    case CM_JOB_WIRING: imest__cm_fit_wiring(c); break;
    case CM_JOB_PROBE: imest__cm_fit_probe(c); break;
    case CM_JOB_AXIS: imest__cm_fit_axis(c, (kind >> 4) % 3u); break;
    case CM_JOB_STANDSTILL: imest__cm_fit_standstill(c); break;
    case CM_JOB_ROTATION: imest__cm_fit_rotation(c); break;
    default: break;
    }
    IMEST_BARRIER(); /* results before the acknowledgement */
    c->done = job;
    did = 1;
  }
  if (c->state == IMEST_COMM_COMPUTING && c->done == c->job) {
    if (c->final_fail) {
      c->reason = c->final_fail;
      c->res.stage = IMEST_COMM_STAGE_ROTATE;
      c->state = IMEST_COMM_FAILED;
    } else if (c->final_ready) {
      c->state = IMEST_COMM_DONE;
    }
  }
  return did;
}
