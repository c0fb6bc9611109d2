/* SPDX-License-Identifier: Apache-2.0 */
/* Firmware CAN port: forwards each frame to the HAL transmit hook. */
#include "imest_can_callback.h"

#include <stddef.h>

static int cb_send(void *ctx, const imest_can_frame_t *f)
{
  imest_can_callback_t *cb = (imest_can_callback_t *)ctx;
  int ext;
  uint32_t id;
  if (cb == NULL || f == NULL || cb->tx == NULL || f->dlc > 8u) {
    return -1;
  }
  ext = (f->id & IMEST_CAN_ID_EXT) ? 1 : 0;
  id = f->id & (ext ? IMEST_CAN_EFF_MASK : IMEST_CAN_SFF_MASK);
  if (cb->tx(cb->hal, id, ext, f->data, f->dlc) != 0) {
    cb->failed++;
    return -1;
  }
  cb->sent++;
  return 0;
}

int imest_can_callback_init(imest_can_callback_t *cb, imest_can_hal_tx_fn_t tx, void *hal)
{
  if (cb == NULL || tx == NULL) {
    return -1;
  }
  cb->port.send = cb_send;
  cb->port.ctx = cb;
  cb->tx = tx;
  cb->hal = hal;
  cb->sent = 0u;
  cb->failed = 0u;
  return 0;
}
