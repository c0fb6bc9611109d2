/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 1 of the background solve: power-of-two scaling (docs/METHOD.md §5), the
 * scaled cost tables e2, e1, e0 (§3) and the p1/p2w coefficients (§4, with the
 * speed-normalised cost of bg_tables.h). float64 throughout. Every scaling is a
 * multiplication by an exact power of two, so the scaled tables equal the
 * unscaled ones times powers of two, bit for bit (barring under/overflow of
 * garbage input). No libm: ldexp/frexp/isfinite cost ~70 instructions per call
 * on a soft-double core, a bit test a few. */
#include <stdint.h>

#include "bg_tables.h"

/* Exponents of K_i = K1^EXP_E[i] * K2^EXP_F[i] (docs/METHOD.md §3). */
static const int EXP_E[8] = {1, 0, 0, 1, 0, 1, 1, 0};
static const int EXP_F[8] = {0, 1, 2, 1, -1, -1, -2, -2};

static double *table_of(bg_tables_t *t, int order)
{
  return (order == 2) ? t->e2 : (order == 1) ? t->e1 : t->e0;
}

/* bw[j] = (j-5) t[j-1] + cw (j+1) t[j+1], j = 0..len (t has len entries). */
BG_NOINLINE static void weighted_b(const double *tab, int len, double cw, double *bw)
{
  bw[0] = 0.0;
  for (int j = 1; j <= len; ++j) bw[j] = (double)(j - 5) * tab[j - 1];
  if (cw != 0.0) /* one soft-double comparison, not one per entry */
    for (int j = 0; j + 1 < len; ++j) bw[j] += cw * (double)(j + 1) * tab[j + 1];
}

void imest__bg_tables_weight(bg_tables_t *t, double weight_c)
{
  t->cw = weight_c * imest__bg_pow2(-2 * t->sexp);
  weighted_b(t->e2, 7, t->cw, t->bw2);
  weighted_b(t->e1, 8, t->cw, t->bw1);
  weighted_b(t->e0, 9, t->cw, t->bw0);
}

/* a1, a0 and, with the weight c_w (0: the paper's cost), bw* */
BG_NOINLINE static void p_coefficients(bg_tables_t *t, double weight_c)
{
  for (int m = 0; m < 7; ++m) t->a1[m] = BG_SCALE2(t->e2[m], 1, 2.0);
  for (int m = 0; m < 8; ++m) t->a0[m] = t->e1[m];
  imest__bg_tables_weight(t, weight_c);
#if BG_SOFT_DOUBLE
  t->ff_ok = imest__bg_ff_of(t->e2, 7, t->ff) && imest__bg_ff_of(t->e1, 8, t->ff + 7) &&
             imest__bg_ff_of(t->e0, 9, t->ff + 15);
#endif
}

/* a + b; 2 a (exact) without the soft-double addition where a and b are the
 * same number, as in every symmetric R_W the window gives */
static double pair_sum(double a, double b)
{
  union {
    double d;
    uint64_t u;
  } x, y;
  x.d = a;
  y.d = b;
  return (BG_SOFT_DOUBLE && x.u == y.u) ? BG_SCALE2(a, 1, 2.0) : a + b;
}

/* e2 *= g^2, e1 *= g (exact powers of two) */
static void scale_g(bg_tables_t *t, int gexp)
{
  if (gexp == 0) return;
  const double g1 = imest__bg_pow2(gexp), g2 = imest__bg_pow2(2 * gexp);
  for (int m = 0; m < 7; ++m) t->e2[m] = BG_SCALE2(t->e2[m], 2 * gexp, g2);
  for (int m = 0; m < 8; ++m) t->e1[m] = BG_SCALE2(t->e1[m], gexp, g1);
}

/* The tables of imest__bg_tables_scaled without a*, bw*. */
BG_NOINLINE static void tables_fill(const bg_sums_t *in, int sexp, int gexp, int cexp, bg_tables_t *t)
{
  t->sexp = sexp;
  t->gexp = gexp;
  t->cexp = cexp;
  t->s = imest__bg_pow2(sexp);
  t->g = imest__bg_pow2(gexp);
  t->c = imest__bg_pow2(cexp);
  for (int m = 0; m < 7; ++m) t->e2[m] = 0.0;
  for (int m = 0; m < 8; ++m) t->e1[m] = 0.0;
  for (int m = 0; m < 9; ++m) t->e0[m] = 0.0;
  /* every entry of table_q[f + 4] is scaled by 2^(q gexp + f sexp - cexp) */
  double fs[9];
  for (int f = -4; f <= 4; ++f) fs[f + 4] = imest__bg_pow2(sexp * f - cexp);

  for (int i = 0; i < 8; ++i) {
    /* diagonal, then each unordered pair once with R_ij + R_ji (= 2 R_ij exactly
     * for symmetric input; the symmetric part otherwise) */
    for (int j = i; j < 8; ++j) {
      const int order = EXP_E[i] + EXP_E[j];
      const int pow_k2 = EXP_F[i] + EXP_F[j];
      const double rij = (i == j) ? in->rw[i][i] : pair_sum(in->rw[i][j], in->rw[j][i]);
      table_of(t, order)[pow_k2 + 4] += BG_SCALE2(rij, sexp * pow_k2 - cexp, fs[pow_k2 + 4]);
    }
    const int f = EXP_F[i];
    table_of(t, EXP_E[i])[f + 4] += BG_SCALE2(BG_SCALE2(-in->rwy[i], 1, 2.0), sexp * f - cexp, fs[f + 4]);
  }
  t->e0[4] += BG_SCALE2(in->ry, -cexp, fs[4]);
  scale_g(t, gexp);
}

