/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest.h
 * @brief imest: online rotor time constant (T_R) and stator resistance (R_S)
 *        estimator for induction machines (Wang, Chiasson, Bodson, Tolbert,
 *        IEEE TCST 2007), for inverter firmware.
 *
 * Usage (CMSIS-DSP style, every struct is caller-owned, nothing is allocated):
 *
 *     imest_config_t cfg;
 *     imest_config_default(&cfg);             // then set the motor constants:
 *     cfg.pole_pairs = 2; cfg.ls_h = 0.2908f; cfg.sigma = 0.096f; cfg.fs_hz = 4000.0f;
 *     static imest_t est;
 *     if (imest_init(&est, &cfg) != IMEST_OK) { ... }
 *
 *     // PWM-synchronous ISR, once per sample:
 *     if (imest_isr_abc(&est, u_abc_v, i_abc_a, theta_rad)) { wake background task }
 *
 *     // background task (any priority below the ISR):
 *     imest_result_t r;
 *     while (imest_background(&est, &r) == 1) { use r (r.valid, r.tr_s, r.rs_ohm ...) }
 *
 * Algorithm, per sample (ISR path, float32, fixed instruction count):
 *   3-2 transform (power invariant, docs/METHOD.md §1) -> rotation by n_p*theta into the
 *   rotor frame -> 3rd-order Butterworth (second-order sections, same filter on
 *   every channel, including the speed) -> time-aligned central differences
 *   (value, first and second derivative all refer to sample n-1) -> regressor
 *   W (2x7, columns 1,2,4..8) and y -> accumulation of the 36 independent
 *   entries of R_W, R_Wy, R_y over a window -> lock-free hand-off.
 *
 * Per window (background path, bounded iterations):
 *   rebuild the 8x8 R_W -> power-of-two scaling -> cost tables e0,e1,e2 ->
 *   p1, p2 coefficients -> resultant r(K2) (degree 19) -> every positive root by
 *   a Sturm sequence with bisection (float32 chain, float64 polish) ->
 *   back-substitution K1 = -a0/a1 -> selection (K1 > 0, T_R in
 *   [tr_min_s, tr_max_s], least cost) -> T_R = 1/K2,
 *   R_S = sigma*L_S*K1 - (1-sigma)*L_S*K2 -> Hessian, E_I, parametric error
 *   indices -> validity with a reason.
 *
 * The cost minimised is the paper's E_p^2 divided by (1 + c/K2^2)^2 with
 * c = n_p^2 w^2 of the window (current-weighted). The paper's regressor
 * equation is its model equation multiplied by (1 + n_p^2 w^2 T_R^2); E_p^2
 * therefore weighs the residual ~2e5 times more at the true T_R than at the
 * spurious stationary point K2 ~ n_p w, and with 12-bit sensors the spurious
 * point wins in most steady-state windows below rated load. Dividing the
 * weight out keeps every exact-data solution (it is the same model) and
 * removes that bias (README, "Method"). E and E_I are reported as the
 * paper's E_p^2 at the selected point; the Hessian and the parametric error
 * indices are those of the minimised cost.
 *
 * Concurrency contract (ISR <-> background):
 *   - imest_isr_abc()/imest_isr_ab()/imest_isr_duty()/imest_isr_flush() are
 *     called from exactly one context (the sampling ISR); imest_background()
 *     from exactly one other context of lower priority (or the same one, e.g.
 *     in a host replay loop). Neither blocks nor waits for the other. No
 *     locks, no disabling of interrupts.
 *   - Two window buffers: the ISR fills one while the background owns the
 *     other. When a window completes, the ISR hands its buffer over only if the
 *     background has released the previous one; otherwise the finished window
 *     is dropped, `overruns` is incremented and the sequence number still
 *     advances, so the gap is visible in the next result (`seq`, `overruns`).
 *     A window is never torn: the background reads a buffer only after the ISR
 *     published it, and the ISR writes it again only after the background
 *     released it.
 *   - The background reads nothing of the ISR's live state: what it judges a
 *     window by (the input kind, the bus voltage, the offsets) travels in the
 *     window, as it was at the window's end; and it writes nothing the ISR
 *     reads but its release index (the ISR engages the angle observer itself,
 *     from its own window sums). So the results do not depend on when the
 *     background runs (as long as no window is dropped), and a host replay
 *     reproduces the firmware exactly.
 *   - Publication uses one index written only by the ISR and one written only
 *     by the background, stored with release and loaded with acquire ordering
 *     (GCC/Clang atomics: one DMB each at a window's end on a Cortex-M), which
 *     holds on single- and multi-core, cached or not. With other compilers the
 *     indices are volatile words ordered by IMEST_BARRIER (a compiler barrier
 *     by default): on a multi-core or cached system define IMEST_BARRIER to a
 *     full memory barrier (e.g. __DMB()). test/concurrency runs the two
 *     contexts on two threads under ThreadSanitizer.
 *   - imest_init() must not run concurrently with either call.
 *
 * Numerics: the ISR path is float32 only (builds with -Wdouble-promotion
 * -Werror); products are summed in short float32 blocks folded into the window
 * sums one entry per sample (no data-dependent loop), and y is centred on the
 * previous valid estimate (docs/METHOD.md §10), which keeps T_R within 0.01 % of an
 * all-float64 run. The background uses float64 where the precision needs it
 * (cost tables, E, E_I, Hessian, error indices) and float32 where it does not.
 *
 * No malloc, no stdio, no global mutable state; <math.h> is used only outside
 * the ISR (init and background).
 */
#ifndef IMEST_IMEST_H
#define IMEST_IMEST_H

#include <stdint.h>

#include "imest/imest_version.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ----------------------------------------------------------------------------
 * Errors of the API calls, and reasons a window is not valid
 * ------------------------------------------------------------------------- */

/** Errors of the API calls. Every call that can fail returns an int: 0
 *  (IMEST_OK) or a non-negative count on success, a negative imest_err_t on
 *  error; each function documents its values with @retval. */
typedef enum {
  IMEST_OK = 0,          /**< success */
  IMEST_ERR_NULL = -1,   /**< a pointer argument was NULL */
  IMEST_ERR_CONFIG = -2, /**< a config field is out of range; imest_config_check() names it */
  IMEST_ERR_ARG = -3     /**< an argument is out of range (an index, an identifier) */
} imest_err_t;

/** Short lower-case name of an error ("ok", "null_argument", "bad_config", "bad_argument"). */
const char *imest_err_name(int err);

/** Why a window's estimate is not valid (imest_result_t.status, .tr_reason,
 *  .rs_reason), most fundamental first. The values are stable: they travel on
 *  CAN (tools/imest.dbc). */
typedef enum {
  IMEST_REASON_NONE = 0,               /**< valid */
  IMEST_REASON_WARMUP = 10,            /**< filters were still settling (start or after a fault) */
  IMEST_REASON_INPUT_FAULT = 11,       /**< non-finite or absurd sample (NaN, Inf, beyond limits) */
  IMEST_REASON_ADC_SATURATION = 12,    /**< a current or voltage sample reached the ADC limit */
  IMEST_REASON_ENCODER_FAULT = 13,     /**< angle step beyond the speed limit (glitch, jump) */
  IMEST_REASON_NO_CURRENT = 14,        /**< stator current below min_current_a: nothing to identify */
  IMEST_REASON_STANDSTILL = 15,        /**< rotor (nearly) at rest without AC excitation */
  IMEST_REASON_ZERO_SLIP = 16,         /**< rotor currents ~0 (no load, constant speed): T_R unobservable */
  IMEST_REASON_NUMERIC = 17,           /**< non-finite window sums or polynomial */
  IMEST_REASON_NO_ROOT = 18,           /**< no stationary point with K1 > 0 and T_R in [tr_min, tr_max] */
  IMEST_REASON_NOT_MINIMUM = 19,       /**< Hessian at the selected point not positive definite */
  IMEST_REASON_POORLY_DETERMINED = 20, /**< relative parametric error index of K2 too large */
  IMEST_REASON_HIGH_RESIDUAL = 21,     /**< E_I above max_ei: the data do not fit the model */
  IMEST_REASON_RS_OUT_OF_RANGE = 22,   /**< R_S outside [rs_min_ohm, rs_max_ohm] */
  /** the data contradict the configured conventions: encoder direction, phase order, pole pairs,
   *  electrical instead of mechanical angle, units (README remedies) */
  IMEST_REASON_WIRING_MISMATCH = 23,
  /** R_S far outside what heating explains around rs_nominal_ohm: L_S, sigma or the nominal R_S
   *  are wrong */
  IMEST_REASON_CONSTANTS_MISMATCH = 24,
  /* R_S only (T_R may still be valid): */
  /** R_S's error bound (inverter voltage error, timing, noise) exceeds rs_tolerance */
  IMEST_REASON_RS_UNCERTAIN = 25,
  IMEST_REASON_GAIN_MISMATCH = 26, /**< the current sensors' gains differ by more than R_S tolerates */
  /** T_R's error bound (the PWM staircase, timing, with the duty-cycle input the inverter
   *  model's uncertainty) exceeds tr_tolerance: light load, where T_R is weakly coupled to the
   *  data (R_S then refused too) */
  IMEST_REASON_TR_UNCERTAIN = 27,
  /** the constants' stated uncertainty (ls_uncertainty, sigma_uncertainty) alone moves T_R (or
   *  R_S) by more than its tolerance: commission the motor (imest_commission.h) or state what the
   *  constants are known to */
  IMEST_REASON_CONSTANTS_UNCERTAIN = 28,
  /** a load or speed step inside the window, seen through the angle observer, alone moves T_R (or
   *  R_S) by more than its tolerance, or the rotor swung at a steady mean through zero slip (a V/f
   *  drive's hunting): a transient; the next steady window is estimated again */
  IMEST_REASON_TRANSIENT = 29
} imest_reason_t;

/** Short lower-case name of a reason ("ok", "warmup", "zero_slip", ...). */
const char *imest_reason_name(int reason);

/** Window flag bits (imest_result_t.flags): everything noticed in the window. */
#define IMEST_FLAG_WARMUP        0x0001u /**< some samples were warm-up (not accumulated) */
#define IMEST_FLAG_INPUT_FAULT   0x0002u
#define IMEST_FLAG_ADC_SAT       0x0004u
#define IMEST_FLAG_ENCODER_FAULT 0x0008u
#define IMEST_FLAG_OVERRUN       0x0010u /**< one or more windows before this one were dropped */
#define IMEST_FLAG_CURRENT_STEP  0x0020u /**< a current step beyond what the voltage can drive (a spike) */
#define IMEST_FLAG_COMBINED      0x0040u /**< the estimate combines this window with earlier ones */
#define IMEST_FLAG_GAIN_MISMATCH                                                                             \
  0x0080u                             /**< the zero sequence of three current sensors shows a gain mismatch */
#define IMEST_FLAG_HESSIAN_PD 0x0100u /**< Hessian positive definite at the selected point */

/* ----------------------------------------------------------------------------
 * Configuration
 * ------------------------------------------------------------------------- */

/** How the duty cycles passed to imest_isr_duty() relate to the sample instants t_k
 *  (centre-aligned PWM; T = 1/fs_hz, one sample every N carrier periods). */
typedef enum {
  /** the duties passed with sample k are applied during [t_k, t_k + T): computed in the previous
   *  ISR, loaded into the shadow registers at the carrier valley where sample k is taken (the usual
   *  scheme; default) */
  IMEST_PWM_NEXT_PERIOD = 0,
  /** applied during [t_k - T/2, t_k + T/2): e.g. loaded at the carrier peak half a period before
   *  sample k */
  IMEST_PWM_CENTRED = 1,
  IMEST_PWM_LAST_PERIOD = 2 /**< applied during [t_k - T, t_k): the period that just ended */
} imest_pwm_timing_t;

/** What the phase voltages passed to imest_isr_abc() / imest_isr_ab() look like between samples:
 *  it sets the PWM staircase's share of R_S's (and T_R's) error bound, docs/METHOD.md §17.2.
 *  Configured, not detected from the data. The duty-cycle input (imest_isr_duty) is a staircase
 *  at pwm_hz by construction, whatever this says. */
typedef enum {
  /** a PWM staircase at pwm_hz (an inverter's phase voltages sampled unfiltered; default): the bound
   *  takes the staircase's aliased images in full (the source may be smooth, so they are not
   *  corrected) */
  IMEST_VOLTAGE_STAIRCASE = 0,
  /** sinusoidal or filtered (a line-fed motor, a voltage channel behind a filter well below the
   *  carrier): no staircase images, their share of the bound is 0. Set on a PWM staircase, the
   *  bound misses the staircase's error and R_S reads as valid while low by what it is
   *  uncorrected (docs/METHOD.md §17.2: 4 kW at 4 kHz, rated speed, -10 %; 11 kW -21 %). The
   *  default on a smooth source is the opposite mistake, only conservative: R_S is rs_uncertain
   *  wherever the staircase's share lifts its bound above rs_tolerance (high speed, large
   *  motors, slow sampling; 4 kW at 4 kHz: every window) */
  IMEST_VOLTAGE_SMOOTH = 1
} imest_voltage_kind_t;

/** The inverter's voltage error per leg, for the duty-cycle input: how much less a
 *  leg delivers than its commanded d * V_dc, for the phase current i (into the motor):
 *
 *      e(i, d) = s(i) * [ t_d f_pwm V_dc + V_d0 + r_d |i| + d_c ((V_sw0 - V_d0) + (r_sw - r_d) |i|) ]
 *
 *  with d_c the share of the period the active switch conducts (d for i > 0, 1 - d
 *  for i < 0) and s(i) = i / sqrt(i^2 + b^2) the sign of i faded over about |i| < b
 *  (the current ripple crosses zero inside the period there, so the error fades
 *  rather than jumping): b = i_band_a if set, else per leg and sample the leg's own
 *  ripple at its switching instants plus the current's change within the dead time
 *  (docs/METHOD.md §17.1). All zero: an ideal (or fully compensated) inverter. The library's
 *  standstill commissioning measures these numbers. edge_band_a > 0 selects the
 *  switching-instant model instead (docs/METHOD.md §17.1): the dead time's volt-seconds take
 *  the sign of the current at the leg's two switching instants (the sample plus and minus
 *  the phase ripple there, closed form from the three duties, V_dc and sigma L_S), the
 *  device drops the current's own sign over each conducting interval and their slopes
 *  the current itself. */
typedef struct {
  float dead_time_s;  /**< effective dead time, switching delays included [s] */
  float v_switch_v;   /**< switch (IGBT, MOSFET) threshold voltage V_sw0 [V] */
  float r_switch_ohm; /**< switch slope resistance r_sw [ohm] */
  float v_diode_v;    /**< freewheeling diode threshold voltage V_d0 [V] */
  float r_diode_ohm;  /**< diode slope resistance r_d [ohm] */
  /** half-width of the zero-crossing transition [A], the same for every leg and sample (0, the
   *  default: per leg and sample |D_x| + V_dc t_d / (6 sigma L_S), the leg's phase-current ripple at
   *  its switching instants, closed form from the three duties, V_dc and sigma L_S, plus half the
   *  current's change within the dead time; docs/METHOD.md §17.1) */
  float i_band_a;
  /** > 0: the switching-instant model (docs/METHOD.md §17.1), with the devices' own smoothing
   *  of the sign at a switching instant b = edge_band_a [A] beyond the ripple it computes (the
   *  output capacitance C_oss smooths over about C_oss V_dc / t_d; the simulator's ideal
   *  switches fit a tenth of the ripple's peak); i_band_a is then unused. 0: the smooth sign
   *  above (default). Either model's uncertain harmonics enter the bounds through the window's fit
   *  (docs/METHOD.md §18.1): with the numbers exact the switching-instant model gives more valid
   *  windows on the dead-time table, with them 20 % high fewer, and with either none wrong */
  float edge_band_a;
  /** relative uncertainty of this model's error (e.g. 0.2 for 20 %); negative: the error is unknown
   *  (default), so R_S is never valid with the duty-cycle input. R_S's bound takes it as stated;
   *  the harmonics' shares take at least 0.2 (the error's shape near the zero crossings is not the
   *  model's even when its numbers are exact; docs/METHOD.md §18.1); 1 or more: the harmonics are
   *  unbounded, neither T_R nor R_S is valid with the duty-cycle input */
  float uncertainty;
} imest_inverter_t;

/** Points of the magnetising curve (imest_config_t.ls_curve_i_a, ls_curve_h). */
#define IMEST_LS_CURVE_POINTS 4

/** Configuration. Fill with imest_config_default(), then set the motor. */
typedef struct {
  /* Motor constants (known, from the data sheet or a commissioning test). */
  unsigned int pole_pairs; /**< n_p */
  float ls_h;              /**< stator inductance L_S [H] */
  float sigma;             /**< total leakage factor 1 - M^2/(L_S L_R) */
  /** largest relative error of ls_h, e.g. 0.1 for 10 % (default 0.1: L_S typed from a data sheet
   *  or derived from its equivalent circuit, where 10 % is usual; 0 = exact, e.g. a simulator's
   *  own constants). At one operating point the fit absorbs a wrong L_S in T_R and R_S without
   *  raising the residual (4 kW at rated load: L_S 10 % high gives T_R +8 %, R_S -80 %), so the
   *  move this uncertainty can cause at the window's operating point (docs/METHOD.md §18.1: the
   *  first-order move for a motor's L_S up to u / (1 - u) from ls_h, times 1 + u for the second
   *  order; measured 1.1 to 1.9 times the actual move) is added to tr_bound_rel and
   *  rs_bound_rel. With the default T_R is refused as constants_uncertain at loaded operating
   *  points, where a data-sheet L_S moves it by more than tr_tolerance: commission the motor
   *  (imest_comm_apply() states what commissioning measured: 0.2 % on the simulator's motors)
   *  or state what L_S is known to. In [0, 1) */
  float ls_uncertainty;
  /** largest relative error of sigma (default 0.2: a data-sheet leakage factor; 0 = exact;
   *  commissioning: 0.5 %). Its move of T_R and R_S adds to the bounds as ls_uncertainty's does,
   *  the two summed (not in quadrature: sigma is sigma L_S / L_S, so the two errors are
   *  correlated). In [0, 1) */
  float sigma_uncertainty;

  /* Sampling. */
  float fs_hz;    /**< sample rate of the ISR call [Hz] (default 4000) */
  float window_s; /**< window length [s] (default 1.0) */

  /* Front end. */
  /** Butterworth-3 cut-off [Hz] (default 100: works for run-up and steady state with 12-bit
   *  sensors) */
  float filter_hz;
  /** if the analog current/voltage channels have a 2nd-order anti-alias filter, its cut-off [Hz];
   *  the angle is then passed through a digital model of it so all channels see the same delay (0 =
   *  none, default) */
  float aa_hz;
  /** how much the voltage lags the currents [s], beyond what pwm_timing already accounts for;
   *  negative: the voltage leads (e.g. currents sampled late). |u_delay_s| <= 1/fs_hz (default 0).
   *  E.g. a phase voltage taken from the duty cycles of the PWM period that just ended lags by half
   *  a period (50 us at 10 kHz): uncompensated, that biases R_S by about +5 % at 30 Hz. Compensated
   *  by linear interpolation of whichever side leads. */
  float u_delay_s;
  /** natural frequency [Hz] of the tracking observer between the encoder and the rotation
   *  (src/estimator/isr/isr_angle.h), engaged while the speed is steady: it attenuates an encoder's
   *  quantisation steps above this (1024 counts, paper motor at 30 Hz: R_S +6.6 % -> -0.02 %)
   *  (default 0: filter_hz / 4; negative: off, the encoder angle as it is; at most fs_hz / 4) */
  float angle_observer_hz;
  /** the encoder's counts per mechanical revolution after decoding (e.g. 4096 for a 1024-line
   *  quadrature encoder; a resolver's or an absolute encoder's 2^bits). The true angle lies within
   *  one count of the reading, so an angle observer's correction beyond one count is its lag on a
   *  real motion, not quantisation: the encoder's angle and speed are then used for the rest of
   *  that window and the next (src/estimator/isr/isr_angle.h). A rotor whose speed swings inside
   *  the observer's band (a V/f drive's hunting: 11 kW, 2 us dead time, 30 Hz, 25 % load, 5 % of
   *  the speed at 12 Hz) otherwise reads the observer's lag as R_S: +65 % -> +2.5 % with 16384
   *  counts given, as with the observer off; such a window (a swing at a steady mean speed) gets
   *  its bounds at the least slip the swing visits, `transient` where that reaches zero. 1024
   *  counts on the paper motor keep the observer's gain (R_S +0.2 %, off +7 %). (default 0:
   *  unknown, the observer as configured; below 2^24) */
  float encoder_counts_per_rev;
  /** cut-off [Hz] of a first-order high-pass applied alike to the alpha/beta voltages and currents
   *  before the rotation: it removes sensor offsets (default 1; 0 = off). Applied to both, it
   *  leaves the motor's equations intact at constant speed; see README "Method" (sensor offsets).
   *  The first start (unless start_at_rest) waits 5 time constants more for it: 0.8 s at 1 Hz. */
  float dc_block_hz;
  /** samples discarded after start/fault while the filters settle [s] (default 0: derived from
   *  filter_hz) */
  float warmup_s;
  /** nonzero: the first sample follows a zero history (drive just enabled, motor at rest, no
   *  current), so no warm-up is needed at start (default 0) */
  int start_at_rest;

  /* Duty-cycle input (imest_isr_duty). */
  /** carrier frequency [Hz] (default 0: fs_hz, one sample per period). Both inputs: the PWM
   *  staircase's share of the T_R and R_S error bounds scales with its period squared (a fast carrier:
   *  its rate; a sine source or filtered voltages: voltage_kind) */
  float pwm_hz;
  imest_pwm_timing_t pwm_timing; /**< when the duties passed with a sample apply (default NEXT_PERIOD) */
  /** phase-voltage input (imest_isr_abc, imest_isr_ab): a PWM staircase or a smooth source, for
   *  the error bounds (default IMEST_VOLTAGE_STAIRCASE); the duty input is a staircase whatever
   *  this says */
  imest_voltage_kind_t voltage_kind;
  imest_inverter_t inverter; /**< the inverter's voltage error (default: unknown) */

  /* Solve and selection. */
  /** nominal T_R, used for scaling and the first centring (default 0.1 s) */
  float tr_nominal_s;
  /** nonzero: tr_nominal_s is the motor's own (data sheet L_R / R_R, or commissioning), so an
   *  estimate outside 0.45 .. 1.5 of it is constants_mismatch (default 0: a guess for scaling) */
  int tr_nominal_known;
  float tr_min_s; /**< admissible T_R band [s] (default 1 ms .. 10 s) */
  float tr_max_s;
  float rs_min_ohm; /**< admissible R_S band [ohm] (default 0 .. 1e3) */
  float rs_max_ohm;

  /* Validity (see README "When is a window valid"). */
  float max_pe_k2_rel; /**< largest relative parametric error index of K2 (default 0.1) */
  /** largest residual error index E_I (default 3.0: a sanity bound; the PE index is the evidence of
   *  trust, README) */
  float max_ei;
  float min_current_a; /**< least rms stator current (alpha/beta amplitude) [A] (default 0.05) */
  /** least slip excitation: mean rotation rate of the rotor-frame current x tr_nominal_s, i.e. slip
   *  frequency x T_R in steady state (default 0.1, i.e. rotor current >= ~10 % of the magnetising
   *  current; rated load is about 1) */
  float min_slip_ratio;
  float rs_tolerance; /**< R_S is valid only if its error bound is within this, relative (default 0.05) */
  float tr_tolerance; /**< T_R is valid only if its error bound is within this, relative (default 0.02) */
  /** phase-voltage input: uncertainty of the measured voltage's fundamental [V] (default 0: measured
   *  voltages are trusted) */
  float u_uncertainty_v;
  /** uncertainty of the voltage/current alignment after pwm_timing and u_delay_s [s] (default 1e-6: an ADC sampling instant) */
  float timing_uncertainty_s;
  /** R_S at ambient temperature, from the data sheet or commissioning (0: unknown, default). A window
   *  whose R_S lies outside what heating explains (0.7 .. 1.9 x this) is constants_mismatch */
  float rs_nominal_ohm;

  /* The rotor at high rotor frequency (deep bars, a double cage; docs/METHOD.md §18.1). The
   * inverter's dead time has the 5th, 7th ... harmonics, which drive the rotor near a slip of 1
   * (about 6 f_e in the rotor frame); a deep-bar rotor answers them with another impedance than
   * the single cage the fit assumes, and the fit reads the difference as T_R and R_S. Described
   * by one pole: the rotor branch's resistance rises from R_R' (at slip frequency) to
   * rotor_hf_rr_ratio x R_R' and the leakage falls from sigma L_S to rotor_hf_sigma_ratio x
   * sigma L_S, with the time constant these two give (tau = (1 - sigma ratio) sigma L_S /
   * ((rr ratio - 1) R_R')). imest_comm_apply() fills both where commissioning found such a rotor
   * (IMEST_COMM_FLAG_ROTOR_HF: the square wave's R and sigma L_S at fs/8). The harmonics'
   * first-order move of the fit (twice it) is added to tr_bound_rel and rs_bound_rel. */
  /** the rotor's resistance at high rotor frequency over R_R' at slip frequency, above 1 (default
   *  0: a single cage, the term is 0 and every output is as without these fields). A core built
   *  without the term (IMEST_WITH_ROTOR_HF=0, CMake -DIMEST_ROTOR_HF=OFF) refuses any other value:
   *  imest_config_check() names this field */
  float rotor_hf_rr_ratio;
  /** sigma L_S at high rotor frequency over sigma L_S at slip frequency, in (0, 1] (read only with
   *  rotor_hf_rr_ratio; default 0) */
  float rotor_hf_sigma_ratio;
  /** phase-voltage input with rotor_hf_rr_ratio: the DC bus [V] of the inverter the measured
   *  voltages come from; with `inverter` it sizes the dead time's harmonics (t_d f_pwm V_dc plus
   *  the drops). 0 (default): unknown, and with a PWM source (voltage_kind staircase) and a
   *  deep-bar rotor T_R's bound is then infinite (tr_uncertain): give the bus and the inverter
   *  model (commissioning fills both), or say the source is smooth (a line-fed motor: no
   *  harmonics). The duty-cycle input has its own bus voltage */
  float inverter_vdc_v;

  /* Main-flux saturation: L_S at the window's flux (docs/METHOD.md §18.5). The points of a no-load
   * test at several voltages (the reactive power over |i|^2 w_e at each, or the no-load windows'
   * ls_noload_h): L_S against the magnetising current. In a window where the steady-state picture
   * holds (slip frequency x T_R x sigma below 1, as for tr_uncertain) the estimate is moved to
   * L_S at the window's magnetising current |i_m| = i_d |1 + j a L_lr / L_R|, i_d = |i| /
   * sqrt(1 + a^2), a = slip frequency x T_R, |i| the motor's (the ISR's high-pass and delay
   * undone), the leakage split equally, with sigma L_S held (saturation moves the main flux, not the leakage), and the curve's
   * uncertainty enters tr_bound_rel and rs_bound_rel. ls_h stays what the solve uses, and what the
   * no-load check compares with when there is no curve. */
  /** the curve's magnetising currents [A], alpha/beta amplitude (sqrt 3 x the phase rms, the unit
   *  of i_rms_a), strictly increasing, positive; piecewise linear between the points, clamped
   *  outside them, with a bound from what saturation allows (docs/METHOD.md §18.5): below the
   *  first point the first segment's straight continuation, above the last point the fall of
   *  L_S to the last point's flux (L_S x_n / i). Cover the flux range the drive runs at:
   *  commissioning's curve runs from rated flux down to 0.45 of it, field weakening to twice
   *  base speed (default 0) */
  float ls_curve_i_a[IMEST_LS_CURVE_POINTS];
  /** L_S measured at no load at each of ls_curve_i_a [H], positive (default 0). Each point is
   *  taken as uncertain by ls_uncertainty x (the last point's flux / its flux), L_S i the flux:
   *  measured as ls_h is, at no load and one frequency, a voltage error that is ls_uncertainty
   *  of the last point's reactive voltage is that much larger a share at a lower flux */
  float ls_curve_h[IMEST_LS_CURVE_POINTS];
  /** points of the curve in use, 2 .. IMEST_LS_CURVE_POINTS (default 0: no curve, L_S is taken as
   *  flux-independent and every output is as without these fields); a core built with
   *  IMEST_WITH_FLUX=0 (docs/integrating.md "Flags") refuses any curve */
  unsigned int ls_curve_points;

  /* Input plausibility (per sample, ISR). */
  float i_limit_a;  /**< |phase current| >= this counts as ADC saturation (default 0 = off) */
  float u_limit_v;  /**< |phase voltage| >= this counts as ADC saturation (default 0 = off) */
  float i_absurd_a; /**< |current| beyond this (or non-finite) is an input fault (default 1e4) */
  float u_absurd_v; /**< |voltage| beyond this (or non-finite) is an input fault (default 1e5) */
  /** |mechanical angle step| * fs beyond this is an encoder fault (default 3000 rad/s, about 28 600
   *  rpm) */
  float speed_limit_rad_s;
} imest_config_t;

/** Fill a config with defaults: every field is written (motor constants zero: the caller must
 *  set them), so a config on the stack needs no initialiser. */
void imest_config_default(imest_config_t *cfg);

/** Check a config.
 *  @param field  optional: receives the name of the first bad field (NULL if none)
 *  @retval IMEST_OK          the config is usable
 *  @retval IMEST_ERR_NULL    cfg is NULL
 *  @retval IMEST_ERR_CONFIG  a field is out of range (*field names it) */
int imest_config_check(const imest_config_t *cfg, const char **field);

/* ----------------------------------------------------------------------------
 * Result of one window
 * ------------------------------------------------------------------------- */

#define IMEST_MAX_ROOTS 20

/** Result of one window. Every estimate carries its quality: T_R and R_S
 *  each have their own verdict (T_R can be trusted where R_S cannot, e.g.
 *  with an uncertain inverter voltage error); `valid` is both. An estimate
 *  keeps its number when it is not valid: only the verdict says whether to
 *  use it. */
typedef struct {
  uint32_t seq;          /**< window sequence number (0, 1, 2, ...; gaps = dropped windows) */
  uint32_t samples;      /**< samples in the window */
  uint32_t used_samples; /**< samples accumulated (not warm-up, not faulty) */
  uint32_t overruns;     /**< windows dropped since init (background too slow) */
  int valid;             /**< 1: T_R and R_S can both be trusted (tr_valid && rs_valid) */
  /** IMEST_REASON_NONE, else the first reason (tr_reason if T_R is not valid, else rs_reason):
   *  imest_reason_t */
  int status;
  int tr_valid;       /**< 1: T_R can be trusted (feed it to the IFOC) */
  int tr_reason;      /**< why T_R is not valid (imest_reason_t; NONE if tr_valid) */
  int rs_valid;       /**< 1: R_S can be trusted */
  int rs_reason;      /**< why R_S is not valid (imest_reason_t; NONE if rs_valid) */
  unsigned int flags; /**< IMEST_FLAG_* bits */
  double t_end_s;     /**< time of the window's last sample since init [s] */
  /** time the estimate is drawn from [s]: the window length, longer when consecutive windows were
   *  combined */
  double span_s;
  unsigned int windows;      /**< windows combined into this estimate (1: this one alone) */
  double tr_s;               /**< rotor time constant T_R [s] (NaN if no candidate) */
  double rs_ohm;             /**< stator resistance R_S [ohm] */
  double tr_bound_rel;       /**< error bound of T_R, relative, constants' share in (NaN: none) */
  double rs_bound_rel;       /**< error bound of R_S, relative, constants' share in (NaN: none) */
  double k1;                 /**< K1 = gamma [1/s] */
  double k2;                 /**< K2 = 1/T_R [1/s] */
  double e;                  /**< E_p^2 at the minimum (units of y^2 * samples) */
  double e_i;                /**< residual error index sqrt(E/R_y) */
  double e_i_noise;          /**< the part of E_I that the sensors' white noise explains */
  double noise_i_a;          /**< white noise of the current per alpha/beta axis, rms [A] */
  double noise_u_v;          /**< white noise of the measured voltage per axis, rms [V] (0: duty input) */
  double hessian[2][2];      /**< d2E/dK^2 at the minimum, K = (K1, K2) */
  double pe_k1;              /**< parametric error index of K1 (absolute, 1/s) */
  double pe_k2;              /**< parametric error index of K2 (absolute, 1/s) */
  double pe_k1_rel;          /**< pe_k1 / K1 */
  double pe_k2_rel;          /**< pe_k2 / K2 */
  double slip_ratio;         /**< slip excitation (slip frequency x tr_nominal_s), see min_slip_ratio */
  double i_rms_a;            /**< rms stator current over the window (alpha/beta amplitude) */
  double ls_noload_h;        /**< L_S measured in a window at no load (NaN: none); more than 6 % from
                                  the configured L_S (with a magnetising curve: the curve's L_S at
                                  this window's current) is constants_mismatch from then on */
  double ls_window_h;        /**< L_S at the window's flux from the magnetising curve [H]; T_R and
                                  R_S are then the estimate with this L_S and sigma x ls_h /
                                  ls_window_h (sigma L_S held), k1 and k2 the fit's with ls_h.
                                  NaN: no curve, or a window where the correction does not apply
                                  (no estimate, beyond the pull-out slip) */
  unsigned int n_roots;      /**< positive roots of the resultant */
  unsigned int n_admissible; /**< roots with K1 > 0 and T_R in band */
  double roots_k2[IMEST_MAX_ROOTS]; /**< the positive roots, ascending */
} imest_result_t;

/* The instance's layout (private; public for static allocation). */
#include "imest/imest_instance.h"

/* ----------------------------------------------------------------------------
 * API
 * ------------------------------------------------------------------------- */

/** Initialise an instance from a config (checked); computes the filter
 *  coefficients. Must not run concurrently with the ISR or background calls.
 *  @retval IMEST_OK          initialised
 *  @retval IMEST_ERR_NULL    s or cfg is NULL
 *  @retval IMEST_ERR_CONFIG  a config field is out of range (imest_config_check() names it) */
int imest_init(imest_t *s, const imest_config_t *cfg);

/**
 * ISR call with phase quantities. Fixed instruction count.
 * @param u_abc_v   phase-to-neutral voltages [V]
 * @param i_abc_a   phase currents [A], positive into the motor
 * @param theta_rad mechanical rotor angle [rad], any range (wrapped or not; the
 *                  step between calls must stay below pi), increasing with the
 *                  a-b-c field. Pass it wrapped (e.g. [0, 2pi)) so float32
 *                  keeps its resolution.
 * @retval 1  this sample completed a window that was handed to the background (wake it)
 * @retval 0  otherwise (no error is possible: bad samples are flagged in the window)
 */
int imest_isr_abc(imest_t *s, const float u_abc_v[3], const float i_abc_a[3], float theta_rad);

/**
 * ISR call for drives that know the phase voltage only from their duty cycles.
 * The library keeps the previous duties and forms the phase-to-neutral voltage
 * centred on this sample (pwm_timing), zero sequence removed, minus its model
 * of the inverter's voltage error (cfg.inverter). Fixed instruction count.
 * @param duty_abc  the upper switches' duty cycles in [0, 1] that apply as
 *                  cfg.pwm_timing says (default: during the period that starts
 *                  at this sample, i.e. what the previous ISR computed)
 * @param vdc_v     DC-bus voltage sampled now [V]
 * @param i_abc_a   phase currents [A], positive into the motor
 * @param theta_rad mechanical rotor angle [rad], as for imest_isr_abc()
 * @retval 1, 0  as imest_isr_abc()
 */
int imest_isr_duty(imest_t *s, const float duty_abc[3], float vdc_v, const float i_abc_a[3], float theta_rad);

/** ISR call with alpha/beta quantities (power-invariant 3-2 transform, docs/METHOD.md
 *  §1: amplitude = line-to-line rms; an amplitude-invariant Clarke transform
 *  scales u and i alike, which leaves T_R and R_S unchanged but changes E,
 *  min_current_a and the saturation check, which then apply to alpha/beta).
 *  @retval 1, 0  as imest_isr_abc() */
int imest_isr_ab(imest_t *s, float u_alpha_v, float u_beta_v, float i_alpha_a, float i_beta_a,
                 float theta_rad);

/** End the current window now, shorter than window_s (a drive that stops, a
 *  recording that ends): it is handed to the background like a completed one
 *  and judged on the samples it has. Call from the ISR context.
 *  @retval 1  the window was handed over
 *  @retval 0  the window was empty, or dropped (overrun) */
int imest_isr_flush(imest_t *s);

/**
 * Background call: if a finished window is waiting, solve it, judge it and
 * fill *out. Bounded time (no unbounded iteration); stack: fw/README.md.
 * Call it until it returns 0.
 * @retval 1               *out holds the next window's result
 * @retval 0               no finished window is waiting
 * @retval IMEST_ERR_NULL  s or out is NULL
 */
int imest_background(imest_t *s, imest_result_t *out);

/** Windows dropped because the background had not released the previous one. */
uint32_t imest_overruns(const imest_t *s);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_H */
