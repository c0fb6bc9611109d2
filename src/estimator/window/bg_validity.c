/* SPDX-License-Identifier: Apache-2.0 */
/* Background stage: is this window's estimate trustworthy, and for which
 * parameter? The first reason found, most fundamental first, becomes the
 * reason; T_R and R_S get their own verdicts (R_S is far more sensitive to
 * the voltage's and the timing's errors than T_R). imest__bg_judge() runs
 * the ordered lists of checks at the end of this file (TR_CHECKS, RS_CHECKS). A threshold a user
 * tunes is a config field (each table row names it); a threshold physics
 * fixes is a named constant below, with its reason. README "When is a window
 * valid" and docs/METHOD.md §13 give the measurements behind the defaults.
 * Every evidence is dimensionless: the same rule holds for any motor size. */
#include <math.h>
#include <stddef.h>

#include "bg_impedance.h"
#include "bg_transient.h"
#include "bg_validity.h"
#include "common/imest_math.h"
#include "estimator/solve/bg_float.h" /* BG_FMAXF...: no libm fmaxf on a core without VMAXNM */

/* The window's operating point, from its sums: stator frequency, slip,
 * power and impedance (power-invariant alpha/beta: the power is the motor's).
 * float32 throughout this file: every evidence is a ratio, and the FPU's
 * arithmetic keeps the verdict small and fast on a single-precision core. */
typedef struct {
  float we;    /* stator (field) frequency [rad/s]: the current's rotation in the stator frame */
  float slip;  /* slip fraction: the rotor-frame current's rotation / we */
  float p_w;   /* mean electrical power u.i [W] */
  float s_va;  /* mean |u| |i| [VA] */
  float z_ohm; /* |u| / |i| [ohm] */
  float i2;    /* mean |i|^2 [A^2] */
  float i_pk;  /* peak phase current of the fundamental [A] */
} op_point_t;

/* a sign-type error dV has the fundamental (4/pi) dV */
#define FOUR_OVER_PI_F (4.0f / IMEST_PI_F)

/* Constants of the checks (their reasons where they are used):
 * R_S within what heating explains around its nominal: 20 C .. 200 C copper
 * and a 10 % data-sheet error. */
#define RS_NOMINAL_MIN     0.7f
#define RS_NOMINAL_MAX     1.9f
/* T_R within its band around a known nominal: the rotor heats (T_R falls to
 * about 0.6 of cold) and data-sheet values are off. */
#define TR_NOMINAL_MIN     0.45f
#define TR_NOMINAL_MAX     1.5f
/* L_S at no load that differs from ls_h by more than this cannot be the motor's. */
#define LS_NOLOAD_TOL      0.06f
/* No load: slip ratio below this (L_S measured 1 % low), field above 5 Hz. */
#define NOLOAD_SLIP_RATIO  0.1f
#define NOLOAD_MIN_HZ      5.0f
/* At rest: the mean speed below this (about 10 rpm; an encoder toggling by
 * a count averages to zero here). */
#define AT_REST_RAD_S      1.0f
/* A current-sensor gain mismatch |E| worth flagging (0.2 %). */
#define GAIN_MISMATCH_FLAG 0.002f
/* The wiring checks: judged above this field frequency only. */
#define WIRING_MIN_HZ      2.0f

static void operating_point(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                            op_point_t *op)
{
  const float n = nreg > 0u ? (float)nreg : 1.0f;
  const float slip_rate = st->slip_rate;
  op->we = (float)(slip_rate + s->n * st->w_mean);
  op->slip = fabsf(op->we) > 0.0f ? slip_rate / op->we : 0.0f;
  /* W1.W4 - W2.W4 = u.i / (sigma L_S) exactly (i_perp.i = 0) */
  op->p_w = (float)((float)(sm->rw[0][3] - sm->rw[1][3]) / s->inv_s / n);
  const float i2 = BG_FMAXF((float)sm->rw[3][3] / n, 0.0f), u2 = BG_FMAXF(2.0f * st->u_ms, 0.0f);
  op->i2 = i2;
  op->s_va = sqrtf(i2 * u2); /* balanced: |u|^2 = 2 u_alpha^2 */
  op->z_ohm = i2 > 0.0f ? sqrtf(u2 / i2) : 0.0f;
  op->i_pk = sqrtf(i2 * (2.0f / 3.0f)); /* |i_alphabeta| = sqrt(3/2) phase peak */
}

/* The data contradict the conventions the config says (README remedies):
 * - the rotor-frame current turns faster than the field (slip > 1.25): the
 *   rotor would turn against its field at steady speed. An encoder counting
 *   backwards gives 2.
 * - negative slip while the motor takes power: generating gives power back.
 *   Phases b and c swapped, or the electrical angle given for the
 *   mechanical, give -1 (with 2 pole pairs). And motoring slip while power
 *   flows back: the currents' sign.
 * - a slip of half the field or more at a slip frequency no motor reaches
 *   (5 Hz, above breakdown for motors from 0.4 kW up): pole pairs half the
 *   motor's, or an angle in the wrong unit.
 * - an impedance no motor with these constants has: below a third of the
 *   leakage reactance, or above three times the magnetising one plus a
 *   generous R_S (currents in mA, volts for kilovolts ...).
 * Judged only with a stator frequency above 2 Hz and real power flowing. */
static int wiring_mismatch(const imest_t *s, const op_point_t *op)
{
  const float we = fabsf(op->we);
  if (!(we > IMEST_2PI_F * WIRING_MIN_HZ) || !(op->s_va > 0.0f)) return 0;
  const float ls = s->ls_h, sl = s->sigma * ls;
  if (op->slip > 1.25f) return 1;
  if (op->slip < -0.25f && op->p_w > 0.1f * op->s_va) return 1;
  if (op->slip > 0.02f && op->p_w < -0.1f * op->s_va) return 1;
  if (op->slip > 0.45f && fabsf(op->slip) * we > IMEST_2PI_F * 5.0f) return 1;
  if (op->z_ohm < we * sl / 3.0f) return 1;
  const float rs_max = (s->rs_nominal_ohm > 0.0f) ? 3.0f * s->rs_nominal_ohm : 10.0f * we * ls;
  return op->z_ohm > 3.0f * we * ls + rs_max;
}

