/* Stage 5 of the background solve: quality of the selected minimiser
 * (MATH.md §7), float64, in the scaled unknowns (k, kappa) and scaled back
 * exactly (powers of two) to (K1, K2).
 *
 *  - Hessian (eq. 28) with P = e2 k^2 + e1 k + e0, ' = d/dkappa at fixed k:
 *    H11 = 2 e2/kappa^4, H12 = (2 e2' k + e1')/kappa^4 - 4 (2 e2 k + e1)/kappa^5,
 *    H22 = P''/kappa^4 - 8 P'/kappa^5 + 20 P/kappa^6;
 *    H = c diag(1/g, 1/s) H~ diag(1/g, 1/s). PD: H11 > 0 and det > 0.
 *  - Quadratic indices sqrt(0.5 E (H^-1)_ii); if H is not PD they are set to
 *    IMEST_PE_UNBOUNDED (1e30, finite even in float32) and IMEST_PE_FLAG_NOT_PD.
 *  - Exact indices with L = 1.25 E*:
 *    PE_K2: crossings of the profile E_red(kappa) = kappa^-4 (e0 - e1^2/(4 e2))
 *    with L on both sides of kappa*. Step out from kappa* by 1.1 d0, then x1.5
 *    per probe (d0 = quadratic index, or 1 % of kappa* if H is not PD), at
 *    most IMEST_PE_MAX_PROBE probes, never beyond the T_R band; then Illinois
 *    (<= IMEST_PE_MAX_ROOT iterations, to 2^-40 relative). A profile that
 *    dips below L again between two probes is not seen (the first upward
 *    crossing found is used). If no crossing lies inside the band on a side,
 *    that side's distance to the band edge is used and
 *    IMEST_PE_FLAG_K2_{LO,HI}_EDGE is set: the index is then a lower bound,
 *    large relative to K2 for any sensible band, so the window is flagged as
 *    poorly determined by the caller; never NaN.
 *    PE_K1: on [kappa_lo, kappa_hi], max of k+(kappa) and min of k-(kappa),
 *    k+- = (-e1 +- sqrt(e1^2 - 4 e2 (e0 - L kappa^4)))/(2 e2) (where the
 *    discriminant is negative, k+- = the profile's k), each by Brent's
 *    minimisation (golden section + parabolic steps, <= IMEST_PE_MAX_MIN
 *    iterations, 1e-8 relative in kappa: the extreme value is then exact to
 *    ~1e-16 relative since it is stationary).
 *  - E* <= 0 (exact fit): all indices 0, IMEST_PE_FLAG_DEGENERATE.
 * Cost: typically ~40 profile evaluations of ~30 float64 multiply-adds. */
#include <float.h>
#include <math.h>

#include "bg_poly.h"

typedef struct {
  const imest_tables_t *t;
  double lt;       /* L~ (scaled level) */
  double kprof;    /* fallback k where the discriminant is negative */
  unsigned int nev;
} pe_ctx_t;

static void tab_values(const imest_tables_t *t, double x, double *e2, double *e1, double *e0) {
  double p2 = t->e2[6], p1 = t->e1[7], p0 = t->e0[8];
  p1 = p1 * x + t->e1[6];
  p0 = p0 * x + t->e0[7];
  p0 = p0 * x + t->e0[6];
  for (int m = 5; m >= 0; --m) {
    p2 = p2 * x + t->e2[m];
    p1 = p1 * x + t->e1[m];
    p0 = p0 * x + t->e0[m];
  }
  *e2 = p2;
  *e1 = p1;
  *e0 = p0;
}

/* E_red(x) - L~, scaled; a large positive value where undefined. */
static double profile_minus_l(pe_ctx_t *c, double x) {
  double e2, e1, e0;
  ++c->nev;
  tab_values(c->t, x, &e2, &e1, &e0);
  const double x2 = x * x;
  const double v = (e0 - e1 * e1 / (4.0 * e2)) / (x2 * x2) - c->lt;
  return (e2 > 0.0 && isfinite(v)) ? v : DBL_MAX;
}

