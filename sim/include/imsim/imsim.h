/* SPDX-License-Identifier: Apache-2.0 */
/*
 * imsim: host-side induction-motor simulator for the imest project.
 *
 * Model: eq. (1) of Wang, Chiasson, Bodson, Tolbert (IEEE TCST 2007) in the stationary
 * (a, b) frame, power-invariant 3-2 transform (docs/METHOD.md §1). Supplies: ideal sine,
 * ideal V/f, PWM inverter (event-exact; dead time and switch/diode drops; sine-triangle or
 * space-vector modulation; ideal or firmware timing), indirect field-oriented control (IFOC),
 * and commands from a controller outside the simulator (closed loop, firmware timing).
 * Sensors: ADCs (bits, range, clipping, seeded white noise), optional 2nd-order analog
 * anti-alias filter, incremental encoder. Thermal drift of R_S and R_R. Optional real-motor
 * effects (off by default): main-flux saturation, iron loss, double-cage rotor, in a
 * flux-linkage model (sim/README.md, Real-motor effects).
 *
 * Host only: never linked into the firmware. No malloc: the caller owns every struct.
 *
 * Usage:
 *   imsim_config_t c; imsim_config_preset(&c, "exp2"); c.supply = IMSIM_SUPPLY_PWM;
 *   imsim_t sim; imsim_sample_t s;
 *   if (imsim_init(&sim, &c, &s) != 0) { puts(imsim_error(&sim)); }
 *   ... s holds t = 0 ...
 *   for (;;) { imsim_step(&sim, &s); ... s holds t = T, 2T, ... }
 *
 * Units: SI (V, A, rad, s, N m, Wb, ohm, H, kg m^2). Phase quantities are phase-to-neutral,
 * currents positive into the motor, theta = mechanical angle (rad, unwrapped, increasing with
 * the a-b-c field).
 */
#ifndef IMSIM_IMSIM_H
#define IMSIM_IMSIM_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  IMSIM_SUPPLY_SINE = 0, /* ideal balanced sine, fixed vll/freq from t = 0 (DOL start)     */
  IMSIM_SUPPLY_VF = 1,   /* ideal sine following a V/f ramp over vf_ramp_s                */
  IMSIM_SUPPLY_PWM = 2,  /* PWM inverter, reference = the V/f ramp (or step)                */
  IMSIM_SUPPLY_IFOC = 3, /* IFOC current control driving the PWM inverter (or ideal stage)  */
  IMSIM_SUPPLY_EXT = 4   /* PWM inverter driven by the caller's commands, sample by sample
                            (imsim_set_duty / imsim_set_voltage), with firmware timing     */
} imsim_supply_t;

/* When the inverter's duties change (see sim/README.md, Firmware timing). */
typedef enum {
  IMSIM_TIMING_IDEAL = 0,   /* reference sampled at every half carrier period's centre: no
                               delay, duties change every half period (the default)          */
  IMSIM_TIMING_FIRMWARE = 1 /* as a drive's firmware: sample k at a carrier valley, duties
                               computed from it applied during [t_k+1, t_k+2); fs = f_c / N  */
} imsim_timing_t;

/* How phase references become leg duties. */
typedef enum {
  IMSIM_MOD_SPWM = 0, /* sine-triangle, no zero sequence: V_dc >= 2 sqrt(2/3) V_ll (default)  */
  IMSIM_MOD_SVPWM = 1 /* min-max zero-sequence injection (= symmetric space-vector PWM):
                         V_dc >= sqrt(2) V_ll                                                   */
} imsim_modulation_t;

typedef enum {
  IMSIM_VMEAS_AUTO = 0, /* AVG with PWM stages, INST with ideal supplies                      */
  IMSIM_VMEAS_AVG = 1,  /* phase-to-neutral volt-seconds of the carrier period that just ended,
                           from commanded duties and Vdc (what a drive knows); delay 1/(2 f_c) */
  IMSIM_VMEAS_AA = 2,   /* measured phase-to-neutral voltage through the AA filter            */
  IMSIM_VMEAS_INST = 3  /* raw instantaneous sample; ideal supplies only (with PWM every sample
                           falls in a zero vector, so imsim_init refuses it)                    */
} imsim_vmeas_t;

