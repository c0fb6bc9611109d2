/* SPDX-License-Identifier: Apache-2.0 */
/* ISR stage 4: accumulation of the 36 independent entries of
 * [W e]^T [W e] (upper triangle of an 8x8, row-major: R_W 7x7, R_We, R_ee),
 * then the window's other evidence (IMEST_ACC_*: the rotation of the
 * rotor-frame current, the noise, the current sensors' zero sequence). The
 * hand-off itself is in isr_sample.c.
 *
 * Precision: each entry is summed into a short float32 block; every sample
 * folds ONE entry's block into its window sum (round robin), so each block
 * holds at most IMEST_NACC products and no sample pays for more than one fold. */
#ifndef IMEST_ISR_ACCUMULATE_H
#define IMEST_ISR_ACCUMULATE_H

#include "common/imest_math.h"

/* The entries beyond [W e]'[W e] (include/imest/imest.h, IMEST_ACC_*). */
typedef struct {
  imest_real_t cross;            /* i x di/dt of the rotor-frame current */
  imest_real_t noise_i, noise_u; /* squared third differences of i_alpha, u_alpha */
  imest_real_t i0, ia, ib;       /* zero sequence of the phase currents, alpha/beta current */
  imest_real_t ua;               /* u_alpha */
} isr_extra_t;

/* The accumulation of one regressor sample is split over two ISR calls (the
 * sample's own call, A, and the next, B), so that no call pays for the
 * regressor and all 36 products: the even call of a pair forms the regressor,
 * stores it and sums the first entries; the odd call sums the rest. Only every
 * second sample's regressor is accumulated: the front end's 100 Hz filter makes
 * consecutive samples nearly the same information (its correlation time is
 * several samples at 4 kHz). Written out (no loop): a compiler need not unroll
 * a triangular loop. Two separate multiply-adds per entry: one fused
 * instruction each. The regressor is read into locals first: the sums and the
 * regressor are both float arrays of the instance, so the compiler must assume
 * each store to a sum may change the regressor and reloads both factors of
 * every product (on the Cortex-M4F 3 loads more per entry). */
// clang-format off
#define ACC(p, i, j) b[p] = (b[p] + x##i * x##j) + y##i * y##j
#define ZLOAD(k) const imest_real_t x##k = zx[k], y##k = zy[k]
static inline void isr_accumulate_a(imest_window_t *w, const imest_real_t zx[8], const imest_real_t zy[8],
                                    const isr_extra_t *x)
{
  imest_real_t *b = w->blk;
  ZLOAD(0); ZLOAD(1); ZLOAD(2); ZLOAD(3); ZLOAD(4); ZLOAD(5); ZLOAD(6); ZLOAD(7);
  ACC(0, 0, 0); ACC(1, 0, 1); ACC(2, 0, 2); ACC(3, 0, 3); ACC(4, 0, 4); ACC(5, 0, 5); ACC(6, 0, 6); ACC(7, 0, 7);
  b[IMEST_ACC_ROT] += x->cross;
  b[IMEST_ACC_NOISE_I] += x->noise_i;
  b[IMEST_ACC_NOISE_U] += x->noise_u;
  b[IMEST_ACC_I0A] += x->i0 * x->ia;
  b[IMEST_ACC_I0B] += x->i0 * x->ib;
  b[IMEST_ACC_UU] += x->ua * x->ua;
}

static inline void isr_accumulate_b(imest_window_t *w, const imest_real_t zx[8], const imest_real_t zy[8])
{
  imest_real_t *b = w->blk;
  ZLOAD(1); ZLOAD(2); ZLOAD(3); ZLOAD(4); ZLOAD(5); ZLOAD(6); ZLOAD(7);
  ACC(8, 1, 1); ACC(9, 1, 2); ACC(10, 1, 3); ACC(11, 1, 4); ACC(12, 1, 5); ACC(13, 1, 6); ACC(14, 1, 7);
  ACC(15, 2, 2); ACC(16, 2, 3); ACC(17, 2, 4); ACC(18, 2, 5); ACC(19, 2, 6); ACC(20, 2, 7);
  ACC(21, 3, 3); ACC(22, 3, 4); ACC(23, 3, 5); ACC(24, 3, 6); ACC(25, 3, 7);
  ACC(26, 4, 4); ACC(27, 4, 5); ACC(28, 4, 6); ACC(29, 4, 7);
  ACC(30, 5, 5); ACC(31, 5, 6); ACC(32, 5, 7);
  ACC(33, 6, 6); ACC(34, 6, 7);
  ACC(35, 7, 7);
  w->nreg++;
}
#undef ACC
#undef ZLOAD
// clang-format on

/* Every call folds one entry's block into its window sum (round robin), so a
 * block holds a bounded number of products and no call pays for more. */
static inline void isr_fold(imest_window_t *w, uint32_t fold)
{
  w->sum[fold] += w->blk[fold];
  w->blk[fold] = RL(0);
}

/* Index of entry (i, j), i <= j, in the packed upper triangle of an 8x8. */
#define IMEST_ACC_INDEX(i, j) ((i)*8u - ((i) * ((i)-1u)) / 2u + ((j) - (i)))

#endif
