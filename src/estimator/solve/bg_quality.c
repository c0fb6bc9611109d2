/* SPDX-License-Identifier: Apache-2.0 */
/* Stage 5 of the background solve: quality of the selected minimiser
 * (docs/METHOD.md §7), float64, in the scaled unknowns (k, kappa) and scaled back
 * exactly (powers of two) to (K1, K2). Everything here refers to the
 * minimised cost E_w = P F(kappa), F = 1/D^2, D = kappa^2 + cw, P = e2 k^2 +
 * e1 k + e0 (E_w = E_p^2 when cw = 0, i.e. exactly the paper's indices).
 *
 *  - Hessian (eq. 28 generalised), ' = d/dkappa at fixed k:
 *    H11 = 2 e2 F, H12 = P_kkappa F + P_k F', H22 = P'' F + 2 P' F' + P F'',
 *    F' = -4 kappa / D^3, F'' = (20 kappa^2 - 4 cw) / D^4 (cw = 0: the paper's
 *    -4/kappa^5, 20/kappa^6); H = c diag(1/g, 1/s) H~ diag(1/g, 1/s).
 *    PD: H11 > 0 and det > 0.
 *  - Quadratic indices sqrt(0.5 E_w (H^-1)_ii); if H is not PD they are set to
 *    BG_PE_UNBOUNDED (1e30, finite even in float32) and BG_PE_FLAG_NOT_PD.
 *  - Exact indices with L = 1.25 E_w*:
 *    PE_K2: crossings of the profile E_w,red(kappa) = (e0 - e1^2/(4 e2)) F
 *    with L on both sides of kappa*, found as the zeros of the division-free
 *    g(kappa) = 4 e2 (e0 - L D^2) - e1^2 (same sign as E_w,red - L where
 *    e2 > 0). Probes at d0, 1.5 d0, 2.25 d0 ... from kappa* (d0 = quadratic
 *    index, or 1 % of kappa* if H is not PD), at most BG_PE_MAX_PROBE, never
 *    beyond the T_R band; then Illinois on the bracket until it is narrower
 *    than 2^-12 of the crossing's distance from kappa* (PE_K2 to ~1e-4
 *    relative; <= BG_PE_MAX_ROOT steps). A profile that dips below L again
 *    between two probes is not seen. If no crossing lies inside the band on a
 *    side, that side's distance to the band edge is used and
 *    BG_PE_FLAG_K2_{LO,HI}_EDGE is set (a lower bound, large relative to
 *    K2: the caller flags the window as poorly determined); never NaN.
 *    PE_K1: on [kappa_lo, kappa_hi], max of k+(kappa) and min of k-(kappa),
 *    k+- = (-e1 +- sqrt(-g))/(2 e2) (where g > 0, k+- = the profile's k), each
 *    by successive parabolic interpolation started at the extreme of the
 *    quadratic model (three points a quarter of the quadratic K2 index apart),
 *    stepping outwards while the extreme is not bracketed, until the vertex
 *    moves by less than 2^-10 of that spacing (<= BG_PE_MAX_MIN steps). The
 *    extreme value is stationary, so it is then exact to ~1e-6 relative.
 *  - E_w* <= 0 (exact fit): all indices 0, BG_PE_FLAG_DEGENERATE.
 * Cost: typically ~20 evaluations of the three tables (21 multiply-adds). */
#include <float.h>
#include <math.h>

#include "bg_quality.h"

typedef struct {
  const bg_tables_t *t;
  double lt;    /* L~ (scaled level) */
  double kprof; /* fallback k where the tables are not usable */
  unsigned int nev;
} pe_ctx_t;

/* g(x) = 4 e2 (e0 - L D^2) - e1^2 (< 0 inside the level set); v = tables. */
BG_NOINLINE static double level_g(pe_ctx_t *c, double x, double v[3])
{
  ++c->nev;
  imest__bg_tables_values(c->t, x, v);
  const double dd = x * x + c->t->cw;
  return 4.0 * v[0] * (v[2] - c->lt * dd * dd) - v[1] * v[1];
}

/* Profile level function for the crossings: a large positive value where undefined. */
static double level_fn(pe_ctx_t *c, double x)
{
  double v[3];
  const double g = level_g(c, x, v);
  return (v[0] > 0.0 && imest__bg_finite(g)) ? g : DBL_MAX;
}

/* sign = +1: k+(x); sign = -1: -k-(x) (both to be maximised). */
BG_NOINLINE static double kbound(pe_ctx_t *c, double x, int sign)
{
  double v[3];
  const double g = level_g(c, x, v);
  double k;
  if (!(v[0] > 0.0) || !imest__bg_finite(g)) {
    k = (double)sign * c->kprof;
  } else {
    const double root = (g < 0.0) ? BG_SQRT(-g) : 0.0;
    k = BG_DIV((double)(-sign) * v[1] + root, 2.0 * v[0]);
  }
  return imest__bg_finite(k) ? k : (double)sign * c->kprof;
}

