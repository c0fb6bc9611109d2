/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_instance.h
 * The estimator instance's layout: public only so that the caller can
 * allocate it statically (`static imest_t est;`). Every field is private to
 * the library; none is part of the API, and the layout changes between
 * versions without notice. Included by imest.h; do not include it alone.
 *
 * Who writes what (the concurrency contract of imest.h): the fields marked
 * "ISR" are written only by the ISR calls; "window" fields of win[] are
 * written by the ISR while it fills that buffer and read by the background
 * only after the buffer is published; "background" fields are written and
 * read only by imest_background(); "init" fields are written by imest_init()
 * alone and read by both.
 */
#ifndef IMEST_IMEST_INSTANCE_H
#define IMEST_IMEST_INSTANCE_H

#ifndef IMEST_IMEST_H
#error "include imest/imest.h, not imest/imest_instance.h"
#endif

/* ----------------------------------------------------------------------------
 * Instance (caller-owned storage; every field is private to the library)
 * ------------------------------------------------------------------------- */

/** Arithmetic type of the ISR path: float32. IMEST_REAL_DOUBLE (defined only
 *  by the host-side float64 reference build, never in a firmware) makes it
 *  float64. */
#ifdef IMEST_REAL_DOUBLE
typedef double imest_real_t;
#else
typedef float imest_real_t;
#endif

/** Number of accumulated entries: 28 of R_W (7 columns), 7 of R_Wy, 1 of R_y,
 *  the rotation of the rotor-frame current (sum of i x di/dt: slip excitation),
 *  the white-noise evidence of the currents and voltages (sums of squared third
 *  differences), and the zero sequence of the phase currents (its correlation
 *  with i_alpha and i_beta, and its square: current-sensor gain mismatch). */
#define IMEST_NACC        42
/** Indices of the entries after the 36 of [W e]'[W e]. */
#define IMEST_ACC_ROT     36u
#define IMEST_ACC_NOISE_I 37u
#define IMEST_ACC_NOISE_U 38u
#define IMEST_ACC_I0A     39u
#define IMEST_ACC_I0B     40u
#define IMEST_ACC_UU      41u

/** One window's sums, as handed from the ISR to the background. */
typedef struct {
  imest_real_t sum[IMEST_NACC]; /**< folded block sums */
  imest_real_t blk[IMEST_NACC]; /**< the current (unfolded) block of each entry */
  imest_real_t c0[7];           /**< centring vector used for this window (y - W c0 accumulated) */
  imest_real_t rot;             /**< sum of the angle steps of the used samples [rad] */
  uint32_t seq;
  uint32_t samples;
  uint32_t used; /**< samples that passed (not warm-up, not faulty) */
  uint32_t nreg; /**< regressor samples in the sums (every second used sample) */
  uint32_t flags;
  /* What the background needs of the ISR's state, as it was when the window
   * closed (the background reads nothing of the ISR's live state): */
  uint32_t duty_input;         /**< the window's last sample came through imest_isr_duty */
  imest_real_t vdc_v;          /**< duty input: the bus voltage of the window's last sample [V] */
  imest_real_t off_ia, off_ib; /**< the offsets the high-pass tracked at the window's end [A] */
  imest_real_t dth_end_rad;    /**< the angle observer's step (speed x T) at the window's end [rad] */
} imest_window_t;
/** A flag of imest_window_t.flags above the 16 bits a result carries (internal): the angle
 *  observer was engaged in the window (its angle and speed used, src/estimator/isr/isr_angle.h). */
#define IMEST_WFLAG_OBSERVER 0x10000u
/** ... the rotor swung at a steady mean speed: the angle observer's correction exceeded one encoder
 *  count (a V/f drive's hunting), so the steady-state bounds are taken at the least slip the swing
 *  visits (bg_validity.c, bounds()): `transient` where it reaches zero. */
#define IMEST_WFLAG_SWING    0x20000u

/** Butterworth-3 as a first-order and a second-order section (transposed DF-II).
 *  Bilinear low-pass sections have binomial numerators, so only their gains
 *  are stored. */
typedef struct {
  imest_real_t b0, a1;     /**< section 1: b0 (1 + z^-1) / (1 + a1 z^-1) */
  imest_real_t c0, d1, d2; /**< section 2: c0 (1 + 2 z^-1 + z^-2) / (1 + d1 z^-1 + d2 z^-2) */
} imest_bw3_t;

/** Filter state of one channel: 3 section states and the last two outputs. */
typedef struct {
  imest_real_t s1, s2a, s2b;
  imest_real_t y1, y2; /**< x_f[n-1], x_f[n-2] */
} imest_chan_t;

/** 2nd-order analog anti-alias model applied to the speed channel (bilinear:
 *  c0 (1 + 2 z^-1 + z^-2) / (1 + d1 z^-1 + d2 z^-2)). */
typedef struct {
  imest_real_t c0, d1, d2;
} imest_sos_t;

