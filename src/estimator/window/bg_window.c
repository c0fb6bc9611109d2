/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage 1: take one window's ISR sums to float64 8x8 form.
 * The ISR accumulated Z = [W1 W2 W4 W5 W6 W7 W8 e] with e = y - W c0; here
 * R_Wy = R_We + R_W c0 and R_y = R_ee + 2 c0.R_We + c0' R_W c0 (float64), and
 * row/column 3 = -m x row/column 4 (docs/METHOD.md §2). The centred form (c0, R_We,
 * R_ee) is passed on too, for E without cancellation (bg_select.c). */
#include <math.h>

#include "bg_window.h"
#include "isr_accumulate.h"
#include "estimator/solve/bg_float.h" /* BG_FMAXF...: no libm fmaxf on a core without VMAXNM */

void imest__bg_window_sums(const imest_window_t *w, double m, double fs, bg_sums_t *out,
                           bg_window_stats_t *st)
{
  double z[8][8];
  for (unsigned int i = 0; i < 8u; ++i) {
    for (unsigned int j = i; j < 8u; ++j) {
      const unsigned int p = IMEST_ACC_INDEX(i, j);
      z[i][j] = (double)w->sum[p] + (double)w->blk[p];
      z[j][i] = z[i][j];
    }
  }
  double c0[7];
  for (unsigned int i = 0; i < 7u; ++i) c0[i] = (double)w->c0[i];

  double rwy7[7];
  double ry = z[7][7];
  for (unsigned int i = 0; i < 7u; ++i) {
    double acc = z[i][7];
    for (unsigned int j = 0; j < 7u; ++j) acc += z[i][j] * c0[j];
    rwy7[i] = acc;
    ry += c0[i] * (z[i][7] + acc); /* 2 c0.R_We + c0' R_W c0 = c0.(R_We + R_Wy) */
  }

  for (unsigned int i = 0; i < 7u; ++i) {
    out->rwy[imest__bg_k_of_col[i]] = rwy7[i];
    for (unsigned int j = 0; j < 7u; ++j) out->rw[imest__bg_k_of_col[i]][imest__bg_k_of_col[j]] = z[i][j];
  }
  for (unsigned int j = 0; j < 8u; ++j) {
    out->rw[2][j] = -m * out->rw[3][j];
  }
  for (unsigned int i = 0; i < 8u; ++i) {
    out->rw[i][2] = -m * out->rw[i][3];
  }
  out->rw[2][2] = m * m * out->rw[3][3];
  out->rwy[2] = -m * out->rwy[3];
  out->ry = ry;
  /* centred form (bg_solve.h): E of a candidate without the cancellation of
   * the un-centred R_y, R_Wy (floor ~1e-5 R_y with float32 sums) */
  out->centred = 1;
  out->e_slack = 0.0;
  out->ree = z[7][7];
  for (unsigned int i = 0; i < 7u; ++i) {
    out->c0[imest__bg_k_of_col[i]] = c0[i];
    out->rwe[imest__bg_k_of_col[i]] = z[i][7];
  }
  out->c0[2] = 0.0;
  out->rwe[2] = -m * out->rwe[3];

  /* the sums hold every second used sample (isr_accumulate.h); the angle
   * steps all of them */
  const float n = w->nreg > 0u ? (float)w->nreg : 1.0f;
  const float n_used = w->used > 0u ? (float)w->used : 1.0f;
  const float r44 = (float)out->rw[3][3];
  st->i_rms_a = sqrtf(BG_FMAXF(r44, 0.0f) / n);
  st->w_mean = (float)w->rot * (float)fs / n_used;
  const float cross = (float)(w->sum[IMEST_ACC_ROT] + w->blk[IMEST_ACC_ROT]);
  st->slip_rate = (r44 > 0.0f) ? cross / r44 : 0.0f;
  st->u_ms = (float)(w->sum[IMEST_ACC_UU] + w->blk[IMEST_ACC_UU]) / n;
}

/* Centring vector c0 (7-column form) for a given K1, K2 (docs/METHOD.md §2, §10),
 * in the ISR's type: any c0 is correct (the background undoes it exactly,
 * imest__bg_window_sums), a close one only keeps the ISR's float32 sums
 * small, so a rounding more or less in it changes nothing that matters. */
void imest__bg_centre_from_k(imest_real_t c0[7], imest_real_t k1, imest_real_t k2, imest_real_t m)
{
  const imest_real_t ik = RL(1) / k2;
  c0[0] = k1;
  c0[1] = k2;
  c0[2] = k2 * (k1 - m * k2); /* K4 - m K3 (column 3 folded into 4) */
  c0[3] = ik;
  c0[4] = k1 * ik;
  c0[5] = k1 * ik * ik;
  c0[6] = ik * ik;
}
