/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: the verdict on one window (docs/METHOD.md §7; README "When
 * is a window valid"). Internal: not part of the public API. */
#ifndef IMEST_BG_VALIDITY_H
#define IMEST_BG_VALIDITY_H

#include "bg_flux.h"
#include "bg_window.h"

/* The deep-bar rotor's share of the bounds (rotor_hf_rr_ratio, docs/METHOD.md §18.1) is built in
 * unless the build defines IMEST_WITH_ROTOR_HF=0 (CMake: -DIMEST_ROTOR_HF=OFF); without it a
 * config with a deep-bar rotor is refused (rotor_hf_rr_ratio) and imest_comm_apply() leaves the
 * rotor as a single cage. */
#ifndef IMEST_WITH_ROTOR_HF
#define IMEST_WITH_ROTOR_HF 1
#endif

/* Fills valid/status and the per-parameter verdicts of r from the window
 * flags, the window's statistics and the solve; fx: the magnetising curve's
 * share of the bounds (bg_flux.h; NULL: none). */
void imest__bg_judge(imest_t *s, const imest_window_t *w, const bg_window_stats_t *st, const bg_sums_t *sm,
                     const bg_solve_out_t *so, const bg_flux_t *fx, int steady, imest_result_t *r);

#endif /* IMEST_BG_VALIDITY_H */