/* The error's shape near the zero crossings (the ripple's, the devices'
 * capacitances) is not known to better than this share of it even when every
 * number of the model is exact: with the numbers exact and stated 3 %
 * uncertain, T_R at 25 % load was valid and 1.0-1.9 % off (2.2 / 4 kW,
 * 1-3 us); the harmonics' bounds take at least that. */
#define SHAPE_FLOOR 0.2f

/* The inverter model's error in the window as the harmonics' bounds need it
 * (duty input with a known uncertainty; else all 0). */
typedef struct {
  float shape_v; /* the uncertainty whose harmonics T_R sees [V] (the fitted term) */
  float sign_v;  /* the model's sign-type error, the part with harmonics [V]: the dead time's and the
                    thresholds' (V_sw0 + V_d0)/2, and the switch-diode differences' half; not the
                    slopes' mean (r_sw + r_d)/2 i, a resistance */
  float u;       /* its relative uncertainty for the harmonics, at least SHAPE_FLOOR */
  /* a deep-bar rotor (rotor_hf_rr_ratio): the largest sign-type error the inverter's harmonics can
     have, the model's up to 1 / (1 - u) [V] (either input; INFINITY: not known, 0: no term) */
  float hf_v;
} inv_share_t;

/* The sign-type part of an inverter model's error, the part with harmonics [V] (inv_share_t.sign_v). */
static float sign_error(const imest_inverter_t *v, float dead, float a)
{
  return fabsf(dead + 0.5f * (v->v_switch_v + v->v_diode_v)) +
         0.5f * (fabsf(v->v_switch_v - v->v_diode_v) + fabsf(v->r_switch_ohm - v->r_diode_ohm) * a);
}

/* The dead time's harmonics a deep-bar rotor sees (docs/METHOD.md §18.1): the duty input's own
 * model and bus; measured phase voltages: the configured model and bus (inverter_vdc_v), nothing
 * from a smooth source (voltage_kind: no inverter), unknown (INFINITY) without either. The
 * harmonics are taken as a square wave's, 1 / |k| of the fundamental, which bound those of any
 * smoothing of the sign near the zero crossings (a positive kernel only lowers them): the shape
 * floor is not needed here, only the model's numbers' uncertainty (the truth up to 1 / (1 - u)). */
static float rotor_hf_share(const imest_t *s, const imest_window_t *w, float a)
{
  if (!IMEST_WITH_ROTOR_HF || !(s->rotor_hf_rr_ratio > 0.0f)) return 0.0f;
  if (!w->duty_input && !(s->t_stair_s[0] > 0.0f)) return 0.0f; /* a smooth source */
  const imest_inverter_t *v = &s->inverter;
  const float vdc = w->duty_input ? (float)w->vdc_v : s->inverter_vdc_v;
  const float u = v->uncertainty;
  if (!(u >= 0.0f && u < 1.0f) || !(vdc > 0.0f)) return INFINITY;
  return sign_error(v, v->dead_time_s * s->pwm_hz * vdc, a) / (1.0f - u);
}

/* The uncertainty of the voltage's fundamental per phase [V]: the inverter
 * model's error at this current times its relative uncertainty (duty input),
 * or u_uncertainty_v (measured voltages); negative: unknown. *h: what the
 * harmonics' bounds take. */
static float voltage_uncertainty(const imest_t *s, const imest_window_t *w, const op_point_t *op,
                                 inv_share_t *h)
{
  h->shape_v = 0.0f;
  h->sign_v = 0.0f;
  h->u = 0.0f;
  const float a = op->i_pk;
  h->hf_v = rotor_hf_share(s, w, a);
  if (!w->duty_input) return s->u_uncertainty_v;
  const imest_inverter_t *v = &s->inverter;
  if (v->uncertainty < 0.0f) return -1.0f;
  const float dead = v->dead_time_s * s->pwm_hz * (float)w->vdc_v;
  const float e = fabsf(dead + v->v_diode_v + v->r_diode_ohm * a +
                        0.5f * ((v->v_switch_v - v->v_diode_v) + (v->r_switch_ohm - v->r_diode_ohm) * a));
  const float dv = v->uncertainty * e;
  h->shape_v = BG_FMAXF(dv, SHAPE_FLOOR * e);
  h->sign_v = sign_error(v, dead, a);
  h->u = BG_FMAXF(v->uncertainty, SHAPE_FLOOR);
  return dv;
}

/* Error bounds of T_R and R_S from the systematic errors the config states,
 * through the motor's steady-state impedance Z = R_S + j we L_S (1 + j sigma a)
 * / (1 + j a), a = slip frequency x T_R (docs/METHOD.md §18):
 * - a voltage error in phase with the current (the inverter's, sign-type:
 *   fundamental (4/pi) dV) moves Re Z only, i.e. R_S only, by (4/pi) dV / I;
 * - a timing error tau turns Z by -j we tau: R_S and T_R both move. Twice
 *   the first-order sensitivity, which the simulator shows to be about half
*   the measured effect (the delay also moves the currents against the angle).
 * - the PWM staircase's aliased images (docs/METHOD.md §17.2) add
 *   -(T^2 / 12 sigma L_S) du/dt to the sampled current: the admittance gains
 *   -j eps, eps = we T^2 / (12 sigma L_S), so Z gains j eps Z^2 and Re Z
 *   -2 eps Re Z Im Z, all of it R_S. With measured phase voltages (not
 *   corrected: the source may be smooth) the whole effect is uncertain, unless
 *   the config says the source is smooth (voltage_kind: t_stair_s 0, no
 *   images); the duty input corrects it to within about 20 % (measured),
 *   30 % is kept.
 *   Measured on 11 kW at rated speed, half load, 8 kHz: R_S -8.3 %; this
 *   term says 9 %. It scales with (we T)^2 and |Z|^2 / R_S: high speed,
 *   large motors, light load.
 * - the inverter model's uncertain share (duty input) is sign-type too: its
 *   harmonics (1/5, 1/7 ... of the fundamental) drive current harmonics at a
 *   slip near 1, where the rotor resistance (1 - sigma) L_S / T_R is in series,
 *   so the fit reads them as T_R. No first-order formula; on the simulator
 *   (2.2-37 kW, 0-3 us, 1 V drops, model exact or 20 % off) T_R moved by 0.2
 *   to 0.45 times what the in-phase term (4/pi) dV / I would move it taken in
 *   quadrature (largest at 25 % load, where dZ/dT_R is small). The bound
 *   takes 0.5 times it, in Im Z, as a measured floor beside the derived
 *   share (inverter_harmonics(), bounds()).
 * - the constants' stated uncertainty (ls_uncertainty, sigma_uncertainty):
 *   the fit matches the measured Z with the configured L_S and sigma, so an
 *   error of theirs moves T_R and R_S (imest__bg_constants_shift, first
 *   order: within 25 % of the exact move for L_S, 3 % for sigma), taken at
 *   e = u (1 + u) / (1 - u) of the stated u (imest_init.c: the motor's value
 *   up to u / (1 - u) away, and the second order). |move| for
 *   L_S plus |move| for sigma, not in quadrature: commissioning's sigma is
 *   sigma L_S / L_S, its two errors are correlated. *c_tr_rel, *c_rs_rel:
 *   this share alone (the reason constants_uncertain); it is also in the
 *   totals *tr_rel, *rs_rel.
 * dv_v: the voltage uncertainty [V] (negative: unknown); harm_v: the
 * uncertainty whose harmonics T_R sees (duty input; 0 otherwise). */
