/* Internal interface of the background-solve stages (docs/METHOD.md §3..§7), one
 * function group per source file, so that tests can call each stage alone.
 * Not part of the public API. No stage allocates, none keeps state. */
#ifndef IMEST_BG_POLY_H
#define IMEST_BG_POLY_H

#include "bg_solve.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Helpers called from several places are kept out of line: at -O2 GCC
 * inlines them into every caller, which costs flash (the ISR flags must stay
 * -O2, so the background code says it here). */
#if defined(__GNUC__)
#define IMEST_NOINLINE __attribute__((noinline))
#else
#define IMEST_NOINLINE
#endif

/* Largest polynomial degree the root finder accepts (generic resultant: 20). */
#define IMEST_POLY_MAXDEG 20

/* ---------------------------------------------------------------- bg_tables.c
 * Power-of-two scalings (docs/METHOD.md §5) and the scaled cost tables (§3) and
 * p1/p2 coefficients (§4), all float64, in the scaled unknowns (k, kappa):
 * K1 = g k, K2 = s kappa, E = c E~.
 * Weighted cost (cfg.weight_c = c_w, scaled cw = c_w/s^2, D = kappa^2 + cw):
 * E_w~ = P/D^2 with P = sum_m (e2[m] k^2 + e1[m] k + e0[m]) kappa^m
 * (E_p^2~ = P/kappa^4). dE_w/dk = 0 <=> p1 = a1 k + a0 = 0 (as the paper);
 * dE_w/dkappa = 0 <=> p2w = D P' - 4 kappa P = bw2 k^2 + bw1 k + bw0 = 0 with
 * bw_t(kappa) = kappa b_t(kappa) + cw t'(kappa), b_t[m] = (m-4) t[m] the
 * paper's. With cw = 0, p2w = kappa p2 exactly (bw_t[m+1] = b_t[m], bw_t[0] = 0). */
typedef struct {
  int sexp, gexp, cexp;       /* s = 2^sexp, g = 2^gexp, c = 2^cexp */
  double s, g, c;
  double cw;                  /* weight c_w / s^2 (0: the paper's cost) */
  double e2[7], e1[8], e0[9]; /* E~ = kappa^-4 sum_m (e2[m] k^2 + e1[m] k + e0[m]) kappa^m */
  double a1[7], a0[8];        /* p1 = a1(kappa) k + a0(kappa) */
  double bw2[8], bw1[9], bw0[10]; /* p2w = bw2 k^2 + bw1 k + bw0 */
} imest_tables_t;

/* Exact power-of-two and IEEE-754 helpers (no libm: ldexp/frexp/isfinite cost
 * ~70 instructions per call on a soft-double core). */
double imest_pow2(int e);           /* 2^e, e clamped to [-1022, 1023] */
int imest_finite(double x);         /* isfinite by the exponent bits */
/* round(log2(x)) for finite x > 0, exact (mantissa compared with sqrt 2). */
int imest_round_log2(double x);

/* Tables for given exponents (no data-driven choice): R~ = D R D / c with
 * D = diag(g, s, s^2, g s, 1/s, g/s, g/s^2, 1/s^2), each entry scaled by one
 * power-of-two multiplication (exact unless it under/overflows). cw is set
 * from weight_c (c_w / s^2). Also fills a*, bw*. */
void imest_tables_scaled(const imest_sums_t *in, int sexp, int gexp, int cexp, imest_tables_t *t);
void imest_tables_weight(imest_tables_t *t, double weight_c); /* sets cw, refills bw* */

/* Choose s from tr_nominal_s, c from R_y and g from the data (docs/METHOD.md §5) and
 * build the tables (cw = 0; call imest_tables_weight for c_w > 0). Returns
 * IMEST_OK, or IMEST_REASON_NUMERIC for non-finite sums, R_y <= 0 or non-finite
 * tables. */
int imest_tables_build(const imest_sums_t *in, double tr_nominal_s, imest_tables_t *t);

/* Values of e2(kappa), e1(kappa), e0(kappa) (polynomials in kappa) and their
 * first and second kappa-derivatives. */
