/* SPDX-License-Identifier: Apache-2.0 */
/* imest-demo: the paper's experiments end to end, with the library in the loop
 * exactly as a drive firmware runs it.
 *
 * For every experiment a simulated motor (imsim: PWM inverter, 12-bit ADCs,
 * current-sensor offsets,
 * 4096-count encoder, thermal drift) produces one sample per 1/fs; each sample
 * goes through imest_isr_abc() as float32 with the encoder angle wrapped to
 * [0, 2pi); when the ISR call reports a finished window, imest_background()
 * solves it and the run publishes the result over the CAN port
 * (imest_can_publish: a candump -L log, and a live SocketCAN interface if
 * asked). Alongside, the simulator's truth is averaged
 * over the same window's samples so every estimate can be compared with it.
 *
 * First, commissioning: the library's self-commissioning routine (imest_commission.h) runs
 * closed loop on the same motor behind a firmware-timed 8 kHz inverter with 2 us dead time and
 * device drops (tools/commission/commission_sim.c); every experiment's estimator is then set up
 * with the constants it identified (n_p, L_S, sigma, nominal R_S and T_R), not the simulator's.
 * A second estimator with the true constants runs alongside on the same samples
 * (<exp>_true_constants.csv), so the summary shows what commissioning costs. --no-commission
 * uses the true constants instead.
 *
 * Experiments (run in parallel threads):
 *   exp1           60 Hz, 230 V applied at standstill, no load, run-up (2 s);
 *                  then the motor is simulated again with the identified T_R
 *                  and R_S (same inverter voltages) for the paper's Figs. 3-4.
 *   exp2           30 Hz V/f, rated load 2.064 N m, one hour of heating.
 *   ifoc_fixed     the same heat run under IFOC speed control, the
 *                  controller's T_R fixed at the cold value.
 *   ifoc_adaptive  the same, the controller's T_R set from the estimator's
 *                  results through the T_R tracker (imest_tracker.h: hold,
 *                  rate limit, outlier confirmation, stale fallback;
 *                  imsim_set_ifoc_tr); --adaptive-tr raw: every valid window
 *                  as it is, for comparison.
 *   ifoc11_fixed, ifoc11_adaptive
 *                  the same pair on an 11 kW motor (imsim preset 11kw: 8 kHz
 *                  drive, firmware timing) at half load, heating 6x faster
 *                  over a sixth of the duration (beyond the paper's motor).
 *   duty4kw        a drive without phase-voltage sensors (imsim preset 4kw): the
 *                  commissioning routine first identifies its constants, sensor
 *                  offsets and gains and the IGBT inverter's error model (2 us dead
 *                  time, 1 V / 0.8 V drops + slopes), then V/f at rated speed and
 *                  75 % of rated torque, heating 6x faster over a sixth of the
 *                  duration; the estimator is fed the duties and the bus voltage
 *                  (imest_isr_duty) with the identified model (imest_comm_apply).
 *
 * Output in --out DIR/raw: <exp>.candump.log, <exp>_direct.csv (one row per
 * window: the result as returned by imest_background, the truth, and the
 * drive's state) and exp1_wave.csv (waveforms of the run-up). tools/demo-run
 * decodes the logs with imest-monitor and makes the figures and the summary.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "commission_sim.h"
#include "drive_loop.h"
#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest/imest_temperature.h"
#include "imest/imest_tracker.h"
#include "imest_candump.h"
#include "imsim/imsim.h"
#include "tool_args.h"
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
#include "imest_socketcan.h"
#endif

/* A double NaN: the C library's NAN is a float, and clang's -Wdouble-promotion
   flags its conversion. */
#define D_NAN ((double)NAN)

/* ------------------------------------------------------------------------- */
/* Options                                                                    */

typedef struct {
  const char *out;
  double duration_s;      /* exp2 and the IFOC runs */
  double exp1_duration_s; /* exp1 */
  const char *can_iface;  /* live SocketCAN interface (exp2's frames), NULL = none */
  unsigned long seed;
  int quiet;
  unsigned int only; /* bit mask of experiments to run */
  int no_commission; /* the estimators get the true constants, nothing is commissioned */
  int adaptive_raw;  /* the adaptive runs take every valid window as it is, not the tracker's T_R */
} options_t;

/* The constants the experiments' estimators get: commissioning's, or the truth. */
typedef struct {
  int commissioned; /* 1: identified by the routine */
  imest_comm_result_t r;
} demo_constants_t;

enum {
  EXP1 = 0,
  EXP2 = 1,
  IFOC_FIXED = 2,
  IFOC_ADAPTIVE = 3,
  IFOC11_FIXED = 4,
  IFOC11_ADAPTIVE = 5,
  DUTY4 = 6,
  NEXP = 7
};
static const char *const k_exp_name[NEXP] = {
    "exp1", "exp2", "ifoc_fixed", "ifoc_adaptive", "ifoc11_fixed", "ifoc11_adaptive", "duty4kw"};

/* The 11 kW pair: half load, heating sped up so that a sixth of the heat run's motor time
   covers the same heating (its rotor's thermal time constant is 2100 s). */
#define IFOC11_LOAD_REL  0.5
#define IFOC11_THERMAL_X 6.0
#define IS_IFOC11(id)    ((id) == IFOC11_FIXED || (id) == IFOC11_ADAPTIVE)
/* The duty-cycle run: the 4 kW drive (imsim preset 4kw behind commissioning's IGBT inverter) at
   rated speed (V/f 390 V, 50 Hz) and 75 % of rated torque, heating 6x faster over a sixth of the
   duration (like the 11 kW pair). */
#define DUTY4_LOAD_REL   0.75
#define DUTY4_THERMAL_X  6.0
#define SHORT_RUN(id)    (IS_IFOC11(id) || (id) == DUTY4)
#define IS_ADAPTIVE(id)  ((id) == IFOC_ADAPTIVE || (id) == IFOC11_ADAPTIVE)

/* ------------------------------------------------------------------------- */
/* Per-window truth and drive state                                           */

typedef struct {
  double n;
  double tr, rs, speed, te, te_ref, te_err2, psi, psi_ref, i2, temp_s, temp_r, ifoc_tr, load;
} acc_t;

typedef struct {
  double tr, rs, speed, te, te_ref, te_err_rms, psi, psi_ref, i_rms, temp_s, temp_r, ifoc_tr, load;
} truth_t;

static void acc_add(acc_t *a, const imsim_sample_t *s)
{
  a->n += 1.0;
  a->tr += s->tr_s;
  a->rs += s->rs_ohm;
  a->speed += s->speed_rad_s;
  a->te += s->torque_nm;
  a->load += s->load_nm;
  a->psi += s->psi_r_wb;
  a->i2 += s->i_ab_true[0] * s->i_ab_true[0] + s->i_ab_true[1] * s->i_ab_true[1];
  a->temp_s += s->temp_stator_c;
  a->temp_r += s->temp_rotor_c;
  if (isfinite(s->ifoc_torque_ref_nm)) {
    const double e = s->torque_nm - s->ifoc_torque_ref_nm;
    a->te_ref += s->ifoc_torque_ref_nm;
    a->te_err2 += e * e;
    a->psi_ref += s->ifoc_flux_ref_wb;
    a->ifoc_tr += s->ifoc_tr_s;
  } else {
    a->te_ref = a->psi_ref = a->ifoc_tr = D_NAN;
  }
}