static void systematic_bounds(const imest_t *s, const imest_window_t *w, const op_point_t *op,
                              float slip_rate, float tr, float rs, float dv_v, float harm_v, float *tr_rel,
                              float *rs_rel, float *c_tr_rel, float *c_rs_rel, float dw_rad_s,
                              float *x_tr_rel, float *x_rs_rel)
{
  const float we = op->we, ls = s->ls_h, sg = s->sigma;
  bg_impedance_t z;
  imest__bg_impedance(we, slip_rate, ls, sg, tr, rs, &z);
  const float zr = z.zr, zi = z.zi, dr = z.dr, di = z.di;
  const float tau = 2.0f * s->timing_uncertainty_s;
  const float t_pwm = s->t_stair_s[w->duty_input]; /* duty_input is 0 or 1; 0: a smooth source */
  const float share = (w->duty_input && s->duty.zoh > 0.0f) ? 0.3f : 1.0f;
  const float eps = share * fabsf(we) * t_pwm * t_pwm / (12.0f * sg * ls);
  const float dzr = fabsf(we) * tau * fabsf(zi) + eps * 2.0f * fabsf(zr * zi);
  const float harm = 0.5f * FOUR_OVER_PI_F * harm_v / op->i_pk;
  const float dzi = fabsf(we) * tau * fabsf(zr) + eps * fabsf(zr * zr - zi * zi) + harm;
  const float dt = fabsf(di) > 0.0f ? dzi / fabsf(di) : INFINITY;
  /* L_S's move, then sigma's (one copy of the shift in the code) */
  *c_tr_rel = 0.0f;
  *c_rs_rel = 0.0f;
  for (int k = 0; k < 2; ++k) {
    float t, r;
    imest__bg_constants_shift(&z, sg, k == 0 ? s->ls_shift_e : 0.0f, k == 0 ? 0.0f : s->sigma_shift_e, tr, rs,
                              &t, &r);
    *c_tr_rel += fabsf(t);
    *c_rs_rel += fabsf(r);
  }
  /* a speed step through the angle observer (bg_transient.c) */
  imest__bg_transient_share(s, &z, dw_rad_s, slip_rate, tr, rs, x_tr_rel, x_rs_rel);
  *tr_rel = dt / tr + *c_tr_rel + *x_tr_rel;
  const float dr_volt = dv_v < 0.0f ? INFINITY : FOUR_OVER_PI_F * dv_v / op->i_pk;
  *rs_rel = (dzr + fabsf(dr) * dt + dr_volt) / rs + *c_rs_rel + *x_rs_rel;
}

/* The current sensors' gain mismatch from the zero sequence (three sensors:
 * i_a + i_b + i_c is the sensors' error), as the complex pattern E = sum_x
 * eps_x e^(-j 2 pi x / 3) of the per-phase gain errors: |E| (0 with two
 * sensors, where the third is computed and the zero sequence is exactly 0). */
static float gain_mismatch(const imest_window_t *w, float s2)
{
  if (!(s2 > 0.0f)) return 0.0f;
  const float ca = (float)(w->sum[IMEST_ACC_I0A] + w->blk[IMEST_ACC_I0A]);
  const float cb = (float)(w->sum[IMEST_ACC_I0B] + w->blk[IMEST_ACC_I0B]);
  return IMEST_SQRT3_2_F * sqrtf(ca * ca + cb * cb) / s2;
}

/* The L_S a no-load window is compared with: ls_h, or the magnetising
 * curve's at the window's flux-producing current |i| / sqrt(1 + slip ratio^2);
 * *tol: 6 %, plus the curve's own uncertainty there. */
static float noload_ls_ref(const imest_t *s, const op_point_t *op, float slip_ratio, float *tol)
{
  float err_h;
  const float ls = imest__bg_flux_ls(s, sqrtf(op->i2 / (1.0f + slip_ratio * slip_ratio)), &err_h);
  *tol = LS_NOLOAD_TOL + err_h / ls;
  return ls;
}

/* L_S at no load: the reactance the motor shows with (nearly) no rotor
 * current is w_e L_S (slip ratio 0.1: 1 % lower), the reactive power over
 * |i|^2. A configured L_S that differs by more than 6 % cannot be the motor's:
 * at one operating point the estimator absorbs it in T_R and R_S (L_S 10 %
 * high: T_R +11 %, R_S -42 %, residual unchanged), so this is the only place
 * it shows. Latched: every later window is constants_mismatch. With a
 * magnetising curve the configured L_S is the curve's at this window's
 * current (noload_ls_ref): a saturating motor at no load at another voltage
 * than ls_h's is not a mismatch. */
