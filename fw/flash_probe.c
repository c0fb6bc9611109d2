/* SPDX-License-Identifier: Apache-2.0 */
/* Flash probe: links every public function of the core a firmware calls,
 * and the CAN publisher (the telemetry a drive sends; the reader is host
 * code). Built twice, with and without the library calls (FW_FLASH_BASELINE);
 * the size difference is the flash a firmware pays for the core, including
 * what it pulls from libm, libgcc and libc, with --gc-sections. With
 * FW_FLASH_DUTY it also links the duty-cycle input, reported on its own line.
 * FW_FLASH_COMM adds the self-commissioning API (imest_commission.h); with
 * FW_FLASH_COMM_ONLY it is linked alone. FW_FLASH_MINIMAL links the least a
 * firmware needs: one voltage input, no CAN publisher, no reason names. */
#include <stdint.h>
#if !defined(FW_FLASH_BASELINE) && !defined(FW_FLASH_COMM_ONLY)
#include "imest/imest.h"
#include "imest/imest_can.h"
static imest_t est;
static imest_result_t res;
#ifndef FW_FLASH_MINIMAL
static imest_can_pub_t pub;
static int probe_send(void *ctx, const imest_can_frame_t *f)
{
  (void)ctx;
  return (int)f->data[7]; /* uses the frame, so nothing is optimised away */
}
static const imest_can_port_t probe_port = {probe_send, 0};
#endif
#endif
#if defined(FW_FLASH_COMM) || defined(FW_FLASH_COMM_ONLY)
#include "imest/imest_commission.h"
static imest_comm_t comm;
static int probe_comm(void)
{
  imest_comm_config_t cc;
  const char *field = 0;
  imest_comm_config_default(&cc);
  if (imest_comm_config_check(&cc, &field) != IMEST_OK) return 1;
  if (imest_comm_init(&comm, &cc) != IMEST_OK) return 1;
  const float i[3] = {0.0f, 0.0f, 0.0f};
  float d[3];
  int n = imest_comm_isr(&comm, i, 1.0f, 0.0f, d);
  n += imest_comm_background(&comm);
  (void)imest_comm_abort(&comm);
  imest_comm_status_t st;
  (void)imest_comm_status(&comm, &st);
  imest_comm_result_t r;
  (void)imest_comm_result(&comm, &r);
  imest_config_t cfg;
  imest_config_default(&cfg);
  n += imest_comm_apply(&r, &cfg);
  (void)imest_comm_reason_name(r.reason);
  (void)imest_comm_stage_name(st.stage);
  (void)imest_comm_state_name(st.state);
  return n + (int)d[0];
}
#endif
int main(void);
void fw_mark_b0(void);

int main(void)
{
#ifdef FW_FLASH_COMM_ONLY
  return probe_comm();
#elif !defined(FW_FLASH_BASELINE)
#ifdef FW_FLASH_COMM
  if (probe_comm() != 0) return 1;
#endif
  imest_config_t cfg;
  const char *field = 0;
  imest_config_default(&cfg);
  if (imest_config_check(&cfg, &field) != IMEST_OK) return 1;
  if (imest_init(&est, &cfg) != IMEST_OK) return 1;
  const float u[3] = {0.0f, 0.0f, 0.0f}, i[3] = {0.0f, 0.0f, 0.0f};
  (void)imest_isr_abc(&est, u, i, 0.0f);
#ifndef FW_FLASH_MINIMAL
  (void)imest_isr_ab(&est, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f);
#endif
#ifdef FW_FLASH_DUTY
  (void)imest_isr_duty(&est, u, 0.0f, i, 0.0f);
#endif
  (void)imest_background(&est, &res);
#ifdef FW_FLASH_MINIMAL
  return (int)imest_overruns(&est) + (int)res.tr_valid;
#else
  (void)imest_reason_name(res.status);
  if (imest_can_pub_init(&pub, &probe_port, IMEST_CAN_DEFAULT_BASE_ID) != IMEST_OK) return 1;
  (void)imest_can_publish(&pub, &res);
  return (int)imest_overruns(&est);
#endif
#else
  fw_mark_b0();
  return 0;
#endif
}