static truth_t acc_mean(const acc_t *a)
{
  truth_t t;
  const double n = a->n > 0 ? a->n : D_NAN;
  t.tr = a->tr / n;
  t.rs = a->rs / n;
  t.speed = a->speed / n;
  t.te = a->te / n;
  t.load = a->load / n;
  t.te_ref = a->te_ref / n;
  t.te_err_rms = sqrt(a->te_err2 / n);
  t.psi = a->psi / n;
  t.psi_ref = a->psi_ref / n;
  t.i_rms = sqrt(a->i2 / n / 3.0); /* power-invariant |i_ab|^2 = 3 I_phase,rms^2 */
  t.temp_s = a->temp_s / n;
  t.temp_r = a->temp_r / n;
  t.ifoc_tr = a->ifoc_tr / n;
  if (!isfinite(t.te_ref)) t.te_err_rms = D_NAN;
  return t;
}

/* ------------------------------------------------------------------------- */
/* CAN: candump log, optionally teed to a live SocketCAN interface            */

typedef struct {
  imest_can_port_t port;
  imest_candump_port_t log;
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  imest_socketcan_t sc;
#endif
  int live;
  unsigned long live_sent, live_failed;
  imest_can_pub_t pub; /* publishes each result through this port */
} tee_port_t;

static int tee_send(void *ctx, const imest_can_frame_t *f)
{
  tee_port_t *t = (tee_port_t *)ctx;
  const int rc = t->log.port.send(t->log.port.ctx, f);
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  if (t->live) {
    if (t->sc.port.send(t->sc.port.ctx, f) == 0)
      t->live_sent++;
    else
      t->live_failed++;
  }
#endif
  return rc; /* the log is the record: its failure is the port's failure */
}

/* ------------------------------------------------------------------------- */
/* One experiment                                                             */

typedef struct {
  int id;
  const options_t *opt;
  const demo_constants_t *k;
  double duration_s;
  double fs_hz;
  /* the duty-cycle run's own commissioning (of the 4 kW drive) */
  imest_comm_result_t duty_comm;
  /* exp1 hands its estimate to the identified-parameter simulation */
  double id_tr, id_rs;
  int id_seq, id_status;
  /* progress and outcome */
  _Atomic unsigned long long done;
  unsigned long long total;
  int rc;
  char err[2048];
  long windows, valid;
  double wall_s;
  unsigned long can_lines, can_failed, live_sent, live_failed;
  int live;
  char live_note[512];
} job_t;

static double now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sim_config(int id, unsigned long seed, imsim_config_t *c)
{
  if (IS_IFOC11(id)) {
    imsim_config_preset(c, "11kw"); /* 8 kHz drive, firmware timing, 16384-count encoder */
    c->supply = IMSIM_SUPPLY_IFOC;  /* speed loop to rated speed from rest, load from 2.5 s */
    c->start = IMSIM_START_REST;
    c->ifoc_mode = IMSIM_IFOC_SPEED;
    c->ifoc_tr_s = 0.0;
    c->load_nm = IFOC11_LOAD_REL * c->rated_torque_nm;
    c->thermal_speedup = IFOC11_THERMAL_X;
    /* offsets as below, scaled to its 75 A range */
    for (int k = 0; k < 3; ++k)
      c->i_offset_a[k] = (k == 0 ? 0.040 : k == 1 ? -0.025 : 0.010) * c->i_range_a / 20.0;
    c->seed = seed + (unsigned long)id;
    return;
  }
  if (id == EXP1) {
    imsim_config_preset(c, "exp1"); /* 60 Hz, 230 V at standstill, no load */
    c->supply = IMSIM_SUPPLY_PWM;   /* applied at once (no ramp) through the inverter */
  } else {
    imsim_config_preset(c, "exp2"); /* 30 Hz V/f, 2.064 N m, 1 h */
    c->supply = id == EXP2 ? IMSIM_SUPPLY_PWM : IMSIM_SUPPLY_IFOC;
    c->ifoc_mode = IMSIM_IFOC_SPEED;
    c->ifoc_tr_s = 0.0; /* cold value */
  }
  /* Current sensors as delivered: offsets of 0.1 .. 0.2 % of the +-20 A range
   * (the drive calibrates them at power-up only to within this). */
  c->i_offset_a[0] = 0.040;
  c->i_offset_a[1] = -0.025;
  c->i_offset_a[2] = 0.010;
  c->seed = seed + (unsigned long)id;
}

/* k: the commissioned constants, or NULL for the simulator's true ones. */
static void est_config(const imsim_config_t *c, const demo_constants_t *k, imest_config_t *cfg)
{
  imest_config_default(cfg);
  cfg->pole_pairs = (unsigned int)c->pole_pairs; /* the paper's motor: 2, 0.2908 H, 0.096, 4 kHz */
  cfg->ls_h = (float)c->ls_h;
  cfg->sigma = (float)c->sigma;
  cfg->ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg->sigma_uncertainty = 0.0f;
  cfg->fs_hz = (float)c->fs_hz;
  if (k != NULL && k->commissioned) {
    /* and the uncertainty commissioning states for L_S and sigma */
    /* n_p, L_S, sigma, the nominal R_S and T_R as identified; its inverter model is for the
       duty-cycle input, which these runs (measured phase voltages) do not use */
    const float fs = cfg->fs_hz;
    (void)imest_comm_apply(&k->r, cfg);
    cfg->fs_hz = fs;
    imest_inverter_t none;
    memset(&none, 0, sizeof none);
    none.uncertainty = -1.0f;
    cfg->inverter = none;
  }
  /* What the drive knows about its own hardware: it is enabled with the
   * motor at rest, and where its ADCs clip (top code = range - 1 LSB). */
  cfg->start_at_rest = 1;
  cfg->i_limit_a = (float)(c->i_range_a * (1.0 - ldexp(1.0, 1 - c->adc_bits)));
  cfg->u_limit_v = (float)(c->u_range_v * (1.0 - ldexp(1.0, 1 - c->adc_bits)));
  /* Its phase voltages are the volt-seconds of the PWM period that just
   * ended (duty cycles x DC bus): they lag the current samples by half a
   * carrier period, which uncompensated biases R_S by about +5 %. With firmware
   * timing the period is the sample period. */
  const int pwm = c->supply == IMSIM_SUPPLY_PWM || (c->supply == IMSIM_SUPPLY_IFOC && !c->ifoc_ideal_stage);
  if (pwm && (c->vmeas == IMSIM_VMEAS_AUTO || c->vmeas == IMSIM_VMEAS_AVG))
    cfg->u_delay_s = (float)(0.5 / (c->timing == IMSIM_TIMING_FIRMWARE ? c->fs_hz : c->carrier_hz));
  /* and its carrier: the voltage's steps come at its rate, not the sample rate's (the paper's
     motor: 10 kHz sampled at 4 kHz), and the staircase's share of the bounds scales with the
     step's period squared (R_S's bound on exp2: 1.5 % with the sample rate's, 0.53 % with it) */
  if (pwm) cfg->pwm_hz = (float)c->carrier_hz;
}