static void noload_ls_check(imest_t *s, const op_point_t *op, float slip_ratio, int steady, imest_result_t *r)
{
  const float we = fabsf(op->we);
  if (!(steady && slip_ratio < NOLOAD_SLIP_RATIO && we > IMEST_2PI_F * NOLOAD_MIN_HZ && op->i2 > 0.0f &&
        op->s_va > 0.0f))
    return;
  const float q = sqrtf(BG_FMAXF(0.0f, op->s_va * op->s_va - op->p_w * op->p_w));
  const float ls_meas = q / op->i2 / we;
  r->ls_noload_h = (double)ls_meas;
  float tol;
  const float dev = ls_meas / noload_ls_ref(s, op, slip_ratio, &tol) - 1.0f;
  s->ls_check = (fabsf(dev) > tol) ? 2u : (s->ls_check == 2u ? 2u : 1u);
}

/* Everything a check reads: the window, its statistics and sums, the solve,
 * the result filled so far (the estimate, its error indices and bounds). */
typedef struct {
  imest_t *s; /* the no-load L_S check latches its finding in s->ls_check */
  const imest_window_t *w;
  const bg_window_stats_t *st;
  const bg_solve_out_t *so;
  imest_result_t *r;
  op_point_t op;
  /* The result's figures the checks compare, in float32 (converted once,
   * in imest__bg_judge): every check is a comparison with a float32 config
   * value or a product of float32 constants, and a figure rounded to float32
   * (relative 6e-8) against a threshold can change a verdict only where the
   * float64 figure lies within that of the threshold: at the edge, where
   * either verdict is as right. Finiteness is judged on the float64 figures
   * (imest__bg_finite): a finite float64 beyond FLT_MAX stays finite. */
  float tr, rs, e_i, e_i_noise, pe_k2_rel;
  int steady;
  float tr_b, rs_b, g_b; /* T_R's and R_S's systematic bounds, the gain mismatch's share */
  float c_tr, c_rs;      /* the constants' share of tr_b and rs_b (in them) */
  float x_tr, x_rs;      /* a transient's share of tr_b and rs_b (in them; bg_transient.c) */
  /* The bounds are steady-state figures: T_R's is judged only below the
   * pull-out slip (a sigma < 1), where a drive runs steadily; beyond it the
   * window is a transient (a run-up) whose dynamics determine T_R. */
  int tr_judged;
} judge_t;

static inline int input_fault(judge_t *j)
{
  return (j->r->flags & IMEST_FLAG_INPUT_FAULT) != 0u;
}
static inline int adc_saturation(judge_t *j)
{
  return (j->r->flags & IMEST_FLAG_ADC_SAT) != 0u;
}
static inline int encoder_fault(judge_t *j)
{
  return (j->r->flags & IMEST_FLAG_ENCODER_FAULT) != 0u;
}
/* warm-up samples are not accumulated; the rest of the window is clean data,
 * so warm-up invalidates a window only when it took half of it */
static inline int warmup(judge_t *j)
{
  return (j->r->flags & IMEST_FLAG_WARMUP) && 2u * j->r->used_samples < j->r->samples;
}
/* min_current_a. i_rms_a is what passed the offset high-pass. A DC current it
 * removed (magnetising at rest) is in the tracked means: that rotor is at
 * rest with excitation, not without current. */
static inline int low_current(judge_t *j)
{
  return !(j->st->i_rms_a >= j->s->min_current_a);
}
static inline int low_current_at_rest(judge_t *j)
{
  const float ia = (float)j->w->off_ia, ib = (float)j->w->off_ib;
  const int dc = sqrtf(ia * ia + ib * ib) >= j->s->min_current_a;
  return low_current(j) && dc && fabsf(j->st->w_mean) < AT_REST_RAD_S;
}
/* ls_h, sigma, pole_pairs, rs_nominal_ohm */
static inline int wiring(judge_t *j)
{
  return wiring_mismatch(j->s, &j->op);
}
/* ls_h (latched: once L_S at no load disagrees, every later window) */
static inline int ls_mismatch(judge_t *j)
{
  noload_ls_check(j->s, &j->op, (float)j->r->slip_ratio, j->steady, j->r);
  return j->s->ls_check == 2u;
}
/* min_slip_ratio */
static inline int low_slip(judge_t *j)
{
  return !((float)j->r->slip_ratio >= j->s->min_slip_ratio); /* slip_ratio is a float32 product */
}
static inline int low_slip_at_rest(judge_t *j)
{
  return low_slip(j) && fabsf(j->st->w_mean) < AT_REST_RAD_S;
}
static inline int solve_numeric(judge_t *j)
{
  return j->so->status == IMEST_REASON_NUMERIC;
}
/* tr_min_s, tr_max_s */
static inline int solve_no_root(judge_t *j)
{
  return j->so->status != IMEST_OK;
}
static inline int not_minimum(judge_t *j)
{
  return !j->so->hessian_pd;
}
/* max_pe_k2_rel. The parametric error index does not shrink with the span
 * (the residual and the cost's curvature both grow with it); the part of the
 * estimate's error that the sensors' white noise causes does, as
 * 1/sqrt(windows), but a systematic part (an inverter's or a model's error,
 * the same in every window) does not. The index is split by the residual's
 * shares, the noise's (e_i_noise^2 / e_i^2) and the rest's, and only the
 * noise's is credited the n windows: pe^2 (1 - f + f / n) against
 * max_pe_k2_rel^2. */
