/* SPDX-License-Identifier: Apache-2.0 */
/* ISR stage 0 of the duty-cycle input: the phase voltage a drive without
 * voltage sensors knows, from its duty cycles and the DC bus, minus the
 * inverter's voltage error (include/imest/imest.h, imest_inverter_t). Each
 * leg's voltage d * V_dc is averaged over the two PWM periods around the
 * sample (weights from pwm_timing), so the voltage refers to the sample
 * instant like the currents; the zero sequence drops out in the 3-2
 * transform. */
#ifndef IMEST_ISR_DUTY_H
#define IMEST_ISR_DUTY_H

#include "common/imest_math.h"

/* Per-sample constants shared by the three legs. */
typedef struct {
  imest_real_t kp, kn; /* w_prev V_dc,prev and w_now V_dc: a leg's voltage is kp dp + kn d */
  imest_real_t kt;     /* t_d f V_dc / 2 at the weighted bus voltage */
  imest_real_t band2;  /* b^2: the devices' own smoothing, or the smooth sign's fixed band */
  imest_real_t b0;     /* the smooth sign's floor beyond the leg's ripple [A] (0: none) */
} isr_duty_k_t;

/* The per-sample constants for the bus voltages V_dc,prev and V_dc; returns
 * kr = V_dc T / (2 sigma L_S) at the weighted bus voltage (isr_duty_ripple's
 * scale; 0 for the smooth sign with a fixed band). */
static inline imest_real_t isr_duty_constants(const imest_duty_model_t *m, imest_real_t vdc_prev,
                                              imest_real_t vdc, isr_duty_k_t *k)
{
  k->kp = m->w_prev * vdc_prev;
  k->kn = (RL(1) - m->w_prev) * vdc;
  const imest_real_t vbar = k->kp + k->kn;
  k->kt = m->td_f_half * vbar;
  k->b0 = m->floor_per_v * vbar;
  k->band2 = m->band2;
  return m->ripple_per_v * vbar;
}

/* The phase current's ripple at each leg's edges [A] (docs/METHOD.md §17.1):
 * centre-aligned PWM, floating neutral, against the line between the
 * currents at the period's ends, the ripple is +D_x at leg x's rising edge
 * and -D_x at its falling edge,
 *   D_x = V_dc T / (2 sigma L_S) [(d_x - dbar)(d_x - 1/2) - (|d_x - d_y| + |d_x - d_z|) / 6],
 * dbar the mean of the three duties; kr = V_dc T / (2 sigma L_S). */
static inline void isr_duty_ripple(imest_real_t kr, const imest_real_t d[3], imest_real_t r[3])
{
  const imest_real_t mean = ((d[0] + d[1]) + d[2]) * RL(IMEST_ONE_THIRD_LIT);
  const imest_real_t pab = imest__abs(d[0] - d[1]), pbc = imest__abs(d[1] - d[2]),
                     pca = imest__abs(d[2] - d[0]);
  r[0] = kr * ((d[0] - mean) * (d[0] - RL(0.5)) - (pab + pca) * RL(IMEST_ONE_SIXTH_LIT));
  r[1] = kr * ((d[1] - mean) * (d[1] - RL(0.5)) - (pab + pbc) * RL(IMEST_ONE_SIXTH_LIT));
  r[2] = kr * ((d[2] - mean) * (d[2] - RL(0.5)) - (pbc + pca) * RL(IMEST_ONE_SIXTH_LIT));
}

/* The error of one leg [V] (how much less it delivers than d V_dc) for the
 * sampled phase current i, the leg's duty dbar around the sample and its
 * ripple r at the edges:
 *   e = t_d f V_dc s_e + (V_sw0 + V_d0)/2 m + (r_sw + r_d)/2 i + (dbar - 1/2) (dV + dr |i|)
 * The dead time's volt-seconds follow the current at the two edges, i + r and
 * i - r: s_e = (s(i + r) + s(i - r)) / 2. The drops follow the current's own
 * sign over each conducting interval, along which the current runs from
 * i - r to i + r: m is the smooth sign's mean over that ramp, exactly
 * (sqrt((i + r)^2 + b^2) - sqrt((i - r)^2 + b^2)) / 2r = 2 i / (q+ + q-),
 * the two square roots the edges' signs need already (no division by r). The
 * drops' slope part is a resistance: its mean is r_sw,d times the current
 * itself. s(x) = x / sqrt(x^2 + b^2). */
static inline imest_real_t isr_duty_error(const imest_duty_model_t *m, const isr_duty_k_t *k,
                                          imest_real_t dbar, imest_real_t i, imest_real_t r)
{
  const imest_real_t ip = i + r, im = i - r;
  const imest_real_t qp = imest__sqrt(ip * ip + k->band2), qm = imest__sqrt(im * im + k->band2);
  const imest_real_t se2 = ip / qp + im / qm; /* 2 s_e */
  const imest_real_t mh = i / (qp + qm);      /* m / 2 */
  return ((k->kt * se2 + m->v_sum * mh) + m->r_mean * i) + (dbar - RL(0.5)) * (m->dv + m->dr * imest__abs(i));
}

/* The smooth sign's error of one leg [V] (imest_inverter_t, edge_band_a 0):
 *   e = s(i) [ t_d f V_dc + V_d0 + r_d |i| + d_c ((V_sw0 - V_d0) + (r_sw - r_d) |i|) ]
 * with d_c = 1/2 + s (dbar - 1/2) (dbar for i > 0, 1 - dbar for i < 0) and the
 * smooth sign s(i) = i / sqrt(i^2 + b^2), b = |r| + b_0: the current at the
 * leg's edges is i + r and i - r (r its ripple there, isr_duty_ripple; 0 with
 * a fixed band i_band_a, which is then k->band2), so near a zero crossing the
 * error fades instead of jumping; b_0 half the current's change within the
 * dead time, the two edges' mean (docs/METHOD.md §17.1). In the constants of the other model:
 * V_d0 + d_c dV = (V_sw0 + V_d0)/2 + s (dbar - 1/2) dV, the same for the slopes. */
static inline imest_real_t isr_duty_error_smooth(const imest_duty_model_t *m, const isr_duty_k_t *k,
                                                 imest_real_t dbar, imest_real_t i, imest_real_t r)
{
  const imest_real_t a = imest__abs(i), b = imest__abs(r) + k->b0;
  const imest_real_t sgn = i / imest__sqrt((i * i + b * b) + k->band2);
  const imest_real_t mag = ((k->kt + k->kt) + RL(0.5) * m->v_sum) + m->r_mean * a;
  return sgn * (mag + sgn * ((dbar - RL(0.5)) * (m->dv + m->dr * a)));
}

#endif