/* Illinois on [x0, x1] with f0 < 0 <= f1 (either order); xs = kappa*. */
BG_NOINLINE static double illinois(pe_ctx_t *c, double xs, double x0, double f0, double x1, double f1)
{
  int retained = 0; /* +1: x0 kept last time, -1: x1 kept last time */
  double x = x1;
  for (int it = 0; it < BG_PE_MAX_ROOT; ++it) {
    x = x1 - BG_DIV(f1 * (x1 - x0), f1 - f0);
    const double lo = (x0 < x1) ? x0 : x1, hi = (x0 < x1) ? x1 : x0;
    if (!(x > lo && x < hi)) x = 0.5 * (x0 + x1);
    const double fx = level_fn(c, x);
    if (fx == 0.0) return x;
    if (fx > 0.0) { /* replaces x1 */
      x1 = x;
      f1 = fx;
      if (retained == 1) f0 *= 0.5;
      retained = 1;
    } else {
      x0 = x;
      f0 = fx;
      if (retained == -1) f1 *= 0.5;
      retained = -1;
    }
    if (fabs(x1 - x0) <= 2.44140625e-4 * fabs(x - xs)) break; /* 2^-12 */
  }
  return x;
}

/* First crossing of the profile with L on one side of xs; 1 if found (in *xc),
 * 0 if the band edge is reached first (*xc = edge). */
BG_NOINLINE static int crossing(pe_ctx_t *c, double xs, double fs, double d0, double edge, int dir,
                                double *xc)
{
  double xprev = xs, fprev = fs, step = d0;
  for (int j = 0; j < BG_PE_MAX_PROBE; ++j) {
    double x = xs + (double)dir * step;
    int last = 0;
    if ((dir > 0) ? (x >= edge) : (x <= edge)) {
      x = edge;
      last = 1;
    }
    const double fx = level_fn(c, x);
    if (fx >= 0.0) {
      *xc = (fx == 0.0) ? x : illinois(c, xs, xprev, fprev, x, fx);
      return 1;
    }
    if (last) break;
    xprev = x;
    fprev = fx;
    step *= 1.5;
  }
  *xc = edge;
  return 0;
}

/* Maximum of kbound(., sign) on [a, b] by successive parabolic interpolation
 * from x0 with spacing h (see the file comment). */
// One numeric iteration on shared state: a split would move arithmetic across calls (FMA
// contraction; the results must stay bit-identical).
// NOLINTNEXTLINE(readability-function-cognitive-complexity): see the line above
BG_NOINLINE static double pe_max(pe_ctx_t *c, int sign, double a, double b, double x0, double h)
{
  if (!(b > a)) return kbound(c, a, sign);
  if (!(h > 0.0) || h > 0.25 * (b - a)) h = 0.25 * (b - a);
  if (x0 < a + h) x0 = a + h;
  if (x0 > b - h) x0 = b - h;
  const double tol = 9.765625e-4 * h; /* 2^-10 */
  double xa = x0 - h, xb = x0, xc = x0 + h;
  double fa = kbound(c, xa, sign), fb = kbound(c, xb, sign), fc = kbound(c, xc, sign);
  for (int it = 0; it < BG_PE_MAX_MIN; ++it) {
    double u;
    if (fa > fb || fc > fb) {
      /* not bracketed: step outwards on the higher side (golden ratio growth) */
      if (fa > fc) {
        if (xa <= a) break; /* the maximum is at the band edge a */
        u = xa - 1.618 * (xb - xa);
        if (u < a) u = a;
        const double fu = kbound(c, u, sign);
        xc = xb;
        fc = fb;
        xb = xa;
        fb = fa;
        xa = u;
        fa = fu;
      } else {
        if (xc >= b) break;
        u = xc + 1.618 * (xc - xb);
        if (u > b) u = b;
        const double fu = kbound(c, u, sign);
        xa = xb;
        fa = fb;
        xb = xc;
        fb = fc;
        xc = u;
        fc = fu;
      }
      continue;
    }
    /* bracketed (fb >= fa, fc): vertex of the parabola through the three */
    const double p = (xb - xa) * (fb - fc), q = (xb - xc) * (fb - fa);
    const double den = 2.0 * (p - q);
    if (!(den != 0.0)) break;
    u = xb - BG_DIV((xb - xa) * p - (xb - xc) * q, den);
    if (!(u > xa && u < xc)) break;
    if (fabs(u - xb) <= tol) break;
    const double fu = kbound(c, u, sign);
    if (fu >= fb) { /* u becomes the middle */
      if (u < xb) {
        xc = xb;
        fc = fb;
      } else {
        xa = xb;
        fa = fb;
      }
      xb = u;
      fb = fu;
    } else { /* u becomes an outer point */
      if (u < xb) {
        xa = u;
        fa = fu;
      } else {
        xc = u;
        fc = fu;
      }
    }
  }
  double f = fb;
  if (fa > f) f = fa;
  if (fc > f) f = fc;
  return f;
}

static double finite_or_unbounded(double v)
{
  return (imest__bg_finite(v) && v >= 0.0 && v < BG_PE_UNBOUNDED) ? v : BG_PE_UNBOUNDED;
}

