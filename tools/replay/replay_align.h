/* SPDX-License-Identifier: Apache-2.0 */
/* imest-replay's alignment check: the record fitted again with the voltage
 * columns (u_a,u_b,u_c, or d_a,d_b,d_c and v_dc) shifted by one row either way
 * against the currents and the angle, and a note when a shifted alignment
 * fits clearly better (docs/feeding-logs.md, section 3). Nothing is changed:
 * the windows printed are those of the record as given. Host tool code. */
#ifndef IMEST_REPLAY_ALIGN_H
#define IMEST_REPLAY_ALIGN_H

#include "csv_reader.h"
#include "imest/imest.h"
#include "replay_options.h"
#include "replay_scan.h"

/* What the check found: 0 nothing (or it could not tell: see why), -1 the
 * voltage fits better one row earlier (row k with row k-1's voltage), +1 one
 * row later (row k with row k+1's). */
typedef struct {
  int shift;
  int windows;       /* windows compared */
  double spread[3];  /* R_S's weighted standard deviation across the windows [ohm], shifts -1, 0, +1 */
  double rs_mean[3]; /* its weighted mean [ohm] */
  double tr_change;  /* median |T_R(shift) / T_R(as given) - 1| of the better shift */
  double tr_bound;   /* median tr_bound_rel (as given) */
  const char *why;   /* when shift is 0: why not ("" = the alignment as given fits best) */
} replay_align_t;

/* Runs the check (two more passes through the file and the estimator, cfg as
 * configured for the run) and prints a note on stderr when a shift fits
 * clearly better. Returns -1 to go on, or TOOL_EXIT_DATA when the file
 * cannot be read again. */
int replay_align_check(csv_reader_t *r, const replay_opts_t *o, const replay_scan_t *s,
                       const imest_config_t *cfg, replay_align_t *out);

#endif
