/* SPDX-License-Identifier: Apache-2.0 */
/* Host run of the STM32 example: a publisher sends windows through the
 * callback port into the fake HAL. Windows 0 and 1 reach the "bus"; then the
 * controller goes bus-off, the software queue fills and further frames are
 * refused and counted (pub.tx_failed), never retried; after recovery,
 * publishing resumes. Prints what reached the bus. */
#include <stdio.h>
#include <string.h>

#include "example_stm32.h"
#include "imest/imest_can.h"
#include "imest_can_callback.h"

int main(void)
{
  static CAN_HandleTypeDef hcan1;
  static example_can_tx_t tx;
  imest_can_callback_t cb;
  imest_can_pub_t pub; /* the application's, next to its imest_t */
  imest_result_t r;
  unsigned int k;
  memset(&r, 0, sizeof r);
  example_can_tx_init(&tx, &hcan1);
  imest_can_callback_init(&cb, example_stm32_can_tx, &tx);
  if (imest_can_pub_init(&pub, &cb.port, IMEST_CAN_DEFAULT_BASE_ID) != IMEST_OK) return 1;
  for (k = 0u; k < 6u; k++) {
    int failed;
    hcan1.bus_off = (k >= 2u && k <= 4u);
    r.seq = k;
    r.valid = r.tr_valid = r.rs_valid = 1;
    r.status = r.tr_reason = r.rs_reason = IMEST_REASON_NONE;
    r.span_s = 1.0;
    r.windows = 1u;
    r.tr_bound_rel = 0.004;
    r.rs_bound_rel = 0.02;
    r.tr_s = 0.125;
    r.rs_ohm = 1.5;
    r.e_i = 0.02;
    r.pe_k1_rel = 0.01;
    r.pe_k2_rel = 0.005;
    r.n_roots = 3;
    r.n_admissible = 1;
    failed = imest_can_publish(&pub, &r); /* after imest_background() returned r */
    printf("window %u: %d frame(s) refused%s\n", k, failed, hcan1.bus_off ? " (bus-off)" : "");
    while (hcan1.busy[0] || hcan1.busy[1] || hcan1.busy[2]) fake_can_complete(&hcan1);
  }
  printf("accepted %u refused %u tx_failed %u on bus %u\n", (unsigned)cb.sent, (unsigned)cb.failed,
         (unsigned)pub.tx_failed, hcan1.n_log);
  for (k = 0u; k < hcan1.n_log; k++) {
    unsigned int i;
    printf("%03X#", (unsigned)(hcan1.log[k].id & 0x7FFu));
    for (i = 0u; i < hcan1.log[k].dlc; i++) printf("%02X", hcan1.log[k].data[i]);
    printf("\n");
  }
  return 0;
}