typedef enum { IMSIM_START_REST = 0, IMSIM_START_STEADY = 1 } imsim_start_t;
/* Load kind. PASSIVE (default): friction-like (a fan, pump, conveyor, brake): |load| opposes
   the motion and never drives the rotor; at rest it holds the rotor while |T_e| <= |load|
   (static friction) and breaks away when the motor's torque exceeds it. ACTIVE: a constant
   torque of load_nm opposing positive rotation whatever the speed (a hoist's weight, a
   dynamometer): it drives a rotor that stops backwards. See sim/README.md, Load. */
typedef enum { IMSIM_LOAD_PASSIVE = 0, IMSIM_LOAD_ACTIVE = 1 } imsim_load_kind_t;
typedef enum { IMSIM_IFOC_SPEED = 0, IMSIM_IFOC_TORQUE = 1 } imsim_ifoc_mode_t;
typedef enum {
  IMSIM_INTEGRATOR_FAST = 0, /* exact Taylor-Horner propagation of the linear electrical part
                                (event-exact PWM), speed frozen at a predicted mid-step value,
                                trapezoidal/Hermite mechanics                                  */
  IMSIM_INTEGRATOR_RK4 = 1   /* reference: classic RK4 of the full nonlinear model, split at
                                every switching instant, rk4_substeps per piece (slow)        */
} imsim_integrator_t;