static inline int poorly_determined(judge_t *j)
{
  /* float32: e_i, e_i_noise ~1e-3..10 and pe ~1e-4..1e30 (BG_PE_UNBOUNDED)
   * squared stay inside float32's range (pe^2 of an unbounded index is
   * inf: poorly determined, as in float64); a few roundings of 6e-8 */
  const float ei = j->e_i, en = j->e_i_noise, pe = j->pe_k2_rel, lim = j->s->max_pe_k2_rel;
  const float f = ei > 0.0f ? BG_FMINF(1.0f, (en * en) / (ei * ei)) : 1.0f;
  const float pe2 = pe * pe * ((1.0f - f) + f / (float)j->r->windows);
  return !(pe2 <= lim * lim);
}
/* max_ei: the residual beyond what the sensors' white noise explains */
static inline int high_residual(judge_t *j)
{
  /* float32: E_I and its noise share are O(1e-3..10); the difference of
   * their squares loses only what a 6e-8 rounding of each is worth */
  const float em = sqrtf(BG_FMAXF(0.0f, j->e_i * j->e_i - j->e_i_noise * j->e_i_noise));
  return !(em <= j->s->max_ei);
}
/* rs_min_ohm, rs_max_ohm */
static inline int rs_out_of_range(judge_t *j)
{
  return !(j->rs >= j->s->rs_min_ohm && j->rs <= j->s->rs_max_ohm);
}
/* rs_nominal_ohm: constants that cannot be the motor's */
static inline int rs_off_nominal(judge_t *j)
{
  const float rn = j->s->rs_nominal_ohm;
  return rn > 0.0f && !(j->rs >= RS_NOMINAL_MIN * rn && j->rs <= RS_NOMINAL_MAX * rn);
}
/* tr_nominal_s (when given) */
static inline int tr_off_nominal(judge_t *j)
{
  const float tn = j->s->tr_nominal_s;
  return j->s->tr_nominal_known && !(j->tr >= TR_NOMINAL_MIN * tn && j->tr <= TR_NOMINAL_MAX * tn);
}
/* never a confident non-finite number */
static inline int not_finite(judge_t *j)
{
  return !(imest__bg_finite(j->r->tr_s) && imest__bg_finite(j->r->rs_ohm) && imest__bg_finite(j->r->e_i));
}
/* tr_tolerance, ls_uncertainty, sigma_uncertainty: the constants' share alone
 * (judged where T_R's bound is: j->tr_judged) */
static inline int tr_constants_uncertain(judge_t *j)
{
  return j->tr_judged && !(j->c_tr <= j->s->tr_tolerance);
}
/* tr_tolerance: a load or speed step inside the window alone (judged where
 * T_R's bound is), or a swing that reaches zero slip (bounds()) */
static inline int tr_transient(judge_t *j)
{
  return j->tr_judged && !(j->x_tr <= j->s->tr_tolerance);
}
/* tr_tolerance */
static inline int tr_uncertain(judge_t *j)
{
  return j->tr_judged && !(j->tr_b <= j->s->tr_tolerance);
}
/* rs_tolerance: the current sensors' gain mismatch takes most of R_S's bound */
static inline int rs_gain_mismatch(judge_t *j)
{
  return !(j->rs_b + j->g_b <= j->s->rs_tolerance) && j->g_b > j->rs_b;
}
/* rs_tolerance: a load or speed step inside the window alone, or a swing that
 * reaches zero slip */
static inline int rs_transient(judge_t *j)
{
  return !(j->x_rs <= j->s->rs_tolerance);
}
/* rs_tolerance, ls_uncertainty, sigma_uncertainty: the constants' share alone */
static inline int rs_constants_uncertain(judge_t *j)
{
  return !(j->c_rs <= j->s->rs_tolerance);
}
/* rs_tolerance */
static inline int rs_uncertain(judge_t *j)
{
  return !(j->rs_b + j->g_b <= j->s->rs_tolerance);
}

/* The checks in order, as X(reason, predicate): a window gets the reason of
 * the first check it fails, most fundamental first (the predicates above say
 * which config field each reads). An X-list, not a table in memory: it
 * expands into the chain of tests, as small as one written by hand. */
#define TR_CHECKS(X)                                                                                         \
  X(IMEST_REASON_INPUT_FAULT, input_fault)                                                                   \
  X(IMEST_REASON_ADC_SATURATION, adc_saturation)                                                             \
  X(IMEST_REASON_ENCODER_FAULT, encoder_fault)                                                               \
  X(IMEST_REASON_WARMUP, warmup)                                                                             \
  X(IMEST_REASON_STANDSTILL, low_current_at_rest)                                                            \
  X(IMEST_REASON_NO_CURRENT, low_current)                                                                    \
  X(IMEST_REASON_WIRING_MISMATCH, wiring)                                                                    \
  X(IMEST_REASON_CONSTANTS_MISMATCH, ls_mismatch)                                                            \
  X(IMEST_REASON_STANDSTILL, low_slip_at_rest)                                                               \
  X(IMEST_REASON_ZERO_SLIP, low_slip)                                                                        \
  X(IMEST_REASON_NUMERIC, solve_numeric)                                                                     \
  X(IMEST_REASON_NO_ROOT, solve_no_root)                                                                     \
  X(IMEST_REASON_NOT_MINIMUM, not_minimum)                                                                   \
  X(IMEST_REASON_POORLY_DETERMINED, poorly_determined)                                                       \
  X(IMEST_REASON_HIGH_RESIDUAL, high_residual)                                                               \
  X(IMEST_REASON_RS_OUT_OF_RANGE, rs_out_of_range)                                                           \
  X(IMEST_REASON_CONSTANTS_MISMATCH, rs_off_nominal)                                                         \
  X(IMEST_REASON_CONSTANTS_MISMATCH, tr_off_nominal)                                                         \
  X(IMEST_REASON_NUMERIC, not_finite)                                                                        \
  X(IMEST_REASON_TRANSIENT, tr_transient)                                                                    \
  X(IMEST_REASON_CONSTANTS_UNCERTAIN, tr_constants_uncertain)                                                \
  X(IMEST_REASON_TR_UNCERTAIN, tr_uncertain)

/* R_S's own checks, once T_R's verdict is valid. */
#define RS_CHECKS(X)                                                                                         \
  X(IMEST_REASON_GAIN_MISMATCH, rs_gain_mismatch)                                                            \
  X(IMEST_REASON_TRANSIENT, rs_transient)                                                                    \
  X(IMEST_REASON_CONSTANTS_UNCERTAIN, rs_constants_uncertain)                                                \
  X(IMEST_REASON_RS_UNCERTAIN, rs_uncertain)

#define RETURN_IF_FAILS(reason, fails)                                                                       \
  if (fails(j)) return (reason);

static int tr_verdict(judge_t *j)
{
  TR_CHECKS(RETURN_IF_FAILS)
  return IMEST_REASON_NONE;
}