/* sign = +1: -k+(x) (to be minimised); sign = -1: k-(x). */
static double kbound(pe_ctx_t *c, double x, int sign) {
  double e2, e1, e0;
  ++c->nev;
  tab_values(c->t, x, &e2, &e1, &e0);
  const double x2 = x * x;
  const double disc = e1 * e1 - 4.0 * e2 * (e0 - c->lt * x2 * x2);
  double k;
  if (!(e2 > 0.0) || !isfinite(disc)) {
    k = c->kprof;
  } else if (disc <= 0.0) {
    k = -e1 / (2.0 * e2);
  } else {
    k = (-e1 + (double)sign * sqrt(disc)) / (2.0 * e2);
  }
  if (!isfinite(k)) k = c->kprof;
  return (sign > 0) ? -k : k;
}

/* Illinois on [x0, x1] with f0 < 0 <= f1 (either order of x0, x1). */
static double illinois(pe_ctx_t *c, double x0, double f0, double x1, double f1) {
  int retained = 0; /* +1: x0 kept last time, -1: x1 kept last time */
  double x = x1;
  for (int it = 0; it < IMEST_PE_MAX_ROOT; ++it) {
    x = x1 - f1 * (x1 - x0) / (f1 - f0);
    const double lo = fmin(x0, x1), hi = fmax(x0, x1);
    if (!(x > lo && x < hi)) x = 0.5 * (x0 + x1);
    const double fx = profile_minus_l(c, x);
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
    if (fabs(x1 - x0) <= 9.094947017729282e-13 * fabs(x)) break; /* 2^-40 */
  }
  return x;
}

/* First crossing of the profile with L on one side of xs; 1 if found (in *xc),
 * 0 if the band edge is reached first (*xc = edge). */
