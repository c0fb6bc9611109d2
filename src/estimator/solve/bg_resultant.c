/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 2 of the background solve: the resultant r_w(kappa) of p1 and p2w with
 * respect to k (docs/METHOD.md §4, eq. 27, with the weighted p2w of bg_tables.h), float64:
 *   r_w = a0^2 bw2 - a0 a1 bw1 + a1^2 bw0 = a0 (a0 bw2 - a1 bw1) + (a1 a1) bw0,
 * five convolutions, about 405 multiply-adds (the three-term form takes 545).
 * With cw = 0, r_w = kappa r: r_w[0] = 0 exactly and r_w[k+1] = r[k] up to
 * round-off (the paper's degree-18 r, one trailing zero). */
#include "bg_resultant.h"
#include "bg_ff.h"

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

#if BG_SOFT_DOUBLE
/* The same convolutions in float-float (bg_ff.h), a1 a1 as a plain one (49
 * products instead of 28, for less code): ~43 instructions per multiply-add,
 * the loop included, against ~110 in soft double. Every coefficient is within ~(3n + 10) 2^-48
 * sum |terms| of exact (n <= 15 terms per convolution; float64's bound is
 * n 2^-53), then rounded once to float64: a few 1e-13 relative to the terms
 * (docs/METHOD.md §10.4). Range: the inputs are zero or within 2^+-32, so a
 * term (three factors, the weights (j-5) and cw included in bw*, a1 = 2 e2)
 * is zero or within [2^-96, 2^98] and a coefficient below 2^107: no
 * overflow, and a low part that underflows loses at most 2^-149, 2^-53 of
 * the smallest nonzero term.
 * 0 where an input is outside that range: float64 then. */
static void conv_ff(const bg_ff_t *a, int na, const bg_ff_t *b, int nb, bg_ff_t *out, int nout, int clear,
                    float sign)
{
  if (clear)
    for (int k = 0; k < nout; ++k) out[k].hi = out[k].lo = 0.0f;
  for (int i = 0; i < na; ++i) {
    bg_ff_t ai = a[i];
    ai.hi *= sign; /* +-1 and 2: exact */
    ai.lo *= sign;
    const int nj = (nb < nout - i) ? nb : nout - i;
    for (int j = 0; j < nj; ++j) out[i + j] = imest__bg_ff_madd(out[i + j], ai, b[j]);
  }
}

BG_NOINLINE static int resultant_ff(const bg_tables_t *t, double r[22], int nr)
{
  bg_ff_t bw[27], u[15], sq[13], rf[22];      /* bw2 at 0, bw1 at 8, bw0 at 17 */
  const bg_ff_t *a0 = t->ff + 7, *e2 = t->ff; /* a0 = e1, a1 = 2 e2 */
  if (!t->ff_ok || !imest__bg_ff_of(t->bw2, 8, bw) || !imest__bg_ff_of(t->bw1, 9, bw + 8) ||
      !imest__bg_ff_of(t->bw0, 10, bw + 17))
    return 0;
  conv_ff(a0, 8, bw, 8, u, 15, 1, 1.0f);
  conv_ff(e2, 7, bw + 8, 9, u, 15, 0, -2.0f);
  conv_ff(e2, 7, e2, 7, sq, 13, 1, 4.0f);
  conv_ff(a0, 8, u, 15, rf, nr, 1, 1.0f);
  conv_ff(sq, 13, bw + 17, 10, rf, nr, 0, 1.0f);
  for (int k = 0; k < nr; ++k) r[k] = bg_ff_to_d(rf[k]);
  return 1;
}
#endif

void imest__bg_resultant(const bg_tables_t *t, double r[22], int generic)
{
  /* W.3 = -m W.4 makes r[20], r[21] vanish identically (for any cw); in
   * floating point they are round-off that would create spurious roots near
   * 1e9..1e16 (docs/METHOD.md §4): not formed unless generic. */
  const int nr = generic ? 22 : 20;
  for (int k = nr; k < 22; ++k) r[k] = 0.0;
#if BG_SOFT_DOUBLE
  if (resultant_ff(t, r, nr)) return;
#endif
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
  conv_acc(t->a0, 8, u, 15, r, nr, 1, 0);
  conv_acc(sq, 13, t->bw0, 10, r, nr, 0, 0);
}
