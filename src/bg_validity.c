/* Background stage: is this window's estimate trustworthy, and for which
 * parameter? The first reason found, most fundamental first, becomes the
 * reason; T_R and R_S get their own verdicts (R_S is far more sensitive to
 * the voltage's and the timing's errors than T_R). Thresholds are config
 * fields; README "When is a window valid" and docs/METHOD.md §13 give the
 * measurements behind the defaults. Every evidence is dimensionless: the same
 * rule holds for any motor size. */
#include <math.h>

#include "bg_validity.h"

static int first_flag_reason(unsigned int flags, uint32_t used, uint32_t samples)
{
  if (flags & IMEST_FLAG_INPUT_FAULT) return IMEST_REASON_INPUT_FAULT;
  if (flags & IMEST_FLAG_ADC_SAT) return IMEST_REASON_ADC_SATURATION;
  if (flags & IMEST_FLAG_ENCODER_FAULT) return IMEST_REASON_ENCODER_FAULT;
  /* warm-up samples are not accumulated; the rest of the window is clean
   * data, so warm-up invalidates a window only when it took half of it */
  if ((flags & IMEST_FLAG_WARMUP) && 2u * used < samples) return IMEST_REASON_WARMUP;
  return IMEST_REASON_NONE;
}

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

#define TWO_PI_F       6.2831853f
/* a sign-type error dV has the fundamental (4/pi) dV */
#define FOUR_OVER_PI_F (4.0f / 3.14159265f)

static void operating_point(const imest_t *s, const bg_window_stats_t *st, const bg_sums_t *sm, uint32_t nreg,
                            op_point_t *op)
{
  const float n = nreg > 0u ? (float)nreg : 1.0f;
  const float slip_rate = (float)st->slip_rate;
  op->we = slip_rate + s->n * (float)st->w_mean;
  op->slip = fabsf(op->we) > 0.0f ? slip_rate / op->we : 0.0f;
  /* W1.W4 - W2.W4 = u.i / (sigma L_S) exactly (i_perp.i = 0) */
  op->p_w = (float)(sm->rw[0][3] - sm->rw[1][3]) / s->inv_s / n;
  const float i2 = fmaxf((float)sm->rw[3][3] / n, 0.0f), u2 = fmaxf(2.0f * (float)st->u_ms, 0.0f);
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
  if (!(we > TWO_PI_F * 2.0f) || !(op->s_va > 0.0f)) return 0;
  const float ls = s->ls_h, sl = s->sigma * ls;
  if (op->slip > 1.25f) return 1;
  if (op->slip < -0.25f && op->p_w > 0.1f * op->s_va) return 1;
  if (op->slip > 0.02f && op->p_w < -0.1f * op->s_va) return 1;
  if (op->slip > 0.45f && fabsf(op->slip) * we > TWO_PI_F * 5.0f) return 1;
  if (op->z_ohm < we * sl / 3.0f) return 1;
  const float rs_max = (s->rs_nominal_ohm > 0.0f) ? 3.0f * s->rs_nominal_ohm : 10.0f * we * ls;
  return op->z_ohm > 3.0f * we * ls + rs_max;
}

/* The uncertainty of the voltage's fundamental per phase [V]: the inverter
 * model's error at this current times its relative uncertainty (duty input),
 * or u_uncertainty_v (measured voltages); negative: unknown. *shape_v: the
 * uncertainty whose harmonics T_R sees (duty input with a known uncertainty;
 * else 0). */
