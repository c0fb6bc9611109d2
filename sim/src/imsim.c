/* imsim: induction-motor simulator (host only). See sim/README.md for the model, integrator,
 * measured errors and conventions. */
#include "imsim/imsim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PI 3.14159265358979323846
#define SQ23 0.81649658092772603273  /* sqrt(2/3) */
#define SQ3H 0.86602540378443864676  /* sqrt(3)/2 */
#define SQRT2 1.41421356237309504880
#define NAN_D ((double)NAN)

typedef imsim_cpx_ cpx;

static inline cpx cx(double re, double im) {
  cpx r;
  r.re = re;
  r.im = im;
  return r;
}
static inline cpx cmul(cpx a, cpx b) { return cx(a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re); }
static inline cpx cadd(cpx a, cpx b) { return cx(a.re + b.re, a.im + b.im); }
static inline cpx cscale(cpx a, double k) { return cx(a.re * k, a.im * k); }
static inline double cabs2(cpx a) { return a.re * a.re + a.im * a.im; }
static inline cpx cexpj(double ph) { return cx(cos(ph), sin(ph)); }

/* a_k of u = sqrt(2/3) (x1 + a1 x2 + a2 x3): 1, e^{j2pi/3}, e^{-j2pi/3}. */
static const double AK_RE[3] = {1.0, -0.5, -0.5};
static const double AK_IM[3] = {0.0, SQ3H, -SQ3H};

void imsim_abc_to_ab(const double abc[3], double ab[2]) {
  ab[0] = SQ23 * (abc[0] - 0.5 * abc[1] - 0.5 * abc[2]);
  ab[1] = SQ23 * SQ3H * (abc[1] - abc[2]);
}

void imsim_ab_to_abc(const double ab[2], double abc[3]) {
  abc[0] = SQ23 * ab[0];
  abc[1] = SQ23 * (-0.5 * ab[0] + SQ3H * ab[1]);
  abc[2] = SQ23 * (-0.5 * ab[0] - SQ3H * ab[1]);
}

/* ------------------------------------------------------------------------------------------ */
/* Configuration                                                                                */

void imsim_config_default(imsim_config *c) {
  memset(c, 0, sizeof *c);
  /* The paper's motor (Section VI) and docs/METHOD.md §9. */
  c->pole_pairs = 2;
  c->ls_h = 0.2908;
  c->lr_h = 0.2908;
  c->sigma = 0.096;
  c->rs_ohm = 5.04;
  c->tr_s = 0.12;
  c->j_kgm2 = 1.2e-3; /* assumed (not in the paper) */
  c->b_nms = 1e-4;    /* assumed (not in the paper) */

  /* Thermal: calibrated so that exp2 (30 Hz, 2.064 N m, 1 h) gives R_S x1.16 and
     T_R x(0.09/0.115) at t = 3600 s, as in the paper's experiment 2 (see README). */
  c->thermal = true;
  c->t_amb_c = 22.0;
  c->alpha_per_k = 0.00393;
  c->tau_stator_s = 900.0;
  c->tau_rotor_s = 1200.0;
  c->rth_stator_k_per_w = 0.9027;
  c->rth_rotor_k_per_w = 6.22;
  c->thermal_speedup = 1.0;

  c->load_nm = 0.0;
  c->load_on_s = 0.0;
  c->load_ramp_s = 0.0;

  c->supply = IMSIM_SUPPLY_SINE;
  c->vll_v = 230.0;
  c->freq_hz = 60.0;
  c->vf_ramp_s = 0.0;
  c->vf_boost_v = 0.0;

  c->carrier_hz = 10e3;
  c->vdc_v = 400.0;
  c->dead_time_s = 0.0;
  c->pwm_moments = true;

  c->ifoc_mode = IMSIM_IFOC_SPEED;
  c->ifoc_ideal_stage = false;
  c->ifoc_tr_s = 0.0;
  c->ifoc_flux_wb = 0.0;
  c->speed_ref_rpm = 1750.0;
  c->speed_ramp_s = 0.5;
  c->torque_ref_nm = 0.0;
  c->torque_limit_nm = 4.0;
  c->current_bw_hz = 250.0;
  c->speed_bw_hz = 5.0;
  c->speed_filter_hz = 50.0;

  c->fs_hz = 4000.0;
  c->steps_per_sample = 0;
  c->ideal_sensors = false;
  c->adc_bits = 12;
  c->i_range_a = 20.0;
  c->u_range_v = 400.0;
  c->noise_lsb = 1.0;
  c->encoder_counts = 4096;
  c->aa_hz = 0.0;
  c->vmeas = IMSIM_VMEAS_AUTO;
  c->seed = 1;

  c->start = IMSIM_START_REST;
  c->integrator = IMSIM_INTEGRATOR_FAST;
  c->rk4_substeps = 8;
  c->duration_s = 2.0;
}

int imsim_config_preset(imsim_config *c, const char *name) {
  imsim_config_default(c);
  if (name != NULL && strcmp(name, "exp1") == 0) {
    return 0; /* 60 Hz, 230 V applied at standstill, no load, 2 s run-up */
  }
  if (name != NULL && strcmp(name, "exp2") == 0) {
    /* 30 Hz V/f (115 V), rated load 2.064 N m, one hour of heating. Start: V/f ramp 0->30 Hz
       in 1 s without load, load ramped 0->2.064 N m over 1 s starting at t = 1.5 s. */
    c->supply = IMSIM_SUPPLY_VF;
    c->vll_v = 115.0;
    c->freq_hz = 30.0;
    c->vf_ramp_s = 1.0;
    c->load_nm = 2.064;
    c->load_on_s = 1.5;
    c->load_ramp_s = 1.0;
    c->speed_ref_rpm = 850.0;
    c->speed_ramp_s = 1.0;
    c->duration_s = 3600.0;
    return 0;
  }
  return -1;
}

const char *imsim_error(const imsim *sim) { return sim->err; }

/* ------------------------------------------------------------------------------------------ */
/* Random numbers: xoshiro256** seeded by splitmix64, Gaussian by the polar method.            */