typedef struct {
  /* Motor (paper's notation). M = sqrt((1 - sigma) L_S L_R), R_R = L_R / T_R (cold values). */
  int pole_pairs;
  double ls_h, lr_h, sigma;
  double rs_ohm; /* stator resistance at t_amb_c (cold)   */
  double tr_s;   /* rotor time constant at t_amb_c (cold) */
  double j_kgm2, b_nms;
  /* Nameplate, informational (0 = not given; the exp presets leave it so): the motor presets
     set it and size the load, sensors and IFOC limits from it. Line-to-line rms voltage,
     phase rms current, shaft power, torque and speed at the rated point. */
  double rated_voltage_v, rated_freq_hz, rated_power_w, rated_torque_nm, rated_speed_rpm, rated_current_a;

  /* Thermal model (copper): R(T) = R_cold (1 + alpha (T - t_amb_c)); each body first order,
     tau dT/dt = (t_amb + rth * P_cu) - T, P_cu = copper loss of that body (I^2 R). */
  bool thermal;
  double t_amb_c, alpha_per_k;
  double rth_stator_k_per_w, tau_stator_s;
  double rth_rotor_k_per_w, tau_rotor_s;
  double thermal_speedup; /* multiplies both thermal rates (1 = physical), for short tests */

  /* Load torque: 0 before load_on_s, linear ramp over load_ramp_s, then load_nm.
     imsim_set_load() overrides it at run time. load_kind PASSIVE (default): |load_nm| opposes
     the motion (at rest: up to |load_nm| of the motor's torque); ACTIVE: load_nm opposes
     positive rotation at any speed. */
  double load_nm, load_on_s, load_ramp_s;
  imsim_load_kind_t load_kind;
  /* A second change of the load (a load step inside a run): from load_step_on_s the profile
     goes linearly from load_nm to load_step_nm over load_step_ramp_s (0 = a step), then holds.
     load_step_on_s INFINITY (default): none, the profile above alone. */
  double load_step_nm, load_step_on_s, load_step_ramp_s;

  /* Supply. vll_v = line-to-line rms, freq_hz = electrical frequency. The V/f ramp (VF, PWM)
     raises frequency and voltage linearly from 0 over vf_ramp_s (0 = apply at once);
     V_ll(f) = vf_boost_v + (vll_v - vf_boost_v) f / freq_hz. */
  imsim_supply_t supply;
  double vll_v, freq_hz, vf_ramp_s, vf_boost_v;

  /* PWM inverter: regular sampled; with ideal timing the reference is sampled once per half
     carrier period (at its centre, i.e. delay-compensated); dead time and device drops with
     the half bridge's current-direction logic (sim/README.md, Inverter). */
  double carrier_hz, vdc_v, dead_time_s; /* dead time includes the effective switching delays */
  /* Inverter devices, per leg: a conducting switch drops v_switch_v + r_switch_ohm |i|, a
     conducting freewheeling diode v_diode_v + r_diode_ohm |i| (0 = ideal devices). */
  double v_switch_v, r_switch_ohm, v_diode_v, r_diode_ohm;
  imsim_modulation_t modulation;
  imsim_timing_t timing;
  bool pwm_moments; /* fast integrator with PWM. true (default, fast): one step per half carrier
                       period, the PWM input entering through its exact moments; the electrical
                       part is exact for the step's speed, the torque ripple inside the step is
                       resolved only approximately (speed/angle ~3e-5 relative vs reference).
                       false: integrate piecewise between switching instants (~1e-8, ~2.3x
                       slower). See README. */

  /* IFOC (indirect field orientation, slip from the controller's T_R). */
  imsim_ifoc_mode_t ifoc_mode;
  bool ifoc_ideal_stage; /* true: ideal voltage source (ZOH per sample) instead of PWM   */
  double ifoc_tr_s;      /* controller's T_R (<= 0: use the motor's cold tr_s)            */
  double ifoc_flux_wb;   /* rotor flux reference (<= 0: rated flux of the preset)          */
  double speed_ref_rpm;  /* speed mode: reference, reached by a linear ramp over speed_ramp_s */
  double speed_ramp_s;
  /* speed mode: a second reference, from speed_step_on_s reached linearly from speed_ref_rpm over
     speed_step_ramp_s (0 = a step). speed_step_on_s INFINITY (default): none. */
  double speed_step_rpm, speed_step_on_s, speed_step_ramp_s;
  double torque_ref_nm; /* torque mode: reference (applied after flux build-up, see README) */
  double torque_limit_nm;
  double current_bw_hz, speed_bw_hz, speed_filter_hz;

  /* Sampling and sensors. fs_hz must divide 2 * carrier_hz for PWM stages. */
  double fs_hz;
  int steps_per_sample; /* integration steps per sample; 0 = auto (PWM: 2 f_c / fs; else 5) */
  bool ideal_sensors;   /* exact samples: no quantisation, noise, clipping, AA or encoder   */
  int adc_bits;
  double i_range_a, u_range_v; /* symmetric ranges: +-range (clipping)                    */
  double vdc_range_v;          /* DC-bus ADC, unipolar 0..range (PWM stages)               */
  double noise_lsb;            /* white Gaussian noise, rms in LSB, added before the ADC    */
  int encoder_counts;          /* counts per mechanical revolution, floor quantisation      */
  double i_offset_a[3];        /* per-phase sensor offset, added before the ADC [A]         */
  double u_offset_v[3];        /* per-phase sensor offset, added before the ADC [V]         */
  double i_gain_err[3];        /* per-phase relative gain error (0.01 = reads 1 % high)     */
  double aa_hz;                /* 2nd-order Butterworth analog AA filter cut-off; 0 = none  */
  imsim_vmeas_t vmeas;
  uint64_t seed;

  imsim_start_t start;
  imsim_integrator_t integrator;
  int rk4_substeps; /* RK4 steps per constant-input piece */

  /* Real-motor effects (sim/README.md, Real-motor effects). All 0 = off (the default): the
     paper's linear machine, integrated as above. Any of them on: the flux-linkage model
     (states psi_S, psi_R1, psi_R2, psi_m), integrated by sub-stepped RK4 whatever integrator
     says. The rated point (V_n, f_n, T_n) is rated_voltage_v/rated_freq_hz/rated_torque_nm when
     given, else vll_v/freq_hz/load_nm; psi_n = |psi_m| of the linear model there.
     sat_fraction in [0, 0.6): static L_m at psi_n is M = sqrt((1 - sigma) L_S L_R) and the
       unsaturated L_m0 = M / (1 - sat_fraction); i_m = psi/L_m0 (1 + a (psi/psi_n)^6).
     iron_loss_fraction in [0, 0.2): R_fe across the magnetising branch, R_fe = (2 pi f_n psi_n)^2
       / (fraction P_n), P_n = rated_power_w (or the rated point's shaft power).
     rotor_cage_ratio: 0 = single cage; > 1: double cage whose R_R at f_n (standstill) is
       ratio x its DC value R_R, with the DC R_R and DC leakage of the single cage. */
  double sat_fraction, iron_loss_fraction, rotor_cage_ratio;

  double duration_s; /* used by the CLI and the benchmark only */
} imsim_config_t;

