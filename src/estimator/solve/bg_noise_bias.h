/* SPDX-License-Identifier: Apache-2.0 */
/* Background solve stage: the white noise's bias on the window sums and the
 * residual it explains (docs/METHOD.md §16). Internal: not part of the public
 * API. */
#ifndef IMEST_BG_NOISE_BIAS_H
#define IMEST_BG_NOISE_BIAS_H

#include "bg_solve.h"

/* The window's noise and its bias on the sums. */
typedef struct bg_noise {
  float var_i;    /* white-noise variance of the current per alpha/beta axis [A^2] */
  float var_u;    /* ... of the voltage [V^2] (0 with the duty-cycle input) */
  double e_c0;    /* E_p^2 the noise explains at the window's centring (subtracted) */
  int steady;     /* the speed was steady: the bias model applies */
  double scale;   /* share of the bias subtracted (1; less where the whole bias
                      would have made the sums of W'W indefinite) */
  float bias[36]; /* the bias of [W e]'[W e] in the ISR's packed order, for the
                      window's samples (W: the 7 columns, e: y) */
} bg_noise_t;

/* Subtract the bias from the sums (uncentred and centred forms, column 3
 * rebuilt as -m column 4). Where the whole bias would make R_W indefinite,
 * halves it (at most 4 times, else none): nz->scale says how much went. */
void imest__bg_noise_subtract(bg_sums_t *sums, bg_noise_t *nz, double m);

/* The residual the noise explains at K (8-entry K of docs/METHOD.md §2), in
 * the units of E_p^2. */
double imest__bg_noise_e(const bg_noise_t *nz, const double k[8], double m);

/* The same at (K1, K2), the rest of K formed from them. */
double imest__bg_noise_e_at(const bg_noise_t *nz, double k1, double k2, double m);

#endif /* IMEST_BG_NOISE_BIAS_H */