static FILE *open_out(job_t *j, const char *dir, const char *name)
{
  char path[1024];
  snprintf(path, sizeof path, "%.700s/%.200s", dir, name);
  FILE *f = fopen(path, "w");
  if (f == NULL) snprintf(j->err, sizeof j->err, "%s: %s", path, strerror(errno));
  return f;
}

/* Identified-parameter simulation of exp1 (paper Section VII-A): the same
 * inverter voltages (same PWM, no dead time: the applied voltage does not
 * depend on the motor) into a motor with the estimated T_R and R_S, exact
 * sensors. Writes i_alpha_sim and speed_sim next to the measured run. */
static int exp1_wave(job_t *j, const char *dir, double tr_id, double rs_id)
{
  const double dur = j->duration_s;
  imsim_config_t cm, ci;
  sim_config(EXP1, j->opt->seed, &cm);
  ci = cm;
  ci.tr_s = tr_id;
  ci.rs_ohm = rs_id;
  ci.thermal = false;
  ci.ideal_sensors = true;
  static _Thread_local imsim_t sm, si;
  imsim_sample_t a, b;
  if (imsim_init(&sm, &cm, &a) != 0 || imsim_init(&si, &ci, &b) != 0) {
    snprintf(j->err, sizeof j->err, "exp1 identified simulation: %s", imsim_error(&si));
    return -1;
  }
  FILE *f = open_out(j, dir, "exp1_wave.csv");
  if (f == NULL) return -1;
  fprintf(f, "t_s,u_alpha_v,u_beta_v,i_alpha_a,i_beta_a,speed_enc_rad_s,speed_true_rad_s,"
             "i_alpha_sim_a,speed_sim_rad_s,T_R_id_s,R_S_id_ohm\n");
  const long n = lround(dur * cm.fs_hz);
  /* encoder speed: difference over +-10 samples (5 ms), as a drive computes it */
  enum { H = 10 };
  double th[2 * H + 1] = {0};
  imsim_sample_t hist_a[H + 1], hist_b[H + 1];
  for (long k = 0; k <= n + H; ++k) {
    if (k > 0) {
      imsim_step(&sm, &a);
      imsim_step(&si, &b);
    }
    memmove(th, th + 1, sizeof th - sizeof th[0]);
    th[2 * H] = a.theta;
    memmove(hist_a, hist_a + 1, sizeof hist_a - sizeof hist_a[0]);
    memmove(hist_b, hist_b + 1, sizeof hist_b - sizeof hist_b[0]);
    hist_a[H] = a;
    hist_b[H] = b;
    if (k < H) continue; /* row for sample k - H; its speed needs theta[k - 2H .. k] */
    const imsim_sample_t *ma = &hist_a[0], *mb = &hist_b[0];
    double uab[2], iab[2];
    imsim_abc_to_ab(ma->u_abc, uab);
    imsim_abc_to_ab(ma->i_abc, iab);
    const double w_enc = k >= 2 * H ? (th[2 * H] - th[0]) * cm.fs_hz / (2.0 * H) : D_NAN;
    fprintf(f, "%.6f,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.6g,%.6g\n", ma->t, uab[0], uab[1], iab[0],
            iab[1], w_enc, ma->speed_rad_s, mb->i_ab_true[0], mb->speed_rad_s, tr_id, rs_id);
  }
  if (fclose(f) != 0) {
    snprintf(j->err, sizeof j->err, "exp1_wave.csv: write error");
    return -1;
  }
  return 0;
}

/* One experiment while it runs: its simulator, estimator, CAN port, output
 * files, and the truth of every window (the simulator's, averaged over the
 * window's samples). */
typedef struct {
  job_t *j;
  const char *name;
  char dir[1024];
  imsim_config_t c;
  imsim_t *sim;
  imsim_sample_t s;
  imest_t *est;
  imest_t *est_true; /* the same samples with the true constants (commissioned runs only) */
  tee_port_t *tee;
  FILE *log, *csv, *csv_true;
  truth_t *truth;
  uint32_t wn;                 /* samples per window */
  size_t nwin;                 /* truth slots */
  size_t win;                  /* windows whose truth is complete */
  int have_id;                 /* exp1: 0 none yet, 1 the run-up window (not valid), 2 the first valid one */
  imest_tracker_t trk;         /* every run: what the tracker makes of its results (applied if adaptive) */
  float i_off_a[3], i_ginv[3]; /* the duty-cycle run: current correction from commissioning */
  /* every run: the temperatures from its results (imest_temperature.h) */
  imest_temperature_t temp;
} run_t;

static void run_release(run_t *x)
{
  if (x->log) fclose(x->log);
  if (x->csv) fclose(x->csv);
  if (x->csv_true) fclose(x->csv_true);
  free(x->truth);
  x->log = x->csv = x->csv_true = NULL;
  x->truth = NULL;
}

/* The live SocketCAN interface (exp2 only): a note if it cannot be used. */
static void open_live(job_t *j, tee_port_t *tee)
{
  const char *iface = j->opt->can_iface;
  if (j->id != EXP2 || iface == NULL) return;
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  if (imest_socketcan_open(&tee->sc, iface) == 0) {
    tee->live = 1;
    snprintf(j->live_note, sizeof j->live_note, "sending exp2's frames on %s", iface);
  } else {
    snprintf(j->live_note, sizeof j->live_note,
             "--can-iface %.32s: %.256s; continuing with the candump log only", iface, tee->sc.err);
  }
#else
  (void)tee;
  snprintf(j->live_note, sizeof j->live_note,
           "--can-iface %.32s: built without SocketCAN support; continuing with the candump log "
           "only",
           iface);
#endif
}

/* raw/commission.csv, raw/duty4kw_commission.csv: what a commissioning run identified against the
   simulator's truth. 0, or -1 if the file cannot be written (errno set). */
