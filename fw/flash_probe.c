/* Flash probe: links every public function of the core a firmware calls,
 * and the CAN publisher (the telemetry a drive sends; the reader is host
 * code). Built twice, with and without the library calls (FW_FLASH_BASELINE);
 * the size difference is the flash a firmware pays for the core, including
 * what it pulls from libm, libgcc and libc, with --gc-sections. With
 * FW_FLASH_DUTY it also links the duty-cycle input, reported on its own line. */
#include <stdint.h>
#ifndef FW_FLASH_BASELINE
#include "imest/imest.h"
#include "imest/imest_can.h"
static imest_t est;
static imest_result_t res;
static imest_can_pub_t pub;
static int probe_send(void *ctx, const imest_can_frame_t *f)
{
  (void)ctx;
  return (int)f->data[7]; /* uses the frame, so nothing is optimised away */
}
static const imest_can_port_t probe_port = {probe_send, 0};
#endif
int main(void);
void fw_mark_b0(void);

int main(void)
{
#ifndef FW_FLASH_BASELINE
  imest_config_t cfg;
  const char *field = 0;
  imest_config_default(&cfg);
  if (imest_config_check(&cfg, &field) != IMEST_OK) return 1;
  if (imest_init(&est, &cfg) != IMEST_OK) return 1;
  const float u[3] = {0.0f, 0.0f, 0.0f}, i[3] = {0.0f, 0.0f, 0.0f};
  (void)imest_isr_abc(&est, u, i, 0.0f);
  (void)imest_isr_ab(&est, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f);
#ifdef FW_FLASH_DUTY
  (void)imest_isr_duty(&est, u, 0.0f, i, 0.0f);
#endif
  (void)imest_background(&est, &res);
  (void)imest_reason_name(res.status);
  if (imest_can_pub_init(&pub, &probe_port, IMEST_CAN_DEFAULT_BASE_ID) != IMEST_OK) return 1;
  (void)imest_can_publish(&pub, &res);
  return (int)imest_overruns(&est);
#else
  fw_mark_b0();
  return 0;
#endif
}
