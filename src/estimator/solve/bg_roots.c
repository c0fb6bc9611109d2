/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 3 of the background solve: every distinct positive root of a real
 * polynomial of degree <= 20 by Sturm sequences and bisection (docs/METHOD.md §6).
 * No companion matrix, no eigenvalues, no allocation, no static mutable data.
 *
 * Design
 *  - Normalise: strip exact-zero leading and trailing coefficients (a root at 0
 *    is not positive), scale by a power of two so that max|c| is in
 *    [2^-1/2, 2^1/2). All power-of-two scalings are exact (BG_SCALE2: the
 *    exponent field where double is soft), no ldexp/frexp.
 *  - Four domains, each searched on (lo, 1 + 2^-8] so that neighbouring
 *    domains overlap (a root at a domain boundary, where the sign of p is
 *    round-off, lies inside one of them): kappa in (0,1] on p(y); (1,16] on
 *    p(16y) and (16,256] on p(256y), y > 1/16 - 2^-12; (256,inf) on q(z/256),
 *    q(x) = x^n p(1/x) the reversed polynomial. Each domain polynomial is
 *    scaled exactly (powers of two) and renormalised, so the coefficients that
 *    matter in that range of kappa are not lost relative to the others: with
 *    only the split at 1 (docs/METHOD.md §6) the float32 chain missed in-band roots
 *    near kappa = 40 (K2 = 320) of realistic windows. Every evaluation is on
 *    [0, 1.004]: nothing overflows in float32. Roots closer than 2^-36
 *    relative are reported once (a root found from two domains, or two
 *    distinct roots that close). An ill-conditioned multiple root at a domain
 *    boundary can be reported twice, as two float64 roots further apart than
 *    2^-36 (each a root to round-off level).
 *  - Chain precision (sreal_t): float32 by default, float64 with
 *    -DIMEST_ROOTS_DOUBLE. The chain P0 = p, P1 = p', P_{k+1} = -rem(P_{k-1},P_k)
 *    keeps each P_k normalised to max|c| = 1, drops leading coefficients
 *    <= TOL (TOL = 16 eps_f, or 64 eps_d), and stops when max|rem| <=
 *    TOL*len(P_{k-1}) (a gcd: multiple roots; the chain then counts distinct
 *    roots) or at degree 0. V(x) = sign changes of the chain (zeros ignored);
 *    distinct roots in (a,b] = V(a) - V(b).
 *  - Isolation: depth-first halving of the domain while the count is >= 2, at most
 *    BG_ROOTS_MAX_DEPTH halvings deep and BG_ROOTS_MAX_SPLITS halvings per
 *    domain; an interval that cannot be split further (depth, split budget, or
 *    its midpoint not representable) is refined as one root ("unresolved").
 *  - Refinement in chain precision down to a relative width of 2^-20: sign
 *    bisection when p changes sign on the interval, else (even multiplicity, or
 *    float32 sign noise) bisection on the Sturm count; <= BG_ROOTS_MAX_BISECT.
 *  - Polish in float64 on the full (untruncated) polynomial, one method
 *    (polish) for p and, if float64 sees no sign change of p (even
 *    multiplicity), for p' (odd multiplicity there): find a float64 sign
 *    change (values only) on the refined bracket, widening it by 4x up to
 *    BG_ROOTS_MAX_EXPAND times (limited to the isolating interval plus 1/16
 *    of its width), then safeguarded Newton (newton_bracketed: a Newton step
 *    that leaves the bracket becomes a bisection, the bracket is kept at every
 *    step; each step evaluates p and p' only), <= BG_ROOTS_MAX_POLISH
 *    evaluations, until a Newton step is <= 2^-30 |x| (then the error is
 *    ~ |x p''/(2p')| 2^-60 |x|: full double accuracy for simple roots) or the
 *    bracket is 4 ulp wide. A root of p' is kept only if
 *    |p(x)| <= 32 (n+1) eps_d sum|c_k x^k|; otherwise the interval is rejected
 *    (counted in stats.rejected). The widening is needed: the chain's root is
 *    a root of p rounded to float32, which can lie outside its 2^-20 bracket
 *    in float64, and one jump to the whole isolating interval finds the wrong
 *    root or none (for p', whose roots the isolation does not separate).
 *  - Safety net in float64 (parity_rescue): if the odd-multiplicity roots
 *    found in a domain do not match the parity of the float64 sign change of p
 *    over the domain (its end signs from the float32 P0 where a bound makes
 *    them certain: sign_at), p is sampled on a fixed grid (bg_bounds.h) and cells with a
 *    sign change but no root are solved by the same newton_bracketed
 *    (stats.rescues). Every
 *    reported root is a float64 root (sign change or |p| at round-off level):
 *    a chain that lost accuracy can miss roots but never invent one.
 *
 * Bounds, per call: BG_ROOTS_BOUND_STURM V(x) evaluations,
 * BG_ROOTS_BOUND_BISECT chain-precision bisection steps and
 * BG_ROOTS_BOUND_POLISH float64 polish evaluations (bg_bounds.h). The counts
 * of a typical window are printed by imest-bench-solve (test/solve).
 *
 * Typical cost per root: 2 float64 value evaluations at the bracket ends and
 * 2 Newton steps (p, p'), i.e. 6 Horner passes: the float32 bracket of 2^-20
 * puts Newton in its quadratic regime at once.
 *
 * Stack: chain packed triangular (P_k has at most n - k + 1 coefficients):
 * 231 sreal_t (924 B float32, 1848 B float64) + one remainder scratch +
 * isolation stack 50 intervals (0.8 KB) + two coefficient copies (2 x 168 B) +
 * one domain's roots; found roots are merged straight into roots[] (sorted,
 * near-duplicates dropped). About 2.4 KB with the float32 chain.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>

#include "bg_roots.h"

#ifdef BG_ROOTS_DOUBLE
typedef double sreal_t;
#define SR_TOL    (64.0 * DBL_EPSILON)
#define SR_EPS    DBL_EPSILON
#define SR_ABS(x) fabs(x)
#else
typedef float sreal_t;
#define SR_TOL    (16.0f * FLT_EPSILON)
#define SR_EPS    FLT_EPSILON
#define SR_ABS(x) fabsf(x)
#endif

#define NMAX        BG_POLY_MAXDEG
#define REFINE_REL  ((sreal_t)9.5367431640625e-07) /* 2^-20 */
#define NEWTON_STOP 9.313225746154785e-10          /* 2^-30 */
#define DOMAIN_TOP  ((sreal_t)1.00390625)          /* 1 + 2^-8: the domains overlap */
/* Domains in kappa: (0,1] on p, (1,16] on p(16y), (16,256] on p(256y), each
 * y in (1/16 - 2^-12, 1 + 2^-8], and (256, inf) on q(z/256), q the reversed p. */
#define DOMAINS     ((int)BG_ROOTS_DOMAINS)
static const int DOMAIN_EXP[DOMAINS] = {0, 4, 8, 8};
static const int DOMAIN_REV[DOMAINS] = {0, 0, 0, 1};
static const double DOMAIN_LO[DOMAINS] = {0.0, 0.062255859375, 0.062255859375, 0.0};
#define MERGE_REL 1.4551915228366852e-11 /* 2^-36 */

#define CHAIN_CAP (((NMAX) + 1) * ((NMAX) + 2) / 2)
typedef struct {
  sreal_t c[CHAIN_CAP]; /* chain polynomials, ascending coefficients, packed */
  short off[NMAX + 1];  /* P_k starts at c + off[k] (capacity n - k + 1) */
  short deg[NMAX + 1];
  int len;
} chain_t;
#define CH(ch, k) ((ch)->c + (ch)->off[k])

typedef struct {
  sreal_t a, b;
  short va, vb, depth;
} ival_t;

static uint64_t bits_of(double x)
{
  union {
    double d;
    uint64_t u;
  } b;
  b.d = x;
  return b.u;
}

/* |x| as an integer: ordered like fabs(x) for every non-NaN x (a soft-double
 * comparison costs ~25 instructions, this a few). */
static uint64_t mag(double x)
{
  return bits_of(x) & 0x7FFFFFFFFFFFFFFFull;
}

static int sgn_s(sreal_t v)
{
  return (v > 0) - (v < 0);
}
/* (v > 0) - (v < 0), NaN 0, from the bits: two soft-double comparisons less */
BG_NOINLINE static int sgn_d(double v)
{
  const uint64_t a = mag(v);
  if (a == 0u || a > 0x7FF0000000000000ull) return 0;
  return (a == bits_of(v)) ? 1 : -1;
}

static sreal_t horner_s(const sreal_t *c, int n, sreal_t x)
{
  sreal_t p = c[n];
  for (int k = n - 1; k >= 0; --k) p = p * x + c[k];
  return p;
}

double imest__bg_poly_eval(const double *c, int deg, double x)
{
  double p = c[deg];
  for (int k = deg - 1; k >= 0; --k) p = p * x + c[k];
  return p;
}

/* f = p^(order)(x), df = p^(order+1)(x), order 0 (two Horner passes) or 1 (three). */
BG_NOINLINE static void eval_d(const double *c, int n, int order, double x, double *f, double *df)
{
  double p = c[n], p1 = 0.0, p2 = 0.0;
  if (order == 0) {
    for (int k = n - 1; k >= 0; --k) {
      p1 = p1 * x + p;
      p = p * x + c[k];
    }
    *f = p;
    *df = p1;
    return;
  }
  for (int k = n - 1; k >= 0; --k) {
    p2 = p2 * x + 2.0 * p1;
    p1 = p1 * x + p;
    p = p * x + c[k];
  }
  *f = p1;
  *df = p2;
}

/* p^(order)(x) alone (order 0: one Horner pass). */
BG_NOINLINE static double eval_v(const double *c, int n, int order, double x)
{
  if (order == 0) return imest__bg_poly_eval(c, n, x);
  double f, df;
  eval_d(c, n, 1, x, &f, &df);
  return f;
}

BG_NOINLINE static double abs_sum_d(const double *c, int n, double x)
{
  double p = 0.0;
  for (int k = n; k >= 0; --k) p = p * fabs(x) + fabs(c[k]);
  return p;
}

/* Normalise P_k to max|c| = 1 (optionally negated) and drop small leading terms. */
BG_NOINLINE static void chain_normalise(chain_t *ch, int k, sreal_t sign)
{
  sreal_t *c = CH(ch, k);
  int d = ch->deg[k];
  sreal_t mx = 0;
  for (int i = 0; i <= d; ++i)
    if (SR_ABS(c[i]) > mx) mx = SR_ABS(c[i]);
  if (mx > 0) {
    const sreal_t f = sign / mx;
    for (int i = 0; i <= d; ++i) c[i] *= f;
  }
  while (d > 0 && SR_ABS(c[d]) <= SR_TOL) --d;
  ch->deg[k] = (short)d;
}

BG_NOINLINE static void chain_build(chain_t *ch, const double *pd, int n)
{
  for (int k = 0, o = 0; k <= n; ++k) { /* P_k has degree <= n - k */
    ch->off[k] = (short)o;
    o += n - k + 1;
  }
  sreal_t *c0 = CH(ch, 0);
  for (int i = 0; i <= n; ++i) c0[i] = (sreal_t)pd[i];
  ch->deg[0] = (short)n;
  chain_normalise(ch, 0, 1);
  ch->len = 1;
  if (ch->deg[0] == 0) return;
  ch->deg[1] = (short)(ch->deg[0] - 1);
  sreal_t *c1 = CH(ch, 1);
  for (int i = 0; i < ch->deg[0]; ++i) c1[i] = (sreal_t)(i + 1) * c0[i + 1];
  chain_normalise(ch, 1, 1);
  ch->len = 2;
  sreal_t r[NMAX + 1] = {0}; /* remainder scratch (P_len has room for db terms only), zeroed once */
  while (ch->deg[ch->len - 1] > 0 && ch->len <= n) {
    const sreal_t *a = CH(ch, ch->len - 2);
    const sreal_t *b = CH(ch, ch->len - 1);
    const int da = ch->deg[ch->len - 2], db = ch->deg[ch->len - 1];
    for (int i = 0; i <= da; ++i) r[i] = a[i];
    for (int i = da; i >= db; --i) {
      const sreal_t q = r[i] / b[db];
      for (int j = 0; j < db; ++j) r[i - db + j] -= q * b[j];
      r[i] = 0;
    }
    sreal_t mx = 0;
    for (int i = 0; i < db; ++i)
      if (SR_ABS(r[i]) > mx) mx = SR_ABS(r[i]);
    if (!(mx > SR_TOL * (sreal_t)(da + 1))) break; /* gcd reached (or NaN) */
    sreal_t *cr = CH(ch, ch->len);
    for (int i = 0; i < db; ++i) cr[i] = r[i];
    ch->deg[ch->len] = (short)(db - 1);
    chain_normalise(ch, ch->len, -1);
    ++ch->len;
  }
}

static int sign_changes(const chain_t *ch, sreal_t x, bg_roots_stats_t *st)
{
  int v = 0, last = 0;
  ++st->sturm_evals;
  for (int k = 0; k < ch->len; ++k) {
    const int s = sgn_s(horner_s(CH(ch, k), ch->deg[k], x));
    if (s != 0) {
      if (last != 0 && s != last) ++v;
      last = s;
    }
  }
  return v;
}

/* Safeguarded Newton on p^(order) in [a,b], where the signs at a and b differ
 * (fa is the value at a). */
BG_NOINLINE static double newton_bracketed(const double *c, int n, int order, double a, double b, double fa,
                                           bg_roots_stats_t *st)
{
  double x = 0.5 * (a + b);
  int prev_newton = 0;
  for (int it = 0; it < BG_ROOTS_MAX_POLISH; ++it) {
    double f, df;
    eval_d(c, n, order, x, &f, &df);
    ++st->polish_evals;
    if (f == 0.0) return x;
    if (sgn_d(f) == sgn_d(fa))
      a = x;
    else
      b = x;
    const double step = BG_DIV(f, df);
    if (fabs(step) <= 4.0 * DBL_EPSILON * fabs(x)) return x - step; /* converged to ulp level */
    double xn = x - step;
    const int newton = (xn > a && xn < b); /* false for NaN/Inf too */
    if (!newton) xn = 0.5 * (a + b);
    /* two Newton steps in a row: in the convergent regime */
    if (newton && prev_newton && fabs(xn - x) <= NEWTON_STOP * fabs(xn)) return xn;
    prev_newton = newton;
    if (b - a <= 4.0 * DBL_EPSILON * fabs(b)) return xn;
    x = xn;
  }
  return x;
}

/* The polish of one refined bracket [a,b] of an isolating interval [lo,hi],
 * one method for p and, when float64 sees no sign change of p (even
 * multiplicity), for p' (order 1): find a float64 sign change of p^(order) on
 * [a,b] or on a widening of it by 4x per step, each step testing the left
 * side first, within [lo,hi] widened by 1/16 of its width; then
 * newton_bracketed on it. The root of p' is kept only if |p| is at round-off
 * level there. Returns 0 (rejected), 1 (sign change of p: odd multiplicity)
 * or 2 (even). */
// One numeric iteration on shared state: a split would move arithmetic across calls (FMA
// contraction; the results must stay bit-identical).
// NOLINTNEXTLINE(readability-function-cognitive-complexity): see the line above
static int polish(const double *c, int n, double a, double b, double lo, double hi, double *root,
                  bg_roots_stats_t *st)
{
  const double ext = (hi - lo) * 0.0625;
  lo = (lo - ext > 0.0) ? lo - ext : 0.0;
  hi = hi + ext;
  for (int order = 0; order < 2; ++order) {
    double e[2] = {a, b}; /* the bracket */
    double fe[2] = {eval_v(c, n, order, a), eval_v(c, n, order, b)};
    st->polish_evals += 2;
    double w = b - a;
    if (!(w > 0.0)) w = fabs(b) * 1e-6 + DBL_MIN;
    int hit = 0;
    for (int j = 0; !hit && fe[0] != 0.0 && sgn_d(fe[0]) == sgn_d(fe[1]) && j < BG_ROOTS_MAX_EXPAND; ++j) {
      w *= 4.0;
      for (int s = 0; s < 2 && !hit; ++s) { /* s = 0: [e0 - w, e0], s = 1: [e1, e1 + w] */
        const double t = s ? ((e[1] + w < hi) ? e[1] + w : hi) : ((e[0] - w > lo) ? e[0] - w : lo);
        double ft = fe[s];
        if (s ? t > e[1] : t < e[0]) {
          ft = eval_v(c, n, order, t);
          ++st->polish_evals;
        }
        if (sgn_d(ft) != sgn_d(fe[s])) { /* the new bracket is [t, e0] or [e1, t] */
          e[1 - s] = e[s];
          fe[1 - s] = fe[s];
          hit = 1;
        }
        e[s] = t;
        fe[s] = ft;
      }
      if (e[0] <= lo && e[1] >= hi) break;
    }
    double x;
    if (fe[0] == 0.0)
      x = e[0];
    else if (fe[1] == 0.0)
      x = e[1];
    else if (sgn_d(fe[0]) != sgn_d(fe[1]))
      x = newton_bracketed(c, n, order, e[0], e[1], fe[0], st);
    else
      continue; /* no float64 sign change of p^(order) */
    if (order == 0) {
      *root = x;
      return 1;
    }
    const double px = imest__bg_poly_eval(c, n, x);
    ++st->polish_evals;
    if (fabs(px) <= 32.0 * (double)(n + 1) * DBL_EPSILON * abs_sum_d(c, n, x)) {
      *root = x;
      return 2;
    }
    return 0;
  }
  return 0;
}

/* Refine one interval (count >= 1) in chain precision and polish it in float64.
 * Returns 0 (rejected), 1 (float64 sign change: odd multiplicity) or 2 (even). */
// One numeric iteration on shared state: a split would move arithmetic across calls (FMA
// contraction; the results must stay bit-identical).
// NOLINTNEXTLINE(readability-function-cognitive-complexity): see the line above
BG_NOINLINE static int refine(const chain_t *ch, const double *pd, int n, ival_t iv, double *root,
                              bg_roots_stats_t *st)
{
  const double lo = (double)iv.a, hi = (double)iv.b;
  sreal_t a = iv.a, b = iv.b;
  const sreal_t *p0 = CH(ch, 0);
  const int d0 = ch->deg[0];
  sreal_t fa = horner_s(p0, d0, a);
  const sreal_t fb = horner_s(p0, d0, b);
  const int by_sign = sgn_s(fa) * sgn_s(fb) < 0; /* else by the Sturm count */
  int va = iv.va;
  if (!by_sign && fb == 0) a = b; /* exact zero at b in chain precision */
  for (int it = 0; it < BG_ROOTS_MAX_BISECT && (b - a) > REFINE_REL * b; ++it) {
    const sreal_t m = a + (b - a) * (sreal_t)0.5;
    if (!(m > a && m < b)) break;
    ++st->bisect_steps;
    sreal_t fm = 0;
    int vm = 0;
    if (by_sign) {
      fm = horner_s(p0, d0, m);
      if (fm == 0) {
        a = m;
        b = m;
        break;
      }
    } else {
      vm = sign_changes(ch, m, st);
    }
    if (by_sign ? sgn_s(fm) != sgn_s(fa) : va - vm >= 1) {
      b = m;
    } else {
      a = m;
      fa = fm;
      va = vm;
    }
  }
  const int kind = polish(pd, n, (double)a, (double)b, lo, hi, root, st);
  if (kind == 0) return 0;
  const double est = 0.5 * ((double)a + (double)b);
  const double dev = fabs(*root - est), ar = fabs(*root);
  if (dev > st->max_chain_rel * ar) st->max_chain_rel = dev / ar; /* a division only when it grows */
  return kind;
}

/* The sign of the float64 Horner value of pd at x (x = a domain end, exact
 * in chain precision), as +-1 or 0: from the chain's copy P0 = f pd (f > 0,
 * all n + 1 coefficients, each rounded twice) where that is certain, else by
 * the float64 evaluation. Certain: |P0(x)| in chain precision exceeds
 * (4n + 8) u S, S = sum |P0_k| x^k, u the unit round-off, i.e. twice the
 * rounding of P0's coefficients and of its Horner evaluation ((2n + 2) u S) plus
 * the float64 evaluation's; SR_TINY covers underflow. Far from a root (the
 * domain ends, as a rule) one chain-precision pass instead of a float64 one. */
#define SR_TINY ((sreal_t)1.925929944387236e-34) /* 2^-112: 2^14 underflows of 2^-126 */
BG_NOINLINE static int sign_at(const chain_t *ch, const double *pd, int n, double x)
{
#if BG_SOFT_DOUBLE
  const sreal_t *c = CH(ch, 0), xs = (sreal_t)x;
  sreal_t h = 0, a = 0;
  for (int k = n; k >= 0; --k) {
    h = h * xs + c[k];
    a = a * xs + SR_ABS(c[k]);
  }
  if (SR_ABS(h) > (sreal_t)(4 * n + 8) * (SR_EPS * (sreal_t)0.5) * a + SR_TINY) return sgn_s(h);
#else
  (void)ch;
#endif
  return sgn_d(imest__bg_poly_eval(pd, n, x));
}

/* float64 safety net for a chain that lost accuracy: the number of odd-
 * multiplicity roots in (0, TOP] must have the parity of the sign change of p
 * between 0+ and TOP. If not, p is sampled in float64 at a fixed grid
 * (0, 2^-16 .. 2^-1, 0.75, TOP: BG_ROOTS_RESCUE_CELLS cells) and every grid cell with a sign
 * change and no root yet is solved by newton_bracketed. Only signs of p are
 * used (newton_bracketed takes the sign of fa). */
BG_NOINLINE static int parity_rescue(const chain_t *ch, const double *pd, int n, double ylo, double *out,
                                     int *odd, int nout, bg_roots_stats_t *st)
{
  const double top = (double)DOMAIN_TOP;
  const int stop = sign_at(ch, pd, n, top);
  int slo = sgn_d(pd[0]);
  if (ylo > 0.0) {
    slo = sign_at(ch, pd, n, ylo);
    ++st->polish_evals;
  }
  ++st->polish_evals;
  int nodd = 0;
  for (int i = 0; i < nout; ++i) nodd += odd[i];
  if (stop == 0 || slo == 0 || ((slo != stop) == ((nodd & 1) == 1))) return nout;
  ++st->rescues;
  double glo = ylo;
  for (int k = 1; k <= (int)BG_ROOTS_RESCUE_CELLS; ++k) {
    const int p2 = (int)BG_ROOTS_RESCUE_POW2_CELLS;
    const double ghi = (k <= p2) ? imest__bg_pow2(k - p2 - 1) : (k == p2 + 1) ? 0.75 : top;
    if (ghi <= glo) continue;
    const int shi = sgn_d(imest__bg_poly_eval(pd, n, ghi));
    ++st->polish_evals;
    if (slo * shi < 0) {
      int inside = 0;
      for (int i = 0; i < nout; ++i) inside += (out[i] > glo && out[i] <= ghi);
      if (inside == 0 && nout < NMAX) {
        out[nout] = newton_bracketed(pd, n, 0, glo, ghi, (double)slo, st);
        odd[nout++] = 1;
      }
    }
    glo = ghi;
    slo = shi;
  }
  return nout;
}

/* Roots of pd (float64, normalised, degree n >= 1, pd[0] != 0) in (ylo, 1 + 2^-8]. */
static int domain_roots(chain_t *ch, const double *pd, int n, double ylo, double *out, bg_roots_stats_t *st)
{
  ival_t stack[BG_ROOTS_MAX_DEPTH + 2];
  int odd[NMAX];
  int top = 0, nout = 0, splits = 0;
  chain_build(ch, pd, n);
  if ((unsigned int)ch->len > st->chain_len) st->chain_len = (unsigned int)ch->len;
  if (ch->deg[0] == 0) return 0;
  stack[top].a = (sreal_t)ylo;
  stack[top].b = DOMAIN_TOP;
  stack[top].va = (short)sign_changes(ch, (sreal_t)ylo, st);
  stack[top].vb = (short)sign_changes(ch, DOMAIN_TOP, st);
  stack[top].depth = 0;
  ++top;
  while (top > 0) {
    const ival_t *ivp = &stack[--top];
    const ival_t iv = *ivp;
    const int cnt = iv.va - iv.vb;
    if (cnt <= 0) continue;
    if (cnt >= 2) {
      const sreal_t m = iv.a + (iv.b - iv.a) * (sreal_t)0.5;
      if (iv.depth < BG_ROOTS_MAX_DEPTH && splits < BG_ROOTS_MAX_SPLITS && m > iv.a && m < iv.b &&
          top + 2 <= BG_ROOTS_MAX_DEPTH + 2) {
        const short vm = (short)sign_changes(ch, m, st);
        ++splits;
        /* right half first so that the left half is processed first */
        stack[top].a = m;
        stack[top].b = iv.b;
        stack[top].va = vm;
        stack[top].vb = iv.vb;
        stack[top].depth = (short)(iv.depth + 1);
        ++top;
        stack[top].a = iv.a;
        stack[top].b = m;
        stack[top].va = iv.va;
        stack[top].vb = vm;
        stack[top].depth = (short)(iv.depth + 1);
        ++top;
        continue;
      }
      ++st->unresolved;
    }
    double x;
    const int kind = (nout < NMAX) ? refine(ch, pd, n, iv, &x, st) : 0;
    if (kind != 0) {
      odd[nout] = (kind == 1);
      out[nout++] = x;
    } else {
      ++st->rejected;
    }
  }
  return parity_rescue(ch, pd, n, ylo, out, odd, nout, st);
}

/* Insert x into the ascending roots[0..*nr-1] (at most max), dropping it if a
 * root within MERGE_REL lies next to it; when full, the largest is dropped. */
BG_NOINLINE static void merge_root(double x, double *roots, int *nr, int max, bg_roots_stats_t *st)
{
  if (!(x > 0.0) || !imest__bg_finite(x)) {
    ++st->rejected;
    return;
  }
  int i = *nr;
  while (i > 0 && roots[i - 1] > x) --i; /* roots[i-1] <= x < roots[i] */
  if ((i > 0 && x - roots[i - 1] <= MERGE_REL * x) || (i < *nr && roots[i] - x <= MERGE_REL * roots[i])) {
    ++st->merged;
    return;
  }
  if (i >= max) return;
  const int last = (*nr < max) ? *nr : max - 1;
  for (int k = last; k > i; --k) roots[k] = roots[k - 1];
  roots[i] = x;
  if (*nr < max) ++*nr;
}

// The input checks, the normalisation and the domain loop share their state: a split would move
// arithmetic across calls (FMA contraction; the results must stay bit-identical).
// NOLINTNEXTLINE(readability-function-cognitive-complexity): see the line above
int imest__bg_roots_positive_ex(const double *c, int deg, double *roots, int max, bg_roots_stats_t *st)
{
  bg_roots_stats_t dummy;
  if (st == 0) st = &dummy;
  st->sturm_evals = st->bisect_steps = st->polish_evals = st->chain_len = 0;
  st->unresolved = st->rejected = st->merged = st->rescues = 0;
  st->max_chain_rel = 0.0;
  if (c == 0 || deg < 0 || deg > NMAX || (max > 0 && roots == 0)) return -1;
  int hi = -1, lo = -1, kmx = 0;
  for (int k = 0; k <= deg; ++k) {
    if (!imest__bg_finite(c[k])) return -1;
    if (mag(c[k]) != 0u) {
      if (lo < 0) lo = k;
      hi = k;
      if (mag(c[k]) > mag(c[kmx])) kmx = k;
    }
  }
  if (hi < 0) return -1; /* all zero */
  const int n = hi - lo;
  if (n == 0) return 0;
  double p[NMAX + 1], d[NMAX + 1];
  const int pe = -imest__bg_round_log2(fabs(c[kmx]));
  const double pn = imest__bg_pow2(pe);
  for (int k = 0; k <= n; ++k) p[k] = BG_SCALE2(c[lo + k], pe, pn);

  chain_t ch;
  double xd[NMAX];
  int nr = 0;
  for (int dom = 0; dom < DOMAINS; ++dom) {
    /* domain polynomial: p(2^e y) or q(2^-e z) with q[k] = p[n-k] (the
     * reversed p), exactly scaled by powers of two, renormalised */
    const int ex = DOMAIN_EXP[dom], rev = DOMAIN_REV[dom], es = rev ? -ex : ex;
    const double step = imest__bg_pow2(es);
    double f = 1.0;
    double dmax = 0.0;
    for (int k = 0; k <= n; ++k) {
      d[k] = BG_SCALE2(rev ? p[n - k] : p[k], k * es, f); /* f = 2^(k es), |k es| <= 160: exact */
      f *= step;
      if (mag(d[k]) > mag(dmax)) dmax = d[k];
    }
    const int de = -imest__bg_round_log2(fabs(dmax));
    const double dn = imest__bg_pow2(de);
    for (int k = 0; k <= n; ++k) d[k] = BG_SCALE2(d[k], de, dn);
    const double ylo = DOMAIN_LO[dom];
    const int nd = domain_roots(&ch, d, n, ylo, xd, st);
    const double back = imest__bg_pow2(ex);
    for (int i = 0; i < nd; ++i) merge_root(rev ? BG_DIV(back, xd[i]) : xd[i] * back, roots, &nr, max, st);
  }
  return nr;
}

int imest__bg_roots_positive(const double *c, int deg, double *roots, int max)
{
  return imest__bg_roots_positive_ex(c, deg, roots, max, 0);
}