static int rs_verdict(judge_t *j)
{
  RS_CHECKS(RETURN_IF_FAILS)
  return IMEST_REASON_NONE;
}

/* Harmonic pairs of the inverter's sign-type error the derived share sums
 * (the 5th and 7th ... the 95th and 97th): the filter and the 1/k of a sign
 * wave leave the rest below 1e-4 of the first pair's share wherever the
 * 5th passes the filter (the share grows as 1/k^2 G^2, G^2 ~ (w_c / w)^6). */
#define HARMONIC_PAIRS  16
/* power-invariant alpha/beta: a balanced set of phase amplitude A has |.| = sqrt(3/2) A */
#define AB_PER_PHASE_F  1.2247449f
/* the deep-bar rotor's share: twice its first-order move (inverter_harmonics) */
#define ROTOR_HF_MARGIN 2.0f

#if IMEST_WITH_ROTOR_HF
/* The deep-bar rotor's one pole as inverter_harmonics() needs it */
typedef struct {
  float ehh; /* |E_1|^2 / (sigma L_S) of the largest error (hf_v has the 1 / (1 - u)) [V^2/H] */
  float rm1; /* rr ratio - 1 */
  float tau; /* the pole x = w_k tau: (1 - sigma ratio) sigma T_R / ((rr ratio - 1) (1 - sigma)) [s] */
} rotor_hf_t;

static void rotor_hf_setup(const imest_t *s, const inv_share_t *h, float lin, float tr, rotor_hf_t *rh)
{
  const float eh = lin * h->hf_v, sg = s->sigma;
  rh->ehh = eh * eh * (float)s->inv_s;
  rh->rm1 = s->rotor_hf_rr_ratio - 1.0f;
  rh->tau = (1.0f - s->rotor_hf_sigma_ratio) * sg * tr / (rh->rm1 * (1.0f - sg));
}

/* Z_k of the deep-bar rotor's motor at the harmonic k w_e, rotor frequency wk: the rotor branch
 * R_R' rho, rho = 1 + (rr ratio - 1) x^2 / (1 + j x) (1 at slip frequency; rr ratio R_R' and the
 * leakage (1 - sigma ratio) sigma L_S lower at high frequency):
 * Z = R_S + j w L_S (sigma + (1 - sigma) / (1 + j a / rho)), a = w_k T_R, with
 * 1 / (1 + j a / rho) = N / (N + j a (1 + j x)), N = 1 + (rr ratio - 1) x^2 + j x */
static void rotor_hf_z(const imest_t *s, const rotor_hf_t *rh, float tr, float rs, float kwe, float wk,
                       float *zr, float *zi)
{
  const float sg = s->sigma, xh = wk * rh->tau, a = wk * tr;
  const float nr = 1.0f + rh->rm1 * xh * xh, dr = nr - a * xh, di = xh + a, inv = 1.0f / (dr * dr + di * di);
  const float lr = (nr * dr + xh * di) * inv, li = (xh * dr - nr * di) * inv;
  const float wl = kwe * s->ls_h;
  *zr = rs - wl * (1.0f - sg) * li;
  *zi = wl * (sg + (1.0f - sg) * lr);
}

/* One harmonic's move of the fit by the rotor's deviation: the voltage the single cage would need
 * for the data's current is off by eps_k E_k, eps_k = 1 - Z_k / Z_k,double = 1 - Z_k y;
 * Re(eps y*) |K2 + j w_k|^2 and Re(eps t), t = (K2 + j w_k) conj(m y F), each harmonic's move
 * summed in magnitude (their phases are the rotor's, which the one-pole description does not
 * pin). gk: k^2 / G^2 of the harmonic; zk: the single cage's Z_k; y = 1 / Z_k,double; q2 = (K2, w_k);
 * p = m y F; hs = (h11, h12, h22) */
static void rotor_hf_move(const rotor_hf_t *rh, float gk, const bg_impedance_t *zk, float yr, float yi,
                          float dd, float tr_, const float q2[2], float pr, float pi, const float hs[3],
                          float *a1, float *a2)
{
  const float wh = rh->ehh / gk; /* G^2 |E_k|^2 / (sigma L_S) */
  const float cr = 1.0f - (zk->zr * yr - zk->zi * yi), ci = -(zk->zr * yi + zk->zi * yr);
  const float u1 = wh * dd * (cr * yr + ci * yi), u2 = wh * (cr * tr_ - ci * (q2[1] * pr - q2[0] * pi));
  *a1 += fabsf(hs[2] * u1 - hs[1] * u2);
  *a2 += fabsf(hs[0] * u2 - hs[1] * u1);
}
#endif /* IMEST_WITH_ROTOR_HF */

/* How far the inverter model's uncertain share can move K1 and K2 through
 * its harmonics (docs/METHOD.md §18.1), derived per window from the fit
 * itself rather than fitted to a table. A sign-type leg error of amplitude A
 * has the harmonics k = -5, 7, -11, 13 ... (alpha/beta, signed by their
 * sequence) of amplitude sqrt(3/2) (4/pi) A / |k|, at the rotor-frame
 * frequency w_k = (k - 1) w_e + w_s. The cost E_w is, at a steady speed, the
 * sum over the samples of |q|^2, q = dz/dt + K2 z - m (1 - j n w / K2) K2^2 i,
 * z = di/dt - u/(sigma L_S) + K1 i + j n w i (docs/METHOD.md §2.3), every
 * channel through the same low-pass G. A voltage error dU_k moves q by
 * dq_k = G (j w_k + K2) dU_k / (sigma L_S), and through the gradient
 * 2 N sum_k Re(dq_k conj(dq_k/dK)) the minimiser by -H^-1 of that, H the
 * cost's Hessian (the result's). dq/dK1 = G (j w_k + K2) i_k and dq/dK2 = G
 * (z_k - m (2 K2 - j n w) i_k), z_k = m K2 (K2 - j n w) i_k / (j w_k + K2)
 * (the rotor flux's harmonic), i_k the current's harmonic: the data's error
 * harmonic (the model's error e, up to (1 + u) of it) over the motor's
 * impedance at k w_e and the slip w_k. Every term is taken at its largest
 * (|cos| = 1, magnitudes summed); the digital filter's gain is below the
 * analogue one at 2 f_s tan(pi f_c / f_s) (tan x >= x). Not counted: the
 * fundamental (in phase with the current: R_S only, exactly) and the
 * harmonics aliased beyond f_s / 2. *dk1, *dk2: the largest moves [1/s], the
 * model's and, with a deep-bar rotor, the rotor's (rotor_hf_move()); infinite
 * where H is not positive definite or the harmonics are not bounded. */
