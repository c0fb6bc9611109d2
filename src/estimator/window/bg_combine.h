/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: consecutive windows combined where one has too little
 * information (docs/METHOD.md §19). Internal: not part of the public API. */
#ifndef IMEST_BG_COMBINE_H
#define IMEST_BG_COMBINE_H

#include "bg_solve.h"

/* Window combination is built in unless the build defines IMEST_WITH_COMBINE=0
 * (CMake: -DIMEST_COMBINE=OFF), for a firmware short of flash: the stage's code
 * is then not linked (fw/README.md gives the saving) and a window that is
 * poorly determined alone stays so (`windows` is always 1). */
#ifndef IMEST_WITH_COMBINE
#define IMEST_WITH_COMBINE 1
#endif

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
