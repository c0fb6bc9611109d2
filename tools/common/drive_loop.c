/* SPDX-License-Identifier: Apache-2.0 */
#include "drive_loop.h"

#include <math.h>
#include <string.h>

#define TWO_PI 6.283185307179586476925

_Static_assert(IMEST_REASON_TRANSIENT < DRIVE_NSTATUS, "drive_t.by_status too small");

void drive_init(drive_t *d, imest_t *est, drive_window_fn on_window, void *ctx)
{
  memset(d, 0, sizeof *d);
  d->est = est;
  d->on_window = on_window;
  d->ctx = ctx;
}

float drive_wrap_angle(double theta_rad)
{
  double th = fmod(theta_rad, TWO_PI);
  if (th < 0.0) th += TWO_PI;
  float f = (float)th;
  if (f >= (float)TWO_PI) f = 0.0f;
  return f;
}

/* Background task: runs until imest_background() has nothing more (0). */
static int drain(drive_t *d)
{
  imest_result_t r;
  int n = 0, rc;
  while ((rc = imest_background(d->est, &r)) == 1) {
    d->windows++;
    d->valid += r.valid ? 1 : 0;
    d->tr_valid += r.tr_valid ? 1 : 0;
    d->rs_valid += r.rs_valid ? 1 : 0;
    if (r.status >= 0 && r.status < DRIVE_NSTATUS) d->by_status[r.status]++;
    d->tr_constants += r.tr_reason == IMEST_REASON_CONSTANTS_UNCERTAIN ? 1 : 0;
    if (d->on_window) d->on_window(d->ctx, &r);
    n++;
  }
  if (rc < 0) {
    if (d->error == 0) d->error = rc;
    return rc;
  }
  return n;
}

int drive_sample(drive_t *d, const double u_abc_v[3], const double i_abc_a[3], double theta_rad)
{
  const float u[3] = {(float)u_abc_v[0], (float)u_abc_v[1], (float)u_abc_v[2]};
  const float i[3] = {(float)i_abc_a[0], (float)i_abc_a[1], (float)i_abc_a[2]};
  if (!imest_isr_abc(d->est, u, i, drive_wrap_angle(theta_rad))) return 0;
  return drain(d);
}

int drive_sample_duty(drive_t *d, const double duty_abc[3], double vdc_v, const double i_abc_a[3],
                      double theta_rad)
{
  const float duty[3] = {(float)duty_abc[0], (float)duty_abc[1], (float)duty_abc[2]};
  const float i[3] = {(float)i_abc_a[0], (float)i_abc_a[1], (float)i_abc_a[2]};
  if (!imest_isr_duty(d->est, duty, (float)vdc_v, i, drive_wrap_angle(theta_rad))) return 0;
  return drain(d);
}

int drive_flush(drive_t *d)
{
  if (!imest_isr_flush(d->est)) return 0;
  return drain(d);
}
