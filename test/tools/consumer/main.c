/* SPDX-License-Identifier: Apache-2.0 */
#include <stdio.h>
#include "imest/imest.h"
int main(void)
{
  imest_config_t c;
  imest_config_default(&c);
  c.pole_pairs = 2;
  c.ls_h = 0.29f;
  c.sigma = 0.1f;
  static imest_t s;
  const int rc = imest_init(&s, &c);
  printf("imest_init %d\n", rc);
  return rc;
}
