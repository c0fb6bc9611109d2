/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_commission.h
 * @brief imest self-commissioning: identifies, on the drive and before normal
 *        operation, the constants the estimator needs (R_S, sigma*L_S, L_S,
 *        sigma, n_p, the inverter's voltage error) and checks the wiring
 *        (current channels, encoder direction and counts, phase order).
 *
 * The routine is a state machine the firmware calls once per sample from its
 * PWM-synchronous ISR, in place of its own controller. It reads the phase
 * currents, the DC bus and the encoder angle and returns the three duty cycles
 * for the next PWM period. Fitting runs in a background call. Nothing is
 * allocated; the instance is caller-owned (about 4 KiB, needed only while
 * commissioning: it may share memory with the estimator's instance).
 *
 * Usage:
 *
 *     imest_comm_config_t cc;
 *     imest_comm_config_default(&cc);
 *     cc.fs_hz = 8000.0f;  cc.i_max_a = 11.6f;          // peak phase current allowed
 *     cc.allow_rotation = 1;                             // the shaft may turn (no load)
 *     cc.rated_voltage_v = 400.0f; cc.rated_freq_hz = 50.0f; cc.rated_speed_rpm = 1441.0f;
 *     cc.encoder_cpr = 4096.0f;                          // what the firmware assumes
 *     static imest_comm_t comm;
 *     if (imest_comm_init(&comm, &cc) != IMEST_OK) { imest_comm_config_check() names the field }
 *
 *     // PWM ISR, once per sample, instead of the controller:
 *     float d[3];
 *     if (imest_comm_isr(&comm, i_abc_a, vdc_v, theta_rad, d) == 1) load_shadow_registers(d);
 *     else disable_pwm_outputs();                         // finished, failed or aborted
 *
 *     // background task (any lower priority), as often as convenient (>= every 10 ms):
 *     (void)imest_comm_background(&comm);
 *
 *     // when imest_comm_status() says DONE:
 *     imest_comm_result_t r;  imest_comm_result(&comm, &r);
 *     imest_config_t cfg; imest_config_default(&cfg); cfg.fs_hz = ...;
 *     imest_comm_apply(&r, &cfg);                         // pole_pairs, ls_h, sigma, rs_nominal_ohm,
 *                                                         // tr_nominal_s, inverter, and how well
 *                                                         // L_S and sigma are known
 *     // and apply r.encoder_dir / r.encoder_cpr in the firmware's angle computation
 *
 * What the firmware must provide:
 *   - the three phase currents [A], positive into the motor, from three sensors (or two, with
 *     i_c = -i_a - i_b: then the gain mismatch is not observable), sampled at the carrier valley
 *     (the centre of the zero vector, as for current control);
 *   - the DC-bus voltage [V] sampled at the same instant;
 *   - the mechanical angle [rad] as the firmware computes it from its encoder with the counts per
 *     revolution it assumes (cc.encoder_cpr), wrapped or not;
 *   - the duties (upper switch on-time / period, centre-aligned PWM) returned by call k must be
 *     applied during the PWM period(s) that start at the next sample, k+1 (the usual scheme:
 *     written to the shadow registers, loaded at the next valley); cc.pwm_hz is the carrier
 *     (one or more periods per sample). The dead time must be the inverter's own, not compensated
 *     by the firmware: the routine measures it;
 *   - an ISR at a fixed rate cc.fs_hz, a background call at least every 10 ms (it does the
 *     fitting; the ISR waits for it at a few points, at most 10 s), and a motor at rest, free to turn
 *     if cc.allow_rotation (no load coupled, or only a small one).
 *
 * The sequence (durations for the motors of the README's table: 0.4 kW to 37 kW):
 *   1. Offsets (0.25 s): zero voltage (all duties 0.5); the mean currents are the sensors'
 *      offsets, subtracted from here on. Fails if a current flows (> 5 % of i_max_a).
 *   2. Wiring (< 0.2 s): short bipolar voltage pulses along the a, b and c axes, doubled until
 *      the current responds; the 3x3 response says which channel reads which leg and with which
 *      sign, and whether a phase is open. A rough sigma*L_S sets the current controller.
 *   3. Time constant (0.1 .. 8 s, about 3 T_R): a DC current on the a axis; the decay of the
 *      voltage as the rotor flux builds gives T_R, which sets the length of what follows.
 *   4. For each axis a, b, c: a DC current staircase 1/3, 2/3, 1, 2/3, 1/3 of level_frac * i_max_a,
 *      each plateau about 3 T_R long, under PI current control. Within each plateau the
 *      modulation alternates between three patterns with the same voltage: centred (every leg
 *      switches), lower-clamped (the two return legs' lower switches stay on) and upper-clamped.
 *      Clamped legs do not switch, so they lose no dead time and conduct one device type only.
 *      Then, at 1/3 level, a square-wave voltage (fs/8) on top of the DC current (0.2 s): the
 *      current's slope gives sigma*L_S. Then, at the same DC current, sigma*L_S at slip-frequency
 *      scale: a current of two tones, f1 = 6 / (2 pi T_R) and 3 f1, each 0.35 of the DC current
 *      (the phase currents never change sign, so the inverter's error is a constant and a
 *      resistance), each started at the phase that leaves the rotor flux no transient; 2 T_R
 *      to settle, then three periods of f1 (5.1 T_R in all). Then zero current until the rotor
 *      flux has decayed.
 *   5. With cc.allow_rotation only: a current-fed rotating field at no load, the identified
 *      inverter model as feed-forward (on the curve's levels one leg clamped to its rail, of
 *      the highest- and the lowest-voltage leg the one whose current is nearer zero:
 *      discontinuous PWM, so that no leg switches while its current is inside the ripple band,
 *      where the dead time's error is not the model's and, at no load, its fundamental lies
 *      along the voltage, in the reactive impedance):
 *      magnetise on the a axis (1 s + 3 T_R), ramp to speed_frac of rated frequency (ramp_s),
 *      then levels of magnetising current, the first settled 1 s + 3 T_R, each next 1 s and as
 *      many of its own rotor time constant as leave less than 0.02 % of its flux step (T_R at
 *      the level's flux, tau L_S / L_S standstill: below rated flux the iron is less saturated
 *      and T_R up to twice the standstill tails'), and measured (>= 1 s, whole electrical
 *      periods); ramp down. Every level
 *      stays within the staircase's top (a phase peak of level_frac * i_max_a, which the
 *      standstill part has driven already); the first is the rated flux's current with the
 *      standstill L_S (within 80 % of that top); each measured level's L_S sets the next (the
 *      background computes it while the ISR holds the level): the search for the current i* at
 *      which the no-load stator flux L_S(i) i is the rated flux psi, the stator flux at rated
 *      voltage and frequency at no load, V_rated / (w_rated sqrt(1 + (R_S / (w_rated L_S))^2))
 *      (the R_S drop taken off; at most 4 levels, until a step changes the current by < 1 %),
 *      then 3 levels for the magnetising curve at 0.82, 0.63 and 0.45 of the rated point's flux
 *      (field weakening to twice base speed: half the flux, less the load's drops). On a linear
 *      motor the first level is i* (4 levels in all); on a saturating one, whose standstill L_S
 *      is about half the rated-flux one, 5 to 7. (A voltage-fed V/f run oscillates at no load
 *      on a low-inertia motor.)
 *   The routine ends with zero voltage; its ISR call then returns 0 and the background call
 *   completes the result. Measured totals: 10.4 s at standstill for a 4 kW motor (T_R 128 ms;
 *   the slip-frequency test 2.0 s of it, at most 5.3 A of the 11.6 A limit), 38.7 s for 37 kW
 *   (T_R 553 ms; the test 8.5 s, 45.6 A of 96 A), plus 17 to 30 s of rotation (28 s for the 4 kW motor with
 *   saturation, 55 s for 11 kW and 60 s for 37 kW with their real motors' saturation; README,
 *   Commissioning, tools/commission/readme-tables).
 *
 * What is measured, and how (per axis, then combined; the spread between the three axes is
 * reported as a quality figure for each quantity):
 *   - R_S: slope of the plateau voltage against current, fitted per axis with a model of the
 *     flux tail (V = V_inf + A_p exp(-t/T_R) on each plateau, T_R shared), so the plateaus need
 *     not settle; the three patterns share R. A resistance in series with every leg cannot be
 *     told from R_S by any terminal measurement: the common part of the switch and diode slope
 *     resistances, min(r_sw, r_d), and the cables are in the identified R_S (subtract a known
 *     value with cc.r_series_ohm). That is also what the online estimator sees.
 *   - the inverter's voltage error (imest_inverter_t): the centred pattern loses twice the dead
 *     time per period along the axis (both legs switch), a clamped pattern once, and both have
 *     one switch and one diode drop in the loop: the difference gives the dead time, the rest the
 *     sum of the threshold voltages (split evenly between switch and diode: their difference
 *     enters only with the active-vector share, ~2 % at standstill, and is not separable); the
 *     upper- and lower-clamped patterns put the switch and the diode in the loop with different
 *     currents, which separates r_sw - r_d. i_band_a is 0: the estimator then sets the smooth
 *     sign's band per leg and sample from its own duties (imest_inverter_t).
 *   - current-sensor gains (three sensors): the motor's neutral floats, so the true currents sum
 *     to zero; the measured sum against the axis current gives each sensor's gain relative to
 *     the mean of the three (a common gain error is not observable: it scales R_S and L_S).
 *   - sigma*L_S: the current's response to the square wave (regression of the current step per
 *     period on the applied voltage, the current and a constant); that is the leakage at fs/8.
 *   - sigma*L_S at slip frequency (sigma_ls_slip_h): the impedance Z = U / I at each tone (U the
 *     commanded voltage, its zero-order hold's half-period delay removed) less the axis's DC
 *     resistance R is, in the inverse-Gamma circuit, Z - R = j w S + 1 / (1 / R_R' + 1 /
 *     (j w L_M)), S = sigma L_S. The tones measure the circuit linearised at the test's DC
 *     current: on a saturating motor L_M there is the incremental inductance at that flux, and
 *     no T_R the standstill tails give (large steps through the curve: 0.5 to 0.8 x the tones'
 *     T_R on the 4 kW real motor) is the T_R the tones see. So T_R is not taken from anywhere:
 *     L_M is the same at both tones and R_R' may differ (deep bars), which makes S the root of
 *     w_1 Im y_1 = w_2 Im y_2 (= -1 / L_M), y_k = 1 / (Z_k - R - j w_k S), a root that the
 *     resistance's frequency dependence does not move and R's error hardly does. Why these
 *     frequencies: the estimator works at the slip frequency, which at rated torque is w_sl T_R
 *     = i_q / i_d, 1.5 to 3 on most motors (0.7 to 2.3 Hz on the 4 to 37 kW presets); at x =
 *     w T_R = 6 (f1, about 3 x the rated slip frequency) the rotor flux swings by 1 / 6 of what
 *     the tone's current would drive at DC (its magnetising current is 1 / sqrt(1 + x^2) of the
 *     tone), so the tones stay on the curve's tangent at the DC flux, and a deep-bar rotor is
 *     still near its DC values (R_R 0.3-1 %, its leakage 0.1-0.2 % off at 5 Hz on the
 *     simulator's). The upper tone is 3 f1, an odd multiple: the DC bias makes the curve's
 *     second-order term the largest of its nonlinearity, and its products (0, 2 f1, 4 f1,
 *     6 f1) miss both tones; with 2 f1 (the first design) the square of f1 fell on 2 f1 and
 *     f1's product with 2 f1 on f1, +1 % on S on the 4 kW real motor, by the tones' phases. What is
 *     left of the rotor's frequency dependence is the leakage's: a ladder network's R(w) and
 *     L(w) are even in w, so S(w) = S(0) - c (w / w_1)^2, and the root is S(0) - (M^2 + 1) c
 *     (M = 3: the root weights the tones 9:-1 over 8). A double cage (the usual model of a deep
 *     bar; the simulator's) has one pole tau, its leakage falling by tau x its resistance's rise:
 *     tau = (S - S_hf) / (R_hf - R - R_R'_1) from the square wave's S_hf and R_hf, and R_R'
 *     rises as w^2, (R_R'_2 - R_R'_1) / (M^2 - 1) up to f1, so c = tau x that rise. The value is
 *     the root plus (M^2 + 1) c, S(0) (the slip frequencies, up to about 3 x rated below f1,
 *     are within c of it), and (M^2 + 1) c its frequency dependence in spread_rel (0.6 % on the
 *     4 kW double cage, 0.02 % on the 11 and 37 kW ones, whose tones are at 2 Hz). After the
 *     rotating run spread_rel also covers S's move from the tones' incremental L_M to the
 *     static one at rated flux, (L_lr / L_R)^2 |dL_m| <= (S / L_M)^2 |dL_M| (the bound takes
 *     all of the leakage as the rotor's: the split is not observable at the terminals).
 *   - T_R: the flux tail's time constant (reported; fills tr_nominal_s). L_S at standstill:
 *     sigma*L_S plus (1-sigma)L_S from the tail amplitudes at the current steps (used only when
 *     the shaft may not turn).
 *   - L_S (rotating): reactive part of the impedance at the field's frequency, from the commanded
 *     voltage (the inverter error compensated by its model) and the current, demodulated at the
 *     commanded angle; at no load the slip is ~1e-4, and is corrected for. Reported at the rated
 *     flux psi: interpolated (linearly in the current) between the search's last two levels to
 *     the current where L_S i = psi; the flux a drive runs at in its base speed range, where
 *     the estimator needs L_S (a saturating motor's L_m there is 15-25 % below unsaturated).
 *     If the current limit stops the search below psi, at that limit (the flux is then lower).
 *   - the magnetising curve (ls_curve_*): L_S at the three curve levels and at i*, each measured
 *     as L_S; the levels' fluxes spread evenly from the rated point's down to 0.45 of it, the
 *     flux range a drive runs at from base speed to field weakening at twice base speed (each
 *     level's current: its flux over L_S predicted from the levels measured before it, high
 *     where a saturating curve is concave, below about 0.85 of rated flux, so the lowest level's
 *     flux is at or below its target); its spread is L_S's flux dependence.
 *   - n_p, encoder direction and counts: the ratio of the commanded electrical frequency to the
 *     measured mechanical speed is dir * n_p * cpr_assumed / cpr_true. With cc.rated_speed_rpm,
 *     n_p = floor(60 f_rated / n_rated) (the nameplate is the only independent evidence: a
 *     4-pole motor with a 2048-count encoder looks exactly like a 2-pole motor with 4096), and the
 *     ratio gives the true counts per revolution. Without it, the firmware's counts are assumed
 *     right and n_p is the ratio rounded; a ratio more than 2 % from an integer fails with
 *     IMEST_COMM_REASON_POLE_PAIRS_AMBIGUOUS. The direction is the ratio's sign: -1 means the
 *     angle decreases while the field turns a-b-c (negate it, or swap two motor phases).
 *   - phase order: the wiring pulses (standstill) and, rotating, the current's negative-sequence
 *     share (a swapped pair of current channels makes the measured current turn backwards).
 *
 * Accuracy (closed loop on the simulator: 12-bit sensors with offsets and +-1 % gain mismatch,
 * 4096-count encoder, 2 us dead time, 1 V / 0.8 V drops with slopes; README, Commissioning, for
 * the table per motor, 0.4 to 37 kW): R_S within 0.15 % of the identifiable value (winding plus
 * the devices' common slope resistance), L_S within 0.1 % rotating (0.1 % standstill), sigma
 * within 0.25 %, T_R within 0.2 %, dead time within 2 ns, the inverter's per-leg voltage error
 * within 0.1 V where the switch and diode thresholds differ by 0.2 V (the part standstill cannot
 * see; the rest of the model is right to a few mV).
 *
 * On a saturating motor (the simulator's static magnetising curve, `imest-commission --saturation
 * 0.25`, and its real motor with iron loss and a double cage, `--real-motor`), against the truth
 * at the rated V/f flux at no load, before (the rotating run at the standstill L_S's current)
 * and with the levels:
 *
 *     motor                 L_S before / now     sigma before / now    T_R (standstill)
 *     4 kW, saturation 0.25  -10.5 % / +0.12 %   +11.9 % / -0.02 %     -20.0 %
 *     4 kW, real motor       -10.5 % / +0.38 %   -37.6 % / -44.4 %     -19.9 %
 *     11 kW, saturation 0.25 -19.0 % / +0.21 %   +23.3 % / -0.31 %     -30.0 %
 *     11 kW, real motor      -18.6 % / +0.43 %   -29.6 % / -43.0 %     -30.0 %
 *
 * and the curve's points within 0.35 % of the truth at their currents (0.15 % on the linear
 * motors; L_S there unchanged): +0.33 % at the lowest flux on the 4 kW real motor, stated
 * 0.69 % there (ls_uncertainty x rated flux / its flux), +0.07 / +0.15 / +0.14 % on the 4 / 11 /
 * 37 kW motors with saturation alone. Before the clamp on the curve's levels and the per-level
 * settle the lowest point read +0.67 / +1.45 / +1.75 % high (+1.38 % on the 4 kW real motor): the
 * dead time's error (its current 3 x the ripple band on the 4 kW motor) and the rotor flux still
 * settling (11 and 37 kW: T_R at that flux about twice the standstill one). What the levels do not fix, and the result says so: T_R comes from the
 * standstill flux tails, which on a saturating motor run at other currents (incremental, not
 * static, inductance): tr_s.spread_rel is at least the standstill L_S's departure from the
 * rated-flux one (41 % and 53 % on these motors), and T_R at rated flux may be off by as much.
 * A double-cage rotor's sigma*L_S at the square wave's fs/8 is its outer cage's leakage, not
 * the leakage at slip frequency the estimator needs (sigma -44 % on the 4 kW real motor): the
 * square wave's resistance shows such a rotor (IMEST_COMM_FLAG_ROTOR_HF: 6 to 37 x R_R' on the
 * simulator's double cages, at most 2.2 x on its single cages, saturating or not), and sigma
 * then comes from the slip-frequency test (IMEST_COMM_FLAG_SIGMA_SLIP). Without saturation
 * (`imest-commission --real-motor --saturation 0 --iron-loss 0`) sigma is +0.01 % (0.4 kW),
 * -0.01 % (4 kW), -0.06 % (11 kW), -0.14 % (37 kW) off the truth at slip frequency, stated to
 * 0.77 / 0.95 / 0.5 / 0.5 % (was -44 %, or the data sheet's 20 %). With saturation (the real
 * motor) the tones find their own magnetising branch (the standstill T_R, from the tails at
 * other currents, once put sigma 35 % low on the 4 kW real motor, stated 77 % uncertain):
 * sigma +0.19 % (0.4 kW), -0.45 % (4 kW) off the truth at rated flux, stated 4.8 / 1.4 %, most of
 * it the bound on the leakage's move between the test's incremental L_M and the rated-flux one
 * (the measured move: +0.5 % / +0.08 % on sigma*L_S).
 *
 * Limits: the current never exceeds i_max_a in any phase (the routine stops with
 * IMEST_COMM_REASON_OVERCURRENT if it does: the firmware's own protection stays in charge); the
 * phase voltage stays below v_max_v and the bus; the whole run stops after time_max_s. Every call
 * is bounded: the ISR call has no data-dependent loop (a few hundred instructions, fw/README.md);
 * the background's fits have fixed iteration counts.
 *
 * Concurrency: imest_comm_isr() from one context, imest_comm_background() from one other of
 * lower priority (or the same one); imest_comm_abort() and the read-only calls from anywhere.
 * The ISR hands blocks of sums to the background through counters, as the estimator does
 * (IMEST_BARRIER).
 */
#ifndef IMEST_IMEST_COMMISSION_H
#define IMEST_IMEST_COMMISSION_H

#include <stdint.h>

#include "imest/imest.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ----------------------------------------------------------------------------
 * Configuration
 * ------------------------------------------------------------------------- */

/** Commissioning configuration. Fill with imest_comm_config_default(), then set at least fs_hz
 *  and i_max_a (and the rated values for the rotating part). */
typedef struct {
  float fs_hz;  /**< rate of the ISR call [Hz] (default 8000) */
  float pwm_hz; /**< carrier frequency [Hz]; a multiple of fs_hz (default 0: = fs_hz) */
  /** largest phase current the routine may reach, peak [A] (required; e.g. sqrt(2) x rated rms).
   *  The DC staircase goes up to level_frac of it; beyond it the routine stops. */
  float i_max_a;
  float level_frac;       /**< top of the DC staircase as a fraction of i_max_a (default 0.8) */
  float v_max_v;          /**< largest phase voltage amplitude commanded [V] (default 0: the bus) */
  float time_max_s;       /**< the whole run stops after this [s] (default 300) */
  float tr_max_s;         /**< longest rotor time constant to expect [s] (default 3) */
  unsigned int n_sensors; /**< current sensors: 3, or 2 (i_c computed by the firmware) (default 3) */
  /** counts per mechanical revolution the firmware assumes when it computes theta (0: not
   *  given; the result then reports the ratio only) */
  float encoder_cpr;
  /** known resistance in series with each phase that should not count as R_S [ohm]: cables, or the
   *  common part of the switch and diode slope resistances from a data sheet (default 0) */
  float r_series_ohm;
  /** PWM layout: nonzero (default) if the upper switches' on-time is centred on the sample
   *  instant (output high while the up-down counter is below the compare value, sample at the
   *  counter's zero; the simulator's layout); 0 if the lower switches' on-time is (high while
   *  above). One clamped pattern then has its sample inside the active pulse, which the dead
   *  time shifts by half its length: the routine corrects for it. */
  int pwm_on_centred;

  /* Rotating part. */
  int allow_rotation;    /**< nonzero: the shaft may turn, at no load (default 0: standstill only) */
  float rated_voltage_v; /**< rated line-to-line rms voltage [V] (required for rotation) */
  float rated_freq_hz;   /**< rated frequency [Hz] (required for rotation) */
  /** rated speed [rpm] from the nameplate (0: unknown): n_p = floor(60 f_rated / n_rated), and
   *  the encoder counts are then checked, not assumed */
  float rated_speed_rpm;
  float speed_frac; /**< speed of the rotating run as a fraction of rated (default 0.4) */
  float ramp_s;     /**< frequency ramp time up and down [s] (default 2) */
} imest_comm_config_t;

/** Fill with defaults (fs 8 kHz, level 0.8, 300 s, standstill only; i_max_a must be set); every
 *  field is written. */
void imest_comm_config_default(imest_comm_config_t *cc);

/** Check a commissioning config.
 *  @param field  optional: receives the name of the first bad field (NULL if none)
 *  @retval IMEST_OK          usable
 *  @retval IMEST_ERR_NULL    cc is NULL
 *  @retval IMEST_ERR_CONFIG  a field is out of range (*field names it) */
int imest_comm_config_check(const imest_comm_config_t *cc, const char **field);

/* ----------------------------------------------------------------------------
 * Progress and result
 * ------------------------------------------------------------------------- */

/** State of a run. */
typedef enum {
  IMEST_COMM_IDLE = 0,      /**< initialised, no sample yet */
  IMEST_COMM_RUNNING = 1,   /**< commanding the inverter (imest_comm_isr returns 1) */
  IMEST_COMM_COMPUTING = 2, /**< finished commanding; the background completes the result */
  IMEST_COMM_DONE = 3,      /**< result complete (check its flags and qualities) */
  IMEST_COMM_FAILED = 4,    /**< stopped: imest_comm_result_t.reason says why */
  IMEST_COMM_ABORTED = 5    /**< stopped by imest_comm_abort() */
} imest_comm_state_t;

/** The stage being run (progress). */
typedef enum {
  IMEST_COMM_STAGE_OFFSETS = 0,
  IMEST_COMM_STAGE_WIRING = 1,
  IMEST_COMM_STAGE_TIME_CONSTANT = 2,
  IMEST_COMM_STAGE_STAIRCASE = 3, /**< DC current staircase with the three modulation patterns */
  IMEST_COMM_STAGE_PULSES = 4,    /**< square-wave voltage for sigma*L_S */
  IMEST_COMM_STAGE_SLIP = 5,      /**< two-tone current at slip-frequency scale for sigma*L_S there */
  IMEST_COMM_STAGE_DEMAGNETISE = 6,
  IMEST_COMM_STAGE_ROTATE = 7, /**< rotating field: magnetise, ramp, settle, measure, ramp down */
  IMEST_COMM_STAGE_END = 8
} imest_comm_stage_t;

/** Why a run failed (imest_comm_result_t.reason). Stable values. */
typedef enum {
  IMEST_COMM_REASON_NONE = 0,
  IMEST_COMM_REASON_ABORTED = 1,         /**< imest_comm_abort() */
  IMEST_COMM_REASON_INPUT_FAULT = 2,     /**< a non-finite sample, or the bus voltage absent or moving */
  IMEST_COMM_REASON_OVERCURRENT = 3,     /**< a phase current beyond i_max_a */
  IMEST_COMM_REASON_CURRENT_AT_REST = 4, /**< current flows at zero voltage: offsets beyond 5 % of i_max_a */
  IMEST_COMM_REASON_OPEN_PHASE = 5,      /**< an axis draws no current: open phase, motor not connected */
  /** the current channels do not match the legs (permuted or reversed): details in
   *  imest_comm_result_t.wiring_map */
  IMEST_COMM_REASON_WIRING = 6,
  IMEST_COMM_REASON_CURRENT_NOT_REACHED = 7, /**< the voltage limit is reached before the current level */
  IMEST_COMM_REASON_ROTOR_MOVED = 8,         /**< the rotor turned during the standstill tests */
  IMEST_COMM_REASON_TIMEOUT = 9,             /**< time_max_s reached */
  IMEST_COMM_REASON_BACKGROUND = 10,         /**< imest_comm_background() not called in time */
  IMEST_COMM_REASON_FIT = 11,                /**< a fit failed (no decay, singular, residual) */
  IMEST_COMM_REASON_IMPLAUSIBLE = 12,        /**< identified values outside physical ranges */
  IMEST_COMM_REASON_ENCODER_STILL = 13, /**< the motor turned (by its currents) but the angle did not move */
  IMEST_COMM_REASON_ROTOR_BLOCKED = 14, /**< the field turned but the rotor did not */
  IMEST_COMM_REASON_PHASE_ORDER = 15,   /**< the measured current turns against the commanded field */
  /** the speed ratio fits no integer n_p with the firmware's counts, and no rated speed was given */
  IMEST_COMM_REASON_POLE_PAIRS_AMBIGUOUS = 16,
  IMEST_COMM_REASON_CURRENT_LIMIT_ROTATING = 17 /**< the rotating run needs more than i_max_a */
} imest_comm_reason_t;

/** Short lower-case names ("none", "overcurrent", ...; "offsets", "staircase", ...). */
const char *imest_comm_reason_name(int reason);
const char *imest_comm_stage_name(int stage);
const char *imest_comm_state_name(int state);

/** Result flags (imest_comm_result_t.flags): what the result holds and what to watch. */
#define IMEST_COMM_FLAG_STANDSTILL    0x0001u /**< the standstill part completed */
#define IMEST_COMM_FLAG_ROTATED       0x0002u /**< the rotating part completed (L_S, n_p, encoder) */
#define IMEST_COMM_FLAG_GAINS         0x0004u /**< sensor gains identified (three sensors) */
#define IMEST_COMM_FLAG_LS_STANDSTILL 0x0008u /**< L_S and sigma from standstill only (less accurate) */
#define IMEST_COMM_FLAG_NP_NAMEPLATE  0x0010u /**< n_p from the rated speed; encoder counts measured */
#define IMEST_COMM_FLAG_NP_ASSUMED_CPR                                                                       \
  0x0020u /**< n_p from the speed ratio with the firmware's counts assumed right */
#define IMEST_COMM_FLAG_ENCODER_REVERSED 0x0040u /**< the angle decreases with the a-b-c field */
#define IMEST_COMM_FLAG_CPR_MISMATCH     0x0080u /**< the encoder counts differ from encoder_cpr */
#define IMEST_COMM_FLAG_AXIS_SPREAD      0x0100u /**< R_S or sigma*L_S differ by > 3 % between axes */
#define IMEST_COMM_FLAG_ROTOR_CREPT                                                                          \
  0x0200u /**< the rotor moved at standstill, by more than 0.01 rad (the stop is at 1 rad) */
#define IMEST_COMM_FLAG_LOAD_ON_SHAFT   0x0400u /**< slip x T_R > 0.05 while rotating: not at no load */
#define IMEST_COMM_FLAG_GAIN_MISMATCH   0x0800u /**< sensor gains differ by more than 0.5 % */
/** dead time and threshold voltages not separable (the clamped patterns' pulses were too short):
 *  the whole error is in dead_time_s */
#define IMEST_COMM_FLAG_INVERTER_LUMPED 0x1000u
/** the rotor's resistance at the square wave's frequency (fs/8) is over 3 x R_R' from the flux
 *  tails: deep bars or a double cage. Its sigma*L_S there (sigma_ls_hf_h) is below the one at
 *  slip frequency the estimator needs (44 % below on the simulator's double cages), so
 *  sigma_ls_h and sigma are the slip-frequency test's (IMEST_COMM_FLAG_SIGMA_SLIP); if that test
 *  has no value, sigma_ls_h.spread_rel is at least 0.5 and imest_comm_apply does not fill sigma:
 *  give it from the data sheet (its equivalent circuit at rated slip) */
#define IMEST_COMM_FLAG_ROTOR_HF        0x2000u
/** sigma_ls_h (and sigma) are the slip-frequency test's sigma_ls_slip_h, not the square wave's
 *  (set with IMEST_COMM_FLAG_ROTOR_HF when that test has a value) */
#define IMEST_COMM_FLAG_SIGMA_SLIP      0x4000u

/** One identified value with its quality. */
typedef struct {
  float value;   /**< the estimate (NaN if not identified) */
  float std_rel; /**< relative standard error from the fit's residuals (NaN if not known) */
  /** (max - min) / mean over the three axes (NaN if not per axis); for ls_h, sigma and tr_s
   *  after the rotating run, the flux dependence: see each */
  float spread_rel;
} imest_comm_value_t;

/** Result of a run. Every quantity carries its quality; `valid` says whether the result as a
 *  whole may fill a config (imest_comm_apply). */
typedef struct {
  int state;          /**< imest_comm_state_t */
  int reason;         /**< imest_comm_reason_t: why it failed (NONE if not) */
  int stage;          /**< imest_comm_stage_t reached (where it failed, if it did) */
  int valid;          /**< 1: DONE and every identified value plausible */
  unsigned int flags; /**< IMEST_COMM_FLAG_* */
  float time_s;       /**< duration of the run so far [s] */
  float i_peak_a;     /**< largest phase current seen [A] */
  float vdc_v;        /**< mean DC-bus voltage at the offsets stage [V] */

  /* current sensors */
  float i_offset_a[3]; /**< offsets (subtracted by the routine; the firmware should too) */
  float i_gain_rel[3]; /**< gain of each sensor relative to the mean of the three (1 if unknown) */
  /** channel read for each leg (0..2) times the sign (+1/-1), encoded as (channel + 1) * sign;
   *  {1, 2, 3} when the wiring is right */
  int wiring_map[3];

  /* standstill */
  imest_comm_value_t rs_ohm; /**< stator resistance (incl. min(r_sw, r_d), minus r_series_ohm) */
  float rs_axis_ohm[3];      /**< R_S per axis (gain corrected) */
  /** transient inductance sigma*L_S [H] the result's sigma is made of: the square wave's
   *  (sigma_ls_hf_h), or with IMEST_COMM_FLAG_SIGMA_SLIP the slip-frequency test's */
  imest_comm_value_t sigma_ls_h;
  imest_comm_value_t sigma_ls_hf_h; /**< sigma*L_S from the square wave at fs/8 [H] */
  /** sigma*L_S at the rotor's slip frequency [H] (stage 5, the two-tone test): its value at
   *  rotor frequency 0, within the spread of it up to slip_test_hz. std_rel: NaN (one value per
   *  axis: their scatter is in the spread); spread_rel: the larger of the three axes' spread
   *  (their noise and the gains' errors), the leakage's frequency dependence the value is
   *  corrected for and, after the rotating run, its move to rated flux ("What is measured") */
  imest_comm_value_t sigma_ls_slip_h;
  float slip_test_hz; /**< the slip-frequency test's lower tone [Hz] (the upper one is 3 x it) */
  /** rotor time constant from the flux tails [s] (at the staircase's currents; after the rotating
   *  run spread_rel is at least |L_S - L_S standstill| / L_S: on a saturating motor T_R at rated
   *  flux differs from the standstill one by up to that) */
  imest_comm_value_t tr_s;
  imest_comm_value_t rr_ohm; /**< rotor resistance referred to the stator, (1-sigma)L_S/T_R [ohm] */
  /** the rotor's resistance at the square wave's fs/8 [ohm]: its R less R_S's axis resistance (with
   *  IMEST_COMM_FLAG_ROTOR_HF: over 3 x rr_ohm; imest_comm_apply() then describes the rotor at high
   *  frequency by it and sigma_ls_hf_h, imest_config_t.rotor_hf_rr_ratio) */
  imest_comm_value_t rr_hf_ohm;
  /** R_R' at the slip-frequency test's lower tone [ohm] (the inverse-Gamma circuit's, stage 5): the
   *  rotor resistance the high-frequency one is compared with (the flux tails' rr_ohm is far off
   *  on a saturating motor: 0.80 against 1.30 on the 4 kW real motor) */
  imest_comm_value_t rr_slip_ohm;
  imest_comm_value_t ls_standstill_h; /**< L_S from the standstill flux tails [H] */
  imest_inverter_t inverter;          /**< the inverter's voltage error model (incl. i_band_a, uncertainty) */
  imest_comm_value_t dead_time_s;     /**< dead time with its quality (also in inverter) */
  imest_comm_value_t v_threshold_v;   /**< (V_sw0 + V_d0) / 2 [V] */
  imest_comm_value_t dr_ohm;          /**< r_sw - r_d [ohm] */
  float dc_fit_rms_v;                 /**< rms residual of the plateau fits [V] */
  float rotor_moved_rad;              /**< largest angle change during the standstill part [rad] */

  /* rotating */
  /** stator inductance L_S [H]: rotating, at the rated flux (else standstill). std_rel: the
   *  rated point's standard error: the two levels' it is interpolated between, 0.1 % each (the
   *  rotating measurement's repeatability) through the interpolation's weights, plus a third of
   *  a bound on what the straight line leaves of the curve there (commission_fit_rotation.c).
   *  The interpolation's correction itself is measured, not an error; spread_rel: (max - min) /
   *  L_S over the magnetising curve, L_S's flux dependence (below 0.5 % on a linear motor,
   *  30-40 % on a saturating one) */
  imest_comm_value_t ls_h;
  /** total leakage factor sigma_L_S / L_S at rated flux. std_rel: sigma_ls_h's plus ls_h's;
   *  spread_rel: the larger of sigma_ls_h's and ls_h's (sigma follows L_S with the flux) */
  imest_comm_value_t sigma;
  unsigned int pole_pairs; /**< n_p (0 if not identified) */
  int encoder_dir;         /**< +1: the angle increases with the a-b-c field; -1: reversed; 0: unknown */
  float encoder_cpr;       /**< true counts per revolution (NaN if encoder_cpr not given) */
  float speed_ratio;       /**< commanded electrical / measured mechanical speed (signed) */
  float slip;              /**< slip of the rotating run (no load: ~1e-4) */
  float neg_seq_rel;       /**< |negative-sequence current| / |positive|, rotating (wiring check) */
  /** resistive part of the impedance rotating (R_S + losses), at the level nearest rated flux [ohm] */
  float rotating_r_ohm;
  float rotating_i_a;  /**< magnetising current at rated flux (alpha/beta amplitude) [A] */
  float rotating_f_hz; /**< electrical frequency of the rotating run [Hz] */
  /** the magnetising curve (rotating; 0 points otherwise): L_S at no load against the
   *  magnetising current, in increasing current: the three curve levels, at about 0.45, 0.63
   *  and 0.82 of the rated point's flux (the lowest at or below it), then the rated point (= ls_h, at
   *  rotating_i_a). From base speed to field weakening at twice base speed (imest.h,
   *  ls_curve_i_a, for the estimator's use of it outside the points). 2 to 4 points */
  unsigned int ls_curve_points;
  float ls_curve_i_a[4]; /**< magnetising current of each point (alpha/beta amplitude) [A] */
  /** L_S at that current [H]; each point is measured as ls_h is, and carries its uncertainty
   *  (ls_h.std_rel; imest_comm_apply's ls_uncertainty covers each point) */
  float ls_curve_h[4];
} imest_comm_result_t;

/** Progress, readable from any context. */
typedef struct {
  int state;         /**< imest_comm_state_t */
  int stage;         /**< imest_comm_stage_t */
  int reason;        /**< imest_comm_reason_t (NONE while running) */
  unsigned int axis; /**< axis of the staircase (0..2) */
  float time_s;      /**< elapsed [s] */
  float progress;    /**< 0..1, estimated */
} imest_comm_status_t;

/* ----------------------------------------------------------------------------
 * Instance (caller-owned; every field is private)
 * ------------------------------------------------------------------------- */

#define IMEST_COMM_NSUM 9 /**< sums per block */
/** blocks of one axis (5 plateaus x 9 + 8 square-wave), the three axes' slip-frequency sums, or
 *  the probe's */
#define IMEST_COMM_NBLK 56

/** One block of samples in one state, handed from the ISR to the background. */
typedef struct {
  uint32_t k0;  /**< index of its first sample */
  uint32_t n;   /**< samples summed */
  uint32_t tag; /**< kind, plateau and pattern */
  float s[IMEST_COMM_NSUM];
} imest_comm_block_t;

/** Per-axis fit (background): computed in float64, kept as float (each to well below its
 *  standard error). */
typedef struct {
  float r_ohm, r_std, td_s, td_std, vth_v, vth_std, dr_ohm, dr_std;
  float tau_s, tau_std, lm_h, slsig_h, slsig_std, rhf_ohm, gain_dev, rms_v, i_top_a;
  int ok, separable;
} imest_comm_axis_fit_t;

/** Commissioning instance. */
typedef struct {
  /* configuration and derived constants */
  imest_comm_config_t cfg;
  float ts_s, fpwm, i_trip, v_lim, wc, kp, ki, level_a, tau;
  uint32_t n_off, n_disc_level, n_disc_pattern, n_blk, n_hf_half, n_hf_blk, n_zero, n_max;
  uint32_t n_ramp, n_settle, n_meas;

  /* ISR state */
  uint32_t k;     /* samples since start */
  uint32_t stage; /* imest_comm_stage_t */
  uint32_t step;  /* sub-step within the stage */
  uint32_t cnt;   /* samples in the sub-step or block */
  uint32_t axis;  /* 0..2 */
  uint32_t plateau, block, posted, probe_k0, wait, lim_cnt, cnt_demag;
  float off[3];    /* current offsets */
  float ginv[3];   /* 1 / relative gains (after the standstill part) */
  float vdc0;      /* bus at the offsets stage */
  float d_app[3];  /* duties applied during the present period */
  float d_next[3]; /* duties returned at the last call (applied from the next sample) */
  float v_app;     /* axis voltage applied during the present period */
  float i_prev;    /* axis current at the last sample */
  float i_ref, i_ref_old, integ[3], step_area, i_mag;
  float sl_rough;             /* sigma*L_S the controller is tuned with [H] */
  float v_hf;                 /* square-wave amplitude */
  float th0, th_prev, th_dev; /* encoder */
  int32_t wraps;
  float i_peak;
  float acc_m[3], acc_m2[3], acc_vdc;
  float pulse_v, pulse_resp[3][3], pulse_vk[3], pulse_ik[3];
  uint32_t pulse_n, pulse_tries, pulse_nk[3];
  imest_comm_block_t cur; /* block being accumulated */
  /* rotation */
  float we, we_test, psi, psi_im, ls_ss, rs_ff, ph_c, ph_s;
  float rot_sum[9]; /* I_sync d/q, I_neg d/q, U d/q, |i|^2, n, w_e */
  float rot_th0, rot_th1;
  int32_t rot_w0, rot_wraps;
  float inv_td_f, inv_v, inv_rsw, inv_rd, inv_band; /* inverter feed-forward model */
  /* slip-frequency test: the tones' phasors e^{j (w k T + phi)} and their steps e^{j w T}; DC
     current, each tone's amplitude, the DC voltage; the lower tone [rad/s] and its period in
     samples */
  float sl_c[2], sl_s[2], sl_cw[2], sl_sw[2], sl_bias, sl_amp, sl_u0, sl_w;
  float sl_lm; /* the tones' magnetising branch L_M [H] (incremental at the test's DC current) */
  uint32_t n_slip, n_slip_settle;

  /* hand-off */
  imest_comm_block_t blk[IMEST_COMM_NBLK];
  volatile uint32_t nblk;     /* blocks written (ISR) */
  volatile uint32_t job;      /* jobs posted (ISR) */
  volatile uint32_t job_kind; /* what to do (ISR) */
  volatile uint32_t job_nblk; /* blocks of the job (ISR) */
  volatile uint32_t done;     /* jobs done (background) */
  volatile uint32_t abort_req;
  volatile int state, reason;

  /* background results (the ISR reads them once their job is done) */
  float bg_tau, bg_sl, bg_ginv[3];
  int bg_tau_ok, bg_fail, final_ready, final_fail;
  imest_comm_axis_fit_t fit[3];
  imest_comm_result_t res;
} imest_comm_t;

/* ----------------------------------------------------------------------------
 * API
 * ------------------------------------------------------------------------- */

/** Initialise (config checked). Not concurrently with the other calls.
 *  @retval IMEST_OK, IMEST_ERR_NULL, IMEST_ERR_CONFIG (imest_comm_config_check() names the field) */
int imest_comm_init(imest_comm_t *c, const imest_comm_config_t *cc);

/**
 * ISR call, once per sample. Bounded, no data-dependent loop.
 * @param i_abc_a   phase currents [A], positive into the motor (as sampled, offsets included)
 * @param vdc_v     DC-bus voltage sampled now [V]
 * @param theta_rad mechanical angle [rad] as the firmware computes it (encoder_cpr assumed)
 * @param duty_abc  out: upper-switch duties in [0, 1] for the period(s) starting at the next
 *                  sample; 0.5 each when the return value is not 1
 * @retval 1               running: apply duty_abc
 * @retval 0               not commanding (finished, failed or aborted): disable the PWM outputs
 * @retval IMEST_ERR_NULL  a pointer is NULL
 */
int imest_comm_isr(imest_comm_t *c, const float i_abc_a[3], float vdc_v, float theta_rad, float duty_abc[3]);

/**
 * Background call: runs the fits the ISR has handed over. Call it at least every 10 ms while
 * the state is RUNNING or COMPUTING. Bounded (fixed iteration counts).
 * @retval 1               a fit was done
 * @retval 0               nothing to do
 * @retval IMEST_ERR_NULL  c is NULL
 */
int imest_comm_background(imest_comm_t *c);

/** Stop at the next ISR call (zero voltage, state ABORTED). Any context.
 *  @retval IMEST_OK, IMEST_ERR_NULL */
int imest_comm_abort(imest_comm_t *c);

/** Progress. @retval IMEST_OK, IMEST_ERR_NULL */
int imest_comm_status(const imest_comm_t *c, imest_comm_status_t *st);

/** The result (complete when the state is DONE; partial otherwise, with the failure reason).
 *  @retval IMEST_OK, IMEST_ERR_NULL */
int imest_comm_result(const imest_comm_t *c, imest_comm_result_t *r);

/** How imest_comm_apply() states the uncertainty of the L_S and sigma it fills
 *  (ls_uncertainty, sigma_uncertainty of imest_config_t), relative:
 *
 *      ls_uncertainty    = max(F_ls, q(ls_h))                     (standstill: also q(ls_standstill_h))
 *      sigma_uncertainty = max(F_sigma, q(sigma), q(sigma_ls_h) + ls_uncertainty)
 *
 *  q(v) = max(3 v.std_rel, v.spread_rel) (a NaN term left out): a coverage factor of 3 on the
 *  fit's standard error, and the spread between the axes (rotating L_S: between the rotating and
 *  the standstill value); sigma is sigma*L_S / L_S, so its error is at most the two's summed.
 *  The floors F, rotating, are twice the accuracy stated above (L_S 0.1 %, sigma 0.25 %; what
 *  commissioning's own tests measure on the linear simulator, 0.4 to 37 kW: L_S within 0.07 %,
 *  sigma within 0.21 %): 0.2 % for L_S and 0.5 % for sigma. With IMEST_COMM_FLAG_LS_STANDSTILL
 *  (L_S from the flux tails at the staircase's DC flux, not at the running flux; 0.08 % on the
 *  linear simulator) 1 % and 2 %, the limits the standstill test holds. Each at most
 *  IMEST_COMM_UNCERTAINTY_MAX. What these cost: on the 4 kW motor at rated load T_R's bound
 *  gains about 0.3 % and R_S's about 3 % (R_S is small against the impedance there). A motor
 *  whose L_S depends on its flux (saturation): ls_h's and sigma's spread_rel hold their change
 *  over the magnetising curve (32-40 % on the saturating simulated motors), so without the curve
 *  in the config T_R is refused (constants_uncertain) rather than wrong; with the curve in the
 *  config (imest_comm_apply() copies it) the estimator takes L_S at each window's flux, and q()
 *  of ls_h and sigma is their 3 standard errors only: ls_h's the rated point's two levels and
 *  the interpolation's remainder, not its correction to the nearest level (which, counted as an
 *  error, stated 1.8 % and 5.5 % on the simulator's 11 and 37 kW motors with saturation, right
 *  to 0.11 % and 0.16 %; now 0.37 % and 0.53 %). Each curve point is measured as ls_h is
 *  and stated to ls_uncertainty x (rated flux / its flux) (imest.h, ls_curve_h: the same
 *  voltage error at a lower voltage), 2.2 x at the lowest. */
#define IMEST_COMM_LS_FLOOR               0.002f
#define IMEST_COMM_SIGMA_FLOOR            0.005f
#define IMEST_COMM_LS_FLOOR_STANDSTILL    0.01f
#define IMEST_COMM_SIGMA_FLOOR_STANDSTILL 0.02f
#define IMEST_COMM_UNCERTAINTY_MAX        0.5f

/**
 * Fill an estimator config from a result: pole_pairs, ls_h, sigma, rs_nominal_ohm, tr_nominal_s
 * and inverter (with i_band_a and uncertainty, and the bus in inverter_vdc_v), with IMEST_COMM_FLAG_ROTOR_HF
 * and IMEST_COMM_FLAG_SIGMA_SLIP the rotor at high frequency (rotor_hf_rr_ratio = rr_hf_ohm / rr_slip_ohm,
 * rotor_hf_sigma_ratio = sigma_ls_hf_h / sigma_ls_slip_h) - each only if the result holds it (sigma not with
 * IMEST_COMM_FLAG_ROTOR_HF unless IMEST_COMM_FLAG_SIGMA_SLIP: the config's stays, with its stated sigma_uncertainty, and
 * imest_config_check() names it if unset) - and, with ls_h and sigma, ls_uncertainty and
 * sigma_uncertainty by the rule above; the magnetising curve (ls_curve_points, ls_curve_i_a,
 * ls_curve_h) when the result has 2 or more points and the build follows L_S with the flux
 * (not with IMEST_WITH_FLUX=0). The sample rate, window and the other fields stay as they are;
 * set pwm_hz to the carrier.
 * @return the number of fields filled (0..8: the curve counts as one, the uncertainties are not
 *         counted; the deep-bar rotor's description, rotor_hf_rr_ratio and rotor_hf_sigma_ratio
 *         with IMEST_COMM_FLAG_ROTOR_HF and IMEST_COMM_FLAG_SIGMA_SLIP, as one; inverter_vdc_v
 *         goes with the inverter), or
 * @retval IMEST_ERR_NULL  a pointer is NULL
 * @retval IMEST_ERR_ARG   the result is not valid (r->valid == 0): nothing filled
 */
int imest_comm_apply(const imest_comm_result_t *r, imest_config_t *cfg);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_COMMISSION_H */