typedef struct {
  double e2, e1, e0;
  double d2, d1, d0;    /* first derivatives */
  double dd2, dd1, dd0; /* second derivatives */
} imest_tabval_t;
void imest_tables_eval(const imest_tables_t *t, double kappa, imest_tabval_t *v);
/* Values only: v[0] = e2, v[1] = e1, v[2] = e0 at kappa. */
void imest_tables_values(const imest_tables_t *t, double kappa, double v[3]);

/* ------------------------------------------------------------- bg_resultant.c
 * r_w = a0^2 bw2 - a0 a1 bw1 + a1^2 bw0, 22 coefficients ascending (docs/METHOD.md §4
 * with the weighted p2w): with cw = 0, r_w = kappa r (r the paper's).
 * generic = 0: this regressor: degree 19, r_w[20] = r_w[21] = 0 are set (they
 *   vanish identically because W.3 = -m W.4, for any cw; r_w[19] = r[18]).
 * generic = 1: keep all 22 coefficients (degree 21, arbitrary symmetric R_W). */
#define IMEST_RES_DEG 19
void imest_resultant(const imest_tables_t *t, double r[22], int generic);

/* ----------------------------------------------------------------- bg_roots.c
 * All distinct positive roots of sum_k c[k] x^k (deg <= IMEST_POLY_MAXDEG) by
 * Sturm sequences and bisection, (0,1] on p and (1,inf) on the reversed
 * polynomial in four scaled domains, each root polished in float64 (see
 * bg_roots.c for the design).
 * The Sturm chain is float32 unless IMEST_ROOTS_DOUBLE is defined.
 * Returns the number of roots written to roots[] (ascending, at most max), or
 * -1 for a non-finite or all-zero polynomial or a bad deg. */
typedef struct {
  unsigned int sturm_evals;   /* evaluations of the sign-change count V(x) */
  unsigned int bisect_steps;  /* sign or count bisection steps (chain precision) */
  unsigned int polish_evals;  /* float64 polynomial evaluations in the polish */
  unsigned int chain_len;     /* longest Sturm chain built (number of polynomials) */
  unsigned int unresolved;    /* clusters that could not be separated (reported once) */
  unsigned int rejected;      /* isolated intervals whose float64 check failed */
  unsigned int merged;        /* duplicates merged (a root found from both sides of 1) */
  unsigned int rescues;       /* domains where the float64 parity check triggered the grid rescue */
  double max_chain_rel;       /* largest |polished - chain-precision estimate| / root, in the
                                 domain variable: what the chain precision alone would give */
} imest_roots_stats_t;

/* Bounds (per polynomial domain; IMEST_ROOTS_DOMAINS domains per call). */
#define IMEST_ROOTS_MAX_DEPTH 48   /* isolation: interval halvings from (0,1] */
#define IMEST_ROOTS_MAX_BISECT 48  /* refinement bisections in chain precision */
#define IMEST_ROOTS_MAX_POLISH 40  /* safeguarded Newton/bisection steps in float64 */
#define IMEST_ROOTS_MAX_EXPAND 8   /* bracket expansions when float64 sees no sign change */
#define IMEST_ROOTS_MAX_SPLITS 1024 /* isolation halvings per domain */
#define IMEST_ROOTS_DOMAINS 4u    /* kappa in (0,1], (1,16], (16,256], (256,inf) */
/* Hard bounds per call (4 domains, <= 20 roots each), asserted by the tests. */
#define IMEST_ROOTS_BOUND_STURM (IMEST_ROOTS_DOMAINS * (2u + IMEST_ROOTS_MAX_SPLITS + IMEST_POLY_MAXDEG * IMEST_ROOTS_MAX_BISECT))
#define IMEST_ROOTS_BOUND_BISECT (IMEST_ROOTS_DOMAINS * IMEST_POLY_MAXDEG * IMEST_ROOTS_MAX_BISECT)
#define IMEST_ROOTS_BOUND_POLISH                                                                      \
  (IMEST_ROOTS_DOMAINS * (IMEST_POLY_MAXDEG * (2u * (2u + 2u * IMEST_ROOTS_MAX_EXPAND + IMEST_ROOTS_MAX_POLISH) + 1u) + \
                          20u + 18u * IMEST_ROOTS_MAX_POLISH))