/** Constants of the duty-cycle input (imest_isr_duty): how the two periods
 *  around a sample are weighted, and the inverter model per leg
 *  (src/estimator/isr/isr_duty.h, docs/METHOD.md §17.1). */
typedef struct {
  imest_real_t w_prev;    /**< weight of the previous call's leg voltage (this call's: 1 - w_prev) */
  imest_real_t td_f_half; /**< dead time x carrier frequency / 2 */
  imest_real_t v_sum;     /**< switch plus diode threshold [V] */
  imest_real_t r_mean;    /**< mean of the switch's and the diode's slope [ohm] */
  imest_real_t dv, dr;    /**< switch minus diode: threshold [V] and slope [ohm] */
  /** T / (2 sigma L_S): the phase ripple's scale per bus volt [A/V] (0: the smooth sign with a
   *  fixed band, no ripple term) */
  imest_real_t ripple_per_v;
  imest_real_t band2;       /**< b^2 of a fixed band (i_band_a, edge_band_a), else 1e-12 [A^2] */
  imest_real_t floor_per_v; /**< the smooth sign's floor per bus volt, t_d / (6 sigma L_S) (0: none) [A/V] */
  imest_real_t vdc2_w;      /**< 12 / u_absurd_v^2: the bus voltage's weight in the absurdity test */
  imest_real_t zoh; /**< T / (12 sigma L_S): the staircase's aliased share of a sampled current [A/V] */
} imest_duty_model_t;

/** Angle tracking observer between the encoder and the rotation (src/estimator/isr/isr_angle.h). */
typedef struct {
  imest_real_t k1, k2, k3; /**< gains per sample */
  imest_real_t d;          /**< estimated angle minus encoder angle [rad] */
  imest_real_t dth;        /**< estimated angle step per sample [rad] */
  imest_real_t ddth;       /**< estimated change of the step per sample [rad] */
  imest_real_t d_max;      /**< one encoder count [rad] (huge: counts unknown) */
  uint32_t state;          /**< IMEST_ANG_* bits */
} imest_angle_t;
/** imest_angle_t.state: |d| exceeded d_max in this window (the tracker lags a motion) ... */
#define IMEST_ANG_OVER      1u
/** ... and in the window that ended last */
#define IMEST_ANG_OVER_LAST 2u
/** this window's decision found the mean speed steady */
#define IMEST_ANG_STEADY    4u
/** the observer's estimate in use (else the encoder as it is): set by the ISR from the last two
 *  windows' mean speeds */
#define IMEST_ANG_ENGAGED   8u
/** configured (angle_observer_hz >= 0) */
#define IMEST_ANG_ENABLED   16u

/** Consecutive windows' sums combined by the background (src/estimator/window/bg_combine.c). */
typedef struct {
  double rw[36]; /**< upper triangle of the 8x8 R_W (K form) */
  double rwy[8], rwe[8];
  double ry, ree;
  double e_c0;      /**< the noise's E at the centring, summed */
  double ry_raw;    /**< R_y before the noise compensation, summed */
  float c0[8];      /**< the centring of the last window */
  uint32_t n;       /**< windows combined (0: none) */
  uint32_t samples; /**< their samples */
  uint32_t centred; /**< every window had the same centring: rwe, ree hold */
} imest_combo_t;

/** imest_t.stages: the ISR's optional stages, one bit each, so that a drive that
 *  uses none pays one test per sample (src/estimator/isr/isr_sample.c). */
#define IMEST_STAGE_DELAY_I    1u /**< the currents and the angle delayed (the voltage lags) */
#define IMEST_STAGE_DELAY_U    2u /**< the voltage delayed (it leads) */
#define IMEST_STAGE_AA         4u /**< the angle through the anti-alias filter's model */
#define IMEST_STAGE_ALIGN      7u /**< any of the three above */
#define IMEST_STAGE_DUTY_EDGES 8u /**< duty input: the switching-instant inverter model */

/** Estimator instance. All fields are private; sizes are what the ISR needs.
 *  sizeof(imest_t) is 2016 B on a Cortex-M4F and a Cortex-M7 (measured by tools/firmware-budget,
 *  fw/README.md) and on an x86-64 host too (every member is 32-bit: no pointers, no padding that
 *  differs); the test tools_documented_defaults checks this figure against the host's sizeof. */