static int write_commission_csv(const char *path, const comm_sim_out_t *out)
{
  const imest_comm_result_t *r = &out->r;
  FILE *f = fopen(path, "w");
  if (f == NULL) return -1;
  fprintf(f, "quantity,identified,true,unit\n");
  fprintf(f, "state,%s,,\nreason,%s,,\nvalid,%d,,\n", imest_comm_state_name(r->state),
          imest_comm_reason_name(r->reason), r->valid);
  fprintf(f, "time_s,%.3f,,s\ni_peak_a,%.4f,%.4f,A\n", (double)r->time_s, out->i_peak_true_a,
          (double)out->cc.i_max_a);
  fprintf(f, "R_S,%.6g,%.6g,ohm\nR_S_winding,%.6g,%.6g,ohm\n", (double)r->rs_ohm.value,
          out->rs_identifiable_ohm, (double)r->rs_ohm.value, out->rs_ohm);
  fprintf(f, "L_S,%.6g,%.6g,H\nsigma,%.6g,%.6g,\nsigma_L_S,%.6g,%.6g,H\nT_R,%.6g,%.6g,s\n",
          (double)r->ls_h.value, out->ls_h, (double)r->sigma.value, out->sigma, (double)r->sigma_ls_h.value,
          out->sigma_ls_h, (double)r->tr_s.value, out->tr_s);
  fprintf(f, "pole_pairs,%u,%u,\nencoder_dir,%d,1,\n", r->pole_pairs, out->pole_pairs, r->encoder_dir);
  fprintf(f, "dead_time,%.6g,%.6g,s\nv_threshold,%.6g,%.6g,V\ninverter_err_max,%.4f,,V\n",
          (double)r->inverter.dead_time_s, out->sim.dead_time_s, (double)r->v_threshold_v.value,
          0.5 * (out->sim.v_switch_v + out->sim.v_diode_v), out->inv_err_model_v);
  /* the inverter model as the estimator gets it (imest_inverter_t) */
  fprintf(f, "v_switch,%.6g,%.6g,V\nv_diode,%.6g,%.6g,V\nr_switch,%.6g,%.6g,ohm\nr_diode,%.6g,%.6g,ohm\n",
          (double)r->inverter.v_switch_v, out->sim.v_switch_v, (double)r->inverter.v_diode_v,
          out->sim.v_diode_v, (double)r->inverter.r_switch_ohm, out->sim.r_switch_ohm,
          (double)r->inverter.r_diode_ohm, out->sim.r_diode_ohm);
  fprintf(f, "r_slope_diff,%.6g,%.6g,ohm\ni_band,%.6g,,A\nuncertainty,%.4g,,\ninverter_err_total,%.4f,,V\n",
          (double)r->dr_ohm.value, out->sim.r_switch_ohm - out->sim.r_diode_ohm, (double)r->inverter.i_band_a,
          (double)r->inverter.uncertainty, out->inv_err_total_v);
  for (int p = 0; p < 3; ++p)
    fprintf(f, "i_gain_rel_%c,%.6g,,\ni_offset_%c,%.6g,,A\n", 'a' + p, (double)r->i_gain_rel[p], 'a' + p,
            (double)r->i_offset_a[p]);
  return fclose(f) == 0 ? 0 : -1;
}

/* The duty-cycle run: commissioning closed loop on the 4 kW drive (its IGBT inverter: 2 us dead
   time, 1 V + r_sw / 0.8 V + r_d; 12-bit sensors with offsets and gain errors; the shaft free to
   turn, the nameplate's rated speed), raw/duty4kw_commission.csv; then the same drive in operation
   (comm_sim_operating: V/f at its rated point, DUTY4_LOAD_REL of rated torque, steady state) with
   its copper heating on; the estimator gets the identified constants and inverter model
   (imest_comm_apply), the second one the truth (constants and devices). 0, or -1 (j->err). */
static int duty_setup(job_t *j, const char *dir, imsim_config_t *c, imest_config_t *cfg,
                      imest_config_t *cfg_true)
{
  comm_sim_opts_t co;
  static _Thread_local comm_sim_out_t out;
  if (comm_sim_defaults(&co, "4kw") != 0) return -1;
  co.seed = j->opt->seed + (unsigned long)j->id;
  memset(&j->duty_comm, 0, sizeof j->duty_comm);
  if (j->opt->no_commission) { /* the true constants and devices, no record */
    if (comm_sim_operating(&co, DUTY4_LOAD_REL, c) != 0) return -1;
  } else if (comm_sim_run(&co, &out) != 0) {
    snprintf(j->err, sizeof j->err, "duty4kw: commissioning could not run");
    return -1;
  }
  if (!j->opt->no_commission) {
    j->duty_comm = out.r;
    char path[1100];
    snprintf(path, sizeof path, "%s/duty4kw_commission.csv", dir);
    if (write_commission_csv(path, &out) != 0) {
      snprintf(j->err, sizeof j->err, "%s: %s", path, strerror(errno));
      return -1;
    }
  }
  if (comm_sim_operating(&co, DUTY4_LOAD_REL, c) != 0) return -1;
  c->thermal = true; /* from cold, 6x faster */
  c->thermal_speedup = DUTY4_THERMAL_X;
  c->seed = j->opt->seed + (unsigned long)j->id;
  for (int t = 0; t < 2; ++t) {
    imest_config_t *e = t == 0 ? cfg : cfg_true;
    imest_config_default(e);
    e->fs_hz = (float)c->fs_hz;
    e->pwm_hz = (float)c->carrier_hz;
    e->i_limit_a = (float)(c->i_range_a * (1.0 - ldexp(1.0, 1 - c->adc_bits)));
  }
  if (j->opt->no_commission) {
    /* nothing identified: the truth below */
  } else if (!out.r.valid || imest_comm_apply(&out.r, cfg) < 0) {
    /* the routine failed: the truth, and the summary says so */
    fprintf(stderr, "imest-demo: duty4kw: commissioning failed (%s): the run uses the true constants\n",
            imest_comm_reason_name(out.r.reason));
    j->duty_comm.valid = 0;
  }
  cfg_true->pole_pairs = (unsigned int)c->pole_pairs;
  cfg_true->ls_h = (float)c->ls_h;
  cfg_true->sigma = (float)c->sigma;
  cfg_true->ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg_true->sigma_uncertainty = 0.0f;
  cfg_true->tr_nominal_s = (float)c->tr_s;
  cfg_true->rs_nominal_ohm = (float)c->rs_ohm;
  cfg_true->inverter.dead_time_s = (float)c->dead_time_s;
  cfg_true->inverter.v_switch_v = (float)c->v_switch_v;
  cfg_true->inverter.r_switch_ohm = (float)c->r_switch_ohm;
  cfg_true->inverter.v_diode_v = (float)c->v_diode_v;
  cfg_true->inverter.r_diode_ohm = (float)c->r_diode_ohm;
  cfg_true->inverter.uncertainty = 0.05f; /* as imest-commission --online's reference */
  if (!j->duty_comm.valid) *cfg = *cfg_true;
  return 0;
}

