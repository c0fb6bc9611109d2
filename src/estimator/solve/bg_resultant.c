/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 2 of the background solve: the resultant r_w(kappa) of p1 and p2w with
 * respect to k (docs/METHOD.md §4, eq. 27, with the weighted p2w of bg_tables.h), float64:
 *   r_w = a0^2 bw2 - a0 a1 bw1 + a1^2 bw0 = a0 (a0 bw2 - a1 bw1) + (a1 a1) bw0,
 * five convolutions, about 405 multiply-adds (the three-term form takes 545).
 * With cw = 0, r_w = kappa r: r_w[0] = 0 exactly and r_w[k+1] = r[k] up to
 * round-off (the paper's degree-18 r, one trailing zero). */
#include "bg_resultant.h"

/* out[0..nout-1] (+)= conv(a[0..na-1], b[0..nb-1]) (nout <= na + nb - 1: the
 * terms of higher degree are not formed), negated if neg (an exact sign
 * flip, not a soft-double multiplication by -1) */
static void conv_acc(const double *a, int na, const double *b, int nb, double *out, int nout, int clear,
                     int neg)
{
  if (clear)
    for (int k = 0; k < nout; ++k) out[k] = 0.0;
  for (int i = 0; i < na; ++i) {
    const double ai = neg ? -a[i] : a[i];
    const int nj = (nb < nout - i) ? nb : nout - i;
    for (int j = 0; j < nj; ++j) out[i + j] += ai * b[j];
  }
}

void imest__bg_resultant(const bg_tables_t *t, double r[22], int generic)
{
  double u[15];  /* a0 bw2 - a1 bw1 */
  double sq[13]; /* a1 a1 */
  conv_acc(t->a0, 8, t->bw2, 8, u, 15, 1, 0);
  conv_acc(t->a1, 7, t->bw1, 9, u, 15, 0, 1);
  /* a1 a1, symmetric: diagonal plus twice each off-diagonal product */
  for (int k = 0; k < 13; ++k) sq[k] = 0.0;
  for (int i = 0; i < 7; ++i) {
    // NOLINTNEXTLINE(bugprone-implicit-widening-of-multiplication-result): i < 7, 2 * i cannot overflow
    sq[2 * i] += t->a1[i] * t->a1[i];
    const double ai2 = 2.0 * t->a1[i];
    for (int j = i + 1; j < 7; ++j) sq[i + j] += ai2 * t->a1[j];
  }
  /* W.3 = -m W.4 makes r[20], r[21] vanish identically (for any cw); in
   * floating point they are round-off that would create spurious roots near
   * 1e9..1e16 (docs/METHOD.md §4): not formed unless generic. */
  const int nr = generic ? 22 : 20;
  conv_acc(t->a0, 8, u, 15, r, nr, 1, 0);
  conv_acc(sq, 13, t->bw0, 10, r, nr, 0, 0);
  for (int k = nr; k < 22; ++k) r[k] = 0.0;
}
