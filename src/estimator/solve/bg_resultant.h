/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: the resultant of p1 and p2 (docs/METHOD.md §4).
 * Internal: not part of the public API. */
#ifndef IMEST_BG_RESULTANT_H
#define IMEST_BG_RESULTANT_H

#include "bg_tables.h"

#ifdef __cplusplus
extern "C" {
#endif

/* r_w = a0^2 bw2 - a0 a1 bw1 + a1^2 bw0, 22 coefficients ascending (docs/METHOD.md §4
 * with the weighted p2w): with cw = 0, r_w = kappa r (r the paper's).
 * generic = 0: this regressor: degree 19, r_w[20] = r_w[21] = 0 are set (they
 *   vanish identically because W.3 = -m W.4, for any cw; r_w[19] = r[18]).
 * generic = 1: keep all 22 coefficients (degree 21, arbitrary symmetric R_W). */
#define BG_RES_DEG 19
void imest__bg_resultant(const bg_tables_t *t, double r[22], int generic);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_RESULTANT_H */