static float voltage_uncertainty(const imest_t *s, const op_point_t *op, float *shape_v)
{
  *shape_v = 0.0f;
  if (!s->duty_input) return s->u_uncertainty_v;
  const imest_inverter_t *v = &s->inverter;
  if (v->uncertainty < 0.0f) return -1.0f;
  const float a = op->i_pk;
  const float e = fabsf(v->dead_time_s * s->pwm_hz * (float)s->vdc_prev + v->v_diode_v + v->r_diode_ohm * a +
                        0.5f * ((v->v_switch_v - v->v_diode_v) + (v->r_switch_ohm - v->r_diode_ohm) * a));
  const float dv = v->uncertainty * e;
  /* the error's shape near the zero crossings (the ripple's, the devices'
   * capacitances) is not known to better than 20 % of it even when every
   * number of the model is exact: with the numbers exact and stated 3 %
   * uncertain, T_R at 25 % load was valid and 1.0-1.9 % off (2.2 / 4 kW,
   * 1-3 us); the harmonics' bound takes at least that */
  *shape_v = fmaxf(dv, 0.2f * e);
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
 *   corrected: the source may be smooth) the whole effect is uncertain; the
 *   duty input corrects it to within about 20 % (measured), 30 % is kept.
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
 *   takes 0.5 times it, in Im Z.
 * dv_v: the voltage uncertainty [V] (negative: unknown); harm_v: the
 * uncertainty whose harmonics T_R sees (duty input; 0 otherwise). */
static void systematic_bounds(const imest_t *s, const op_point_t *op, float slip_rate, float tr, float rs,
                              float dv_v, float harm_v, float *tr_rel, float *rs_rel)
{
  const float we = op->we, ls = s->ls_h, sg = s->sigma;
  const float a = slip_rate * tr, den = 1.0f + a * a;
  /* Z and dZ/dT_R = we L_S ws (1 - sigma) / (1 + j a)^2 */
  const float zr = rs + we * ls * (a * (1.0f - sg)) / den;
  const float zi = we * ls * (1.0f + sg * a * a) / den;
  const float k = we * ls * slip_rate * (1.0f - sg) / (den * den);
  const float dr = k * (1.0f - a * a), di = k * (-2.0f * a);
  const float tau = 2.0f * s->timing_uncertainty_s;
  const float t_pwm = 1.0f / s->pwm_hz;
  const float share = (s->duty_input && s->duty.zoh > 0.0f) ? 0.3f : 1.0f;
  const float eps = share * fabsf(we) * t_pwm * t_pwm / (12.0f * sg * ls);
  const float dzr = fabsf(we) * tau * fabsf(zi) + eps * 2.0f * fabsf(zr * zi);
  const float harm = 0.5f * FOUR_OVER_PI_F * harm_v / op->i_pk;
  const float dzi = fabsf(we) * tau * fabsf(zr) + eps * fabsf(zr * zr - zi * zi) + harm;
  const float dt = fabsf(di) > 0.0f ? dzi / fabsf(di) : INFINITY;
  *tr_rel = dt / tr;
  const float dr_volt = dv_v < 0.0f ? INFINITY : FOUR_OVER_PI_F * dv_v / op->i_pk;
  *rs_rel = (dzr + fabsf(dr) * dt + dr_volt) / rs;
}

/* The current sensors' gain mismatch from the zero sequence (three sensors:
 * i_a + i_b + i_c is the sensors' error), as the complex pattern E = sum_x
 * eps_x e^(-j 2 pi x / 3) of the per-phase gain errors: |E| (0 with two
 * sensors, where the third is computed and the zero sequence is exactly 0). */
static float gain_mismatch(const imest_window_t *w, const bg_sums_t *sm)
{
  const float s2 = (float)sm->rw[3][3];
  if (!(s2 > 0.0f)) return 0.0f;
  const float ca = w->sum[IMEST_ACC_I0A] + w->blk[IMEST_ACC_I0A];
  const float cb = w->sum[IMEST_ACC_I0B] + w->blk[IMEST_ACC_I0B];
  return 1.2247449f * sqrtf(ca * ca + cb * cb) / s2; /* 2 / sqrt(2/3) */
}

/* L_S at no load: the reactance the motor shows with (nearly) no rotor
 * current is w_e L_S (slip ratio 0.1: 1 % lower), the reactive power over
 * |i|^2. A configured L_S that differs by more than 6 % cannot be the motor's:
 * at one operating point the estimator absorbs it in T_R and R_S (L_S 10 %
 * high: T_R +11 %, R_S -42 %, residual unchanged), so this is the only place
 * it shows. Latched: every later window is constants_mismatch. */