static void inverter_harmonics(const judge_t *j, const inv_share_t *h, float slip_rate, float *dk1,
                               float *dk2)
{
  const imest_t *s = j->s;
  const imest_result_t *r = j->r;
  *dk1 = 0.0f;
  *dk2 = 0.0f;
  const int model = h->sign_v > 0.0f, hf = IMEST_WITH_ROTOR_HF && h->hf_v > 0.0f;
  if (!model && !hf) return;
  const float h11 = (float)r->hessian[0][0], h12 = (float)r->hessian[0][1], h22 = (float)r->hessian[1][1];
  const float det = h11 * h22 - h12 * h12;
  /* infinite where H is not positive definite, or the harmonics are not bounded */
  const int pd = h11 > 0.0f && det > 0.0f && isfinite(det);
  if ((model && !(pd && h->u < 1.0f)) || (hf && !(pd && isfinite(h->hf_v)))) {
    *dk1 = *dk2 = INFINITY;
    return;
  }
  const float we = j->op.we, k2 = 1.0f / j->tr, nw = we - slip_rate, m = (float)s->m;
  const float b0 = (float)s->bw.b0, kb = b0 / (1.0f - b0); /* tan(pi f_c / f_s) of the first section */
  const float wq = 2.0f * (float)s->fs * kb;
  const float lin = AB_PER_PHASE_F * FOUR_OVER_PI_F;
  /* eps |E_1|^2 / (sigma L_S). The model within u of the truth puts the truth up to 1 / (1 - u) of
   * the model's, and the model's error up to u / (1 - u) of it from the truth */
  const float e1 = model ? lin * h->sign_v / (1.0f - h->u) : 0.0f;
  const float ee = e1 * e1 * h->u * (float)s->inv_s;
  float g1 = 0.0f, g2 = 0.0f, a1 = 0.0f, a2 = 0.0f;
#if IMEST_WITH_ROTOR_HF
  rotor_hf_t rh = {0.0f, 0.0f, 0.0f};
  if (hf) rotor_hf_setup(s, h, lin, j->tr, &rh);
  const float hs[3] = {h11, h12, h22};
#endif
  for (int p = 1; p <= HARMONIC_PAIRS; ++p) {
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      const float k = (float)(6 * p + sgn) * (float)sgn; /* -5, 7, -11, 13 ... */
      const float wk = (k - 1.0f) * we + slip_rate;
      const float x = wk / wq, x3 = x * x * x;
      const float gk = (1.0f + x3 * x3) * k * k; /* k^2 / G^2 */
      const float w2 = ee / gk;                  /* G^2 eps |E_k|^2 / (sigma L_S) */
      bg_impedance_t zk;
      imest__bg_impedance(k * we, wk, s->ls_h, s->sigma, j->tr, j->rs, &zk);
      float zr = zk.zr, zi = zk.zi;
#if IMEST_WITH_ROTOR_HF
      if (hf)
        rotor_hf_z(s, &rh, j->tr, j->rs, k * we, wk, &zr, &zi); /* the data's current: the double cage's */
#endif
      const float zz = zr * zr + zi * zi;
      if (!(zz > 0.0f)) continue;
      /* y = 1 / Z_k: i_k = -E_k y */
      const float yr = zr / zz, yi = -zi / zz;
      const float dd = k2 * k2 + wk * wk; /* |K2 + j w_k|^2 */
      /* dq/dK1 / (-E_k) = (K2 + j w_k) y; Re((K2 + j w_k) conj of it) = |K2 + j w_k|^2 Re y */
      g1 += w2 * dd * yr;
      /* dq/dK2 / (-E_k) = m y F, F = K2 (K2 - j n w) / (K2 + j w_k) - (2 K2 - j n w) */
      const float ar = k2 * k2, ai = -k2 * nw;                                  /* K2 (K2 - j n w) */
      const float qr = (ar * k2 + ai * wk) / dd, qi = (ai * k2 - ar * wk) / dd; /* / (K2 + j w_k) */
      const float fr = qr - 2.0f * k2, fi = qi + nw;
      const float pr = m * (yr * fr - yi * fi), pi = m * (yr * fi + yi * fr); /* m y F */
      /* t = (K2 + j w_k) conj(p); Re t */
      const float tr_ = k2 * pr + wk * pi;
      g2 += w2 * tr_;
#if IMEST_WITH_ROTOR_HF
      if (hf) {
        const float q2[2] = {k2, wk};
        rotor_hf_move(&rh, gk, &zk, yr, yi, dd, tr_, q2, pr, pi, hs, &a1, &a2);
      }
#endif
    }
  }
  const float n2 = 2.0f * (float)j->w->nreg * (float)r->windows;
  if (model) {
    g1 *= n2;
    g2 *= n2;
    *dk1 = fabsf(h22 * g1 - h12 * g2) / det;
    *dk2 = fabsf(h11 * g2 - h12 * g1) / det;
  }
  /* the deep-bar rotor's: twice the first-order move, as the timing's (measured: 0.8 to 1.9 x it at
   * rated load; at half load its sign is not the data's) */
  *dk1 += ROTOR_HF_MARGIN * a1 * n2 / det;
  *dk2 += ROTOR_HF_MARGIN * a2 * n2 / det;
}

/* The systematic bounds: T_R's (the staircase, the timing, the inverter
 * model's harmonics: the measured floor and their move of the fit) and R_S's: the voltage's uncertainty (the inverter
 * model's, or none known), the timing's, the staircase's, the current
 * sensors' gain mismatch (|E| |Z| / R_S, measured: the paper motor, 1 %
 * between two sensors, R_S -3.5 %); both with the constants' share
 * (ls_uncertainty, sigma_uncertainty) and the magnetising curve's (fx). Infinite without an estimate (have: the
 * solve gave a positive, finite T_R). */
