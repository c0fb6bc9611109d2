/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_can_callback.h
 * @brief Firmware CAN port: adapts imest's frames to a HAL transmit function.
 *
 * The firmware supplies one non-blocking function that puts a frame into a
 * free transmit mailbox / FIFO slot of its CAN controller and returns 0, or
 * returns nonzero at once when none is free (or the controller is bus-off).
 * See example/example_stm32.c for an STM32-HAL-style implementation.
 *
 *     static imest_can_callback_t cb;
 *     static imest_can_pub_t pub;
 *     imest_can_callback_init(&cb, my_can_tx, &hcan1);
 *     imest_can_pub_init(&pub, &cb.port, IMEST_CAN_DEFAULT_BASE_ID);
 *     ...  imest_can_publish(&pub, &result) after imest_background() returned it
 *
 * C11, no stdio, no malloc; octets in `unsigned char`, one per element.
 */
#ifndef IMEST_CAN_CALLBACK_H
#define IMEST_CAN_CALLBACK_H

#include <stdint.h>

#include "imest/imest_can.h"

#ifdef __cplusplus
extern "C" {
#endif

/** HAL transmit hook. id: 11-bit or 29-bit identifier (without flag);
 *  extended: 1 for a 29-bit identifier; data: dlc octets. Must not block.
 *  @return 0 when queued, nonzero when not. */
typedef int (*imest_can_hal_tx_fn_t)(void *hal, uint32_t id, int extended, const unsigned char *data,
                                     unsigned int dlc);

typedef struct imest_can_callback {
  imest_can_port_t port; /**< pass &cb.port to imest_can_pub_init() */
  imest_can_hal_tx_fn_t tx;
  void *hal;       /**< the HAL handle given to tx (e.g. &hcan1) */
  uint32_t sent;   /**< frames the HAL accepted */
  uint32_t failed; /**< frames it refused */
} imest_can_callback_t;

/** Fill cb. @return 0, or -1 if cb or tx is NULL. */
int imest_can_callback_init(imest_can_callback_t *cb, imest_can_hal_tx_fn_t tx, void *hal);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_CAN_CALLBACK_H */
