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
  imest_real_t vdc, vdc_prev;
  imest_real_t e0;    /* t_d f V_dc + V_d0 at the weighted bus voltage */
  imest_real_t band2; /* i_band^2 */
} isr_duty_k_t;

/* Voltage delivered by one leg [V], relative to the negative rail, from the
 * previous call's duty *dprev (replaced by d) and this call's d, for the
 * phase current i:
 *   e = s(i) [ t_d f V_dc + V_d0 + r_d |i| + d_c ((V_sw0 - V_d0) + (r_sw - r_d) |i|) ]
 * with d_c = 1/2 + s (d - 1/2) (d for i > 0, 1 - d for i < 0) and the smooth
 * sign s(i) = i / sqrt(i^2 + i_band^2): the current ripple crosses zero inside
 * the period near a zero crossing, so the error fades instead of jumping. */
static inline imest_real_t isr_duty_leg(const imest_duty_model_t *m, const isr_duty_k_t *k,
                                        imest_real_t *dprev, imest_real_t d, imest_real_t i,
                                        imest_real_t *step)
{
  const imest_real_t dp = *dprev;
  *dprev = d;
  *step = k->vdc * d - k->vdc_prev * dp; /* the leg voltage's step at the sample */
  const imest_real_t v = k->kp * dp + k->kn * d;
  const imest_real_t dbar = m->w_prev * dp + m->w_now * d;
  const imest_real_t a = imest__abs(i);
  const imest_real_t sgn = i / imest__sqrt(i * i + k->band2);
  const imest_real_t dc = RL(0.5) + sgn * (dbar - RL(0.5));
  const imest_real_t mag = (k->e0 + m->r_d * a) + dc * (m->dv + m->dr * a);
  return v - sgn * mag;
}

#endif
