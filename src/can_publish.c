/* CAN telemetry publisher: called from imest_background() (never from the
 * ISR) once per window. Packs the window's frames and hands each to the
 * attached port; a failed send is counted, reported in the IMEST_STAT frame
 * and never retried. No stdio, no malloc. */
#include <stddef.h>

#include "imest/imest_can.h"

int imest_attach_can(imest_t *s, const struct imest_can_port *port, uint32_t base_id) {
  uint32_t id;
  if (s == NULL) {
    return IMEST_ERR_NULL;
  }
  if (port == NULL) {
    s->can = NULL;
    return IMEST_OK;
  }
  if (port->send == NULL) {
    return IMEST_ERR_NULL;
  }
  if (base_id & IMEST_CAN_ID_EXT) {
    id = base_id & ~IMEST_CAN_ID_EXT;
    if (id > IMEST_CAN_EFF_MASK - (IMEST_CAN_NFRAMES - 1u)) {
      return IMEST_ERR_CONFIG;
    }
  } else if (base_id > IMEST_CAN_SFF_MASK - (IMEST_CAN_NFRAMES - 1u)) {
    return IMEST_ERR_CONFIG;
  }
  s->can = port;
  s->can_base_id = base_id;
  s->can_counter = 0u;
  s->can_tx_failed = 0u;
  return IMEST_OK;
}

int imest_can_publish(imest_t *s, const imest_result_t *r) {
  const struct imest_can_port *port;
  struct imest_can_frame f;
  unsigned int i;
  int failed = 0;
  if (s == NULL || r == NULL) {
    return IMEST_ERR_NULL;
  }
  port = s->can;
  if (port == NULL || port->send == NULL) {
    return 0;
  }
  for (i = 0u; i < IMEST_CAN_NFRAMES; i++) {
    /* packed right before sending, so IMEST_STAT (last) carries the failures
     * of this window's earlier frames too */
    (void)imest_can_pack(r, i, s->can_base_id, (unsigned int)(s->can_counter & 0xFFu),
                         s->can_tx_failed, &f);
    if (port->send(port->ctx, &f) != 0) {
      if (s->can_tx_failed != 0xFFFFFFFFu) {
        s->can_tx_failed++;
      }
      failed++;
    }
  }
  s->can_counter++;
  return failed;
}
