/* SPDX-License-Identifier: Apache-2.0 */
/* One integration step of length h_s: the fast path (exact electrical propagation with a
 * predicted mean speed, Hermite mechanics; PWM by moments or piecewise) or the RK4 reference. */
#include <math.h>
#include <stddef.h>

#include "imsim_internal.h"

/* One fast step of length h (coefficients hkv = h^k/k!), input described by in; u0 and u1 are
   the applied voltages just after the start and just before the end (for dTe/dt). rip (may be
   NULL) holds the PWM current-ripple integrals r1 = int r ds and r2 = int (h-s) r ds of
   r(s) = (1/(sigma L_S)) (U(s) - s U(h)/h), U(s) = int_0^s u: the part of i(s) that the smooth
   (Hermite) quadratures below do not see; then u0 = u1 = the mean voltage of the step. */
static void fast_piece(imsim_t *s, double h, const double *hkv, const step_input_t *in, double tl, cpx u0,
                       cpx u1, const cpx *rip)
{
  const imsim_config_t *c = &s->c;
  const double kj = 1.0 / c->j_kgm2;
  const double kt = (double)c->pole_pairs * s->m_h / c->lr_h;
  const double acc0 = (s->te - tl - c->b_nms * s->w) * kj;
  const double ted0 = ims_torque_rate(s, s->x[0], s->x[1], s->w, u0);
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
  ims_fast_step(s, hkv, w_mean, (double)c->pole_pairs * (acc0 + 0.5 * h * w2), in);
  if (in->src) u1 = s->x[6];
  const double te1 = ims_torque_of(s, s->x[0], s->x[1]);
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
  const double ted1 = ims_torque_rate(s, s->x[0], s->x[1], w1t, u1);
  const double tint = 0.5 * h * (s->te + te1) + h * h / 12.0 * (ted0 - ted1) + tr1;
  const double w1 = (s->w * (1.0 - kb) + kj * (tint - h * tl)) / (1.0 + kb);
  const double acc1 = (te1 - tl - c->b_nms * w1) * kj;
  s->th += 0.5 * h * (s->w + w1) + h * h / 12.0 * (acc0 - acc1) + kj * (tr2 - 0.5 * h * tr1);
  s->w = w1;
  s->te = te1;
  s->acc = acc1;
}

/* Phase currents at the start of a piece (only needed by a non-ideal inverter). */
static void piece_currents(const imsim_config_t *c, cpx i, double i_abc[3])
{
  if (ims_inverter_is_ideal(c)) {
    i_abc[0] = i_abc[1] = i_abc[2] = 0.0;
    return;
  }
  const double iab[2] = {i.re, i.im};
  imsim_ab_to_abc(iab, i_abc);
}

/* Sub-pieces of a piece [t0, t0 + len) for the device drops: a piece takes its leg voltages
   from the currents at its start, so a phase current that changes sign inside it would keep the
   old drop until the next switching instant (up to a half period minus the other edges: the
   drops then lag the current by a quarter of a period on average, against a real device, which
   hands the current from switch to diode as it crosses zero). Where a phase current can reach
   zero within the piece (its rate is at most 2 V_dc / (sigma L_S): the bus across the leakage,
   with as much again for the EMF), the piece is split into sub-pieces of at most h / 64, each
   taking the drops from its own start: the lag falls to at most 1/256 of a period. Not in the
   real-motor model: it integrates each piece sub-stepped, and 64 times that made a saturating
   motor's standstill commissioning run past its test's 600 s; it keeps the drops per piece. */
#define DROP_SUBSTEPS 64
static int drop_pieces(const imsim_t *s, double len, const double iabc[3])
{
  const imsim_config_t *c = &s->c;
  if (!ims_inverter_has_drops(c)) return 1;
  const double reach = 2.0 * c->vdc_v / (c->sigma * c->ls_h) * len;
  if (fabs(iabc[0]) > reach && fabs(iabc[1]) > reach && fabs(iabc[2]) > reach) return 1;
  const int n = (int)ceil(len * DROP_SUBSTEPS / s->h_s);
  return n < 1 ? 1 : n;
}

/* One constant-input piece of an integrator that is not the fast path (ctx: its state). */
typedef void (*piece_fn_t)(imsim_t *s, void *ctx, double len, cpx u, const step_input_t *in, double tl);

static void rm_piece(imsim_t *s, void *ctx, double len, cpx u, const step_input_t *in, double tl)
{
  (void)ctx;
  ims_rm_piece(s, len, u, in, tl);
}

static void rk4_piece(imsim_t *s, void *ctx, double len, cpx u, const step_input_t *in, double tl)
{
  ims_rk4_piece(s, (ims_full_state_t *)ctx, len, u, in, tl);
}

/* The half period split at its switching instants, each piece integrated with the inverter's
   voltage for the stator current at its start (*i_s, which the piece advances); the volt-seconds
   applied go to ph->act_avg unless the inverter is ideal. */