typedef struct {
  uint64_t n; /* sample index; t = n / fs */
  double t;

  /* Measured (what the drive sees). */
  double u_abc[3]; /* V, phase-to-neutral (see vmeas)            */
  double i_abc[3]; /* A                                          */
  double theta;    /* rad, unwrapped, encoder-quantised          */

  /* Truth. */
  double tr_s, rs_ohm;       /* present (temperature-dependent) values        */
  double speed_rad_s;        /* mechanical                                    */
  double torque_nm, load_nm; /* electromagnetic torque, load torque           */
  double psi_r_wb;           /* rotor-flux magnitude |psi_R| (alpha-beta)     */
  double temp_stator_c, temp_rotor_c;
  double i_abc_true[3], theta_true;
  double u_abc_true[3];                         /* ideal supplies: instantaneous; PWM: actual applied (dead
                                  time and drops included) average over the last carrier
                                  period (firmware timing: the last sample period)       */
  double i_ab_true[2], psi_ab[2], u_ab_true[2]; /* alpha-beta state (power invariant)   */
  double accel_rad_s2;                          /* d omega / dt from the model at t               */
  double p_cu_stator_w, p_cu_rotor_w;
  /* Real-motor effects (NaN when all are off; sim/README.md, Real-motor effects): main flux
     |psi_m|, static L_m(|psi_m|), the single-cage equivalent an IFOC's slip relation needs at
     the present slip frequency (L_R = L_m + L_lr,eff, R_R,eff; tr_s is then L_R / R_R,eff),
     iron loss, stored magnetic energy. tr_ifoc_s: the T_R for which an IFOC's slip relation
     omega_sl = i_q / (T_R i_d) holds in the steady state at the present flux and slip, with
     i_d, i_q in the rotor-flux frame (sim/README.md, Truth columns with the effects on); it
     equals tr_s without iron loss. */
  double psi_m_wb, lm_h, lr_eff_h, rr_eff_ohm, p_fe_w, w_mag_j, tr_ifoc_s;
  /* IFOC (NaN when not IFOC). */
  double ifoc_torque_ref_nm, ifoc_flux_ref_wb, ifoc_tr_s, ifoc_speed_ref_rad_s;
  /* Drive (PWM stages). duty: upper-switch duty of each leg, in [0, 1], applied during
     [t, t + 1/fs) (computed one sample earlier); firmware timing only, else NaN.
     vdc_v: DC bus sampled at t through its ADC; vdc_true_v: the bus (NaN without PWM). */
  double duty[3];
  double vdc_v, vdc_true_v;
} imsim_sample_t;

/* Steady state of the model under a balanced sinusoidal supply (phasor solution of eq. (1)). */
typedef struct {
  double speed_rad_s, speed_rpm, slip;
  double i_rms_phase, torque_nm, psi_r_wb;
  double i_ab[2], psi_ab[2]; /* alpha-beta state at supply phase 0 (u = vll + j0) */
  /* Real-motor effects (0 when off): main flux |psi_m|, static L_m there, iron loss. */
  double psi_m_wb, lm_h, p_fe_w;
} imsim_steady_t;

/* Private state. Declared here only so that the caller can own the storage (no malloc). */
typedef struct {
  double re, im;
} imsim_cpx_t;
typedef struct {
  uint64_t s[4]; /* xoshiro256** */
  double spare;  /* second Gaussian of the polar method */
  bool has_spare;
} imsim_rng_t;
/* Real-motor model: derived parameters and flux-linkage state (realmotor.c). */
typedef struct {
  bool on, fe, dc;
  double lls_h, llr_h;               /* stator leakage; single-cage rotor leakage L_R - M       */
  double lm0_h, psi_n_wb, sat_a;     /* unsaturated L_m, rated main flux, curve coefficient    */
  double rfe_ohm;                    /* iron-loss resistance (fe)                               */
  double r1_ohm, l1_h, r2_ohm, l2_h; /* cold cage branches (single cage: r1 = R_R, l1 = L_lr) */
  double f_n_hz, h_max_s;
  /* reciprocals for the per-step currents (set once by the derivation; a division costs as
     much as the rest of a Newton step): 1/L_ls, 1/L_1, 1/L_2, 1/L_m0, the sum of 1/L over the
     branches and the magnetising node, and the curve's x^7 coefficient a / (L_m0 psi_n^6) */
  double inv_lls, inv_l1, inv_l2, inv_lm0, inv_psi_n, g_node, sat_k;
  imsim_cpx_t fl[4]; /* psi_S, psi_R1, psi_R2, psi_m (psi_m a state with R_fe only) */
  imsim_cpx_t psi_m_prev;
  double e_fe_j;      /* iron-loss energy integrated with the flux states (fe) */
  double e_fe_prev_j; /* ... and its value at the last sample, with its time   */
  double t_prev_s;
  bool has_prev;
} imsim_real_t;

