/* SPDX-License-Identifier: Apache-2.0 */
/* imsim-bench: motor-seconds simulated per CPU-second of this process (one core; CPU time so
 * that a busy machine does not distort the figure).
 * Default case: exp2, PWM inverter (10 kHz, event-exact), 12-bit sensors with noise, 4 kHz.
 * usage: imsim-bench [motor_seconds]   (default 60) */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "imsim/imsim.h"

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double run(const char *label, const imsim_config_t *c, double motor_s)
{
  static imsim_t sim;
  imsim_sample_t s;
  if (imsim_init(&sim, c, &s) != 0) {
    fprintf(stderr, "%s: %s\n", label, imsim_error(&sim));
    return 0.0;
  }
  const long n = (long)(motor_s * c->fs_hz + 0.5);
  double sink = 0.0;
  const double t0 = now_s();
  for (long k = 0; k < n; ++k) {
    imsim_step(&sim, &s);
    sink += s.i_abc[0];
  }
  const double wall = now_s() - t0;
  const double x = motor_s / wall;
  printf("%-44s %8.1f motor-s/cpu-s  (%.2f s cpu for %.0f s; 1 h in %.1f s)  [%g]\n", label, x, wall, motor_s,
         3600.0 / x, sink * 0.0);
  return x;
}

int main(int argc, char **argv)
{
  const double motor_s = argc > 1 ? atof(argv[1]) : 60.0;
  imsim_config_t c;
  imsim_config_preset(&c, "exp2");
  c.supply = IMSIM_SUPPLY_PWM;
  run("exp2 pwm 10kHz, 12-bit + 1 LSB noise, 4 kHz", &c, motor_s);
  c.pwm_moments = false;
  run("  same, --pwm-segments (reference accuracy)", &c, motor_s);
  c.pwm_moments = true;
  c.aa_hz = 800.0;
  run("exp2 pwm 10kHz, 12-bit, AA 800 Hz", &c, motor_s);
  c.aa_hz = 0.0;
  c.dead_time_s = 2e-6;
  run("exp2 pwm 10kHz, 12-bit, dead time 2 us", &c, motor_s);
  imsim_config_preset(&c, "exp2");
  run("exp2 ideal V/f sine, 12-bit", &c, motor_s);
  imsim_config_preset(&c, "exp2");
  c.supply = IMSIM_SUPPLY_IFOC;
  run("exp2 IFOC + pwm, 12-bit", &c, motor_s);
  imsim_config_preset(&c, "4kw");
  run("4kw drive 8 kHz, svpwm, firmware timing", &c, motor_s);
  c.dead_time_s = 2e-6;
  c.v_switch_v = 1.0;
  c.r_switch_ohm = 0.02;
  c.v_diode_v = 0.8;
  c.r_diode_ohm = 0.01;
  run("  same, dead time 2 us + device drops", &c, motor_s);
  c.pwm_moments = false;
  run("  same, --pwm-segments", &c, motor_s);
  return 0;
}