/* Simulator, estimator, CAN port (candump log, live interface), output files. */
static int job_open(job_t *j, run_t *x)
{
  static _Thread_local imsim_t sim;
  static _Thread_local imest_t est, est_true;
  static _Thread_local tee_port_t tee;
  memset(x, 0, sizeof *x);
  x->j = j;
  x->name = k_exp_name[j->id];
  x->sim = &sim;
  x->est = &est;
  x->tee = &tee;
  snprintf(x->dir, sizeof x->dir, "%.900s/raw", j->opt->out);
  for (int p = 0; p < 3; ++p) {
    x->i_off_a[p] = 0.0f;
    x->i_ginv[p] = 1.0f;
  }

  imest_config_t cfg, cfg_true;
  /* the commissioned constants are the paper motor's: the 11 kW pair gets its true ones; the
     duty-cycle run commissions its own drive */
  const demo_constants_t *k = SHORT_RUN(j->id) ? NULL : j->k;
  if (j->id == DUTY4) {
    if (duty_setup(j, x->dir, &x->c, &cfg, &cfg_true) != 0) return -1;
    if (j->duty_comm.valid)
      for (int p = 0; p < 3; ++p) {
        x->i_off_a[p] = j->duty_comm.i_offset_a[p];
        x->i_ginv[p] = j->duty_comm.i_gain_rel[p] > 0.0f ? 1.0f / j->duty_comm.i_gain_rel[p] : 1.0f;
      }
  } else {
    sim_config(j->id, j->opt->seed, &x->c);
    est_config(&x->c, k, &cfg);
    est_config(&x->c, NULL, &cfg_true);
  }
  if (imsim_init(&sim, &x->c, &x->s) != 0) {
    snprintf(j->err, sizeof j->err, "%s: simulator: %s", x->name, imsim_error(&sim));
    return -1;
  }
  const char *field = NULL;
  if (imest_config_check(&cfg, &field) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: estimator config: bad %s", x->name, field);
    return -1;
  }
  if (imest_init(&est, &cfg) != IMEST_OK || imest_init(&est_true, &cfg_true) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: imest_init failed", x->name);
    return -1;
  }
  if ((k != NULL && k->commissioned) || (j->id == DUTY4 && j->duty_comm.valid)) {
    x->est_true = &est_true;
    char tname[256];
    snprintf(tname, sizeof tname, "%s_true_constants.csv", x->name);
    if ((x->csv_true = open_out(j, x->dir, tname)) == NULL) return -1;
    fprintf(x->csv_true, "experiment,seq,t_end_s,T_R_s,R_S_ohm,valid,status,T_R_true_s,R_S_true_ohm,"
                         "tr_valid,rs_valid,tr_reason,rs_reason\n");
  }

  char fname[256];
  snprintf(fname, sizeof fname, "%s.candump.log", x->name);
  if ((x->log = open_out(j, x->dir, fname)) == NULL) return -1;
  memset(&tee, 0, sizeof tee);
  if (imest_candump_port_open(&tee.log, x->log, "vcan0") != 0) {
    snprintf(j->err, sizeof j->err, "%s: candump port", x->name);
    return -1;
  }
  open_live(j, &tee);
  j->live = tee.live;
  tee.port.send = tee_send;
  tee.port.ctx = &tee;
  if (imest_can_pub_init(&tee.pub, &tee.port, IMEST_CAN_DEFAULT_BASE_ID) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: imest_can_pub_init failed", x->name);
    return -1;
  }

  /* the tracker's nominal is the controller's own cold T_R (imsim: ifoc_tr_s 0 = the motor's) */
  imest_tracker_config_t tc;
  imest_tracker_config_default(&tc, (float)(x->c.ifoc_tr_s > 0.0 ? x->c.ifoc_tr_s : x->c.tr_s));
  if (imest_tracker_init(&x->trk, &tc) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: imest_tracker_init failed", x->name);
    return -1;
  }
  /* the temperatures' references: the motor's cold R_S and T_R at ambient, as commissioning
     measures them; imsim heats both bodies with copper's linear alpha from t_amb_c, which is the
     resistance method with k = 1/alpha - t_amb_c (234.5 at 20 degC): the rotor's k is set to it */
  imest_temperature_config_t mc;
  imest_temperature_config_default(&mc, (float)x->c.t_amb_c, (float)x->c.rs_ohm, (float)x->c.tr_s,
                                   (float)x->c.lr_h);
  if (x->c.alpha_per_k > 0.0) mc.rotor_k_c = mc.stator_k_c = (float)(1.0 / x->c.alpha_per_k - x->c.t_amb_c);
  if (imest_temperature_init(&x->temp, &mc) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: imest_temperature_init failed", x->name);
    return -1;
  }

  snprintf(fname, sizeof fname, "%s_direct.csv", x->name);
  if ((x->csv = open_out(j, x->dir, fname)) == NULL) return -1;
  fprintf(x->csv, "experiment,seq,t_end_s,T_R_s,R_S_ohm,valid,status,T_R_true_s,R_S_true_ohm,E_I,"
                  "pe_k1_rel,pe_k2_rel,slip_ratio,i_rms_a,n_roots,n_admissible,used_samples,flags,"
                  "speed_rad_s,torque_nm,load_nm,torque_ref_nm,torque_err_rms_nm,psi_r_wb,psi_ref_wb,"
                  "i_phase_rms_a,temp_stator_c,temp_rotor_c,ifoc_T_R_s,"
                  "tr_valid,tr_reason,rs_valid,rs_reason,tr_bound_rel,trk_T_R_s,trk_state,trk_age_s,"
                  "trk_bound_rel,rs_bound_rel,est_stator_c,est_stator_uncert_k,est_stator_valid,est_rotor_c,"
                  "est_rotor_uncert_k,est_rotor_valid\n");

  j->fs_hz = x->c.fs_hz;
  j->total = (unsigned long long)llround(j->duration_s * x->c.fs_hz);
  x->wn = (uint32_t)lround((double)cfg.window_s * (double)cfg.fs_hz);
  x->nwin = (size_t)(j->total / x->wn) + 2;
  if ((x->truth = calloc(x->nwin, sizeof *x->truth)) == NULL) {
    snprintf(j->err, sizeof j->err, "%s: out of memory", x->name);
    return -1;
  }
  return 0;
}

/* exp1 keeps an estimate for the identified-parameter simulation. */
static void keep_identified(job_t *j, const imest_result_t *r)
{
  j->id_tr = r->tr_s;
  j->id_rs = r->rs_ohm;
  j->id_seq = (int)r->seq;
  j->id_status = r->status;
}

