/* SPDX-License-Identifier: Apache-2.0 */
/* Example glue between imest's callback port and an STM32-HAL-style (bxCAN)
 * driver: a small software queue in front of the 3 hardware mailboxes, so
 * the IMEST_CAN_NFRAMES (6) frames of a window are accepted at once; the
 * mailbox-empty interrupt drains the queue. */
#ifndef EXAMPLE_STM32_H
#define EXAMPLE_STM32_H

#include <stdint.h>

#include "imest/imest_can.h"
#include "stm32_hal_fake.h" /* on the target: "stm32f4xx_hal.h" */

#define EXAMPLE_CAN_TXQ 8u /* power of two, >= IMEST_CAN_NFRAMES (frames per window) */

typedef struct {
  uint32_t id;
  int extended;
  unsigned int dlc;
  unsigned char data[8];
} example_can_txe_t;

typedef struct {
  CAN_HandleTypeDef *hcan;
  example_can_txe_t q[EXAMPLE_CAN_TXQ];
  volatile unsigned int head; /* written by the background task only */
  volatile unsigned int tail; /* written with the TX interrupt masked, or by it */
} example_can_tx_t;

/* Set up the queue for hcan and enable its mailbox-empty interrupt. */
void example_can_tx_init(example_can_tx_t *t, CAN_HandleTypeDef *hcan);

/* imest_can_hal_tx_fn_t: pass the example_can_tx_t* as `hal`. Never blocks:
 * returns -1 when the software queue is full (e.g. the controller is
 * bus-off and nothing drains it). */
int example_stm32_can_tx(void *hal, uint32_t id, int extended, const unsigned char *data, unsigned int dlc);

#endif