typedef struct {
  imsim_config_t c;
  char err[320];
  imsim_real_t rm;
  /* derived constants */
  double m_h, rr0_ohm, ts_s, h_s;
  int k_steps;
  /* present parameters */
  double rs, rr, tr, gamma, beta;
  /* state: 0 i, 1 psi, 2-3 AA(i), 4-5 AA(u), 6 source voltage */
  imsim_cpx_t x[7];
  double w, th, t;
  uint64_t n;
  double te, acc; /* torque and acceleration at t */
  double temp_s, temp_r;
  double load_override;
  bool load_overridden;
  /* load.c: passive load holding the rotor at rest; stall record (imsim_get_stall) */
  bool load_stuck;
  uint64_t stall_events;
  double stall_first_t_s, stall_first_load_nm, stall_first_torque_nm, stall_held_s;
  /* supply bookkeeping */
  double u_hp_cmd[2][2], u_hp_act[2][2]; /* last two half-period averages (re, im) */
  int hp_count;
  double u_inst[2]; /* instantaneous applied voltage at t (alpha-beta) */
  /* IFOC */
  double ifoc_tr, ifoc_flux, speed_ref;
  double w_meas, th_meas_prev, slip_angle, integ_d, integ_q, integ_w;
  double v_dq[2], rho, we_ctrl, t_ctrl, te_ref, id_ref, iq_ref;
  double u_zoh[2];
  /* sensors: rng for the phase channels, rng_vdc (own stream) for the bus */
  imsim_rng_t rng, rng_vdc;
  double i_meas_ab[2];
  double th_meas;
  double vdc_meas;
  /* firmware timing: duties applied now and those computed at the last sample */
  double duty[3], duty_next[3];
  double u_sp_cmd[2], u_sp_act[2]; /* sums over the half periods of the last sample period */
  /* Taylor coefficients h^k/k! */
  double hk[32];
  /* modulation statistics (imsim_get_pwm_stats) */
  uint64_t pwm_half_periods, pwm_clipped_half_periods;
  double pwm_vdc_needed;
} imsim_t;

/* What the PWM modulator was asked for: a reference beyond the bus is clipped (the inverter
   saturates, as a real one does); these numbers let the caller say so. */
typedef struct {
  uint64_t half_periods;         /* PWM half carrier periods simulated so far                  */
  uint64_t clipped_half_periods; /* of which at least one leg's reference exceeded the bus     */
  double vdc_needed_v;           /* bus voltage that the largest reference so far would need  */
} imsim_pwm_stats_t;

/* Stall record: a run whose motor the load stops. An event is a moving rotor brought to rest
   by a passive load (its speed would have changed sign within an integration step), or, with
   an ACTIVE load, turned backwards by it (speed from > 0 to <= 0 while load_nm > 0, or the
   mirror image). */
typedef struct {
  uint64_t events;        /* stall events so far (0: the motor never stalled)                */
  double first_t_s;       /* time of the first event (NaN if none)                          */
  double first_load_nm;   /* load torque magnitude at it (NaN if none)                      */
  double first_torque_nm; /* the motor's electromagnetic torque at it (NaN if none)         */
  double held_s;          /* total time a passive load held the rotor at rest (static friction,
                             |T_e| <= |load|), including a start from rest before breakaway */
  bool at_rest_now;       /* a passive load holds the rotor at rest at the present sample    */
} imsim_stall_t;

/* Fills c with the paper's motor and the exp1 experiment (same as preset "exp1"). */
void imsim_config_default(imsim_config_t *c);
/* name: "exp1", "exp2" (the paper's motor and experiments) or one of the industrial drives
   "4kw", "11kw", "15kw", "37kw", "75kw" (400 V 50 Hz motors on a 560 V, 8 kHz inverter with
   firmware timing, at rated load; see sim/README.md, Presets). Returns 0, or -1 for an
   unknown name (c then holds exp1). */
int imsim_config_preset(imsim_config_t *c, const char *name);
/* Turns on the real-motor effects with realistic sizes for the motor in c (by its
   rated_power_w: the drive presets' own; otherwise those of the exp presets), see sim/README.md,
   Real-motor effects. */
