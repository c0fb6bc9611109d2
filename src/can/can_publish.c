/* SPDX-License-Identifier: Apache-2.0 */
/* CAN telemetry publisher: caller-owned, fed by the application with each
 * result imest_background() returns (the estimator itself knows nothing of
 * CAN). Packs the window's frames and hands each once to the port; a refusal
 * is counted, reported in the IMEST_STAT frame and never retried. No stdio,
 * no malloc. */
#include <stddef.h>

#include "imest/imest_can.h"

int imest_can_pub_init(imest_can_pub_t *pub, const imest_can_port_t *port, uint32_t base_id)
{
  if (pub == NULL || port == NULL || port->send == NULL) return IMEST_ERR_NULL;
  if (imest_can_base_id_check(base_id) != IMEST_OK) return IMEST_ERR_ARG;
  pub->port = port;
  pub->base_id = base_id;
  pub->counter = 0u;
  pub->tx_failed = 0u;
  return IMEST_OK;
}

int imest_can_publish(imest_can_pub_t *pub, const imest_result_t *r)
{
  imest_can_frame_t f;
  int failed = 0;
  if (pub == NULL || r == NULL || pub->port == NULL || pub->port->send == NULL) return IMEST_ERR_NULL;
  for (unsigned int i = 0u; i < (unsigned int)IMEST_CAN_NFRAMES; i++) {
    /* packed right before sending, so IMEST_STAT carries the failures of this
     * window's earlier frames too */
    if (imest_can_pack(r, i, pub->base_id, (unsigned int)(pub->counter & 0xFFu), pub->tx_failed, &f) !=
        IMEST_OK) {
      return IMEST_ERR_ARG; /* base_id changed behind our back */
    }
    if (pub->port->send(pub->port->ctx, &f) != 0) {
      if (pub->tx_failed != 0xFFFFFFFFu) pub->tx_failed++;
      failed++;
    }
  }
  pub->counter++;
  return failed;
}