/* drive_window_fn: one result as the background task returns it. */
static void on_window(void *ctx, const imest_result_t *r)
{
  run_t *x = (run_t *)ctx;
  job_t *j = x->j;
  (void)imest_can_publish(&x->tee->pub, r); /* refusals are counted by the log port */
  static const truth_t nan_t = {D_NAN, D_NAN, D_NAN, D_NAN, D_NAN, D_NAN, D_NAN,
                                D_NAN, D_NAN, D_NAN, D_NAN, D_NAN, D_NAN};
  const truth_t *t = (r->seq < x->nwin && r->seq < x->win) ? &x->truth[r->seq] : &nan_t;
  (void)imest_tracker_update(&x->trk, r); /* t_end_s only grows: it cannot refuse */
  (void)imest_temperature_update(&x->temp, r);
  fprintf(x->csv,
          "%s,%u,%.6f,%.9g,%.9g,%d,%s,%.9g,%.9g,%.6g,%.6g,%.6g,%.5g,%.6g,%u,%u,%u,%u,"
          "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.5g,%.5g,%.6g,%d,%s,%d,%s,%.4g,%.9g,%s,%.6g,%.4g,%.4g,"
          "%.6g,%.4g,%d,%.6g,%.4g,%d\n",
          x->name, r->seq, r->t_end_s, r->tr_s, r->rs_ohm, r->valid, imest_reason_name(r->status), t->tr,
          t->rs, r->e_i, r->pe_k1_rel, r->pe_k2_rel, r->slip_ratio, r->i_rms_a, r->n_roots, r->n_admissible,
          r->used_samples, r->flags, t->speed, t->te, t->load, t->te_ref, t->te_err_rms, t->psi, t->psi_ref,
          t->i_rms, t->temp_s, t->temp_r, t->ifoc_tr, r->tr_valid, imest_reason_name(r->tr_reason),
          r->rs_valid, imest_reason_name(r->rs_reason), r->tr_bound_rel, (double)x->trk.tr_s,
          imest_tracker_state_name(x->trk.state), (double)x->trk.age_s, (double)x->trk.tr_bound_rel,
          r->rs_bound_rel, (double)x->temp.stator_c, (double)x->temp.stator_uncert_k, x->temp.stator_valid,
          (double)x->temp.rotor_c, (double)x->temp.rotor_uncert_k, x->temp.rotor_valid);
  /* the controller takes the tracker's T_R (or, with --adaptive-tr raw, every window whose T_R is
     trusted, as it is) */
  if (IS_ADAPTIVE(j->id)) {
    if (j->opt->adaptive_raw) {
      if (r->tr_valid) imsim_set_ifoc_tr(x->sim, r->tr_s);
    } else {
      imsim_set_ifoc_tr(x->sim, (double)x->trk.tr_s);
    }
  }
  if (r->valid) {
    if (j->id == EXP1 && x->have_id < 2) {
      x->have_id = 2; /* the first valid window */
      keep_identified(j, r);
    }
  } else if (j->id == EXP1 && x->have_id == 0 && r->seq == 0 && r->tr_s > 0 && r->rs_ohm > 0) {
    x->have_id = 1; /* no valid window yet: the run-up window's estimate, flagged invalid */
    keep_identified(j, r);
  }
}

/* drive_window_fn of the estimator with the true constants: its results beside the truth. */
static void on_window_true(void *ctx, const imest_result_t *r)
{
  run_t *x = (run_t *)ctx;
  static const truth_t nan_t = {D_NAN, D_NAN, D_NAN, D_NAN, D_NAN, D_NAN, D_NAN,
                                D_NAN, D_NAN, D_NAN, D_NAN, D_NAN, D_NAN};
  const truth_t *t = (r->seq < x->nwin && r->seq < x->win) ? &x->truth[r->seq] : &nan_t;
  fprintf(x->csv_true, "%s,%u,%.6f,%.9g,%.9g,%d,%s,%.9g,%.9g,%d,%d,%s,%s\n", x->name, r->seq, r->t_end_s,
          r->tr_s, r->rs_ohm, r->valid, imest_reason_name(r->status), t->tr, t->rs, r->tr_valid, r->rs_valid,
          imest_reason_name(r->tr_reason), imest_reason_name(r->rs_reason));
}

/* The samples: each one's truth into its window, then the drive loop (ISR
 * call with float32 values and the wrapped encoder angle, background drained
 * when a window is done, publishing over CAN). */
static void job_loop(run_t *x)
{
  job_t *j = x->j;
  const unsigned long long total = j->total;
  drive_t d, d_true;
  drive_init(&d, x->est, on_window, x);
  drive_init(&d_true, x->est_true, on_window_true, x);
  acc_t acc;
  memset(&acc, 0, sizeof acc);
  uint32_t in_win = 0;
  for (unsigned long long k = 0; k < total; ++k) {
    if (k > 0) imsim_step(x->sim, &x->s);
    acc_add(&acc, &x->s);
    if (++in_win == x->wn) {
      if (x->win < x->nwin) x->truth[x->win] = acc_mean(&acc);
      x->win++;
      in_win = 0;
      memset(&acc, 0, sizeof acc);
    }
    imest_candump_port_set_time(&x->tee->log, x->s.t); /* frames carry their window's end */
    if (j->id == DUTY4) {
      /* no voltage sensors: the duties and the bus, and the currents corrected with the offsets and
         gains commissioning measured (as its header asks the firmware to) */
      double i_abc[3];
      for (int p = 0; p < 3; ++p) i_abc[p] = (x->s.i_abc[p] - (double)x->i_off_a[p]) * (double)x->i_ginv[p];
      drive_sample_duty(&d, x->s.duty, x->s.vdc_v, i_abc, x->s.theta);
      if (x->est_true) drive_sample_duty(&d_true, x->s.duty, x->s.vdc_v, i_abc, x->s.theta);
    } else {
      drive_sample(&d, x->s.u_abc, x->s.i_abc, x->s.theta);
      if (x->est_true) drive_sample(&d_true, x->s.u_abc, x->s.i_abc, x->s.theta);
    }
    if ((k & 1023u) == 0) atomic_store(&j->done, k);
  }
  atomic_store(&j->done, total);
  j->windows = d.windows;
  j->valid = d.valid;
}

/* Files closed; exp1 goes on to its identified-parameter simulation. */
static int job_close(run_t *x)
{
  job_t *j = x->j;
  j->can_lines = x->tee->log.lines;
  j->can_failed = x->tee->log.failed;
  j->live_sent = x->tee->live_sent;
  j->live_failed = x->tee->live_failed;
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  if (x->tee->live) imest_socketcan_close(&x->tee->sc);
#endif
  /* every file is closed, whichever fails */
  int bad = fclose(x->log) != 0;
  if (fclose(x->csv) != 0) bad = 1;
  if (x->csv_true && fclose(x->csv_true) != 0) bad = 1;
  x->log = x->csv = x->csv_true = NULL;
  run_release(x);
  if (bad) {
    snprintf(j->err, sizeof j->err, "%s: write error in %s", x->name, x->dir);
    return -1;
  }
  if (j->id != EXP1) return 0;
  if (!x->have_id) {
    /* no estimate at all: still draw the run-up, with the nominal parameters */
    j->id_tr = x->c.tr_s;
    j->id_rs = x->c.rs_ohm;
    j->id_seq = -1;
  }
  FILE *f = open_out(j, x->dir, "exp1_identified.csv");
  if (f == NULL) return -1;
  fprintf(f, "seq,valid,status,T_R_s,R_S_ohm,source\n%d,%d,%s,%.9g,%.9g,%s\n", j->id_seq, x->have_id == 2,
          x->have_id ? imest_reason_name(j->id_status) : "none", j->id_tr, j->id_rs,
          x->have_id == 2   ? "first valid window"
          : x->have_id == 1 ? "run-up window 0, NOT valid (no valid window)"
                            : "nominal parameters (no usable estimate)");
  if (fclose(f) != 0) return -1;
  return exp1_wave(j, x->dir, j->id_tr, j->id_rs);
}

static int run_job(job_t *j)
{
  run_t x;
  if (job_open(j, &x) != 0) {
    run_release(&x);
    return -1;
  }
  job_loop(&x);
  return job_close(&x);
}

static void *job_thread(void *arg)
{
  job_t *j = (job_t *)arg;
  const double t0 = now_s();
  j->rc = run_job(j);
  j->wall_s = now_s() - t0;
  return NULL;
}

/* ------------------------------------------------------------------------- */
/* Commissioning, before the experiments                                      */

