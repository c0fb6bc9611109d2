/* Background stage: the sensors' white noise and the bias it puts into the
 * window sums (errors in the variables, docs/METHOD.md §16). Internal: not
 * part of the public API. */
#ifndef IMEST_BG_NOISE_H
#define IMEST_BG_NOISE_H

#include "bg_window.h"

/* The window's noise and its bias on the sums. */
typedef struct {
  double var_i;   /* white-noise variance of the current per alpha/beta axis [A^2] */
  double var_u;   /* ... of the voltage [V^2] (0 with the duty-cycle input) */
  double e_c0;    /* E_p^2 the noise explains at the window's centring (subtracted) */
  int steady;     /* the speed was steady: the bias model applies */
  double scale;   /* share of the bias subtracted (1; less where the whole bias
                      would have made the sums of W'W indefinite) */
  float bias[36]; /* the bias of [W e]'[W e] in the ISR's packed order, for the
                      window's samples (W: the 7 columns, e: y) */
} bg_noise_t;

/* Filter noise gains at init: the covariance of (x, dx, d2x) of the front end
 * (filter and central differences) for unit white noise at its input, packed
 * (xx, x dx, x d2x, dx dx, dx d2x, d2x d2x). Bounded: at most 65536 samples
 * of the impulse response. */
void bg_noise_gains(const imest_bw3_t *bw, double fs, float g[6]);

/* The noise variances from the window's third differences (the smooth
 * signal's share removed), and the bias they put into the sums for the
 * window's mean speed (steady-state approximation: the acceleration's terms
 * are left out). steady: the window's mean speed is the previous window's;
 * otherwise (a run-up: large currents, small bias, and a noise estimate that
 * carries the transient) nothing will be subtracted. */
void bg_noise_estimate(const imest_t *s, const imest_window_t *w, const bg_window_stats_t *st,
                       const bg_sums_t *sums, int steady, bg_noise_t *nz);

/* Subtract the bias from the sums (uncentred and centred forms, column 3
 * rebuilt as -m column 4). Where the whole bias would make R_W indefinite,
 * halves it (at most 4 times, else none): nz->scale says how much went. */
void bg_noise_subtract(bg_sums_t *sums, bg_noise_t *nz, double m);

/* The residual the noise explains at K (8-entry K of docs/METHOD.md §2), in
 * the units of E_p^2. */
double bg_noise_e(const bg_noise_t *nz, const double k[8], double m);

#endif /* IMEST_BG_NOISE_H */
