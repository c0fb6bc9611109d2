/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: the sensors' white noise and the bias it puts into the
 * window sums (errors in the variables, docs/METHOD.md §16). Internal: not
 * part of the public API. */
#ifndef IMEST_BG_NOISE_H
#define IMEST_BG_NOISE_H

#include "bg_noise_bias.h"
#include "bg_window.h"

/* Filter noise gains at init: the covariance of (x, dx, d2x) of the front end
 * (filter and central differences) for unit white noise at its input, packed
 * (xx, x dx, x d2x, dx dx, dx d2x, d2x d2x). Bounded: at most 65536 samples
 * of the impulse response. */
void imest__bg_noise_gains(const imest_bw3_t *bw, float fs, float g[6]);

/* The noise variances from the window's third differences (the smooth
 * signal's share removed), and the bias they put into the sums for the
 * window's mean speed (steady-state approximation: the acceleration's terms
 * are left out). steady: the window's mean speed is the previous window's;
 * otherwise (a run-up: large currents, small bias, and a noise estimate that
 * carries the transient) nothing will be subtracted. */
void imest__bg_noise_estimate(const imest_t *s, const imest_window_t *w, const bg_window_stats_t *st,
                              const bg_sums_t *sums, int steady, bg_noise_t *nz);

#endif /* IMEST_BG_NOISE_H */
