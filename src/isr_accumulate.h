/* ISR stage 4: accumulation of the 36 independent entries of
 * [W e]^T [W e] (upper triangle of an 8x8, row-major: R_W 7x7, R_We, R_ee) and
 * the lock-free hand-off of a finished window.
 *
 * Precision: each entry is summed into a short float32 block; every sample
 * folds ONE entry's block into its window sum (round robin), so each block
 * holds at most 36 products and no sample pays for more than one fold. */
#ifndef IMEST_ISR_ACCUMULATE_H
#define IMEST_ISR_ACCUMULATE_H

#include "isr_real.h"

static inline void isr_accumulate(imest_window_t *w, const imest_real_t zx[8],
                                  const imest_real_t zy[8], uint32_t fold)
{
  imest_real_t *b = w->blk;
  unsigned int p = 0;
  /* fully unrolled by the compiler (constant trip counts) */
  for (unsigned int i = 0; i < 8u; ++i) {
    for (unsigned int j = i; j < 8u; ++j) {
      b[p] += zx[i] * zx[j] + zy[i] * zy[j];
      ++p;
    }
  }
  w->sum[fold] += b[fold];
  b[fold] = RL(0);
}

/* Index of entry (i, j), i <= j, in the packed upper triangle of an 8x8. */
#define IMEST_ACC_INDEX(i, j) ((i) * 8u - ((i) * ((i) - 1u)) / 2u + ((j) - (i)))

#endif