/* The routine closed loop on the paper's motor (its drive: 325 V bus, 8 kHz, firmware timing,
   2 us dead time, 1 V / 0.8 V drops, 12-bit sensors, the 4096-count encoder; no nameplate
   speed), allowed to turn the shaft. Writes raw/commission.csv (identified vs true) and one
   stdout line. Returns 0, or -1 if the file cannot be written; a routine that fails leaves
   k->commissioned = 0 (the runs then get the true constants, and the summary says so). */
static int commission(const options_t *o, const char *raw, demo_constants_t *k)
{
  memset(k, 0, sizeof *k);
  comm_sim_opts_t co;
  if (comm_sim_defaults(&co, "exp1") != 0) return -1;
  co.seed = o->seed;
  static comm_sim_out_t out;
  if (comm_sim_run(&co, &out) != 0) return -1;
  const imest_comm_result_t *r = &out.r;
  k->r = *r;
  k->commissioned = r->valid;
  char path[1100];
  snprintf(path, sizeof path, "%s/commission.csv", raw);
  if (write_commission_csv(path, &out) != 0) {
    fprintf(stderr, "imest-demo: %s: %s\n", path, strerror(errno));
    return -1;
  }
  printf("commission state=%s reason=%s time_s=%.2f i_peak_a=%.3f R_S_ohm=%.5g L_S_h=%.5g sigma=%.5g "
         "T_R_s=%.5g pole_pairs=%u\n",
         imest_comm_state_name(r->state), imest_comm_reason_name(r->reason), (double)r->time_s,
         out.i_peak_true_a, (double)r->rs_ohm.value, (double)r->ls_h.value, (double)r->sigma.value,
         (double)r->tr_s.value, r->pole_pairs);
  if (!k->commissioned)
    fprintf(stderr, "imest-demo: commissioning failed (%s): the runs use the true constants\n",
            imest_comm_reason_name(r->reason));
  return 0;
}

/* ------------------------------------------------------------------------- */
/* Main                                                                       */

static void usage(FILE *f)
{
  fprintf(f, "usage: imest-demo [--out DIR] [--duration S] [--exp1-duration S] [--only LIST]\n"
             "                  [--can-iface NAME] [--seed N] [--no-commission]\n"
             "                  [--adaptive-tr tracker|raw] [--quiet]\n"
             "\n"
             "Commissions the simulated motor with the library's routine first, then runs the\n"
             "paper's experiments with the identified constants and imest in the loop (ISR\n"
             "call per sample, background call per window, telemetry over the CAN port) and\n"
             "writes DIR/raw/commission.csv, DIR/raw/<exp>.candump.log, DIR/raw/<exp>_direct.csv,\n"
             "DIR/raw/<exp>_true_constants.csv, DIR/raw/exp1_wave.csv.\n"
             "Experiments run in parallel threads: exp1 (run-up), exp2 (30 Hz V/f heat run),\n"
             "ifoc_fixed and ifoc_adaptive (the heat run under IFOC, controller T_R fixed at\n"
             "the cold value / taken from the estimator), ifoc11_fixed and ifoc11_adaptive\n"
             "(the same on an 11 kW drive at half load, heating 6x faster for duration / 6),\n"
             "duty4kw (a 4 kW drive without voltage sensors: its own commissioning, then V/f at\n"
             "rated speed and 75 %% load with the duty-cycle input, imest_isr_duty; duration / 6).\n"
             "Options take a value as '--opt VALUE' or '--opt=VALUE'.\n"
             "\n"
             "  --out DIR           output folder (default results)\n"
             "  --duration S        motor time of exp2 and the IFOC runs (default 3600)\n"
             "  --exp1-duration S   motor time of exp1 (default 2)\n"
             "  --only LIST         comma-separated subset of exp1,exp2,ifoc_fixed,ifoc_adaptive,\n"
             "                      ifoc11_fixed,ifoc11_adaptive,duty4kw\n"
             "  --can-iface NAME    also send exp2's frames on this SocketCAN interface\n"
             "  --seed N            sensor noise seed (default 1)\n"
             "  --no-commission     the estimators get the true constants (no commissioning)\n"
             "  --adaptive-tr MODE  what the adaptive runs' controller takes: tracker (default:\n"
             "                      the T_R tracker, imest_tracker.h) or raw (every valid window)\n"
             "  --quiet             no progress on stderr (default: progress if it is a terminal)\n"
             "  -h, --help          this text\n"
             "  --version           the version and licence\n"
             "\n"
             "stdout: one line per experiment, key=value pairs.\n"
             "Exit status: 0 done; 1 commissioning or an experiment failed, or the output cannot\n"
             "be written; 2 bad option or argument.\n");
}

static int mkdir_p(const char *path)
{
  char buf[1024];
  snprintf(buf, sizeof buf, "%s", path);
  for (char *p = buf + 1; *p; ++p) {
    if (*p == '/') {
      *p = '\0';
      if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
      *p = '/';
    }
  }
  if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
  return 0;
}

/* --only exp1,exp2: the bit mask of experiments. */
static int parse_only(const char *v, unsigned int *only)
{
  *only = 0;
  char buf[256];
  snprintf(buf, sizeof buf, "%s", v);
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    int found = 0;
    for (int e = 0; e < NEXP; ++e)
      if (!strcmp(tok, k_exp_name[e])) {
        *only |= 1u << e;
        found = 1;
      }
    if (!found) {
      fprintf(stderr,
              "imest-demo: --only: unknown experiment '%s' (exp1, exp2, ifoc_fixed, "
              "ifoc_adaptive, ifoc11_fixed, ifoc11_adaptive, duty4kw)\n",
              tok);
      return -1;
    }
  }
  if (*only == 0) fprintf(stderr, "imest-demo: --only: no experiment named\n");
  return *only ? 0 : -1;
}

