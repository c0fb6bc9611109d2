/* SPDX-License-Identifier: Apache-2.0 */
/* ISR stage 3: regressor W (2x7: columns 1,2,4,5,6,7,8 of docs/METHOD.md §2) and the
 * centred output e = y - W c0. Column 3 is not formed: W_3 = -m W_4 exactly,
 * so the background rebuilds it. */
#ifndef IMEST_ISR_REGRESSOR_H
#define IMEST_ISR_REGRESSOR_H

#include "isr_filter.h"

/* Rotor-frame signals at one instant (all referred to sample n-1). */
typedef struct {
  isr_deriv_t ix, iy, ux, uy;
  imest_real_t w, dw; /* mechanical speed and acceleration */
} isr_signals_t;

/* z[r][0..6] = W row r, z[r][7] = e row r. */
static inline void isr_regressor(const imest_t *s, const isr_signals_t *g, const imest_real_t c0[7],
                                 imest_real_t zx[8], imest_real_t zy[8])
{
  const imest_real_t ix = g->ix.x, iy = g->iy.x, dix = g->ix.dx, diy = g->iy.dx;
  const imest_real_t d2ix = g->ix.d2x, d2iy = g->iy.d2x;
  const imest_real_t vx = g->ux.x * s->inv_s, vy = g->uy.x * s->inv_s; /* u / (sigma L_S) */
  const imest_real_t dvx = g->ux.dx * s->inv_s, dvy = g->uy.dx * s->inv_s;
  const imest_real_t nw = s->n * g->w, nwp = s->n * g->dw;
  const imest_real_t nw2 = nw * nw, nw3 = nw2 * nw, nwnwp = nw * nwp;
  const imest_real_t m = s->m, m1 = RL(1) + s->m;

  /* W1 */
  zx[0] = -dix;
  zy[0] = -diy;
  /* W2 */
  zx[1] = -dix + m1 * nw * iy + vx;
  zy[1] = -diy - m1 * nw * ix + vy;
  /* W4 */
  zx[2] = -ix;
  zy[2] = -iy;
  /* W7 (needed inside W5) */
  const imest_real_t w7x = nwnwp * ix - nw2 * dix;
  const imest_real_t w7y = nwnwp * iy - nw2 * diy;
  /* W5 */
  zx[3] = nwp * (diy - vy) + w7x + nw2 * vx + m1 * nw3 * iy;
  zy[3] = -nwp * (dix - vx) + w7y + nw2 * vy - m1 * nw3 * ix;
  /* W6 */
  zx[4] = nwp * iy - nw2 * ix;
  zy[4] = -nwp * ix - nw2 * iy;
  zx[5] = w7x;
  zy[5] = w7y;
  /* W8 */
  zx[6] = nwnwp * dix - nw2 * d2ix + nw2 * dvx - nwnwp * vx + nw3 * diy;
  zy[6] = nwnwp * diy - nw2 * d2iy + nw2 * dvy - nwnwp * vy - nw3 * dix;
  /* y, then centred: e = y - W c0 (docs/METHOD.md §10: keeps float32 sums accurate) */
  const imest_real_t yx = d2ix - nw * diy - nwp * iy - m * nw2 * ix - dvx;
  const imest_real_t yy = d2iy + nw * dix + nwp * ix - m * nw2 * iy - dvy;
  zx[7] = yx - (zx[0] * c0[0] + zx[1] * c0[1] + zx[2] * c0[2] + zx[3] * c0[3] + zx[4] * c0[4] +
                zx[5] * c0[5] + zx[6] * c0[6]);
  zy[7] = yy - (zy[0] * c0[0] + zy[1] * c0[1] + zy[2] * c0[2] + zy[3] * c0[3] + zy[4] * c0[4] +
                zy[5] * c0[5] + zy[6] * c0[6]);
}

#endif
