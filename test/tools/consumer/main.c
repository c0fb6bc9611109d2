/* SPDX-License-Identifier: Apache-2.0 */
/* A program outside the project, built against the installed imest: the core
 * (imest_init) and the installed firmware CAN port (share/imest/port/callback,
 * compiled here as a firmware compiles it) publishing one window. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest_can_callback.h"

static int count_tx(void *hal, uint32_t id, int extended, const unsigned char *data, unsigned int dlc)
{
  (void)id;
  (void)extended;
  (void)data;
  (void)dlc;
  ++*(unsigned int *)hal;
  return 0;
}

int main(void)
{
  imest_config_t c;
  imest_config_default(&c);
  c.pole_pairs = 2;
  c.ls_h = 0.29f;
  c.sigma = 0.1f;
  c.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  c.sigma_uncertainty = 0.0f;
  static imest_t s;
  const int rc = imest_init(&s, &c);

  static imest_can_callback_t cb;
  static imest_can_pub_t pub;
  imest_result_t r;
  unsigned int frames = 0;
  memset(&r, 0, sizeof r);
  if (imest_can_callback_init(&cb, count_tx, &frames) != 0 ||
      imest_can_pub_init(&pub, &cb.port, IMEST_CAN_DEFAULT_BASE_ID) != IMEST_OK ||
      imest_can_publish(&pub, &r) != 0 || frames != (unsigned int)IMEST_CAN_NFRAMES) {
    printf("CAN port: %u frames sent\n", frames);
    return 1;
  }
  printf("imest_init %d, %u CAN frames through the callback port\n", rc, frames);
  return rc;
}