/* Returns -1 to go on, or the exit code to end with. */
static int parse_options(int argc, char **argv, options_t *o)
{
  memset(o, 0, sizeof *o);
  o->out = "results";
  o->duration_s = 3600.0;
  o->exp1_duration_s = 2.0;
  o->seed = 1;
  o->only = (1u << NEXP) - 1u;
  tool_args_t a;
  tool_args_init(&a, "imest-demo", argc, argv);
  tool_arg_kind_t kind;
  double x;
  int std_rc;
  while ((kind = tool_args_next(&a)) != TOOL_ARG_END) {
    if (kind == TOOL_ARG_OPERAND) {
      fprintf(stderr, "imest-demo: unexpected argument '%s' (see --help)\n", a.operand);
      return TOOL_EXIT_USAGE;
    } else if ((std_rc = tool_args_standard(&a, usage)) >= 0) {
      return std_rc;
    } else if (tool_args_is(&a, "--out")) {
      if ((o->out = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--duration") || tool_args_is(&a, "--exp1-duration")) {
      if (tool_args_number(&a, &x)) return TOOL_EXIT_USAGE;
      if (x < 1.0) {
        fprintf(stderr, "imest-demo: %s must be at least one window (1 s)\n", a.opt);
        return TOOL_EXIT_USAGE;
      }
      *(tool_args_is(&a, "--duration") ? &o->duration_s : &o->exp1_duration_s) = x;
    } else if (tool_args_is(&a, "--can-iface")) {
      if ((o->can_iface = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--seed")) {
      if (tool_args_number(&a, &x)) return TOOL_EXIT_USAGE;
      if (x < 0 || x != floor(x) || x > 4294967295.0) {
        fprintf(stderr, "imest-demo: --seed must be a whole number >= 0\n");
        return TOOL_EXIT_USAGE;
      }
      o->seed = (unsigned long)x;
    } else if (tool_args_is(&a, "--only")) {
      const char *v = tool_args_value(&a);
      if (v == NULL || parse_only(v, &o->only)) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--quiet")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      o->quiet = 1;
    } else if (tool_args_is(&a, "--adaptive-tr")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (strcmp(v, "tracker") != 0 && strcmp(v, "raw") != 0) {
        fprintf(stderr, "imest-demo: --adaptive-tr: '%s' is not tracker or raw\n", v);
        return TOOL_EXIT_USAGE;
      }
      o->adaptive_raw = strcmp(v, "raw") == 0;
    } else if (tool_args_is(&a, "--no-commission")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      o->no_commission = 1;
    } else {
      return tool_args_unknown(&a);
    }
  }
  return -1;
}

/* One thread per experiment asked for. */
static int start_jobs(const options_t *o, const demo_constants_t *k, job_t jobs[NEXP], pthread_t th[NEXP],
                      int started[NEXP])
{
  for (int e = 0; e < NEXP; ++e) {
    jobs[e].id = e;
    jobs[e].opt = o;
    jobs[e].k = k;
    jobs[e].duration_s = e == EXP1      ? o->exp1_duration_s
                         : SHORT_RUN(e) ? fmax(o->duration_s / IFOC11_THERMAL_X, 10.0)
                                        : o->duration_s;
    jobs[e].fs_hz = SHORT_RUN(e) ? 8000.0 : 4000.0; /* progress only; job_open sets total */
    jobs[e].total = (unsigned long long)llround(jobs[e].duration_s * jobs[e].fs_hz);
    atomic_store(&jobs[e].done, 0);
    started[e] = 0;
    if (!(o->only & (1u << e))) continue;
    /* the threads' simulators and estimators are thread-local statics: the
       default 8 MiB stack is plenty */
    if (pthread_create(&th[e], NULL, job_thread, &jobs[e]) != 0) {
      fprintf(stderr, "imest-demo: cannot start a thread\n");
      return -1;
    }
    started[e] = 1;
  }
  return 0;
}

/* Progress on a terminal until every thread is done; then joins them. */
static void wait_jobs(const options_t *o, job_t jobs[NEXP], pthread_t th[NEXP], const int started[NEXP],
                      double t0)
{
  const int tty = !o->quiet && isatty(2);
  for (;;) {
    int running = 0;
    unsigned long long done = 0, total = 0;
    double motor_s = 0.0;
    for (int e = 0; e < NEXP; ++e) {
      if (!started[e]) continue;
      const unsigned long long d = atomic_load(&jobs[e].done);
      done += d;
      total += jobs[e].total;
      motor_s += (double)d / jobs[e].fs_hz;
      if (d < jobs[e].total) running = 1;
    }
    if (tty) {
      const double el = now_s() - t0;
      const double frac = total ? (double)done / (double)total : 1.0;
      fprintf(stderr, "\rimest-demo: simulating %5.1f %%  (%.0f s of motor time, %.0f s elapsed",
              100.0 * frac, motor_s, el);
      if (frac > 0.02 && frac < 1.0) fprintf(stderr, ", ~%.0f s left", el * (1.0 - frac) / frac);
      fprintf(stderr, ")   ");
    }
    if (!running) break;
    struct timespec ts = {0, 250000000L};
    nanosleep(&ts, NULL);
  }
  for (int e = 0; e < NEXP; ++e)
    if (started[e]) pthread_join(th[e], NULL);
  if (tty) fprintf(stderr, "\n");
}

/* One stdout line per experiment; returns nonzero if any failed. */
static int report(const job_t jobs[NEXP], const int started[NEXP], double t0)
{
  int fail = 0;
  for (int e = 0; e < NEXP; ++e) {
    const job_t *j = &jobs[e];
    if (!started[e]) continue;
    if (j->live_note[0]) fprintf(stderr, "imest-demo: note: %s\n", j->live_note);
    if (j->rc != 0) {
      fprintf(stderr, "imest-demo: %s failed: %s\n", k_exp_name[e], j->err);
      fail = 1;
      continue;
    }
    printf("experiment=%s motor_s=%.0f windows=%ld valid=%ld can_frames=%lu can_failed=%lu "
           "wall_s=%.2f realtime_x=%.0f",
           k_exp_name[e], j->duration_s, j->windows, j->valid, j->can_lines, j->can_failed, j->wall_s,
           j->duration_s / j->wall_s);
    if (e == DUTY4)
      printf(" commissioned=%d dead_time_s=%.4g v_threshold_v=%.4g uncertainty=%.3g", j->duty_comm.valid,
             (double)j->duty_comm.inverter.dead_time_s, (double)j->duty_comm.v_threshold_v.value,
             (double)j->duty_comm.inverter.uncertainty);
    if (e == EXP1)
      printf(" identified_T_R_s=%.6g identified_R_S_ohm=%.6g identified_window=%d", j->id_tr, j->id_rs,
             j->id_seq);
    if (j->live) printf(" live_sent=%lu live_failed=%lu", j->live_sent, j->live_failed);
    printf("\n");
  }
  struct rusage ru;
  double cpu = D_NAN;
  if (getrusage(RUSAGE_SELF, &ru) == 0)
    cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
          1e-6 * (double)ru.ru_stime.tv_usec;
  const long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  printf("simulate_wall_s=%.2f simulate_cpu_s=%.2f cpus=%ld\n", now_s() - t0, cpu, ncpu);
  return fail;
}

int main(int argc, char **argv)
{
  static options_t o;
  int rc = parse_options(argc, argv, &o);
  if (rc >= 0) return rc;
  char raw[1024];
  snprintf(raw, sizeof raw, "%.900s/raw", o.out);
  if (mkdir_p(raw) != 0) {
    fprintf(stderr, "imest-demo: cannot create %s: %s\n", raw, strerror(errno));
    return TOOL_EXIT_DATA;
  }
  static demo_constants_t k;
  if (!o.no_commission && commission(&o, raw, &k) != 0) {
    fprintf(stderr, "imest-demo: commissioning: cannot run or write its results\n");
    return TOOL_EXIT_DATA;
  }
  static job_t jobs[NEXP];
  pthread_t th[NEXP];
  int started[NEXP] = {0}; /* start_jobs stops at a failed thread: the rest stay 0 */
  const double t0 = now_s();
  const int bad_start = start_jobs(&o, &k, jobs, th, started);
  wait_jobs(&o, jobs, th, started, t0);
  if (bad_start) return TOOL_EXIT_DATA;
  return report(jobs, started, t0) ? TOOL_EXIT_DATA : TOOL_EXIT_OK;
}