static int crossing(pe_ctx_t *c, double xs, double fs, double d0, double edge, int dir, double *xc) {
  double xprev = xs, fprev = fs, step = 1.1 * d0;
  for (int j = 0; j < IMEST_PE_MAX_PROBE; ++j) {
    double x = xs + (double)dir * step;
    int last = 0;
    if ((dir > 0) ? (x >= edge) : (x <= edge)) {
      x = edge;
      last = 1;
    }
    const double fx = profile_minus_l(c, x);
    if (fx >= 0.0) {
      *xc = (fx == 0.0) ? x : illinois(c, xprev, fprev, x, fx);
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

/* Brent's minimisation of kbound(., sign) on [a, b]. */
static double brent_min(pe_ctx_t *c, int sign, double a, double b) {
  const double cg = 0.38196601125010515; /* (3 - sqrt 5)/2 */
  double x = a + cg * (b - a), w = x, v = x;
  double fx = kbound(c, x, sign), fw = fx, fv = fx;
  double d = 0.0, e = 0.0;
  for (int it = 0; it < IMEST_PE_MAX_MIN; ++it) {
    const double xm = 0.5 * (a + b);
    const double tol1 = 1e-8 * fabs(x) + 1e-300, tol2 = 2.0 * tol1;
    if (fabs(x - xm) <= tol2 - 0.5 * (b - a)) break;
    int golden = 1;
    if (fabs(e) > tol1) {
      double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw);
      double p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = fabs(q);
      const double eprev = e;
      e = d;
      if (fabs(p) < fabs(0.5 * q * eprev) && p > q * (a - x) && p < q * (b - x)) {
        d = p / q;
        const double u = x + d;
        if (u - a < tol2 || b - u < tol2) d = (xm >= x) ? tol1 : -tol1;
        golden = 0;
      }
    }
    if (golden) {
      e = (x >= xm) ? a - x : b - x;
      d = cg * e;
    }
    const double u = (fabs(d) >= tol1) ? x + d : x + ((d >= 0.0) ? tol1 : -tol1);
    const double fu = kbound(c, u, sign);
    if (fu <= fx) {
      if (u >= x)
        a = x;
      else
        b = x;
      v = w;
      fv = fw;
      w = x;
      fw = fx;
      x = u;
      fx = fu;
    } else {
      if (u < x)
        a = u;
      else
        b = u;
      if (fu <= fw || w == x) {
        v = w;
        fv = fw;
        w = u;
        fw = fu;
      } else if (fu <= fv || v == x || v == w) {
        v = u;
        fv = fu;
      }
    }
  }
  return fx;
}

static double finite_or_unbounded(double v) {
  return (isfinite(v) && v >= 0.0 && v < IMEST_PE_UNBOUNDED) ? v : IMEST_PE_UNBOUNDED;
}

unsigned int imest_quality(const imest_tables_t *t, const imest_solve_cfg_t *cfg, const imest_cand_t *best,
                           imest_solve_out_t *out) {
  const double x = best->kappa, k = best->k;
  imest_tabval_t v;
  imest_tables_eval(t, x, &v);
  const double x2 = x * x, x4 = x2 * x2, x5 = x4 * x, x6 = x4 * x2;
  const double p = v.e2 * k * k + v.e1 * k + v.e0;
  const double p1 = v.d2 * k * k + v.d1 * k + v.d0;
  const double p2 = v.dd2 * k * k + v.dd1 * k + v.dd0;
  const double h11 = 2.0 * v.e2 / x4;
  const double h12 = (2.0 * v.d2 * k + v.d1) / x4 - 4.0 * (2.0 * v.e2 * k + v.e1) / x5;
  const double h22 = p2 / x4 - 8.0 * p1 / x5 + 20.0 * p / x6;
  const double det = h11 * h22 - h12 * h12;
  out->hessian[0][0] = ldexp(h11, t->cexp - 2 * t->gexp);
  out->hessian[0][1] = ldexp(h12, t->cexp - t->gexp - t->sexp);
  out->hessian[1][0] = out->hessian[0][1];
  out->hessian[1][1] = ldexp(h22, t->cexp - 2 * t->sexp);
  out->hessian_pd = (h11 > 0.0 && det > 0.0 && isfinite(det)) ? 1 : 0;
  out->pe_flags = 0;

  const double es = p / x4; /* E~* */
  if (!(es > 0.0)) {
    out->pe_k1 = out->pe_k2 = 0.0;
    out->pe_quad[0] = out->pe_quad[1] = 0.0;
    out->pe_flags |= IMEST_PE_FLAG_DEGENERATE;
    return 1;
  }

  double dk_q = IMEST_PE_UNBOUNDED, dx_q = IMEST_PE_UNBOUNDED;
  if (out->hessian_pd) {
    dk_q = sqrt(0.5 * es * h22 / det);
    dx_q = sqrt(0.5 * es * h11 / det);
    out->pe_quad[0] = finite_or_unbounded(ldexp(dk_q, t->gexp));
    out->pe_quad[1] = finite_or_unbounded(ldexp(dx_q, t->sexp));
  } else {
    out->pe_quad[0] = out->pe_quad[1] = IMEST_PE_UNBOUNDED;
    out->pe_flags |= IMEST_PE_FLAG_NOT_PD;
  }

  pe_ctx_t c;
  c.t = t;
  c.lt = 1.25 * es;
  c.kprof = k;
  c.nev = 0;
  const double fs = es - c.lt; /* profile at kappa* minus L~ (< 0) */
  double d0 = (out->hessian_pd && isfinite(dx_q)) ? dx_q : 0.01 * x;
  if (!(d0 >= 1e-9 * x)) d0 = 1e-9 * x;
  if (d0 > x) d0 = 0.5 * x;
  /* band in kappa */
  const double x_lo_edge = ldexp(1.0 / cfg->tr_max_s, -t->sexp);
  const double x_hi_edge = ldexp(1.0 / cfg->tr_min_s, -t->sexp);
  double xlo, xhi;
  if (!crossing(&c, x, fs, d0, fmin(x_lo_edge, x), -1, &xlo)) out->pe_flags |= IMEST_PE_FLAG_K2_LO_EDGE;
  if (!crossing(&c, x, fs, d0, fmax(x_hi_edge, x), +1, &xhi)) out->pe_flags |= IMEST_PE_FLAG_K2_HI_EDGE;
  out->pe_k2 = finite_or_unbounded(ldexp(fmax(xhi - x, x - xlo), t->sexp));

  const double kmax = -brent_min(&c, +1, xlo, xhi);
  const double kmin = brent_min(&c, -1, xlo, xhi);
  out->pe_k1 = finite_or_unbounded(ldexp(fmax(kmax - k, k - kmin), t->gexp));
  return c.nev;
}
