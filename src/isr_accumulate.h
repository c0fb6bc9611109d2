/* ISR stage 4: accumulation of the 36 independent entries of
 * [W e]^T [W e] (upper triangle of an 8x8, row-major: R_W 7x7, R_We, R_ee) and
 * the rotation of the rotor-frame current i x di/dt (entry 36). The hand-off
 * itself is in isr_sample.c.
 *
 * Precision: each entry is summed into a short float32 block; every sample
 * folds ONE entry's block into its window sum (round robin), so each block
 * holds at most 37 products and no sample pays for more than one fold. */
#ifndef IMEST_ISR_ACCUMULATE_H
#define IMEST_ISR_ACCUMULATE_H

#include "isr_real.h"

static inline void isr_accumulate(imest_window_t *w, const imest_real_t zx[8], const imest_real_t zy[8],
                                  imest_real_t cross, uint32_t fold)
{
  imest_real_t *b = w->blk;
  /* Written out (no loop): a compiler need not unroll a triangular loop, and
   * on a Cortex-M4 the loop overhead alone would cost ~250 cycles. Two
   * separate multiply-adds per entry: one fused instruction each. */
  /* one line per row of the triangle */
  // clang-format off
#define ACC(p, i, j) b[p] = (b[p] + zx[i] * zx[j]) + zy[i] * zy[j]
  ACC(0, 0, 0); ACC(1, 0, 1); ACC(2, 0, 2); ACC(3, 0, 3); ACC(4, 0, 4); ACC(5, 0, 5); ACC(6, 0, 6); ACC(7, 0, 7);
  ACC(8, 1, 1); ACC(9, 1, 2); ACC(10, 1, 3); ACC(11, 1, 4); ACC(12, 1, 5); ACC(13, 1, 6); ACC(14, 1, 7);
  ACC(15, 2, 2); ACC(16, 2, 3); ACC(17, 2, 4); ACC(18, 2, 5); ACC(19, 2, 6); ACC(20, 2, 7);
  ACC(21, 3, 3); ACC(22, 3, 4); ACC(23, 3, 5); ACC(24, 3, 6); ACC(25, 3, 7);
  ACC(26, 4, 4); ACC(27, 4, 5); ACC(28, 4, 6); ACC(29, 4, 7);
  ACC(30, 5, 5); ACC(31, 5, 6); ACC(32, 5, 7);
  ACC(33, 6, 6); ACC(34, 6, 7);
  ACC(35, 7, 7);
#undef ACC
  // clang-format on
  b[36] += cross;
  w->sum[fold] += b[fold];
  b[fold] = RL(0);
}

/* Index of entry (i, j), i <= j, in the packed upper triangle of an 8x8. */
#define IMEST_ACC_INDEX(i, j) ((i)*8u - ((i) * ((i)-1u)) / 2u + ((j) - (i)))

#endif
