/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: Hessian and parametric error indices at the selected
 * candidate (docs/METHOD.md §7). Internal: not part of the public API. */
#ifndef IMEST_BG_QUALITY_H
#define IMEST_BG_QUALITY_H

#include "bg_bounds.h"
#include "bg_select.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BG_PE_UNBOUNDED       1e30 /* PE reported when it has no finite meaning (H not PD) */
#define BG_PE_FLAG_K2_LO_EDGE 0x1u /* no crossing below K2*: distance to the band edge reported */
#define BG_PE_FLAG_K2_HI_EDGE 0x2u /* no crossing above K2*: distance to the band edge reported */
#define BG_PE_FLAG_DEGENERATE 0x4u /* E* <= 0: indices are 0 */
#define BG_PE_FLAG_NOT_PD     0x8u /* quadratic indices set to BG_PE_UNBOUNDED */

/* Hessian, positive definiteness, quadratic and exact PE indices at the
 * selected candidate; writes hessian, hessian_pd, pe_k1, pe_k2, pe_quad,
 * pe_flags of out. Returns the number of profile evaluations used. */
unsigned int imest__bg_quality(const bg_tables_t *t, const bg_solve_cfg_t *cfg, const bg_cand_t *best,
                               bg_solve_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_QUALITY_H */