unsigned int imest__bg_quality(const bg_tables_t *t, const bg_solve_cfg_t *cfg, const bg_cand_t *best,
                               bg_solve_out_t *out)
{
  const double x = best->kappa, k = best->k;
  bg_tabval_t v;
  imest__bg_tables_eval(t, x, &v);
  const double dd = x * x + t->cw, idd = BG_DIV(1.0, dd), f = idd * idd;
  const double f1 = -4.0 * x * f * idd, f2 = (20.0 * x * x - 4.0 * t->cw) * f * f;
  const double p = (v.e2 * k + v.e1) * k + v.e0;
  const double pk = 2.0 * v.e2 * k + v.e1;
  const double px = (v.d2 * k + v.d1) * k + v.d0;
  const double pxx = (v.dd2 * k + v.dd1) * k + v.dd0;
  const double h11 = 2.0 * v.e2 * f;
  const double h12 = (2.0 * v.d2 * k + v.d1) * f + pk * f1;
  const double h22 = pxx * f + 2.0 * px * f1 + p * f2;
  const double det = h11 * h22 - h12 * h12;
  out->hessian[0][0] = h11 * imest__bg_pow2(t->cexp - 2 * t->gexp);
  out->hessian[0][1] = h12 * imest__bg_pow2(t->cexp - t->gexp - t->sexp);
  out->hessian[1][0] = out->hessian[0][1];
  out->hessian[1][1] = h22 * imest__bg_pow2(t->cexp - 2 * t->sexp);
  out->hessian_pd = (h11 > 0.0 && det > 0.0 && imest__bg_finite(det)) ? 1 : 0;
  out->pe_flags = 0;

  const double es = p * f; /* E_w~* */
  /* the residual as measured: the compensated one plus what the noise explains */
  const double er = es + BG_DIV(cfg->e_noise, t->c) * (x * x * x * x) * f;
  if (!(er > 0.0)) {
    out->pe_k1 = out->pe_k2 = 0.0;
    out->pe_quad[0] = out->pe_quad[1] = 0.0;
    out->pe_flags |= BG_PE_FLAG_DEGENERATE;
    return 1;
  }

  double dk_q = BG_PE_UNBOUNDED, dx_q = BG_PE_UNBOUNDED;
  if (out->hessian_pd) {
    const double hh = BG_DIV(0.5 * er, det);
    dk_q = BG_SQRT(hh * h22);
    dx_q = BG_SQRT(hh * h11);
    out->pe_quad[0] = finite_or_unbounded(dk_q * t->g);
    out->pe_quad[1] = finite_or_unbounded(dx_q * t->s);
  } else {
    out->pe_quad[0] = out->pe_quad[1] = BG_PE_UNBOUNDED;
    out->pe_flags |= BG_PE_FLAG_NOT_PD;
  }

  pe_ctx_t c;
  c.t = t;
  c.lt = es + 0.25 * er;
  c.kprof = k;
  c.nev = 0;
  /* g at kappa*: 4 e2 D^2 (E_w* - L) < 0 */
  const double fs = 4.0 * v.e2 * (v.e0 - c.lt * dd * dd) - v.e1 * v.e1;
  double d0 = (out->hessian_pd && imest__bg_finite(dx_q)) ? dx_q : 0.01 * x;
  if (!(d0 >= 1e-9 * x)) d0 = 1e-9 * x;
  if (d0 > x) d0 = 0.5 * x;
  /* band in kappa */
  const double x_lo_edge = BG_DIV(1.0, cfg->tr_max_s * t->s);
  const double x_hi_edge = BG_DIV(1.0, cfg->tr_min_s * t->s);
  double xlo, xhi;
  if (!crossing(&c, x, fs, d0, (x_lo_edge < x) ? x_lo_edge : x, -1, &xlo))
    out->pe_flags |= BG_PE_FLAG_K2_LO_EDGE;
  if (!crossing(&c, x, fs, d0, (x_hi_edge > x) ? x_hi_edge : x, +1, &xhi))
    out->pe_flags |= BG_PE_FLAG_K2_HI_EDGE;
  const double dxm = (xhi - x > x - xlo) ? xhi - x : x - xlo;
  out->pe_k2 = finite_or_unbounded(dxm * t->s);

  /* K1 extremes, started at the quadratic model's: dkappa = -(H12/H22) dk */
  double xe_hi = x, xe_lo = x, h = 0.125 * (xhi - xlo);
  if (out->hessian_pd && imest__bg_finite(dk_q) && imest__bg_finite(dx_q)) {
    const double shift = BG_DIV(h12, h22) * dk_q;
    xe_hi = x - shift;
    xe_lo = x + shift;
    h = 0.25 * dx_q;
  }
  const double kmax = pe_max(&c, +1, xlo, xhi, xe_hi, h);
  const double kmin = -pe_max(&c, -1, xlo, xhi, xe_lo, h);
  const double dkm = (kmax - k > k - kmin) ? kmax - k : k - kmin;
  out->pe_k1 = finite_or_unbounded(dkm * t->g);
  return c.nev;
}
