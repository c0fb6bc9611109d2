/* SPDX-License-Identifier: Apache-2.0 */
/* Example: the transmit hook a firmware on an STM32 (bxCAN, vendor HAL)
 * gives to imest_can_callback_init(). bxCAN has only 3 transmit mailboxes and
 * imest sends 6 frames per window, so the hook puts frames into a small
 * software queue and moves them into free mailboxes; the mailbox-empty
 * interrupt moves the rest. Never blocks: a full queue refuses the frame at
 * once (imest counts it and does not retry). */
#include "example_stm32.h"

#include <stddef.h>

_Static_assert(EXAMPLE_CAN_TXQ >= IMEST_CAN_NFRAMES, "the queue must hold one window");

static example_can_tx_t *g_tx_for_isr; /* firmware glue: one CAN controller */

/* Move queued frames into free mailboxes. Runs either in the TX interrupt or
 * in the background task with that interrupt masked: never both at once. */
static void kick(example_can_tx_t *t)
{
  while (t->tail != t->head && HAL_CAN_GetTxMailboxesFreeLevel(t->hcan) > 0u) {
    example_can_txe_t *e = &t->q[t->tail % EXAMPLE_CAN_TXQ];
    CAN_TxHeaderTypeDef h;
    uint8_t buf[8];
    uint32_t mailbox;
    unsigned int i;
    h.StdId = e->extended ? 0u : e->id;
    h.ExtId = e->extended ? e->id : 0u;
    h.IDE = e->extended ? CAN_ID_EXT : CAN_ID_STD;
    h.RTR = CAN_RTR_DATA;
    h.DLC = e->dlc;
    h.TransmitGlobalTime = 0;
    for (i = 0u; i < 8u; i++) buf[i] = (uint8_t)(e->data[i] & 0xFFu);
    if (HAL_CAN_AddTxMessage(t->hcan, &h, buf, &mailbox) != HAL_OK) {
      break; /* bus-off or error: leave it queued */
    }
    t->tail++;
  }
}

void example_can_tx_init(example_can_tx_t *t, CAN_HandleTypeDef *hcan)
{
  t->hcan = hcan;
  t->head = 0u;
  t->tail = 0u;
  g_tx_for_isr = t;
  (void)HAL_CAN_ActivateNotification(hcan, CAN_IT_TX_MAILBOX_EMPTY);
}

int example_stm32_can_tx(void *hal, uint32_t id, int extended, const unsigned char *data, unsigned int dlc)
{
  example_can_tx_t *t = (example_can_tx_t *)hal;
  example_can_txe_t *e;
  unsigned int i;
  if (t == NULL || dlc > 8u) {
    return -1;
  }
  (void)HAL_CAN_DeactivateNotification(t->hcan, CAN_IT_TX_MAILBOX_EMPTY);
  kick(t); /* make room first (e.g. after a bus-off recovery) */
  if (t->head - t->tail >= EXAMPLE_CAN_TXQ) {
    (void)HAL_CAN_ActivateNotification(t->hcan, CAN_IT_TX_MAILBOX_EMPTY);
    return -1; /* queue full: refuse, do not wait */
  }
  e = &t->q[t->head % EXAMPLE_CAN_TXQ];
  e->id = id;
  e->extended = extended;
  e->dlc = dlc;
  for (i = 0u; i < 8u; i++) e->data[i] = (unsigned char)(i < dlc ? (data[i] & 0xFFu) : 0u);
  t->head++;
  kick(t);
  (void)HAL_CAN_ActivateNotification(t->hcan, CAN_IT_TX_MAILBOX_EMPTY);
  return 0;
}

/* The HAL calls this from the CAN TX interrupt (mailbox 1 and 2 callbacks
 * would do the same). */
void HAL_CAN_TxMailbox0CompleteCallback(CAN_HandleTypeDef *hcan)
{
  if (g_tx_for_isr != NULL && g_tx_for_isr->hcan == hcan) {
    kick(g_tx_for_isr);
  }
}