static void noload_ls_check(imest_t *s, const op_point_t *op, float slip_ratio, int steady, imest_result_t *r)
{
  const float we = fabsf(op->we);
  if (!(steady && slip_ratio < 0.1f && we > TWO_PI_F * 5.0f && op->i2 > 0.0f && op->s_va > 0.0f)) return;
  const float q = sqrtf(fmaxf(0.0f, op->s_va * op->s_va - op->p_w * op->p_w));
  const float ls_meas = q / op->i2 / we;
  r->ls_noload_h = (double)ls_meas;
  const float dev = ls_meas / s->ls_h - 1.0f;
  s->ls_check = (fabsf(dev) > 0.06f) ? 2u : (s->ls_check == 2u ? 2u : 1u);
}

void bg_judge(imest_t *s, const imest_window_t *w, const bg_window_stats_t *st, const bg_sums_t *sm,
              const bg_solve_out_t *so, int steady, imest_result_t *r)
{
  int status = first_flag_reason(r->flags, r->used_samples, r->samples);
  op_point_t op;
  operating_point(s, st, sm, w->nreg, &op);
  r->i_rms_a = st->i_rms_a;
  const int have = so->status == IMEST_OK && isfinite(r->tr_s) && r->tr_s > 0.0;

  /* Excitation: the mean rotation rate of the rotor-frame current vector
   * (sum of i x di/dt over sum of |i|^2) times T_R: in steady state the
   * slip frequency x T_R, the ratio of rotor to magnetising current (noise
   * averages out of it: 0.004..0.008 at no load with 12-bit sensors, 1.1 at
   * rated load). Below 0.1 T_R is weakly observable. With the estimate's
   * T_R (the motor's, for any size; the nominal T_R where there is none). */
  r->slip_ratio = (double)(fabsf((float)st->slip_rate) * (have ? (float)r->tr_s : s->tr_nominal_s));

  if (status == IMEST_REASON_NONE && !(st->i_rms_a >= (double)s->min_current_a)) {
    /* i_rms_a is what passed the offset high-pass. A DC current it removed
     * (magnetising at rest) is in the tracked means: that rotor is at rest
     * with excitation, not without current. */
    const double ia = (double)s->off_ia, ib = (double)s->off_ib;
    const int dc = sqrt(ia * ia + ib * ib) >= (double)s->min_current_a;
    status = (dc && fabs(st->w_mean) < 1.0) ? IMEST_REASON_STANDSTILL : IMEST_REASON_NO_CURRENT;
  }
  if (status == IMEST_REASON_NONE && wiring_mismatch(s, &op)) status = IMEST_REASON_WIRING_MISMATCH;
  r->ls_noload_h = (double)NAN;
  if (status == IMEST_REASON_NONE) noload_ls_check(s, &op, (float)r->slip_ratio, steady, r);
  if (status == IMEST_REASON_NONE && s->ls_check == 2u) status = IMEST_REASON_CONSTANTS_MISMATCH;
  if (status == IMEST_REASON_NONE && !(r->slip_ratio >= (double)s->min_slip_ratio)) {
    /* about 10 rpm: an encoder toggling by a count averages to zero here */
    status = (fabs(st->w_mean) < 1.0) ? IMEST_REASON_STANDSTILL : IMEST_REASON_ZERO_SLIP;
  }
  if (status == IMEST_REASON_NONE && so->status != IMEST_OK) status = so->status; /* NUMERIC or NO_ROOT */
  if (status == IMEST_REASON_NONE && !so->hessian_pd) status = IMEST_REASON_NOT_MINIMUM;
  /* The parametric error index does not shrink with the span (the residual
   * and the cost's curvature both grow with it); the part of the estimate's
   * error that the sensors' white noise causes does, as 1/sqrt(windows), but
   * a systematic part (an inverter's or a model's error, the same in every
   * window) does not. The index is split by the residual's shares, the noise's
   * (e_i_noise^2 / e_i^2) and the rest's, and only the noise's is credited
   * the n windows: pe^2 (1 - f + f / n) against max_pe_k2_rel^2. */
  if (status == IMEST_REASON_NONE) {
    const double f = r->e_i > 0.0 ? fmin(1.0, (r->e_i_noise * r->e_i_noise) / (r->e_i * r->e_i)) : 1.0;
    const double pe2 = r->pe_k2_rel * r->pe_k2_rel * ((1.0 - f) + f / (double)r->windows);
    if (!(pe2 <= (double)s->max_pe_k2_rel * (double)s->max_pe_k2_rel))
      status = IMEST_REASON_POORLY_DETERMINED;
  }
  /* the residual beyond what the sensors' white noise explains */
  if (status == IMEST_REASON_NONE) {
    const double em = sqrt(fmax(0.0, r->e_i * r->e_i - r->e_i_noise * r->e_i_noise));
    if (!(em <= (double)s->max_ei)) status = IMEST_REASON_HIGH_RESIDUAL;
  }
  if (status == IMEST_REASON_NONE &&
      !(r->rs_ohm >= (double)s->rs_min_ohm && r->rs_ohm <= (double)s->rs_max_ohm))
    status = IMEST_REASON_RS_OUT_OF_RANGE;
  /* constants that cannot be the motor's: R_S beyond what temperature
   * explains around its nominal (20 C .. 200 C copper, 10 % data-sheet
   * error), T_R likewise (the rotor heats: T_R falls to ~0.6) */
  if (status == IMEST_REASON_NONE && s->rs_nominal_ohm > 0.0f &&
      !(r->rs_ohm >= 0.7 * (double)s->rs_nominal_ohm && r->rs_ohm <= 1.9 * (double)s->rs_nominal_ohm))
    status = IMEST_REASON_CONSTANTS_MISMATCH;
  if (status == IMEST_REASON_NONE && s->tr_nominal_known &&
      !(r->tr_s >= 0.45 * (double)s->tr_nominal_s && r->tr_s <= 1.5 * (double)s->tr_nominal_s))
    status = IMEST_REASON_CONSTANTS_MISMATCH;
  /* never a confident non-finite number */
  if (status == IMEST_REASON_NONE && !(isfinite(r->tr_s) && isfinite(r->rs_ohm) && isfinite(r->e_i)))
    status = IMEST_REASON_NUMERIC;

  /* The systematic bounds: T_R's (the staircase, the timing) against
   * tr_tolerance; then R_S: T_R's verdict, then its own bound: the
   * voltage's uncertainty (the inverter model's, or none known), the
   * timing's, the staircase's, the current sensors' gain mismatch (|E| |Z| /
   * R_S, measured: the paper motor, 1 % between two sensors, R_S -3.5 %). */
  const float mism = gain_mismatch(w, sm);
  if (mism > 0.002f) r->flags |= IMEST_FLAG_GAIN_MISMATCH;
  float tr_b = INFINITY, rs_b = INFINITY, g_b = 0.0f;
  if (have && isfinite(r->rs_ohm) && r->rs_ohm > 0.0) {
    const float rs = (float)r->rs_ohm;
    float harm_v;
    const float dv_v = voltage_uncertainty(s, &op, &harm_v);
    systematic_bounds(s, &op, (float)st->slip_rate, (float)r->tr_s, rs, dv_v, harm_v, &tr_b, &rs_b);
    g_b = mism * op.z_ohm / rs;
    r->tr_bound_rel = (double)tr_b;
    r->rs_bound_rel = (double)(rs_b + g_b);
  }
  /* The bounds are steady-state figures: T_R's is judged only below the
   * pull-out slip (a sigma < 1), where a drive runs steadily; beyond it the
   * window is a transient (a run-up) whose dynamics determine T_R. */
  const float a_slip = (float)st->slip_rate * (float)r->tr_s * s->sigma;
  if (status == IMEST_REASON_NONE && a_slip < 1.0f && !(tr_b <= s->tr_tolerance))
    status = IMEST_REASON_TR_UNCERTAIN;
  int rs_status = status;
  if (rs_status == IMEST_REASON_NONE && !(rs_b + g_b <= s->rs_tolerance))
    rs_status = (g_b > rs_b) ? IMEST_REASON_GAIN_MISMATCH : IMEST_REASON_RS_UNCERTAIN;
  r->tr_reason = status;
  r->tr_valid = (status == IMEST_REASON_NONE);
  r->rs_reason = rs_status;
  r->rs_valid = (rs_status == IMEST_REASON_NONE);
  r->valid = r->tr_valid && r->rs_valid;
  r->status = r->tr_valid ? rs_status : status;
}
