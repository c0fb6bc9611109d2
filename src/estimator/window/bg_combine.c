/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: consecutive windows combined where one window has too
 * little information (partial load, low speed: the parametric error index
 * above its bound while nothing else is wrong). The noise-compensated sums of
 * consecutive steady windows are added (least squares over the longer span);
 * the combination keeps the upper triangle of the 8x8 K-form R_W, R_Wy, R_y
 * and, while every window was centred on the same c0, the centred form too
 * (E without cancellation). float64: the sums' precision. */
#include "bg_combine.h"

static unsigned int tri(unsigned int i, unsigned int j)
{
  return i * 8u - (i * (i - 1u)) / 2u + (j - i);
}

void imest__bg_combine_add(imest_combo_t *c, const bg_sums_t *sm, double e_c0, double ry_raw,
                           uint32_t samples)
{
  const int first = c->n == 0u;
  int same_c0 = 1;
  for (unsigned int i = 0; i < 8u; ++i) same_c0 &= first || c->c0[i] == (float)sm->c0[i];
  for (unsigned int i = 0; i < 8u; ++i) {
    for (unsigned int j = i; j < 8u; ++j) c->rw[tri(i, j)] = (first ? 0.0 : c->rw[tri(i, j)]) + sm->rw[i][j];
    c->rwy[i] = (first ? 0.0 : c->rwy[i]) + sm->rwy[i];
    c->rwe[i] = (first ? 0.0 : c->rwe[i]) + sm->rwe[i];
    c->c0[i] = (float)sm->c0[i];
  }
  c->ry = (first ? 0.0 : c->ry) + sm->ry;
  c->ree = (first ? 0.0 : c->ree) + sm->ree;
  c->e_c0 = (first ? 0.0 : c->e_c0) + e_c0;
  c->ry_raw = (first ? 0.0 : c->ry_raw) + ry_raw;
  c->samples = (first ? 0u : c->samples) + samples;
  c->centred = (first || c->centred) && sm->centred && same_c0;
  c->n = (first ? 0u : c->n) + 1u;
}

void imest__bg_combine_sums(const imest_combo_t *c, double m, bg_sums_t *out)
{
  for (unsigned int i = 0; i < 8u; ++i) {
    for (unsigned int j = i; j < 8u; ++j) out->rw[i][j] = out->rw[j][i] = c->rw[tri(i, j)];
    out->rwy[i] = c->rwy[i];
    out->rwe[i] = c->rwe[i];
    out->c0[i] = (double)c->c0[i];
  }
  /* column 3 is -m column 4 in every window, so in the sum */
  for (unsigned int j = 0; j < 8u; ++j) out->rw[2][j] = out->rw[j][2] = -m * out->rw[3][j];
  out->rw[2][2] = m * m * out->rw[3][3];
  out->ry = c->ry;
  out->ree = c->ree;
  out->centred = (int)c->centred;
  out->e_slack = c->e_c0;
}
