/* SPDX-License-Identifier: Apache-2.0 */
/* The firmware's loop, written once for every host tool that runs the
 * estimator on samples (imest-replay, imest-demo): per sample the float32 ISR
 * call (phase voltages or duty cycles) with the encoder angle wrapped to
 * [0, 2pi); when it reports a finished
 * window, imest_background() drained until it has nothing more, each result
 * handed to the tool and counted. Host tool code. */
#ifndef IMEST_DRIVE_LOOP_H
#define IMEST_DRIVE_LOOP_H

#include "imest/imest.h"

/* Counts per imest_reason_t value (0 = valid). */
#define DRIVE_NSTATUS 32

typedef void (*drive_window_fn)(void *ctx, const imest_result_t *r);

typedef struct {
  imest_t *est;
  drive_window_fn on_window; /* each result, in order (may be NULL) */
  void *ctx;
  long windows, valid;
  long tr_valid, rs_valid; /* windows whose T_R, R_S alone is valid */
  long by_status[DRIVE_NSTATUS];
  long tr_constants; /* windows whose T_R is constants_uncertain */
  int error;         /* first negative return of imest_background(), 0 = none */
} drive_t;

void drive_init(drive_t *d, imest_t *est, drive_window_fn on_window, void *ctx);

/* The angle as firmware passes it: wrapped to [0, 2pi) in double, then
 * float32 (a value that rounds up to 2pi becomes 0). Any input range. */
float drive_wrap_angle(double theta_rad);

/* One sample: ISR call, then the background drained if a window finished.
 * Returns the number of results handed on, or a negative imest_err_t. */
int drive_sample(drive_t *d, const double u_abc_v[3], const double i_abc_a[3], double theta_rad);

/* The same for a drive without voltage sensors: the upper switches' duties
 * (applied as cfg.pwm_timing says) and the bus voltage, imest_isr_duty(). */
int drive_sample_duty(drive_t *d, const double duty_abc[3], double vdc_v, const double i_abc_a[3],
                      double theta_rad);

/* Ends the current window early (imest_isr_flush()) and drains the background.
 * Returns the number of results, or a negative imest_err_t. */
int drive_flush(drive_t *d);

#endif
