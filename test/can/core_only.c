/* SPDX-License-Identifier: Apache-2.0 */
/* The estimator without telemetry: this program calls only the core (init,
 * ISR, background) and runs it over a loaded motor's signals. The test
 * can_core_without_telemetry runs it and checks (nm) that no imest_can_*
 * code was linked: telemetry is the application's, never the estimator's. */
#include <math.h>
#include <stdio.h>

#include "imest/imest.h"

int main(void)
{
  static imest_t est;
  imest_config_t cfg;
  imest_result_t r;
  unsigned int results = 0u;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2u;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.window_s = 0.25f;
  if (imest_init(&est, &cfg) != IMEST_OK) return 1;
  for (int n = 0; n < 4000; n++) {
    const float t = (float)n / 4000.0f, w = 2.0f * 3.14159265f * 20.0f;
    if (imest_isr_ab(&est, 100.0f * cosf(w * t), 100.0f * sinf(w * t), 5.0f * cosf(w * t - 0.5f),
                     5.0f * sinf(w * t - 0.5f), fmodf(0.9f * w * t / 2.0f, 6.2831853f))) {
      while (imest_background(&est, &r) == 1) results++;
    }
  }
  printf("core only: %u window results\n", results);
  return results >= 3u ? 0 : 1;
}
