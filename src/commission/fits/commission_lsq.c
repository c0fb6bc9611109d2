/* SPDX-License-Identifier: Apache-2.0 */
/* Least squares for the commissioning fits: a small dense symmetric positive definite solve
 * (Cholesky) and the weighted straight line. Background only, float64, fixed loop bounds
 * (n <= CM_LSQ_MAX). */
#include <math.h>
#include <stddef.h>

#include "commission_fit.h"

void imest__cm_line_add(cm_line_t *l, double w, double x, double y)
{
  const double wx = w * x, wy = w * y;
  l->w += w;
  l->x += wx;
  l->y += wy;
  l->xx += wx * x;
  l->xy += wx * y;
  l->yy += wy * y;
}

double imest__cm_line_fit(const cm_line_t *l, double *a)
{
  const double det = l->w * l->xx - l->x * l->x;
  if (!(det > 0.0)) {
    *a = 0.0;
    return l->yy - (l->w > 0.0 ? l->y * l->y / l->w : 0.0);
  }
  *a = (l->w * l->xy - l->x * l->y) / det;
  const double c0 = (l->y - *a * l->x) / l->w;
  return l->yy - c0 * l->y - *a * l->xy;
}

// The textbook Cholesky loops (factor, two substitutions, the inverse's diagonal) stay one function:
// split, the arithmetic would cross calls.
// NOLINTNEXTLINE(readability-function-cognitive-complexity)
int imest__cm_chol_solve(double a[CM_LSQ_MAX][CM_LSQ_MAX], double b[CM_LSQ_MAX], unsigned int n,
                         double dinv[CM_LSQ_MAX])
{
  if (n == 0u || n > CM_LSQ_MAX) return -1;
  /* scale to unit diagonal (the columns of the fits differ by many decades) */
  double sc[CM_LSQ_MAX];
  for (unsigned int i = 0; i < n; ++i) {
    if (!(a[i][i] > 0.0)) return -1;
    sc[i] = 1.0 / BG_SQRT(a[i][i]);
  }
  for (unsigned int i = 0; i < n; ++i) {
    for (unsigned int j = 0; j < n; ++j) a[i][j] *= sc[i] * sc[j];
    b[i] *= sc[i];
  }
  /* a = L L^T, L in the lower triangle */
  for (unsigned int j = 0; j < n; ++j) {
    double d = a[j][j];
    for (unsigned int k = 0; k < j; ++k) d -= a[j][k] * a[j][k];
    if (!(d > 1e-13)) return -1;
    d = BG_SQRT(d);
    a[j][j] = d;
    for (unsigned int i = j + 1u; i < n; ++i) {
      double s = a[i][j];
      for (unsigned int k = 0; k < j; ++k) s -= a[i][k] * a[j][k];
      a[i][j] = s / d;
    }
  }
  /* forward and back substitution */
  for (unsigned int i = 0; i < n; ++i) {
    double s = b[i];
    for (unsigned int k = 0; k < i; ++k) s -= a[i][k] * b[k];
    b[i] = s / a[i][i];
  }
  for (unsigned int ii = n; ii-- > 0u;) {
    double s = b[ii];
    for (unsigned int k = ii + 1u; k < n; ++k) s -= a[k][ii] * b[k];
    b[ii] = s / a[ii][ii];
  }
  for (unsigned int i = 0; i < n; ++i) b[i] *= sc[i];
  if (dinv != NULL) {
    /* diagonal of the inverse: (A^-1)_ii = |L^-1 e_i|^2, column by column */
    for (unsigned int i = 0; i < n; ++i) {
      double y[CM_LSQ_MAX];
      double acc = 0.0;
      for (unsigned int r = 0; r < n; ++r) {
        double s = r == i ? 1.0 : 0.0;
        for (unsigned int k = 0; k < r; ++k) s -= a[r][k] * y[k];
        y[r] = r < i ? 0.0 : s / a[r][r];
        acc += y[r] * y[r];
      }
      dinv[i] = acc * sc[i] * sc[i];
    }
  }
  return 0;
}
