/* Stage 2 of the background solve: the resultant r(kappa) of p1 and p2 with
 * respect to k (MATH.md §4, eq. 27), float64:
 *   r = conv(conv(a0,a0),b2) - conv(conv(a0,a1),b1) + conv(conv(a1,a1),b0).
 * About 3 x (~110 + ~115) multiply-adds. */
#include "bg_poly.h"

/* out[0..na+nb-2] = conv(a[0..na-1], b[0..nb-1]) */
static void conv(const double *a, int na, const double *b, int nb, double *out) {
  for (int k = 0; k < na + nb - 1; ++k) out[k] = 0.0;
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < nb; ++j) out[i + j] += a[i] * b[j];
}

void imest_resultant(const imest_tables_t *t, double r[21], int generic) {
  double sq[15]; /* a0*a0 (15), a0*a1 (14), a1*a1 (13) */
  double term[21];
  for (int k = 0; k < 21; ++k) r[k] = 0.0;

  conv(t->a0, 8, t->a0, 8, sq);
  conv(sq, 15, t->b2, 7, term);
  for (int k = 0; k < 21; ++k) r[k] += term[k];

  conv(t->a0, 8, t->a1, 7, sq);
  conv(sq, 14, t->b1, 8, term);
  for (int k = 0; k < 21; ++k) r[k] -= term[k];

  conv(t->a1, 7, t->a1, 7, sq);
  conv(sq, 13, t->b0, 9, term);
  for (int k = 0; k < 21; ++k) r[k] += term[k];

  if (!generic) {
    /* W.3 = -m W.4 makes these vanish identically; in floating point they are
     * round-off that would create spurious roots near 1e9..1e16 (MATH.md §4). */
    r[19] = 0.0;
    r[20] = 0.0;
  }
}