void imsim_config_real_motor(imsim_config_t *c);
/* The preset names, separated by '|'. */
const char *imsim_preset_names(void);

/* Validates c, sets up sim, and fills *first (may be NULL) with the t = 0 sample.
   Returns 0, or -1 with a message in imsim_error(sim). */
int imsim_init(imsim_t *sim, const imsim_config_t *c, imsim_sample_t *first);
const char *imsim_error(const imsim_t *sim);

/* Advances exactly one sample period 1/fs and fills *out with the sample at the new time. */
void imsim_step(imsim_t *sim, imsim_sample_t *out);

/* Modulation statistics since imsim_init (all zero without a PWM stage). */
void imsim_get_pwm_stats(const imsim_t *sim, imsim_pwm_stats_t *out);
void imsim_get_stall(const imsim_t *sim, imsim_stall_t *out); /* see imsim_stall_t              */

/* Run-time controls. */
void imsim_set_ifoc_tr(imsim_t *sim, double tr_s);  /* controller's T_R, takes effect at the next step */
void imsim_set_speed_ref(imsim_t *sim, double rpm); /* IFOC speed reference (no ramp)          */
void imsim_set_torque_ref(imsim_t *sim, double nm); /* IFOC torque-mode reference              */
void imsim_set_load(imsim_t *sim, double load_nm);  /* overrides the load profile              */

/* External commands (supply IMSIM_SUPPLY_EXT), firmware timing: after imsim_init or
   imsim_step has returned the sample at t_k, the caller sets the command computed from it; it
   is applied during [t_k+1, t_k+2) (the step after the next one). A command holds until the
   next call; before the first one the duties are 0.5 (zero voltage).
   imsim_set_duty: upper-switch duties of legs a, b, c in [0, 1] (clipped).
   imsim_set_voltage: phase-voltage command (V, phase-to-neutral; its zero sequence is
   ignored), converted to duties with the configured modulation and the bus voltage measured
   at t_k (the sample's vdc_v), clipped at the bus. Both return 0, or -1 if the supply is not
   IMSIM_SUPPLY_EXT or a value is not finite. Clipping is counted in imsim_get_pwm_stats. */
int imsim_set_duty(imsim_t *sim, const double duty[3]);
int imsim_set_voltage(imsim_t *sim, const double u_abc[3]);

/* Phasor steady state of the configured motor (cold parameters) at the given supply and load
   (load opposes rotation; viscous friction included). With a real-motor effect on, the phasor
   solution of the flux-linkage model (R_fe || jX_m(|psi_m|), the cage's branches; exact, since
   |psi_m| is constant under a balanced sine), psi_r_wb/psi_ab then = psi_m + L_lr i_R, and
   psi_m_wb, lm_h, p_fe_w are set (0 otherwise). Returns 0, or -1 if the load exceeds the
   breakdown torque (or the real-motor configuration is impossible). */
int imsim_steady_state(const imsim_config_t *c, double vll_v, double freq_hz, double load_nm,
                       imsim_steady_t *out);

/* The real-motor parameters derived from c (sim/README.md, Real-motor effects), cold:
   magnetising curve i_m(psi) = psi/lm0_h (1 + sat_a (psi/psi_n_wb)^6) (sat_a = 0: linear,
   lm0_h = M); leakages; rfe_ohm (0 = no iron loss); rotor branches r1/l1 and r2/l2 (single
   cage: r1 = R_R, l1 = L_R - M, r2 = l2 = 0); the rated frequency f_n_hz; the RK4 step bound.
   Returns 0 (all zero when no effect is on), or -1 for an impossible configuration. */
typedef struct {
  double lm0_h, psi_n_wb, sat_a, lls_h, llr_h, rfe_ohm, r1_ohm, l1_h, r2_ohm, l2_h, f_n_hz, h_max_s;
} imsim_real_params_t;
int imsim_real_params(const imsim_config_t *c, imsim_real_params_t *out);

/* Power-invariant transforms (docs/METHOD.md §1). */
void imsim_abc_to_ab(const double abc[3], double ab[2]);
void imsim_ab_to_abc(const double ab[2], double abc[3]);

#ifdef __cplusplus
}
#endif

#endif /* IMSIM_IMSIM_H */
