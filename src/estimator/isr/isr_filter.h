/* SPDX-License-Identifier: Apache-2.0 */
/* ISR stage 2: Butterworth-3 low-pass as second-order sections and
 * time-aligned central differences (docs/METHOD.md §8). Every channel passes the same
 * filter so the delays are identical. */
#ifndef IMEST_ISR_FILTER_H
#define IMEST_ISR_FILTER_H

#include "common/imest_math.h"

/* Offset removal: x minus its tracked mean, first-order (mean += a (x - mean)).
 * Applied alike to every electrical channel; a = 0 passes x unchanged. */
static inline imest_real_t isr_dc_block(imest_real_t a, imest_real_t *mean, imest_real_t x)
{
  const imest_real_t y = x - *mean;
  *mean += a * y;
  return y;
}

/* One sample through a bilinear second-order low-pass section
 * c0 (1 + 2 z^-1 + z^-2) / (1 + d1 z^-1 + d2 z^-2), transposed DF-II. */
static inline imest_real_t isr_lp2(imest_real_t c0, imest_real_t d1, imest_real_t d2, imest_real_t *sa,
                                   imest_real_t *sb, imest_real_t x)
{
  const imest_real_t t = c0 * x;
  const imest_real_t y = t + *sa;
  *sa = (t + t) - d1 * y + *sb;
  *sb = t - d2 * y;
  return y;
}

/* One sample through the first- and second-order sections (transposed DF-II).
 * Returns x_f[n]. */
static inline imest_real_t isr_bw3(const imest_bw3_t *f, imest_chan_t *c, imest_real_t x)
{
  const imest_real_t t = f->b0 * x;
  const imest_real_t v = t + c->s1;
  c->s1 = t - f->a1 * v;
  return isr_lp2(f->c0, f->d1, f->d2, &c->s2a, &c->s2b, v);
}

/* Filtered value and its central derivatives, all referred to sample n-1:
 * x = x_f[n-1], dx = (x_f[n] - x_f[n-2]) / 2T, d2x = (x_f[n] - 2 x_f[n-1] + x_f[n-2]) / T^2. */
typedef struct {
  imest_real_t x, dx, d2x;
} isr_deriv_t;

static inline isr_deriv_t isr_filter_deriv(const imest_t *s, imest_chan_t *c, imest_real_t x)
{
  const imest_real_t xf = isr_bw3(&s->bw, c, x);
  isr_deriv_t d;
  d.x = c->y1;
  d.dx = (xf - c->y2) * s->inv2t;
  d.d2x = ((xf - c->y1) - (c->y1 - c->y2)) * s->invt2;
  c->y2 = c->y1;
  c->y1 = xf;
  return d;
}

/* The speed channel: the filter runs on the angle increments times fs (a
 * float32 unwrapped angle would lose resolution). Since differencing commutes
 * with the filter, omega and domega/dt at n-1 are the mean and the difference
 * of two consecutive filtered increments. */
static inline void isr_filter_speed(const imest_t *s, imest_chan_t *c, imest_real_t w_raw, imest_real_t *w,
                                    imest_real_t *dw)
{
  const imest_real_t wf = isr_bw3(&s->bw, c, w_raw);
  *w = RL(0.5) * (wf + c->y1);
  *dw = (wf - c->y1) * s->fs;
  c->y1 = wf;
}

/* Digital model of a 2nd-order analog anti-alias filter (transposed DF-II). */
static inline imest_real_t isr_aa(const imest_sos_t *f, imest_real_t *s1, imest_real_t *s2, imest_real_t x)
{
  return isr_lp2(f->c0, f->d1, f->d2, s1, s2, x);
}

#endif