typedef struct {
  /* init: constants derived by imest_init(), read by both contexts */
  imest_real_t fs, inv2t, invt2;                    /* fs, 1/(2T), 1/T^2 */
  imest_real_t n, m, inv_s;                         /* n_p, M*beta, 1/(sigma L_S) */
  imest_real_t i_lim, u_lim, i_abs, u_abs, dth_max; /* dth_max: largest angle step [rad] */
  uint32_t window_n, warmup_n;
  uint32_t warmup_fault_n; /* samples the filters settle after a fault */
  uint32_t stages;         /* the optional ISR stages in use: IMEST_STAGE_* bits (0: none) */
  imest_bw3_t bw;
  imest_sos_t aa;
  imest_real_t dly_i;      /* voltage lags: currents and angle delayed by this fraction of a sample */
  imest_real_t dly_u;      /* voltage leads: voltage delayed by this fraction of a sample */
  imest_real_t dcb_a;      /* offset high-pass: mean-tracking gain per sample */
  imest_duty_model_t duty; /* duty-cycle input */
  /* the voltage's staircase period [s] by input, indexed by a window's duty_input (the error
     bounds): [0] phase voltages, 1 / pwm_hz or 0 for a smooth source (voltage_kind); [1] duties,
     1 / pwm_hz */
  float t_stair_s[2];
  /* ISR: written and read only by the ISR calls. The filter of each channel: */
  imest_chan_t f_ux, f_uy, f_ix, f_iy, f_w;
  imest_real_t aa_s1, aa_s2;     /* anti-alias model state (speed) */
  imest_real_t off_ua, off_ub;   /* tracked offsets of u_alpha, u_beta [V] */
  imest_real_t off_ia, off_ib;   /* tracked offsets of i_alpha, i_beta [A] */
  imest_real_t ia1, dia1, d2ia1; /* last i_alpha and its last two differences (noise, delay) */
  imest_real_t ua1, dua1, d2ua1; /* the same for u_alpha */
  imest_real_t ib1, ub1;         /* last i_beta, u_beta (delays) */

  imest_real_t wr_prev;      /* previous raw speed (delay) */
  imest_real_t th_prev;      /* previous mechanical angle (as given) */
  imest_angle_t obs;         /* angle observer */
  imest_real_t zx[8], zy[8]; /* the regressor of an even sample, summed in two calls */
  uint32_t zpend;            /* zx, zy wait for the second half of their sums */
  imest_real_t dleg[3];      /* duty input: previous call's duties */
  imest_real_t vdc_prev;     /* duty input: previous call's bus voltage [V] */
  uint32_t duty_input;       /* the last call was imest_isr_duty (copied into the window at its end) */
  imest_real_t w_win_prev;   /* the last window's mean speed [rad/s] (angle observer) */
  uint32_t w_win_prev_ok;    /* ... and it had used samples */
  imest_real_t obs_rot;      /* the window just ended: rotation and used samples, for */
  uint32_t obs_used;         /* the observer's decision on the next odd sample */
  uint32_t obs_pending;
  uint32_t k;       /* sample index in the current window */
  uint32_t warm;    /* warm-up samples still to discard */
  uint32_t seq;     /* sequence number of the window being filled */
  uint32_t started; /* first sample seen */
  /* hand-off (imest.h, concurrency contract): each index has one writer */
  volatile uint32_t published; /* written by the ISR: count of buffers handed over; the
                                  ISR fills win[published & 1] */
  volatile uint32_t released;  /* written by the background: count of buffers released */
  volatile uint32_t overruns;  /* written by the ISR: windows dropped (read anywhere) */
  imest_window_t win[2];       /* win[published & 1] the ISR's; the other the background's
                                  from its publication until its release */
  /* background: written and read only by imest_background() (init sets them) */
  float sigma, ls_h, ls_shift_e, sigma_shift_e, tr_nominal_s, tr_min_s, tr_max_s, rs_min_ohm, rs_max_ohm;
  float max_pe_k2_rel, max_ei, min_current_a, min_slip_ratio;
  float rs_tolerance, tr_tolerance, u_uncertainty_v, timing_uncertainty_s, rs_nominal_ohm;
  uint32_t tr_nominal_known;
  /* the rotor at high rotor frequency (bg_validity.c, rotor_hf): 0 a single cage; the phase-voltage
     input's bus [V] (0 unknown; a smooth source is t_stair_s[0] = 0) */
  float rotor_hf_rr_ratio, rotor_hf_sigma_ratio, inverter_vdc_v;
  float transient_k; /* a speed step's share of T_R's bound per (rad/s of step / rad/s of slip)
                        through the angle observer's lag (0: no observer; bg_transient.c) */
  float ls_curve_i_a[IMEST_LS_CURVE_POINTS]; /* the magnetising curve as configured (bg_flux.c) */
  float ls_curve_h[IMEST_LS_CURVE_POINTS];
  uint32_t ls_curve_points;  /* 0: no curve */
  uint32_t ls_check;         /* L_S measured at no load: 0 not yet, 1 agrees, 2 differs (latched) */
  imest_inverter_t inverter; /* as configured: the R_S verdict weighs its uncertainty */
  float pwm_hz;
  float noise_g[6];   /* the front end's noise gains (bg_noise.h) */
  float w_prev_rad_s; /* the previous processed window's mean speed (noise model) */
  uint32_t w_prev_valid;
  float w_end_prev_rad_s; /* the previous processed window's speed at its end (bg_transient.c) */
  imest_combo_t combo;    /* windows combined where one has too little information */
  float last_k1, last_k2; /* last valid estimate: centring of later windows */
} imest_t;

#endif /* IMEST_IMEST_INSTANCE_H */