static void split_at_switching(imsim_t *s, pwm_half_t *ph, const cpx *i_s, piece_fn_t piece_fn, void *ctx,
                               const step_input_t *in, double tl, bool split_drops)
{
  const double h = s->h_s;
  double b[8], vs[2] = {0.0, 0.0};
  const int nb = ims_pwm_breaks(ph, h, b);
  for (int piece = 0; piece < nb - 1; ++piece) {
    if (b[piece + 1] <= b[piece]) continue;
    double iabc[3];
    piece_currents(&s->c, *i_s, iabc);
    const int n = split_drops ? drop_pieces(s, b[piece + 1] - b[piece], iabc) : 1;
    for (int q = 0; q < n; ++q) {
      const double t0 = b[piece] + (b[piece + 1] - b[piece]) * q / n;
      const double t1 = q + 1 == n ? b[piece + 1] : b[piece] + (b[piece + 1] - b[piece]) * (q + 1) / n;
      if (q > 0) piece_currents(&s->c, *i_s, iabc);
      const cpx u = ims_pwm_piece_voltage(s, ph, 0.5 * (t0 + t1), iabc);
      vs[0] += u.re * (t1 - t0);
      vs[1] += u.im * (t1 - t0);
      piece_fn(s, ctx, t1 - t0, u, in, tl);
    }
  }
  if (!ims_inverter_is_ideal(&s->c)) {
    ph->act_avg[0] = vs[0] / h;
    ph->act_avg[1] = vs[1] / h;
  }
}

void ims_advance(imsim_t *s, const step_input_t *in, pwm_half_t *ph, double tl)
{
  const imsim_config_t *c = &s->c;
  const double h = s->h_s;
  if (s->rm.on) {
    /* flux-linkage model: sub-stepped RK4, split at the switching instants */
    if (!in->pwm) {
      ims_rm_piece(s, h, cx(0.0, 0.0), in, tl);
      return;
    }
    split_at_switching(s, ph, &s->x[0], rm_piece, NULL, in, tl, false);
    return;
  }
  if (c->integrator == IMSIM_INTEGRATOR_FAST) {
    if (!in->pwm) {
      fast_piece(s, h, s->hk, in, tl, s->x[6], s->x[6], NULL);
    } else if (!in->piecewise) {
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
      double b[8];
      const int nb = ims_pwm_breaks(ph, h, b);
      const bool exact_act = !ims_inverter_is_ideal(c);
      double vs[2] = {0.0, 0.0};
      step_input_t lin;
      lin.pwm = false;
      lin.src = true;
      lin.aa = in->aa;
      lin.we = 0.0;
      lin.piecewise = false;
      const double norm = ims_a_norm(s, s->w, &lin);
      for (int piece = 0; piece < nb - 1; ++piece) {
        /* Pieces shorter than 1e-14 s (coincident edges up to rounding) are dropped: their
           volt-seconds (< 4e-12 V s) are negligible, and their h^k/k! would be denormal. */
        if (b[piece + 1] - b[piece] < 1e-14) continue;
        double iabc[3];
        piece_currents(c, s->x[0], iabc);
        const int n = drop_pieces(s, b[piece + 1] - b[piece], iabc);
        for (int q = 0; q < n; ++q) {
          const double t0 = b[piece] + (b[piece + 1] - b[piece]) * q / n;
          const double t1 = q + 1 == n ? b[piece + 1] : b[piece] + (b[piece + 1] - b[piece]) * (q + 1) / n;
          const double len = t1 - t0;
          if (q > 0) piece_currents(c, s->x[0], iabc);
          const cpx u = ims_pwm_piece_voltage(s, ph, 0.5 * (t0 + t1), iabc);
          vs[0] += u.re * len;
          vs[1] += u.im * len;
          double hkv[32];
          lin.p = ims_taylor_order_rho(norm * len);
          const int kmax = lin.p > 3 ? lin.p : 3;
          hkv[0] = 1.0;
          for (int k = 1; k <= kmax; ++k) hkv[k] = hkv[k - 1] * len * IMS_INV_K[k];
          s->x[6] = u;
          fast_piece(s, len, hkv, &lin, tl, u, u, NULL);
        }
      }
      s->x[6] = cx(0.0, 0.0);
      if (exact_act) {
        ph->act_avg[0] = vs[0] / h;
        ph->act_avg[1] = vs[1] / h;
      }
    }
    return;
  }
  /* RK4 reference, split at switching instants. */
  ims_full_state_t X;
  for (int q = 0; q < 7; ++q) X.x[q] = s->x[q];
  X.w = s->w;
  X.th = s->th;
  if (!in->pwm) {
    ims_rk4_piece(s, &X, h, cx(0.0, 0.0), in, tl);
  } else {
    split_at_switching(s, ph, &X.x[0], rk4_piece, &X, in, tl, true);
  }
  for (int q = 0; q < 7; ++q) s->x[q] = X.x[q];
  s->w = X.w;
  s->th = X.th;
  s->te = ims_torque_of(s, s->x[0], s->x[1]);
  s->acc = (s->te - tl - c->b_nms * s->w) / c->j_kgm2;
}
