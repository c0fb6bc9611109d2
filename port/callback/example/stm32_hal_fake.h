/* SPDX-License-Identifier: Apache-2.0 */
/* A host stand-in for the few STM32 HAL (bxCAN) calls the example uses, so
 * the example compiles and runs on the host. Same names and shapes as the
 * vendor HAL; behaviour: 3 transmit mailboxes, filled by AddTxMessage and
 * emptied by fake_can_complete() (the "bus"). Not part of any firmware. */
#ifndef STM32_HAL_FAKE_H
#define STM32_HAL_FAKE_H

#include <stdint.h>

typedef enum { HAL_OK = 0, HAL_ERROR = 1, HAL_BUSY = 2, HAL_TIMEOUT = 3 } HAL_StatusTypeDef;

#define CAN_ID_STD   0x00000000u
#define CAN_ID_EXT   0x00000004u
#define CAN_RTR_DATA 0x00000000u

typedef struct {
  uint32_t StdId;
  uint32_t ExtId;
  uint32_t IDE;
  uint32_t RTR;
  uint32_t DLC;
  int TransmitGlobalTime;
} CAN_TxHeaderTypeDef;

#define FAKE_CAN_MAILBOXES 3
#define FAKE_CAN_LOG       64

typedef struct {
  uint32_t id; /* with bit 31 set for extended (as IMEST_CAN_ID_EXT) */
  uint32_t dlc;
  uint8_t data[8];
} fake_can_msg_t;

typedef struct {
  int bus_off;         /* set: AddTxMessage fails */
  uint32_t it_enabled; /* CAN_IT_* notifications on */
  int busy[FAKE_CAN_MAILBOXES];
  fake_can_msg_t mailbox[FAKE_CAN_MAILBOXES];
  fake_can_msg_t log[FAKE_CAN_LOG]; /* frames "sent" on the bus */
  unsigned int n_log;
} CAN_HandleTypeDef;

#define CAN_IT_TX_MAILBOX_EMPTY 0x00000001u

uint32_t HAL_CAN_GetTxMailboxesFreeLevel(CAN_HandleTypeDef *hcan);
HAL_StatusTypeDef HAL_CAN_ActivateNotification(CAN_HandleTypeDef *hcan, uint32_t ActiveITs);
HAL_StatusTypeDef HAL_CAN_DeactivateNotification(CAN_HandleTypeDef *hcan, uint32_t InactiveITs);
/* Defined by the application (weak in the vendor HAL): a mailbox finished. */
void HAL_CAN_TxMailbox0CompleteCallback(CAN_HandleTypeDef *hcan);
HAL_StatusTypeDef HAL_CAN_AddTxMessage(CAN_HandleTypeDef *hcan, CAN_TxHeaderTypeDef *pHeader, uint8_t aData[],
                                       uint32_t *pTxMailbox);

/* Fake only: the controller sends every pending mailbox (in mailbox order;
 * priority by identifier is not modelled), then raises the mailbox-empty
 * interrupt if enabled (calls HAL_CAN_TxMailbox0CompleteCallback). */
void fake_can_complete(CAN_HandleTypeDef *hcan);

#endif
