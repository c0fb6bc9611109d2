/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: consecutive windows combined where one has too little
 * information (docs/METHOD.md §19). Internal: not part of the public API. */
#ifndef IMEST_BG_COMBINE_H
#define IMEST_BG_COMBINE_H

#include "bg_solve.h"

/* At most this many windows are combined (the span grows to this many windows). */
#define BG_COMBINE_MAX 9u

/* Start a combination with one window's (noise-compensated) sums, or add
 * them to it. e_c0: the noise's E at the window's centring; ry_raw: R_y
 * before the compensation; samples: the window's samples. */
void imest__bg_combine_add(imest_combo_t *c, const bg_sums_t *sm, double e_c0, double ry_raw,
                           uint32_t samples);

/* The combined sums in the solve's form (column 3 rebuilt from 4 by -m). */
void imest__bg_combine_sums(const imest_combo_t *c, double m, bg_sums_t *out);

#endif /* IMEST_BG_COMBINE_H */