int imest_poly_positive_roots(const double *c, int deg, double *roots, int max);
int imest_poly_positive_roots_ex(const double *c, int deg, double *roots, int max,
                                 imest_roots_stats_t *st);

/* Horner evaluation of sum_k c[k] x^k (float64). */
double imest_poly_eval(const double *c, int deg, double x);

/* ---------------------------------------------------------------- bg_select.c */
typedef struct {
  double kappa, k;   /* scaled root and back-substituted k = -a0/a1 */
  double k1, k2;     /* K1 = g k, K2 = s kappa */
  double e;          /* the paper's E_p^2 (unscaled; centred form if the sums have it) */
  double ew;         /* the minimised cost E_w = E_p^2 kappa^4 / (kappa^2 + cw)^2 (unscaled) */
  double tr_s, rs_ohm;
  int admissible;    /* K1 > 0, T_R in band, all finite, E above -1e-4 R_y */
} imest_cand_t;

/* Evaluate every root as a candidate and pick the admissible one with least
 * E_w (first one on a tie) into *best. cand (may be NULL) receives every
 * candidate. Returns the index of the selected candidate, or -1 if none is
 * admissible. */
int imest_select(const imest_tables_t *t, const double *kappa, int n, const imest_solve_cfg_t *cfg,
                 const imest_sums_t *in, imest_cand_t *best, imest_cand_t *cand, unsigned int *n_admissible);

/* E_p^2(K1, K2) from the centred sums (in->centred must be set). */
double imest_e_centred(const imest_sums_t *in, double k1, double k2);

/* --------------------------------------------------------------- bg_quality.c */
#define IMEST_PE_UNBOUNDED 1e30 /* PE reported when it has no finite meaning (H not PD) */
#define IMEST_PE_FLAG_K2_LO_EDGE 0x1u /* no crossing below K2*: distance to the band edge reported */
#define IMEST_PE_FLAG_K2_HI_EDGE 0x2u /* no crossing above K2*: distance to the band edge reported */
#define IMEST_PE_FLAG_DEGENERATE 0x4u /* E* <= 0: indices are 0 */
#define IMEST_PE_FLAG_NOT_PD     0x8u /* quadratic indices set to IMEST_PE_UNBOUNDED */

#define IMEST_PE_MAX_PROBE 80  /* step-out probes per side */
#define IMEST_PE_MAX_ROOT 40   /* Illinois iterations per crossing */
#define IMEST_PE_MAX_MIN 40    /* parabolic/outward steps per K1 extreme (after 3 start points) */
#define IMEST_QUALITY_BOUND (2u * (IMEST_PE_MAX_PROBE + IMEST_PE_MAX_ROOT) + 2u * (3u + IMEST_PE_MAX_MIN))
#define IMEST_SOLVE_WORK_BOUND \
  (IMEST_ROOTS_BOUND_STURM + IMEST_ROOTS_BOUND_BISECT + IMEST_ROOTS_BOUND_POLISH + IMEST_QUALITY_BOUND)

/* Hessian, positive definiteness, quadratic and exact PE indices at the
 * selected candidate; writes hessian, hessian_pd, pe_k1, pe_k2, pe_quad,
 * pe_flags of out. Returns the number of profile evaluations used. */
unsigned int imest_quality(const imest_tables_t *t, const imest_solve_cfg_t *cfg,
                           const imest_cand_t *best, imest_solve_out_t *out);

/* ----------------------------------------------------------------- bg_solve.c */
typedef struct {
  imest_roots_stats_t roots;
  unsigned int quality_evals;
} imest_solve_stats_t;

/* imest_solve with optional instrumentation (stats may be NULL). */
int imest_solve_ex(const imest_sums_t *in, const imest_solve_cfg_t *cfg, imest_solve_out_t *out,
                   imest_solve_stats_t *stats);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_BG_POLY_H */
