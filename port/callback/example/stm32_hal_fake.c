/* SPDX-License-Identifier: Apache-2.0 */
#include "stm32_hal_fake.h"

#include <stddef.h>

uint32_t HAL_CAN_GetTxMailboxesFreeLevel(CAN_HandleTypeDef *hcan)
{
  uint32_t n = 0u;
  int i;
  for (i = 0; i < FAKE_CAN_MAILBOXES; i++) {
    if (!hcan->busy[i]) n++;
  }
  return n;
}

HAL_StatusTypeDef HAL_CAN_AddTxMessage(CAN_HandleTypeDef *hcan, CAN_TxHeaderTypeDef *pHeader, uint8_t aData[],
                                       uint32_t *pTxMailbox)
{
  int i;
  uint32_t k;
  if (hcan == NULL || pHeader == NULL || aData == NULL || pHeader->DLC > 8u || hcan->bus_off) {
    return HAL_ERROR;
  }
  for (i = 0; i < FAKE_CAN_MAILBOXES; i++) {
    if (!hcan->busy[i]) {
      fake_can_msg_t *m = &hcan->mailbox[i];
      m->id = pHeader->IDE == CAN_ID_EXT ? (pHeader->ExtId | 0x80000000u) : pHeader->StdId;
      m->dlc = pHeader->DLC;
      for (k = 0u; k < 8u; k++) m->data[k] = k < pHeader->DLC ? aData[k] : 0u;
      hcan->busy[i] = 1;
      if (pTxMailbox != NULL) *pTxMailbox = 1u << i;
      return HAL_OK;
    }
  }
  return HAL_ERROR; /* the vendor HAL also fails at once when no mailbox is free */
}

HAL_StatusTypeDef HAL_CAN_ActivateNotification(CAN_HandleTypeDef *hcan, uint32_t ActiveITs)
{
  hcan->it_enabled |= ActiveITs;
  return HAL_OK;
}

HAL_StatusTypeDef HAL_CAN_DeactivateNotification(CAN_HandleTypeDef *hcan, uint32_t InactiveITs)
{
  hcan->it_enabled &= ~InactiveITs;
  return HAL_OK;
}

void fake_can_complete(CAN_HandleTypeDef *hcan)
{
  int i;
  int any = 0;
  for (i = 0; i < FAKE_CAN_MAILBOXES; i++) {
    if (hcan->busy[i]) {
      if (hcan->n_log < FAKE_CAN_LOG) hcan->log[hcan->n_log++] = hcan->mailbox[i];
      hcan->busy[i] = 0;
      any = 1;
    }
  }
  if (any && (hcan->it_enabled & CAN_IT_TX_MAILBOX_EMPTY)) {
    HAL_CAN_TxMailbox0CompleteCallback(hcan);
  }
}