static void bounds(judge_t *j, const bg_sums_t *sm, const bg_flux_t *fx, int have)
{
  imest_result_t *r = j->r;
  const float r2 = (float)sm->rw[3][3]; /* sum |i|^2 */
  const float mism = gain_mismatch(j->w, r2);
  if (mism > GAIN_MISMATCH_FLAG) r->flags |= IMEST_FLAG_GAIN_MISMATCH;
  j->tr_b = INFINITY;
  j->rs_b = INFINITY;
  j->g_b = 0.0f;
  j->c_tr = 0.0f; /* without an estimate the total's INFINITY says tr_uncertain */
  j->c_rs = 0.0f;
  j->x_tr = 0.0f;
  j->x_rs = 0.0f;
  if (have && imest__bg_finite(r->rs_ohm) && j->rs > 0.0f) {
    const float rs = j->rs;
    inv_share_t h;
    float dk1, dk2;
    const float dv_v = voltage_uncertainty(j->s, j->w, &j->op, &h);
    /* A swing at a steady mean (IMEST_WFLAG_SWING): the steady-state bounds hold at one slip, and
     * the window visits slips down to |w_s| less the peak of the electrical speed's swing. They are
     * taken there, where the fit's leverage of every error on T_R is largest (|dZ/dT_R| ~ w_s for
     * a < 1); a swing that reaches zero slip has no bound (transient, below). The swing from the
     * sums (docs/METHOD.md §2.2, §13.1): p = W4.W6 = n^2 w^2 |i|^2, q = W6.W6 = (n^2 w'^2 + n^4 w^4)
     * |i|^2, r = W4.W4 = |i|^2 give q r - p^2 = r^2 (n^2 E[w'^2] + n^4 Var(w^2)), Var(w^2) = 4 E[w]^2
     * Var(w) to first order, so (q r - p^2) / (2 p r) >= 2 n^2 Var(w), a sinusoid's peak squared
     * (the w'^2 term and the encoder's noise in it only add; a negative figure is rounding). */
    const float ws = j->st->slip_rate;
    float ws_b = ws;
    int through_zero = 0;
    if (j->w->flags & IMEST_WFLAG_SWING) {
      const float p = (float)sm->rw[3][5], q = (float)sm->rw[5][5];
      const float peak = sqrtf(fabsf(q * r2 - p * p) / (2.0f * p * r2));
      ws_b = ws * BG_FMAXF(1.0f - peak / fabsf(ws), 0.0f);
      through_zero = ws_b == 0.0f;
    }
    systematic_bounds(j->s, j->w, &j->op, ws_b, j->tr, rs, dv_v, h.shape_v, &j->tr_b, &j->rs_b, &j->c_tr,
                      &j->c_rs, j->st->dw_rad_s, &j->x_tr, &j->x_rs);
    inverter_harmonics(j, &h, ws_b, &dk1, &dk2);
    const float h_tr = dk2 * j->tr,
                h_rs = (j->s->sigma * j->s->ls_h * dk1 + (1.0f - j->s->sigma) * j->s->ls_h * dk2) / rs;
    j->tr_b += h_tr;
    j->rs_b += h_rs;
    /* the magnetising curve's share (bg_flux.c), where T_R's bound is finite;
     * nothing without a curve (the outputs stay as without it) */
    if (fx != NULL && j->s->ls_curve_points != 0u && isfinite(j->tr_b)) {
      j->tr_b += fx->tr_b;
      j->rs_b += fx->rs_b;
    }
    if (through_zero) /* the swing reached zero slip: no bound, T_R and R_S transient */
      j->x_tr = j->tr_b = j->x_rs = j->rs_b = INFINITY;
    j->g_b = mism * j->op.z_ohm / rs;
    r->tr_bound_rel = (double)j->tr_b;
    r->rs_bound_rel = (double)(j->rs_b + j->g_b);
  }
}

void imest__bg_judge(imest_t *s, const imest_window_t *w, const bg_window_stats_t *st, const bg_sums_t *sm,
                     const bg_solve_out_t *so, const bg_flux_t *fx, int steady, imest_result_t *r)
{
  judge_t j = {.s = s, .w = w, .st = st, .so = so, .r = r, .steady = steady};
  operating_point(s, st, sm, w->nreg, &j.op);
  r->i_rms_a = (double)st->i_rms_a;
  j.tr = (float)r->tr_s;
  j.rs = (float)r->rs_ohm;
  j.e_i = (float)r->e_i;
  j.e_i_noise = (float)r->e_i_noise;
  j.pe_k2_rel = (float)r->pe_k2_rel;
  /* a positive T_R of the solve is >= tr_min_s, far above float32's least
   * normal number: j.tr > 0 is r->tr_s > 0 */
  const int have = so->status == IMEST_OK && imest__bg_finite(r->tr_s) && j.tr > 0.0f;
  /* Excitation: the mean rotation rate of the rotor-frame current vector
   * (sum of i x di/dt over sum of |i|^2) times T_R: in steady state the
   * slip frequency x T_R, the ratio of rotor to magnetising current (noise
   * averages out of it: 0.004..0.008 at no load with 12-bit sensors, 1.1 at
   * rated load). Below 0.1 T_R is weakly observable. With the estimate's
   * T_R (the motor's, for any size; the nominal T_R where there is none). */
  const float slip_rate = st->slip_rate;
  r->slip_ratio = (double)(fabsf(slip_rate) * (have ? j.tr : s->tr_nominal_s));
  r->ls_noload_h = (double)NAN; /* the no-load check fills it where it runs */
  bounds(&j, sm, fx, have);
  j.tr_judged = slip_rate * j.tr * s->sigma < 1.0f;
  const int status = tr_verdict(&j);
  const int rs_status = status != IMEST_REASON_NONE ? status : rs_verdict(&j);
  r->tr_reason = status;
  r->tr_valid = (status == IMEST_REASON_NONE);
  r->rs_reason = rs_status;
  r->rs_valid = (rs_status == IMEST_REASON_NONE);
  r->valid = r->tr_valid && r->rs_valid;
  r->status = r->tr_valid ? rs_status : status;
}
