/* SPDX-License-Identifier: Apache-2.0 */
/* Background: a speed transient inside a window seen through the angle
 * observer (docs/METHOD.md §13.1). Internal: not part of the public API. */
#ifndef IMEST_BG_TRANSIENT_H
#define IMEST_BG_TRANSIENT_H

#include "bg_impedance.h"
#include "imest/imest.h"

/* t_lag [s]: the angle observer's lag after a speed step (integral of its
 * speed error over the step) at natural frequency fn_hz (0: no observer). */
float imest__bg_transient_lag_s(float fn_hz);

/* The window's change of speed [rad/s, mechanical] while the angle observer
 * was engaged (0 when it was not): its end speed minus its start speed (the
 * previous window's end; twice the end minus the mean when that is not known:
 * the first window, after an overrun). Keeps the end speed for the next
 * window. Call once per window, before s->w_prev_valid is updated. */
float imest__bg_transient_dw(imest_t *s, const imest_window_t *w, double w_mean);

/* What that change can move T_R and R_S by (relative), or 0 and 0 below a
 * tenth of both tolerances (a steady window's bounds stay as they are). z: the
 * window's impedance at the estimate; ws: the slip frequency [rad/s]. */
void imest__bg_transient_share(const imest_t *s, const bg_impedance_t *z, float dw, float ws, float tr,
                               float rs, float *tr_rel, float *rs_rel);

#endif /* IMEST_BG_TRANSIENT_H */
