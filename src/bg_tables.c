/* Stage 1 of the background solve: power-of-two scaling (MATH.md §5), the
 * scaled cost tables e2, e1, e0 (§3) and the p1/p2 coefficients (§4).
 * float64 throughout. Every scaling is a power of two applied with one ldexp
 * per entry, so it is exact (barring under/overflow of garbage input): the
 * scaled tables equal the unscaled ones times powers of two, bit for bit. */
#include <math.h>

#include "bg_poly.h"

/* Exponents of K_i = K1^EXP_E[i] * K2^EXP_F[i] (MATH.md §3). */
static const int EXP_E[8] = {1, 0, 0, 1, 0, 1, 1, 0};
static const int EXP_F[8] = {0, 1, 2, 1, -1, -1, -2, -2};

int imest_round_log2(double x) {
  int e = 0;
  double f = frexp(x, &e); /* x = f 2^e, f in [0.5, 1) */
  /* log2 x = e + log2 f with log2 f in [-1, 0): round up iff f >= 2^-1/2 */
  return (f >= 0.70710678118654752440) ? e : e - 1;
}

static double *table_of(imest_tables_t *t, int order) {
  return (order == 2) ? t->e2 : (order == 1) ? t->e1 : t->e0;
}

static void p_coefficients(imest_tables_t *t) {
  for (int m = 0; m < 7; ++m) {
    t->a1[m] = 2.0 * t->e2[m];
    t->b2[m] = (double)(m - 4) * t->e2[m];
  }
  for (int m = 0; m < 8; ++m) {
    t->a0[m] = t->e1[m];
    t->b1[m] = (double)(m - 4) * t->e1[m];
  }
  for (int m = 0; m < 9; ++m) t->b0[m] = (double)(m - 4) * t->e0[m];
}

void imest_tables_scaled(const imest_sums_t *in, int sexp, int gexp, int cexp, imest_tables_t *t) {
  t->sexp = sexp;
  t->gexp = gexp;
  t->cexp = cexp;
  t->s = ldexp(1.0, sexp);
  t->g = ldexp(1.0, gexp);
  t->c = ldexp(1.0, cexp);
  for (int m = 0; m < 7; ++m) t->e2[m] = 0.0;
  for (int m = 0; m < 8; ++m) t->e1[m] = 0.0;
  for (int m = 0; m < 9; ++m) t->e0[m] = 0.0;

  for (int i = 0; i < 8; ++i) {
    /* diagonal, then each unordered pair once with R_ij + R_ji (= 2 R_ij exactly
     * for symmetric input; the symmetric part otherwise) */
    for (int j = i; j < 8; ++j) {
      const int order = EXP_E[i] + EXP_E[j];
      const int pow_k2 = EXP_F[i] + EXP_F[j];
      const double rij = (i == j) ? in->rw[i][i] : in->rw[i][j] + in->rw[j][i];
      table_of(t, order)[pow_k2 + 4] += ldexp(rij, gexp * order + sexp * pow_k2 - cexp);
    }
    table_of(t, EXP_E[i])[EXP_F[i] + 4] +=
        ldexp(-2.0 * in->rwy[i], gexp * EXP_E[i] + sexp * EXP_F[i] - cexp);
  }
  t->e0[4] += ldexp(in->ry, -cexp);
  p_coefficients(t);
}

static int all_finite(const double *v, int n) {
  for (int i = 0; i < n; ++i)
    if (!isfinite(v[i])) return 0;
  return 1;
}

int imest_tables_build(const imest_sums_t *in, double tr_nominal_s, imest_tables_t *t) {
  if (!all_finite(&in->rw[0][0], 64) || !all_finite(in->rwy, 8) || !isfinite(in->ry) || !(in->ry > 0.0)) {
    imest_tables_scaled(in, 0, 0, 0, t); /* defined content; caller reports NUMERIC */
    return IMEST_ST_NUMERIC;
  }
  /* s = 2^round(log2(1/T_R0)); a bad nominal falls back to 0.1 s (s = 8). */
  const double trn = (isfinite(tr_nominal_s) && tr_nominal_s > 1e-9 && tr_nominal_s < 1e9) ? tr_nominal_s : 0.1;
  const int sexp = imest_round_log2(1.0 / trn);
  const int cexp = imest_round_log2(in->ry);

  /* g from k^ = -sum(e1)/(2 sum(e2)) at kappa = 1 with g = 1. */
  imest_tables_scaled(in, sexp, 0, cexp, t);
  double se1 = 0.0, se2 = 0.0;
  for (int m = 0; m < 7; ++m) se2 += t->e2[m];
  for (int m = 0; m < 8; ++m) se1 += t->e1[m];
  const double khat = -se1 / (2.0 * se2);
  int gexp = 0;
  if (isfinite(khat) && khat != 0.0) {
    gexp = imest_round_log2(fabs(khat));
    if (gexp > 200) gexp = 200;
    if (gexp < -200) gexp = -200;
  }
  if (gexp != 0) imest_tables_scaled(in, sexp, gexp, cexp, t);

  if (!all_finite(t->e2, 7) || !all_finite(t->e1, 8) || !all_finite(t->e0, 9)) return IMEST_ST_NUMERIC;
  return IMEST_OK;
}

void imest_tables_eval(const imest_tables_t *t, double kappa, imest_tabval_t *v) {
  /* Horner with first and second derivatives, one pass per table. */
  const double *tab[3] = {t->e2, t->e1, t->e0};
  static const int len[3] = {7, 8, 9};
  double val[3], d[3], dd[3];
  for (int q = 0; q < 3; ++q) {
    double p = 0.0, p1 = 0.0, p2 = 0.0;
    for (int m = len[q] - 1; m >= 0; --m) {
      p2 = p2 * kappa + 2.0 * p1;
      p1 = p1 * kappa + p;
      p = p * kappa + tab[q][m];
    }
    val[q] = p;
    d[q] = p1;
    dd[q] = p2;
  }
  v->e2 = val[0];
  v->e1 = val[1];
  v->e0 = val[2];
  v->d2 = d[0];
  v->d1 = d[1];
  v->d0 = d[2];
  v->dd2 = dd[0];
  v->dd1 = dd[1];
  v->dd0 = dd[2];
}