BG_NOINLINE void imest__bg_tables_scaled(const bg_sums_t *in, int sexp, int gexp, int cexp, bg_tables_t *t)
{
  tables_fill(in, sexp, gexp, cexp, t);
  p_coefficients(t, 0.0);
}

static int all_finite(const double *v, int n)
{
  for (int i = 0; i < n; ++i)
    if (!imest__bg_finite(v[i])) return 0;
  return 1;
}

int imest__bg_tables_build(const bg_sums_t *in, double tr_nominal_s, bg_tables_t *t)
{
  return imest__bg_tables_build_weighted(in, tr_nominal_s, 0.0, t);
}

int imest__bg_tables_build_weighted(const bg_sums_t *in, double tr_nominal_s, double weight_c, bg_tables_t *t)
{
  if (!all_finite(&in->rw[0][0], 64) || !all_finite(in->rwy, 8) || !imest__bg_finite(in->ry) ||
      !(in->ry > 0.0)) {
    imest__bg_tables_scaled(in, 0, 0, 0, t); /* defined content; caller reports NUMERIC */
    return IMEST_REASON_NUMERIC;
  }
  /* s = 2^round(log2(1/T_R0)); a bad nominal falls back to 0.1 s (s = 8). */
  const double trn =
      (imest__bg_finite(tr_nominal_s) && tr_nominal_s > 1e-9 && tr_nominal_s < 1e9) ? tr_nominal_s : 0.1;
  const int sx = imest__bg_round_log2(1.0 / trn);
  const int cexp = imest__bg_round_log2(in->ry);

  /* g from k^ = -sum(e1)/(2 sum(e2)) at kappa = 1 with g = 1; the g scaling
   * is then applied to e2 (g^2) and e1 (g) exactly, without a second pass. */
  tables_fill(in, sx, 0, cexp, t);
  double se1 = 0.0, se2 = 0.0;
  for (int m = 0; m < 7; ++m) se2 += t->e2[m];
  for (int m = 0; m < 8; ++m) se1 += t->e1[m];
  const double khat = BG_DIV(-se1, 2.0 * se2);
  int gexp = 0;
  if (imest__bg_finite(khat) && khat != 0.0) {
    gexp = imest__bg_round_log2(khat < 0.0 ? -khat : khat);
    if (gexp > 200) gexp = 200;
    if (gexp < -200) gexp = -200;
  }
  t->gexp = gexp;
  t->g = imest__bg_pow2(gexp);
  scale_g(t, gexp);
  p_coefficients(t, (weight_c > 0.0) ? weight_c : 0.0);

  if (!all_finite(t->e2, 7) || !all_finite(t->e1, 8) || !all_finite(t->e0, 9)) return IMEST_REASON_NUMERIC;
  return IMEST_OK;
}

#if BG_SOFT_DOUBLE
/* Entries within 2^+-32 and 2^-8 <= kappa < 2^8: every term e[m] kappa^m is
 * zero or within 2^+-96, a value below 2^100 (no overflow), and a low part's
 * underflow costs at most 2^-149, 2^-53 of the smallest nonzero term. kappa
 * itself carries 2^-48 (imest__bg_ff_of), so a value is within ~(8 + 3 * 8 +
 * 4) 2^-48 sum |e[m] kappa^m| of exact: a few 1e-13 relative to the terms,
 * where the quality stage's indices need ~1e-6 (bg_quality.c) and the
 * candidates' K1 and E the float32-accumulated sums' ~1e-5 (bg_select.c). */
static int values_ff(const bg_tables_t *t, double kappa, double v[3])
{
  static const int first[4] = {0, 7, 15, 24};
  union {
    double d;
    uint64_t u;
  } b;
  b.d = kappa;
  const int ex = (int)(b.u >> 52) - 1023; /* the sign bit makes a negative kappa fail */
  bg_ff_t x;
  if (t->ff_ok && ex >= -8 && ex <= 7 && imest__bg_ff_of(&kappa, 1, &x)) {
    for (int q = 0; q < 3; ++q) {
      bg_ff_t p = t->ff[first[q + 1] - 1];
      for (int m = first[q + 1] - 2; m >= first[q]; --m) p = imest__bg_ff_madd(t->ff[m], p, x);
      v[q] = bg_ff_to_d(p);
    }
    return 1;
  }
  return 0; /* float64 */
}
#endif

void imest__bg_tables_values(const bg_tables_t *t, double kappa, double v[3])
{
#if BG_SOFT_DOUBLE
  if (values_ff(t, kappa, v)) return;
#endif
  double p2 = t->e2[6], p1 = t->e1[7], p0 = t->e0[8];
  p1 = p1 * kappa + t->e1[6];
  p0 = p0 * kappa + t->e0[7];
  p0 = p0 * kappa + t->e0[6];
  for (int m = 5; m >= 0; --m) {
    p2 = p2 * kappa + t->e2[m];
    p1 = p1 * kappa + t->e1[m];
    p0 = p0 * kappa + t->e0[m];
  }
  v[0] = p2;
  v[1] = p1;
  v[2] = p0;
}

void imest__bg_tables_eval(const bg_tables_t *t, double kappa, bg_tabval_t *v)
{
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
