/* Internal declarations shared by init and the background task. */
#ifndef IMEST_BG_INTERNAL_H
#define IMEST_BG_INTERNAL_H

#include "bg_solve.h"
#include "isr_real.h"

#define IMEST_PI_D 3.14159265358979323846
#define IMEST_SQRT2_D 1.41421356237309504880

/* c0 (7-column centring vector) from K1, K2. */
void imest_centre_from_k(imest_real_t c0[7], double k1, double k2, double m);

/* One window's ISR sums -> full 8x8 float64 sums (undoes the centring and
 * rebuilds column 3). Also returns rms current and the slip/speed measures. */
typedef struct {
  double i_rms_a;     /* rms |i| (alpha/beta amplitude) */
  double w_mean;      /* mean mechanical speed [rad/s] */
  double slip_rate;   /* mean rotation rate of the rotor-frame current [rad/s]:
                         the slip frequency in steady state */
} imest_window_stats_t;

void imest_window_sums(const imest_window_t *w, double m, double fs, imest_sums_t *out,
                       imest_window_stats_t *st);

/* Validity: fills valid/status of r from the window flags, stats and solve. */
void imest_judge(const imest_t *s, const imest_window_stats_t *st, const imest_solve_out_t *so,
                 imest_result_t *r);

#endif