static uint64_t splitmix64(uint64_t *x) {
  uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
static inline uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
static uint64_t rng_next(uint64_t s[4]) {
  const uint64_t result = rotl(s[1] * 5, 7) * 9;
  const uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  return result;
}
static double rng_uniform(uint64_t s[4]) { /* (-1, 1) */
  return (double)(rng_next(s) >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}
static double rng_gauss(imsim *s) {
  if (s->has_spare) {
    s->has_spare = false;
    return s->gauss_spare;
  }
  double u, v, q;
  do {
    u = rng_uniform(s->rng);
    v = rng_uniform(s->rng);
    q = u * u + v * v;
  } while (q >= 1.0 || q == 0.0);
  const double f = sqrt(-2.0 * log(q) / q);
  s->gauss_spare = v * f;
  s->has_spare = true;
  return u * f;
}

/* ------------------------------------------------------------------------------------------ */
/* Parameters                                                                                   */

static void update_params(imsim *s) {
  const imsim_config *c = &s->c;
  s->rs = c->rs_ohm * (1.0 + c->alpha_per_k * (s->temp_s - c->t_amb_c));
  s->rr = s->rr0_ohm * (1.0 + c->alpha_per_k * (s->temp_r - c->t_amb_c));
  s->tr = c->lr_h / s->rr;
  s->gamma = s->rs / (c->sigma * c->ls_h) + (1.0 - c->sigma) / (c->sigma * s->tr);
  s->beta = s->m_h / (c->sigma * c->ls_h * c->lr_h);
}

static double torque_of(const imsim *s, cpx i, cpx psi) {
  return (double)s->c.pole_pairs * s->m_h / s->c.lr_h * (i.im * psi.re - i.re * psi.im);
}

/* dTe/dt along the model at state (i, psi, w) with input u. */
static inline double torque_rate(const imsim *s, cpx i, cpx psi, double w, cpx u) {
  const imsim_config *c = &s->c;
  const double nw = (double)c->pole_pairs * w;
  const cpx di = cadd(cadd(cscale(u, 1.0 / (c->sigma * c->ls_h)), cscale(i, -s->gamma)),
                      cmul(cx(s->beta / s->tr, -s->beta * nw), psi));
  const cpx dpsi = cadd(cscale(i, s->m_h / s->tr), cmul(cx(-1.0 / s->tr, nw), psi));
  return (double)c->pole_pairs * s->m_h / c->lr_h *
         (di.im * psi.re - di.re * psi.im + i.im * dpsi.re - i.re * dpsi.im);
}

static double load_at(const imsim *s, double t) {
  if (s->load_overridden) return s->load_override;
  const imsim_config *c = &s->c;
  if (t < c->load_on_s) return 0.0;
  if (c->load_ramp_s > 0.0 && t < c->load_on_s + c->load_ramp_s)
    return c->load_nm * (t - c->load_on_s) / c->load_ramp_s;
  return c->load_nm;
}

/* Reference of the open-loop supplies: alpha-beta amplitude (= V_ll rms), phase, frequency. */
static void vf_ref(const imsim *s, double t, double *amp, double *phase, double *f_hz) {
  const imsim_config *c = &s->c;
  const double ramp = (c->supply == IMSIM_SUPPLY_SINE || c->start == IMSIM_START_STEADY) ? 0.0 : c->vf_ramp_s;
  if (ramp <= 0.0) {
    *amp = c->vll_v;
    *f_hz = c->freq_hz;
    *phase = 2.0 * PI * c->freq_hz * t;
    return;
  }
  const double r = t < ramp ? t / ramp : 1.0;
  *f_hz = r * c->freq_hz;
  *amp = r > 0.0 ? c->vf_boost_v + (c->vll_v - c->vf_boost_v) * r : 0.0;
  *phase = t < ramp ? PI * c->freq_hz * t * t / ramp : 2.0 * PI * c->freq_hz * (t - 0.5 * ramp);
}

/* ------------------------------------------------------------------------------------------ */
/* Fast propagator: x(h) = sum_k A^k [h^k/k! x0 + m_k B], Horner, A frozen over the step.      */

typedef struct {
  bool aa, src, pwm;
  int p;           /* Taylor order */
  double u_end[2]; /* PWM: applied voltage just before the end of the step */
  double we;       /* source rotation (rad/s), src only */
  cpx mom[32];     /* PWM input moments m_k = int_0^h (h-s)^k/k! u(s) ds */
} step_input;

static const double INV_FACT[34] = {
    1.0, 1.0, 0.5, 1.0 / 6, 1.0 / 24, 1.0 / 120, 1.0 / 720, 1.0 / 5040, 1.0 / 40320,
    1.0 / 362880, 1.0 / 3628800, 1.0 / 39916800, 1.0 / 479001600, 1.0 / 6227020800.0,
    1.0 / 87178291200.0, 1.0 / 1307674368000.0, 1.0 / 20922789888000.0,
    1.0 / 355687428096000.0, 1.0 / 6402373705728000.0, 1.0 / 121645100408832000.0,
    1.0 / 2432902008176640000.0, 1.0 / 51090942171709440000.0,
    1.0 / 1124000727777607680000.0, 1.0 / 25852016738884976640000.0,
    1.0 / 620448401733239439360000.0, 1.0 / 15511210043330985984000000.0,
    1.0 / 403291461126605635584000000.0, 1.0 / 10888869450418352160768000000.0,
    1.0 / 304888344611713860501504000000.0, 1.0 / 8841761993739701954543616000000.0,
    1.0 / 265252859812191058636308480000000.0, 1.0 / 8222838654177922817725562880000000.0,
    1.0 / 263130836933693530167218012160000000.0, 1.0 / 8683317618811886495518194401280000000.0};

static const double INV_K[33] = {0.0, 1.0, 1.0 / 2, 1.0 / 3, 1.0 / 4, 1.0 / 5, 1.0 / 6, 1.0 / 7, 1.0 / 8,
    1.0 / 9, 1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13, 1.0 / 14, 1.0 / 15, 1.0 / 16, 1.0 / 17, 1.0 / 18,
    1.0 / 19, 1.0 / 20, 1.0 / 21, 1.0 / 22, 1.0 / 23, 1.0 / 24, 1.0 / 25, 1.0 / 26, 1.0 / 27, 1.0 / 28,
    1.0 / 29, 1.0 / 30, 1.0 / 31, 1.0 / 32};

/* Smallest Taylor order p with ||A h||^(p+1)/(p+1)! e^||A h|| < 1e-14 (balanced norm bound);
   the system is stable, so this local truncation error stays bounded (order 1e-11 globally). */
static int taylor_order_rho(double rho) {
  double term = 1.0;
  const double er = rho < 1.0 ? 2.72 : exp(rho);
  int p = 0;
  while (p < 30) {
    term *= rho * INV_K[p + 1];
    if (term * er < 1e-14 && p >= 2) break;
    ++p;
  }
  return p;
}

/* Norm bound of the augmented A (per second). */
static double a_norm(const imsim *s, double w, const step_input *in) {
  const imsim_config *c = &s->c;
  const double nw = fabs((double)c->pole_pairs * w);
  double norm = s->gamma + s->beta * s->m_h / s->tr + 2.0 * (1.0 / s->tr + nw);
  if (in->aa) norm += (2.0 + SQRT2) * 2.0 * PI * c->aa_hz;
  if (in->src) norm += fabs(in->we);
  return norm;
}

static int taylor_order(const imsim *s, double w, const step_input *in) {
  return taylor_order_rho(a_norm(s, w, in) * s->h_s);
}

typedef struct {
  double bi, a11, a21, wc, swc;
  cpx a12, a22, jwe;
  bool aa, src;
} amat;

/* z = A y (augmented, frozen omega). */
static inline void apply_a(const amat *m, const cpx *y, cpx *z) {
  z[0] = cadd(cscale(y[0], m->a11), cmul(m->a12, y[1]));
  if (m->src) z[0] = cadd(z[0], cscale(y[6], m->bi));
  z[1] = cadd(cscale(y[0], m->a21), cmul(m->a22, y[1]));
  if (m->aa) {
    const double wc = m->wc, swc = m->swc;
    const cpx uin = m->src ? y[6] : cx(0.0, 0.0);
    z[2] = cscale(y[3], wc);
    z[3] = cx(wc * (y[0].re - y[2].re) - swc * y[3].re, wc * (y[0].im - y[2].im) - swc * y[3].im);
    z[4] = cscale(y[5], wc);
    z[5] = cx(wc * (uin.re - y[4].re) - swc * y[5].re, wc * (uin.im - y[4].im) - swc * y[5].im);
  } else {
    z[2] = z[3] = z[4] = z[5] = cx(0.0, 0.0);
  }
  z[6] = m->src ? cmul(m->jwe, y[6]) : cx(0.0, 0.0);
}

/* Exact (to the Taylor tolerance) propagation over h of the linear electrical system with
   omega frozen at w_mid, plus the leading Magnus correction for omega varying linearly over
   the step: dx = n omega' h^3/12 [A1, A] x_mid, A1 = dA/d(n omega) = [[0, -j beta], [0, j]].
   The input does not enter the correction because A1 B = 0, so it holds for PWM too. */
static void fast_step(imsim *s, const double *hkv, double w_mid, double nwdot, const step_input *in) {
  const imsim_config *c = &s->c;
  const double nw = (double)c->pole_pairs * w_mid;
  amat m;
  m.bi = 1.0 / (c->sigma * c->ls_h);
  m.a11 = -s->gamma;
  m.a12 = cx(s->beta / s->tr, -s->beta * nw);
  m.a21 = s->m_h / s->tr;
  m.a22 = cx(-1.0 / s->tr, nw);
  m.wc = in->aa ? 2.0 * PI * c->aa_hz : 0.0;
  m.swc = SQRT2 * m.wc;
  m.jwe = cx(0.0, in->we);
  m.aa = in->aa;
  m.src = in->src;
  const int p = in->p;
  enum { NS = 7 };
  cpx y[NS];
  const cpx x00 = s->x[0], x01 = s->x[1], x06 = s->x[6];
  if (!in->aa) {
    /* motor block only (+ source state): the common, fast path */
    cpx y0 = cscale(x00, hkv[p]), y1 = cscale(x01, hkv[p]), y6 = cscale(x06, hkv[p]);
    if (in->pwm) y0 = cadd(y0, cscale(in->mom[p], m.bi));
    for (int k = p - 1; k >= 0; --k) {
      const double hk = hkv[k];
      cpx z0 = cadd(cscale(y0, m.a11), cmul(m.a12, y1));
      const cpx z1 = cadd(cscale(y0, m.a21), cmul(m.a22, y1));
      if (in->src) {
        z0 = cadd(z0, cscale(y6, m.bi));
        y6 = cadd(cmul(m.jwe, y6), cscale(x06, hk));
      } else {
        z0 = cadd(z0, cscale(in->mom[k], m.bi));
      }
      y0 = cadd(z0, cscale(x00, hk));
      y1 = cadd(z1, cscale(x01, hk));
    }
    y[0] = y0;
    y[1] = y1;
    for (int q = 2; q < NS; ++q) y[q] = s->x[q];
    y[6] = y6;
  } else {
    cpx x0[NS], z[NS];
    for (int k = 0; k < NS; ++k) x0[k] = s->x[k];
    /* y = hk[p] x0 + m_p B;  then y = A y + hk[k] x0 + m_k B for k = p-1 .. 0 */
    for (int k = 0; k < NS; ++k) y[k] = cscale(x0[k], hkv[p]);
    if (in->pwm) {
      y[0] = cadd(y[0], cscale(in->mom[p], m.bi));
      y[5] = cadd(y[5], cscale(in->mom[p], m.wc));
    }
    for (int k = p - 1; k >= 0; --k) {
      apply_a(&m, y, z);
      const double hk = hkv[k];
      for (int q = 0; q < NS; ++q) y[q] = cx(z[q].re + hk * x0[q].re, z[q].im + hk * x0[q].im);
      if (in->pwm) {
        y[0] = cadd(y[0], cscale(in->mom[k], m.bi));
        y[5] = cadd(y[5], cscale(in->mom[k], m.wc));
      }
    }
  }
  if (nwdot != 0.0) {
    /* [A1, A] xm = A1 (A xm) - A (A1 xm); only i, psi and (with AA) the 2nd current-filter
       state are affected, because A1 has a single non-zero column (psi). */
    const double k3 = nwdot * hkv[3] * 0.5; /* h^3/12 = (h^3/6) / 2 */
    const cpx xm0 = cscale(cadd(x00, y[0]), 0.5), xm1 = cscale(cadd(x01, y[1]), 0.5);
    const cpx axm1 = cadd(cscale(xm0, m.a21), cmul(m.a22, xm1));
    const cpx v0 = cx(s->beta * xm1.im, -s->beta * xm1.re); /* -j beta xm1 */
    const cpx v1 = cx(-xm1.im, xm1.re);                     /*  j xm1      */
    const cpx av0 = cadd(cscale(v0, m.a11), cmul(m.a12, v1));
    const cpx av1 = cadd(cscale(v0, m.a21), cmul(m.a22, v1));
    const cpx c0 = cx(s->beta * axm1.im, -s->beta * axm1.re);
    const cpx c1 = cx(-axm1.im, axm1.re);
    y[0] = cadd(y[0], cscale(cadd(c0, cscale(av0, -1.0)), k3));
    y[1] = cadd(y[1], cscale(cadd(c1, cscale(av1, -1.0)), k3));
    if (in->aa) y[3] = cadd(y[3], cscale(v0, -k3 * m.wc));
  }
  for (int k = 0; k < NS; ++k) s->x[k] = y[k];
}

/* ------------------------------------------------------------------------------------------ */
/* Reference propagator: RK4 of the full nonlinear model.                                      */

typedef struct {
  cpx x[7];
  double w, th;
} full_state;

static void full_deriv(const imsim *s, const full_state *X, cpx u_pwm, const step_input *in, double tl,
                       full_state *d) {
  const imsim_config *c = &s->c;
  const double bi = 1.0 / (c->sigma * c->ls_h);
  const double nw = (double)c->pole_pairs * X->w;
  const cpx u = in->src ? X->x[6] : u_pwm;
  const cpx i = X->x[0], psi = X->x[1];
  const cpx a12 = cx(s->beta / s->tr, -s->beta * nw);
  const cpx a22 = cx(-1.0 / s->tr, nw);
  d->x[0] = cadd(cadd(cscale(u, bi), cscale(i, -s->gamma)), cmul(a12, psi));
  d->x[1] = cadd(cscale(i, s->m_h / s->tr), cmul(a22, psi));
  const double wc = in->aa ? 2.0 * PI * c->aa_hz : 0.0;
  const double swc = SQRT2 * wc;
  d->x[2] = cscale(X->x[3], wc);
  d->x[3] = cx(wc * (i.re - X->x[2].re) - swc * X->x[3].re, wc * (i.im - X->x[2].im) - swc * X->x[3].im);
  d->x[4] = cscale(X->x[5], wc);
  d->x[5] = cx(wc * (u.re - X->x[4].re) - swc * X->x[5].re, wc * (u.im - X->x[4].im) - swc * X->x[5].im);
  d->x[6] = in->src ? cmul(cx(0.0, in->we), X->x[6]) : cx(0.0, 0.0);
  const double te = torque_of(s, i, psi);
  d->w = (te - tl - c->b_nms * X->w) / c->j_kgm2;
  d->th = X->w;
}

static void full_axpy(full_state *out, const full_state *a, double k, const full_state *b) {
  for (int q = 0; q < 7; ++q) out->x[q] = cx(a->x[q].re + k * b->x[q].re, a->x[q].im + k * b->x[q].im);
  out->w = a->w + k * b->w;
  out->th = a->th + k * b->th;
}

static void rk4_piece(const imsim *s, full_state *X, double len, cpx u_pwm, const step_input *in, double tl) {
  const int n = s->c.rk4_substeps;
  const double hh = len / (double)n;
  for (int it = 0; it < n; ++it) {
    full_state k1, k2, k3, k4, tmp;
    full_deriv(s, X, u_pwm, in, tl, &k1);
    full_axpy(&tmp, X, 0.5 * hh, &k1);
    full_deriv(s, &tmp, u_pwm, in, tl, &k2);
    full_axpy(&tmp, X, 0.5 * hh, &k2);
    full_deriv(s, &tmp, u_pwm, in, tl, &k3);
    full_axpy(&tmp, X, hh, &k3);
    full_deriv(s, &tmp, u_pwm, in, tl, &k4);
    for (int q = 0; q < 7; ++q) {
      X->x[q].re += hh / 6.0 * (k1.x[q].re + 2.0 * k2.x[q].re + 2.0 * k3.x[q].re + k4.x[q].re);
      X->x[q].im += hh / 6.0 * (k1.x[q].im + 2.0 * k2.x[q].im + 2.0 * k3.x[q].im + k4.x[q].im);
    }
    X->w += hh / 6.0 * (k1.w + 2.0 * k2.w + 2.0 * k3.w + k4.w);
    X->th += hh / 6.0 * (k1.th + 2.0 * k2.th + 2.0 * k3.th + k4.th);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* One integration step of length h with the given input.                                      */

typedef struct {
  bool rising;
  double edge[3];  /* actual edge times (dead time applied); edge >= h means no edge */
  double vdc;
} pwm_half;

/* One fast step of length h (coefficients hkv = h^k/k!), input described by in; u0 and u1 are
   the applied voltages just after the start and just before the end (for dTe/dt). rip (may be
   NULL) holds the PWM current-ripple integrals r1 = int r ds and r2 = int (h-s) r ds of
   r(s) = (1/(sigma L_S)) (U(s) - s U(h)/h), U(s) = int_0^s u: the part of i(s) that the smooth
   (Hermite) quadratures below do not see; then u0 = u1 = the mean voltage of the step. */
static void fast_piece(imsim *s, double h, const double *hkv, const step_input *in, double tl, cpx u0, cpx u1,
                       const cpx *rip) {
  const imsim_config *c = &s->c;
  const double kj = 1.0 / c->j_kgm2;
  const double kt = (double)c->pole_pairs * s->m_h / c->lr_h;
  const double acc0 = (s->te - tl - c->b_nms * s->w) * kj;
  const double ted0 = torque_rate(s, s->x[0], s->x[1], s->w, u0);
  const cpx psi0 = s->x[1];
  /* ripple torque moments: int T_rip ds and int (h-s) T_rip ds (psi taken constant) */
  double tr1 = 0.0, tr2 = 0.0;
  if (rip != NULL) {
    tr1 = kt * (rip[0].im * psi0.re - rip[0].re * psi0.im);
    tr2 = kt * (rip[1].im * psi0.re - rip[1].re * psi0.im);
  }
  /* omega frozen over the step at its predicted mean over the step (Taylor to omega'', with
     omega'' from dTe/dt): the mean, not the mid-point value, cancels the O(h^3) local error */
  const double w2 = (ted0 - c->b_nms * acc0) * kj;
  const double w_mean = s->w + 0.5 * h * acc0 + h * h / 6.0 * w2 + kj * tr2 / h;
  fast_step(s, hkv, w_mean, (double)c->pole_pairs * (acc0 + 0.5 * h * w2), in);
  if (in->src) u1 = s->x[6];
  const double te1 = torque_of(s, s->x[0], s->x[1]);
  if (rip != NULL) {
    /* int T_rip ds with psi(s) linear over the step: psi_mid r1 + psi' int (s - h/2) r ds,
       int (s - h/2) r ds = h/2 r1 - r2 */
    const cpx pm = cscale(cadd(psi0, s->x[1]), 0.5);
    const cpx dp = cscale(cadd(s->x[1], cscale(psi0, -1.0)), 1.0 / h);
    const cpx q = cadd(cscale(rip[0], 0.5 * h), cscale(rip[1], -1.0));
    tr1 = kt * (rip[0].im * pm.re - rip[0].re * pm.im + q.im * dp.re - q.re * dp.im);
  }
  /* omega: Hermite (corrected trapezoid) quadrature of the torque; theta likewise. dTe/dt at
     the end needs omega at the end: take it from the plain trapezoid first. */
  const double kb = 0.5 * h * c->b_nms * kj;
  const double w1t = (s->w * (1.0 - kb) + kj * (0.5 * h * (s->te + te1) + tr1 - h * tl)) / (1.0 + kb);
  const double ted1 = torque_rate(s, s->x[0], s->x[1], w1t, u1);
  const double tint = 0.5 * h * (s->te + te1) + h * h / 12.0 * (ted0 - ted1) + tr1;
  const double w1 = (s->w * (1.0 - kb) + kj * (tint - h * tl)) / (1.0 + kb);
  const double acc1 = (te1 - tl - c->b_nms * w1) * kj;
  s->th += 0.5 * h * (s->w + w1) + h * h / 12.0 * (acc0 - acc1) + kj * (tr2 - 0.5 * h * tr1);
  s->w = w1;
  s->te = te1;
  s->acc = acc1;
}

/* Voltage applied by the inverter at time tm inside the half period. */
static cpx pwm_voltage_at(const pwm_half *ph, double tm) {
  cpx u = cx(0.0, 0.0);
  for (int k = 0; k < 3; ++k) {
    const bool before = tm < ph->edge[k];
    const bool high = ph->rising ? before : !before;
    if (high) u = cadd(u, cx(AK_RE[k] * SQ23 * ph->vdc, AK_IM[k] * SQ23 * ph->vdc));
  }
  return u;
}

/* Switching instants of the half period, sorted, with 0 and h: b[0..4]. */
static void pwm_breaks(const pwm_half *ph, double h, double b[5]) {
  b[0] = 0.0;
  b[1] = ph->edge[0] < h ? ph->edge[0] : h;
  b[2] = ph->edge[1] < h ? ph->edge[1] : h;
  b[3] = ph->edge[2] < h ? ph->edge[2] : h;
  b[4] = h;
  for (int a = 2; a < 4; ++a)
    for (int q = a; q > 1 && b[q] < b[q - 1]; --q) {
      const double t = b[q];
      b[q] = b[q - 1];
      b[q - 1] = t;
    }
}

static void advance(imsim *s, const step_input *in, const pwm_half *ph, double tl) {
  const imsim_config *c = &s->c;
  const double h = s->h_s;
  if (c->integrator == IMSIM_INTEGRATOR_FAST) {
    if (!in->pwm) {
      fast_piece(s, h, s->hk, in, tl, s->x[6], s->x[6], NULL);
    } else if (c->pwm_moments) {
      /* whole half period at once; the PWM input enters through its exact moments, the
         current ripple through its integrals (mom_k = int (h-s)^k/k! u ds) */
      const double bi = 1.0 / (c->sigma * c->ls_h);
      const cpx ubar = cscale(in->mom[0], 1.0 / h);
      cpx rip[2];
      rip[0] = cscale(cadd(in->mom[1], cscale(in->mom[0], -0.5 * h)), bi);
      rip[1] = cscale(cadd(in->mom[2], cscale(in->mom[0], -h * h / 6.0)), bi);
      fast_piece(s, h, s->hk, in, tl, ubar, ubar, rip);
    } else {
      /* piecewise between the switching instants (constant input on each piece) */
      double b[5];
      pwm_breaks(ph, h, b);
      step_input lin;
      lin.pwm = false;
      lin.src = true;
      lin.aa = in->aa;
      lin.we = 0.0;
      const double norm = a_norm(s, s->w, &lin);
      for (int piece = 0; piece < 4; ++piece) {
        const double len = b[piece + 1] - b[piece];
        /* Pieces shorter than 1e-14 s (coincident edges up to rounding) are dropped: their
           volt-seconds (< 4e-12 V s) are negligible, and their h^k/k! would be denormal. */
        if (len < 1e-14) continue;
        const cpx u = pwm_voltage_at(ph, 0.5 * (b[piece] + b[piece + 1]));
        double hkv[32];
        lin.p = taylor_order_rho(norm * len);
        const int kmax = lin.p > 3 ? lin.p : 3;
        hkv[0] = 1.0;
        for (int k = 1; k <= kmax; ++k) hkv[k] = hkv[k - 1] * len * INV_K[k];
        s->x[6] = u;
        fast_piece(s, len, hkv, &lin, tl, u, u, NULL);
      }
      s->x[6] = cx(0.0, 0.0);
    }
    return;
  }
  /* RK4 reference, split at switching instants. */
  full_state X;
  for (int q = 0; q < 7; ++q) X.x[q] = s->x[q];
  X.w = s->w;
  X.th = s->th;
  if (!in->pwm) {
    rk4_piece(s, &X, h, cx(0.0, 0.0), in, tl);
  } else {
    double b[5];
    pwm_breaks(ph, h, b);
    for (int piece = 0; piece < 4; ++piece) {
      const double t0 = b[piece], t1 = b[piece + 1];
      if (t1 <= t0) continue;
      const cpx u = pwm_voltage_at(ph, 0.5 * (t0 + t1));
      rk4_piece(s, &X, t1 - t0, u, in, tl);
    }
  }
  for (int q = 0; q < 7; ++q) s->x[q] = X.x[q];
  s->w = X.w;
  s->th = X.th;
  s->te = torque_of(s, s->x[0], s->x[1]);
  s->acc = (s->te - tl - c->b_nms * s->w) / c->j_kgm2;
}

/* ------------------------------------------------------------------------------------------ */
/* PWM half carrier period: reference -> duties -> edges -> input moments.                     */

static void pwm_build(imsim *s, uint64_t g, cpx vref, step_input *in, pwm_half *ph, double cmd_avg[2],
                      double act_avg[2], double u_end[2]) {
  const imsim_config *c = &s->c;
  const double h = s->h_s;
  const double vdc = c->vdc_v;
  const bool rising = (g % 2u) == 0u; /* carrier starts at its valley at t = 0 */
  double vabc[3], iabc[3];
  const double vab[2] = {vref.re, vref.im};
  imsim_ab_to_abc(vab, vabc);
  const double iab[2] = {s->x[0].re, s->x[0].im};
  imsim_ab_to_abc(iab, iabc);
  double tau_cmd[3], tau_act[3];
  ph->rising = rising;
  ph->vdc = vdc;
  double end_re = 0.0, end_im = 0.0;
  for (int k = 0; k < 3; ++k) {
    double m = vabc[k] / (0.5 * vdc);
    if (m > 1.0) m = 1.0;
    if (m < -1.0) m = -1.0;
    /* rising: high on [0, e); falling: low on [0, e), high after */
    const double e = rising ? 0.5 * h * (1.0 + m) : 0.5 * h * (1.0 - m);
    double ea = e;
    if (e > 0.0 && e < h && c->dead_time_s > 0.0) {
      /* high->low (rising) is delayed when the current flows out of the motor (i < 0);
         low->high (falling) is delayed when it flows into the motor (i > 0). */
      if ((rising && iabc[k] < 0.0) || (!rising && iabc[k] > 0.0)) ea = e + c->dead_time_s;
      if (ea > h) ea = h;
    }
    ph->edge[k] = ea;
    tau_cmd[k] = h - e;
    tau_act[k] = h - ea < 1e-14 ? 0.0 : h - ea; /* avoid denormal powers */
    const bool high_at_end = rising ? (ea >= h) : (ea < h);
    if (high_at_end) {
      end_re += AK_RE[k];
      end_im += AK_IM[k];
    }
  }
  const double sg = rising ? -1.0 : 1.0;
  const double kc = sg * SQ23 * vdc;
  double p[3] = {tau_act[0], tau_act[1], tau_act[2]};
  const int jmax = s->c.pwm_moments ? in->p : 0;
  for (int j = 0; j <= jmax; ++j) {
    const double f = kc * INV_FACT[j + 1];
    in->mom[j] = cx(f * (AK_RE[0] * p[0] + AK_RE[1] * p[1] + AK_RE[2] * p[2]),
                    f * (AK_IM[0] * p[0] + AK_IM[1] * p[1] + AK_IM[2] * p[2]));
    p[0] *= tau_act[0];
    p[1] *= tau_act[1];
    p[2] *= tau_act[2];
  }
  act_avg[0] = in->mom[0].re / h;
  act_avg[1] = in->mom[0].im / h;
  cmd_avg[0] = kc / h * (AK_RE[0] * tau_cmd[0] + AK_RE[1] * tau_cmd[1] + AK_RE[2] * tau_cmd[2]);
  cmd_avg[1] = kc / h * (AK_IM[0] * tau_cmd[0] + AK_IM[1] * tau_cmd[1] + AK_IM[2] * tau_cmd[2]);
  u_end[0] = SQ23 * vdc * end_re;
  u_end[1] = SQ23 * vdc * end_im;
  in->u_end[0] = u_end[0];
  in->u_end[1] = u_end[1];
}

/* ------------------------------------------------------------------------------------------ */
/* Steady state (phasor) of eq. (1).                                                            */

static void steady_at(const imsim_config *c, double m, double tr, double w, double vll, double we,
                      cpx *i, cpx *psi, double *te) {
  const double sl = c->sigma * c->ls_h;
  const double gamma = c->rs_ohm / sl + (1.0 - c->sigma) / (c->sigma * tr);
  const double beta = m / (c->sigma * c->ls_h * c->lr_h);
  const double nw = (double)c->pole_pairs * w;
  /* (j we - A) z = b U */
  const cpx m11 = cx(gamma, we);
  const cpx m12 = cx(-beta / tr, beta * nw);
  const cpx m21 = cx(-m / tr, 0.0);
  const cpx m22 = cx(1.0 / tr, we - nw);
  const cpx det = cadd(cmul(m11, m22), cscale(cmul(m12, m21), -1.0));
  const double dd = cabs2(det);
  const cpx inv = cx(det.re / dd, -det.im / dd);
  const double bu = vll / sl;
  *i = cmul(cscale(m22, bu), inv);
  *psi = cmul(cscale(m21, -bu), inv);
  *te = (double)c->pole_pairs * m / c->lr_h * (i->im * psi->re - i->re * psi->im);
}

int imsim_steady_state(const imsim_config *c, double vll_v, double freq_hz, double load_nm, imsim_steady *out) {
  const double m = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
  const double we = 2.0 * PI * freq_hz;
  const double wsync = we / (double)c->pole_pairs;
  cpx i, psi;
  double te;
#define F_OF(wv) (steady_at(c, m, c->tr_s, (wv), vll_v, we, &i, &psi, &te), te - load_nm - c->b_nms * (wv))
  double hi = wsync, lo = wsync;
  double fhi = F_OF(hi);
  if (fhi >= 0.0) {
    /* no load and no friction: synchronous speed */
    lo = hi;
  } else {
    int k = 0;
    for (k = 1; k <= 4000; ++k) {
      lo = wsync * (1.0 - (double)k / 4000.0);
      if (F_OF(lo) > 0.0) break;
      hi = lo;
    }
    if (k > 4000) return -1;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (F_OF(mid) > 0.0) lo = mid;
      else hi = mid;
    }
  }
#undef F_OF
  const double w = 0.5 * (lo + hi);
  steady_at(c, m, c->tr_s, w, vll_v, we, &i, &psi, &te);
  out->speed_rad_s = w;
  out->speed_rpm = w * 60.0 / (2.0 * PI);
  out->slip = wsync > 0.0 ? (wsync - w) / wsync : 0.0;
  out->i_rms_phase = sqrt(cabs2(i)) / sqrt(3.0);
  out->torque_nm = te;
  out->psi_r_wb = sqrt(cabs2(psi));
  out->i_ab[0] = i.re;
  out->i_ab[1] = i.im;
  out->psi_ab[0] = psi.re;
  out->psi_ab[1] = psi.im;
  return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Sensors                                                                                      */

static double adc(imsim *s, double x, double range) {
  const imsim_config *c = &s->c;
  const double lsb = 2.0 * range / ldexp(1.0, c->adc_bits);
  if (c->noise_lsb > 0.0) x += c->noise_lsb * lsb * rng_gauss(s);
  double code = floor(x / lsb + 0.5);
  const double top = ldexp(1.0, c->adc_bits - 1);
  if (code > top - 1.0) code = top - 1.0;
  if (code < -top) code = -top;
  return code * lsb;
}

static bool is_pwm_stage(const imsim_config *c) {
  return c->supply == IMSIM_SUPPLY_PWM || (c->supply == IMSIM_SUPPLY_IFOC && !c->ifoc_ideal_stage);
}

static imsim_vmeas vmeas_of(const imsim_config *c) {
  if (c->vmeas != IMSIM_VMEAS_AUTO) return c->vmeas;
  return is_pwm_stage(c) ? IMSIM_VMEAS_AVG : IMSIM_VMEAS_INST;
}

static void fill_sample(imsim *s, imsim_sample *o) {
  const imsim_config *c = &s->c;
  const bool aa = !c->ideal_sensors && c->aa_hz > 0.0;
  o->n = s->n;
  o->t = s->t;
  /* truth */
  const double iab[2] = {s->x[0].re, s->x[0].im};
  imsim_ab_to_abc(iab, o->i_abc_true);
  o->i_ab_true[0] = iab[0];
  o->i_ab_true[1] = iab[1];
  o->psi_ab[0] = s->x[1].re;
  o->psi_ab[1] = s->x[1].im;
  o->psi_r_wb = sqrt(cabs2(s->x[1]));
  o->theta_true = s->th;
  o->speed_rad_s = s->w;
  o->torque_nm = s->te;
  o->load_nm = load_at(s, s->t);
  o->accel_rad_s2 = (s->te - o->load_nm - c->b_nms * s->w) / c->j_kgm2;
  o->tr_s = s->tr;
  o->rs_ohm = s->rs;
  o->temp_stator_c = s->temp_s;
  o->temp_rotor_c = s->temp_r;
  const cpx ir = cscale(cadd(s->x[1], cscale(s->x[0], -s->m_h)), 1.0 / c->lr_h);
  o->p_cu_stator_w = s->rs * cabs2(s->x[0]);
  o->p_cu_rotor_w = s->rr * cabs2(ir);
  double utrue[2];
  if (is_pwm_stage(c)) {
    utrue[0] = 0.5 * (s->u_hp_act[0][0] + s->u_hp_act[1][0]);
    utrue[1] = 0.5 * (s->u_hp_act[0][1] + s->u_hp_act[1][1]);
  } else {
    utrue[0] = s->u_inst[0];
    utrue[1] = s->u_inst[1];
  }
  o->u_ab_true[0] = utrue[0];
  o->u_ab_true[1] = utrue[1];
  imsim_ab_to_abc(utrue, o->u_abc_true);
  if (c->supply == IMSIM_SUPPLY_IFOC) {
    o->ifoc_torque_ref_nm = s->te_ref;
    o->ifoc_flux_ref_wb = s->ifoc_flux;
    o->ifoc_tr_s = s->ifoc_tr;
    o->ifoc_speed_ref_rad_s = c->ifoc_mode == IMSIM_IFOC_SPEED ? s->speed_ref : NAN_D;
  } else {
    o->ifoc_torque_ref_nm = o->ifoc_flux_ref_wb = o->ifoc_tr_s = o->ifoc_speed_ref_rad_s = NAN_D;
  }

  /* measured voltage (alpha-beta, before the ADC) */
  double um[2];
  switch (vmeas_of(c)) {
    case IMSIM_VMEAS_AVG:
      um[0] = 0.5 * (s->u_hp_cmd[0][0] + s->u_hp_cmd[1][0]);
      um[1] = 0.5 * (s->u_hp_cmd[0][1] + s->u_hp_cmd[1][1]);
      break;
    case IMSIM_VMEAS_AA:
      um[0] = s->x[4].re;
      um[1] = s->x[4].im;
      break;
    case IMSIM_VMEAS_INST:
    case IMSIM_VMEAS_AUTO:
    default:
      um[0] = s->u_inst[0];
      um[1] = s->u_inst[1];
      break;
  }
  double uabc[3], imab[2], iabc[3];
  imsim_ab_to_abc(um, uabc);
  imab[0] = aa ? s->x[2].re : s->x[0].re;
  imab[1] = aa ? s->x[2].im : s->x[0].im;
  imsim_ab_to_abc(imab, iabc);
  if (c->ideal_sensors) {
    for (int k = 0; k < 3; ++k) {
      o->u_abc[k] = uabc[k];
      o->i_abc[k] = iabc[k];
    }
    o->theta = s->th;
  } else {
    for (int k = 0; k < 3; ++k)
      o->i_abc[k] = adc(s, iabc[k] * (1.0 + c->i_gain_err[k]) + c->i_offset_a[k], c->i_range_a);
    for (int k = 0; k < 3; ++k) o->u_abc[k] = adc(s, uabc[k] + c->u_offset_v[k], c->u_range_v);
    const double cpr = (double)c->encoder_counts;
    o->theta = floor(s->th * cpr / (2.0 * PI)) * (2.0 * PI / cpr);
  }
  /* what the controller sees */
  imsim_abc_to_ab(o->i_abc, s->i_meas_ab);
  s->th_meas = o->theta;
}

/* ------------------------------------------------------------------------------------------ */
/* IFOC                                                                                          */

static void ifoc_update(imsim *s) {
  const imsim_config *c = &s->c;
  const double ts = s->ts_s;
  const double np = (double)c->pole_pairs;
  const double m = s->m_h;
  const double sl = c->sigma * c->ls_h;
  /* speed from encoder differences, first-order low-pass */
  const double w_raw = (s->th_meas - s->th_meas_prev) / ts;
  s->th_meas_prev = s->th_meas;
  s->w_meas += (1.0 - exp(-2.0 * PI * c->speed_filter_hz * ts)) * (w_raw - s->w_meas);
  const double psi_ref = s->ifoc_flux;
  const double id_ref = psi_ref / m;
  double te_ref;
  if (c->ifoc_mode == IMSIM_IFOC_SPEED) {
    double wref = s->speed_ref;
    if (c->speed_ramp_s > 0.0 && s->t < c->speed_ramp_s) wref *= s->t / c->speed_ramp_s;
    const double kp = c->j_kgm2 * 2.0 * PI * c->speed_bw_hz;
    const double ki = kp * 2.0 * PI * c->speed_bw_hz / 4.0;
    const double e = wref - s->w_meas;
    te_ref = kp * e + s->integ_w;
    if (te_ref > c->torque_limit_nm) te_ref = c->torque_limit_nm;
    else if (te_ref < -c->torque_limit_nm) te_ref = -c->torque_limit_nm;
    else s->integ_w += ki * e * ts;
  } else {
    te_ref = c->torque_ref_nm;
    if (te_ref > c->torque_limit_nm) te_ref = c->torque_limit_nm;
    if (te_ref < -c->torque_limit_nm) te_ref = -c->torque_limit_nm;
  }
  const double iq_ref = te_ref * c->lr_h / (np * m * psi_ref);
  const double w_sl = iq_ref / (s->ifoc_tr * id_ref);
  const double rho = np * s->th_meas + s->slip_angle;
  const cpx rot = cexpj(-rho);
  const cpx idq = cmul(rot, cx(s->i_meas_ab[0], s->i_meas_ab[1]));
  const double we = np * s->w_meas + w_sl;
  const double wbw = 2.0 * PI * c->current_bw_hz;
  const double kp = sl * wbw;
  const double req = c->rs_ohm + c->lr_h / s->ifoc_tr * (m / c->lr_h) * (m / c->lr_h);
  const double ki = req * wbw;
  const double ed = id_ref - idq.re, eq = iq_ref - idq.im;
  double vd = kp * ed + s->integ_d - we * sl * iq_ref;
  double vq = kp * eq + s->integ_q + we * (sl * id_ref + m / c->lr_h * psi_ref);
  const double vmax = sqrt(1.5) * 0.5 * c->vdc_v;
  const double vm = sqrt(vd * vd + vq * vq);
  if (vm > vmax) {
    vd *= vmax / vm;
    vq *= vmax / vm;
  } else {
    s->integ_d += ki * ed * ts;
    s->integ_q += ki * eq * ts;
  }
  s->v_dq[0] = vd;
  s->v_dq[1] = vq;
  s->rho = rho;
  s->we_ctrl = we;
  s->t_ctrl = s->t;
  s->te_ref = te_ref;
  s->id_ref = id_ref;
  s->iq_ref = iq_ref;
  s->slip_angle += w_sl * ts;
}

static cpx ifoc_vref(const imsim *s, double t) {
  return cmul(cx(s->v_dq[0], s->v_dq[1]), cexpj(s->rho + s->we_ctrl * (t - s->t_ctrl)));
}

/* ------------------------------------------------------------------------------------------ */
/* Init and step                                                                                */

static int fail(imsim *s, const char *msg) {
  snprintf(s->err, sizeof s->err, "%s", msg);
  return -1;
}

int imsim_init(imsim *s, const imsim_config *cfg, imsim_sample *first) {
  memset(s, 0, sizeof *s);
  s->c = *cfg;
  imsim_config *c = &s->c;
  if (c->pole_pairs < 1) return fail(s, "pole_pairs must be >= 1");
  if (!(c->ls_h > 0.0) || !(c->lr_h > 0.0)) return fail(s, "ls and lr must be > 0");
  if (!(c->sigma > 0.0 && c->sigma < 1.0)) return fail(s, "sigma must be in (0, 1)");
  if (!(c->rs_ohm > 0.0) || !(c->tr_s > 0.0)) return fail(s, "rs and tr must be > 0");
  if (!(c->j_kgm2 > 0.0) || !(c->b_nms >= 0.0)) return fail(s, "j must be > 0 and b >= 0");
  if (!(c->fs_hz > 0.0)) return fail(s, "fs must be > 0");
  if (!(c->vll_v >= 0.0) || !(c->freq_hz >= 0.0)) return fail(s, "vll and freq must be >= 0");
  if (c->thermal && (!(c->tau_stator_s > 0.0) || !(c->tau_rotor_s > 0.0) || !(c->thermal_speedup > 0.0)))
    return fail(s, "thermal time constants and speed-up must be > 0");
  if (!c->ideal_sensors) {
    if (c->adc_bits < 2 || c->adc_bits > 30) return fail(s, "adc bits must be in 2..30");
    if (!(c->i_range_a > 0.0) || !(c->u_range_v > 0.0)) return fail(s, "ADC ranges must be > 0");
    if (c->encoder_counts < 1) return fail(s, "encoder counts must be >= 1");
    if (!(c->noise_lsb >= 0.0)) return fail(s, "noise must be >= 0");
    for (int k = 0; k < 3; ++k)
      if (!isfinite(c->i_offset_a[k]) || !isfinite(c->u_offset_v[k]) || !(c->i_gain_err[k] > -1.0) ||
          !isfinite(c->i_gain_err[k]))
        return fail(s, "sensor offsets must be finite and gain errors > -1");
    if (!(c->aa_hz >= 0.0)) return fail(s, "aa cut-off must be >= 0");
  }
  if (c->rk4_substeps < 1) return fail(s, "rk4 substeps must be >= 1");
  const imsim_vmeas vm = vmeas_of(c);
  if (vm == IMSIM_VMEAS_AVG && !is_pwm_stage(c)) return fail(s, "voltage measurement 'avg' needs a PWM stage");
  if (vm == IMSIM_VMEAS_AA && (c->ideal_sensors || !(c->aa_hz > 0.0)))
    return fail(s, "voltage measurement 'aa' needs an AA filter (aa_hz > 0, sensors not ideal)");
  s->ts_s = 1.0 / c->fs_hz;
  if (is_pwm_stage(c)) {
    if (!(c->carrier_hz > 0.0) || !(c->vdc_v > 0.0)) return fail(s, "carrier and vdc must be > 0");
    const double ratio = 2.0 * c->carrier_hz / c->fs_hz;
    const double k = floor(ratio + 0.5);
    if (k < 1.0 || fabs(ratio - k) > 1e-9 * ratio) return fail(s, "2 * carrier_hz must be an integer multiple of fs_hz (PWM-synchronous sampling)");
    if (c->steps_per_sample != 0 && c->steps_per_sample != (int)k) return fail(s, "with PWM, steps per sample is fixed to 2 f_c / fs");
    s->k_steps = (int)k;
    if (!(c->dead_time_s >= 0.0) || c->dead_time_s >= 0.5 / c->carrier_hz) return fail(s, "dead time must be in [0, 1/(2 f_c))");
  } else {
    if (c->steps_per_sample < 0) return fail(s, "steps per sample must be >= 0");
    s->k_steps = c->steps_per_sample > 0 ? c->steps_per_sample : 5;
  }
  s->h_s = s->ts_s / (double)s->k_steps;
  s->hk[0] = 1.0;
  for (int k = 1; k < 32; ++k) s->hk[k] = s->hk[k - 1] * s->h_s / (double)k;

  s->m_h = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
  s->rr0_ohm = c->lr_h / c->tr_s;
  s->temp_s = s->temp_r = c->t_amb_c;
  update_params(s);

  uint64_t sm = c->seed;
  for (int k = 0; k < 4; ++k) s->rng[k] = splitmix64(&sm);

  /* IFOC */
  s->ifoc_tr = c->ifoc_tr_s > 0.0 ? c->ifoc_tr_s : c->tr_s;
  s->speed_ref = c->speed_ref_rpm * 2.0 * PI / 60.0;
  if (c->supply == IMSIM_SUPPLY_IFOC) {
    if (c->start == IMSIM_START_STEADY) return fail(s, "start 'steady' is not available with IFOC (it starts from rest)");
    if (c->ifoc_flux_wb > 0.0) {
      s->ifoc_flux = c->ifoc_flux_wb;
    } else {
      imsim_steady st;
      const bool have = c->vll_v > 0.0 && c->freq_hz > 0.0;
      if (imsim_steady_state(c, have ? c->vll_v : 230.0, have ? c->freq_hz : 60.0, c->load_nm, &st) != 0)
        return fail(s, "cannot derive the rated flux; set ifoc_flux_wb");
      s->ifoc_flux = st.psi_r_wb;
    }
  }
  s->te_ref = NAN_D;

  if (c->start == IMSIM_START_STEADY) {
    imsim_steady st;
    if (c->supply == IMSIM_SUPPLY_IFOC) return fail(s, "steady start not available with IFOC");
    if (imsim_steady_state(c, c->vll_v, c->freq_hz, c->load_nm, &st) != 0)
      return fail(s, "steady start: load exceeds the breakdown torque");
    s->x[0] = cx(st.i_ab[0], st.i_ab[1]);
    s->x[1] = cx(st.psi_ab[0], st.psi_ab[1]);
    s->w = st.speed_rad_s;
    /* AA filter states in sinusoidal steady state: f1 = H(j we) x, f2 = (j we / wc) f1 */
    if (c->aa_hz > 0.0 && !c->ideal_sensors) {
      const double wc = 2.0 * PI * c->aa_hz, we = 2.0 * PI * c->freq_hz;
      const cpx den = cx(wc * wc - we * we, SQRT2 * wc * we);
      const double dd = cabs2(den);
      const cpx hh = cx(wc * wc * den.re / dd, -wc * wc * den.im / dd);
      s->x[2] = cmul(hh, s->x[0]);
      s->x[3] = cmul(cx(0.0, we / wc), s->x[2]);
      s->x[4] = cmul(hh, cx(c->vll_v, 0.0));
      s->x[5] = cmul(cx(0.0, we / wc), s->x[4]);
    }
    s->c.load_on_s = 0.0;
    s->c.load_ramp_s = 0.0;
  }
  s->te = torque_of(s, s->x[0], s->x[1]);
  s->acc = (s->te - load_at(s, 0.0) - c->b_nms * s->w) / c->j_kgm2;
  if (c->supply == IMSIM_SUPPLY_SINE || c->supply == IMSIM_SUPPLY_VF) {
    double amp, ph, f;
    vf_ref(s, 0.0, &amp, &ph, &f);
    s->u_inst[0] = amp * cos(ph);
    s->u_inst[1] = amp * sin(ph);
  }
  imsim_sample tmp;
  fill_sample(s, first != NULL ? first : &tmp);
  s->th_meas_prev = s->th_meas;
  return 0;
}

void imsim_set_ifoc_tr(imsim *s, double tr_s) {
  if (tr_s > 0.0) s->ifoc_tr = tr_s;
}
void imsim_set_speed_ref(imsim *s, double rpm) {
  s->speed_ref = rpm * 2.0 * PI / 60.0;
  s->c.speed_ramp_s = 0.0;
}
void imsim_set_torque_ref(imsim *s, double nm) { s->c.torque_ref_nm = nm; }
void imsim_set_load(imsim *s, double load_nm) {
  s->load_override = load_nm;
  s->load_overridden = true;
}

void imsim_step(imsim *s, imsim_sample *out) {
  const imsim_config *c = &s->c;
  const double ts = s->ts_s, h = s->h_s;
  /* 1. thermal: copper losses at t_n drive both first-order models (exact exponential step) */
  if (c->thermal) {
    const cpx ir = cscale(cadd(s->x[1], cscale(s->x[0], -s->m_h)), 1.0 / c->lr_h);
    const double ps = s->rs * cabs2(s->x[0]);
    const double pr = s->rr * cabs2(ir);
    const double ks = 1.0 - exp(-ts * c->thermal_speedup / c->tau_stator_s);
    const double kr = 1.0 - exp(-ts * c->thermal_speedup / c->tau_rotor_s);
    s->temp_s += ks * (c->t_amb_c + c->rth_stator_k_per_w * ps - s->temp_s);
    s->temp_r += kr * (c->t_amb_c + c->rth_rotor_k_per_w * pr - s->temp_r);
    update_params(s);
  }
  /* 2. load torque, held over the sample period (value at its centre) */
  const double tl = load_at(s, s->t + 0.5 * ts);
  /* 3. controller */
  if (c->supply == IMSIM_SUPPLY_IFOC) ifoc_update(s);

  const bool aa = !c->ideal_sensors && c->aa_hz > 0.0;
  const bool pwm = is_pwm_stage(c);
  step_input in;
  in.aa = aa;
  in.pwm = pwm;
  in.src = !pwm;
  in.we = 0.0;
  in.p = 0;
  pwm_half ph;
  memset(&ph, 0, sizeof ph);
  for (int k = 0; k < s->k_steps; ++k) {
    const double t0 = s->t + (double)k * h;
    if (pwm) {
      in.p = taylor_order(s, s->w, &in);
      const double tc = t0 + 0.5 * h;
      cpx vref;
      if (c->supply == IMSIM_SUPPLY_IFOC) {
        vref = ifoc_vref(s, tc);
      } else {
        double amp, phs, f;
        vf_ref(s, tc, &amp, &phs, &f);
        vref = cscale(cexpj(phs), amp);
      }
      const uint64_t g = s->n * (uint64_t)s->k_steps + (uint64_t)k;
      double cmd[2], act[2], uend[2];
      pwm_build(s, g, vref, &in, &ph, cmd, act, uend);
      const int slot = s->hp_count & 1;
      s->u_hp_cmd[slot][0] = cmd[0];
      s->u_hp_cmd[slot][1] = cmd[1];
      s->u_hp_act[slot][0] = act[0];
      s->u_hp_act[slot][1] = act[1];
      s->hp_count++;
      s->u_inst[0] = uend[0];
      s->u_inst[1] = uend[1];
    } else if (c->supply == IMSIM_SUPPLY_IFOC) {
      /* ideal stage: the controller's synchronous-frame voltage, rotating at its we */
      s->x[6] = ifoc_vref(s, t0);
      in.we = s->we_ctrl;
      in.p = taylor_order(s, s->w, &in);
    } else {
      double amp, phs, f, amp_m, phs_m, f_m;
      vf_ref(s, t0, &amp, &phs, &f);
      vf_ref(s, t0 + 0.5 * h, &amp_m, &phs_m, &f_m);
      s->x[6] = cscale(cexpj(phs), amp_m);
      in.we = 2.0 * PI * f_m;
      in.p = taylor_order(s, s->w, &in);
    }
    advance(s, &in, &ph, tl);
  }
  s->n += 1;
  s->t = (double)s->n / c->fs_hz;
  if (!pwm) {
    if (c->supply == IMSIM_SUPPLY_IFOC) {
      s->u_inst[0] = s->x[6].re;
      s->u_inst[1] = s->x[6].im;
    } else {
      double amp, phs, f;
      vf_ref(s, s->t, &amp, &phs, &f);
      s->u_inst[0] = amp * cos(phs);
      s->u_inst[1] = amp * sin(phs);
    }
  }
  fill_sample(s, out);
}
