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
 * Experiments (run in parallel threads):
 *   exp1           60 Hz, 230 V applied at standstill, no load, run-up (2 s);
 *                  then the motor is simulated again with the identified T_R
 *                  and R_S (same inverter voltages) for the paper's Figs. 3-4.
 *   exp2           30 Hz V/f, rated load 2.064 N m, one hour of heating.
 *   ifoc_fixed     the same heat run under IFOC speed control, the
 *                  controller's T_R fixed at the cold value.
 *   ifoc_adaptive  the same, the controller's T_R set from the estimator's
 *                  latest valid window (imsim_set_ifoc_tr).
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

#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest_candump.h"
#include "imsim/imsim.h"
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
#include "imest_socketcan.h"
#endif

#define TWO_PI 6.283185307179586476925

/* ------------------------------------------------------------------------- */
/* Options                                                                    */

typedef struct {
  const char *out;
  double duration_s;      /* exp2 and the IFOC runs */
  double exp1_duration_s; /* exp1 */
  const char *can_iface;  /* live SocketCAN interface (exp2's frames), NULL = none */
  unsigned long seed;
  int quiet;
  unsigned int only;      /* bit mask of experiments to run */
} options_t;

enum { EXP1 = 0, EXP2 = 1, IFOC_FIXED = 2, IFOC_ADAPTIVE = 3, NEXP = 4 };
static const char *const k_exp_name[NEXP] = {"exp1", "exp2", "ifoc_fixed", "ifoc_adaptive"};

/* ------------------------------------------------------------------------- */
/* Per-window truth and drive state                                           */

typedef struct {
  double n;
  double tr, rs, speed, te, te_ref, te_err2, psi, psi_ref, i2, temp_s, temp_r, ifoc_tr, load;
} acc_t;

typedef struct {
  double tr, rs, speed, te, te_ref, te_err_rms, psi, psi_ref, i_rms, temp_s, temp_r, ifoc_tr,
      load;
} truth_t;

static void acc_add(acc_t *a, const imsim_sample *s)
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
    a->te_ref = a->psi_ref = a->ifoc_tr = NAN;
  }
}

static truth_t acc_mean(const acc_t *a)
{
  truth_t t;
  const double n = a->n > 0 ? a->n : (double)NAN;
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
  if (!isfinite(t.te_ref)) t.te_err_rms = NAN;
  return t;
}

/* ------------------------------------------------------------------------- */
/* CAN: candump log, optionally teed to a live SocketCAN interface            */

typedef struct {
  struct imest_can_port port;
  struct imest_candump_port log;
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  struct imest_socketcan sc;
#endif
  int live;
  unsigned long live_sent, live_failed;
} tee_port_t;

static int tee_send(void *ctx, const struct imest_can_frame *f)
{
  tee_port_t *t = (tee_port_t *)ctx;
  const int rc = t->log.port.send(t->log.port.ctx, f);
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  if (t->live) {
    if (t->sc.port.send(t->sc.port.ctx, f) == 0) t->live_sent++;
    else t->live_failed++;
  }
#endif
  return rc; /* the log is the record: its failure is the port's failure */
}

/* ------------------------------------------------------------------------- */
/* One experiment                                                             */

typedef struct {
  int id;
  const options_t *opt;
  double duration_s;
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

static void sim_config(int id, unsigned long seed, imsim_config *c)
{
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

static void est_config(const imsim_config *c, imest_config_t *cfg)
{
  imest_config_default(cfg);
  cfg->pole_pairs = 2;
  cfg->ls_h = 0.2908f;
  cfg->sigma = 0.096f;
  cfg->fs_hz = 4000.0f;
  /* What the drive knows about its own hardware: it is enabled with the
   * motor at rest, and where its ADCs clip (top code = range - 1 LSB). */
  cfg->start_at_rest = 1;
  cfg->i_limit_a = (float)(c->i_range_a * (1.0 - ldexp(1.0, 1 - c->adc_bits)));
  cfg->u_limit_v = (float)(c->u_range_v * (1.0 - ldexp(1.0, 1 - c->adc_bits)));
  /* Its phase voltages are the volt-seconds of the PWM period that just
   * ended (duty cycles x DC bus): they lag the current samples by half a
   * carrier period, which uncompensated biases R_S by about +5 %. */
  const int pwm = c->supply == IMSIM_SUPPLY_PWM || (c->supply == IMSIM_SUPPLY_IFOC && !c->ifoc_ideal_stage);
  if (pwm && (c->vmeas == IMSIM_VMEAS_AUTO || c->vmeas == IMSIM_VMEAS_AVG))
    cfg->u_delay_s = (float)(0.5 / c->carrier_hz);
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
  imsim_config cm, ci;
  sim_config(EXP1, j->opt->seed, &cm);
  ci = cm;
  ci.tr_s = tr_id;
  ci.rs_ohm = rs_id;
  ci.thermal = false;
  ci.ideal_sensors = true;
  static _Thread_local imsim sm, si;
  imsim_sample a, b;
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
  imsim_sample hist_a[H + 1], hist_b[H + 1];
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
    const imsim_sample *ma = &hist_a[0], *mb = &hist_b[0];
    double uab[2], iab[2];
    imsim_abc_to_ab(ma->u_abc, uab);
    imsim_abc_to_ab(ma->i_abc, iab);
    const double w_enc = k >= 2 * H ? (th[2 * H] - th[0]) * cm.fs_hz / (2.0 * H) : (double)NAN;
    fprintf(f, "%.6f,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.6g,%.6g\n", ma->t, uab[0],
            uab[1], iab[0], iab[1], w_enc, ma->speed_rad_s, mb->i_ab_true[0], mb->speed_rad_s,
            tr_id, rs_id);
  }
  if (fclose(f) != 0) {
    snprintf(j->err, sizeof j->err, "exp1_wave.csv: write error");
    return -1;
  }
  return 0;
}

static int run_job(job_t *j)
{
  const options_t *o = j->opt;
  char dir[1024];
  snprintf(dir, sizeof dir, "%.900s/raw", o->out);
  const char *name = k_exp_name[j->id];

  imsim_config c;
  sim_config(j->id, o->seed, &c);
  static _Thread_local imsim sim;
  imsim_sample s;
  if (imsim_init(&sim, &c, &s) != 0) {
    snprintf(j->err, sizeof j->err, "%s: simulator: %s", name, imsim_error(&sim));
    return -1;
  }
  imest_config_t cfg;
  est_config(&c, &cfg);
  const char *field = NULL;
  if (imest_config_check(&cfg, &field) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: estimator config: bad %s", name, field);
    return -1;
  }
  static _Thread_local imest_t est;
  if (imest_init(&est, &cfg) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: imest_init failed", name);
    return -1;
  }

  char fname[256];
  snprintf(fname, sizeof fname, "%s.candump.log", name);
  FILE *log = open_out(j, dir, fname);
  if (log == NULL) return -1;
  static _Thread_local tee_port_t tee;
  memset(&tee, 0, sizeof tee);
  if (imest_candump_port_open(&tee.log, log, "vcan0") != 0) {
    snprintf(j->err, sizeof j->err, "%s: candump port", name);
    fclose(log);
    return -1;
  }
  if (j->id == EXP2 && o->can_iface != NULL) {
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
    const int rc = imest_socketcan_open(&tee.sc, o->can_iface);
    if (rc == 0) {
      tee.live = 1;
      snprintf(j->live_note, sizeof j->live_note, "sending exp2's frames on %s", o->can_iface);
    } else {
      snprintf(j->live_note, sizeof j->live_note,
               "--can-iface %.32s: %.256s; continuing with the candump log only", o->can_iface,
               tee.sc.err);
    }
#else
    snprintf(j->live_note, sizeof j->live_note,
             "--can-iface %.32s: built without SocketCAN support; continuing with the candump log "
             "only",
             o->can_iface);
#endif
  }
  j->live = tee.live;
  tee.port.send = tee_send;
  tee.port.ctx = &tee;
  static _Thread_local imest_can_pub_t pub;
  if (imest_can_pub_init(&pub, &tee.port, IMEST_CAN_DEFAULT_BASE_ID) != IMEST_OK) {
    snprintf(j->err, sizeof j->err, "%s: imest_can_pub_init failed", name);
    fclose(log);
    return -1;
  }

  snprintf(fname, sizeof fname, "%s_direct.csv", name);
  FILE *csv = open_out(j, dir, fname);
  if (csv == NULL) {
    fclose(log);
    return -1;
  }
  fprintf(csv,
          "experiment,seq,t_end_s,T_R_s,R_S_ohm,valid,status,T_R_true_s,R_S_true_ohm,E_I,"
          "pe_k1_rel,pe_k2_rel,slip_ratio,i_rms_a,n_roots,n_admissible,used_samples,flags,"
          "speed_rad_s,torque_nm,load_nm,torque_ref_nm,torque_err_rms_nm,psi_r_wb,psi_ref_wb,"
          "i_phase_rms_a,temp_stator_c,temp_rotor_c,ifoc_T_R_s\n");

  const uint32_t wn = (uint32_t)lround((double)cfg.window_s * (double)cfg.fs_hz);
  const unsigned long long total = (unsigned long long)llround(j->duration_s * c.fs_hz);
  j->total = total;
  size_t nwin = (size_t)(total / wn) + 2;
  truth_t *truth = calloc(nwin, sizeof *truth);
  if (truth == NULL) {
    snprintf(j->err, sizeof j->err, "%s: out of memory", name);
    fclose(log);
    fclose(csv);
    return -1;
  }
  acc_t acc;
  memset(&acc, 0, sizeof acc);
  uint32_t in_win = 0;
  size_t win = 0;
  imest_result_t r;
  int have_id = 0;

  for (unsigned long long k = 0; k < total; ++k) {
    if (k > 0) imsim_step(&sim, &s);
    /* truth of this sample belongs to the window being filled */
    acc_add(&acc, &s);
    if (++in_win == wn) {
      if (win < nwin) truth[win] = acc_mean(&acc);
      win++;
      in_win = 0;
      memset(&acc, 0, sizeof acc);
    }
    /* what the firmware's ISR gets: float32 ADC values, wrapped encoder angle */
    const float u[3] = {(float)s.u_abc[0], (float)s.u_abc[1], (float)s.u_abc[2]};
    const float i[3] = {(float)s.i_abc[0], (float)s.i_abc[1], (float)s.i_abc[2]};
    double thw = fmod(s.theta, TWO_PI);
    if (thw < 0) thw += TWO_PI;
    float th = (float)thw;
    if (th >= (float)TWO_PI) th = 0.0f;
    if (imest_isr_abc(&est, u, i, th)) {
      /* background task: runs when woken, publishes over CAN */
      imest_candump_port_set_time(&tee.log, s.t);
      while (imest_background(&est, &r) == 1) {
        (void)imest_can_publish(&pub, &r);
        const truth_t *t = (r.seq < nwin) ? &truth[r.seq] : NULL;
        const truth_t nan_t = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
        if (t == NULL || r.seq >= win) t = &nan_t;
        fprintf(csv,
                "%s,%u,%.6f,%.9g,%.9g,%d,%s,%.9g,%.9g,%.6g,%.6g,%.6g,%.5g,%.6g,%u,%u,%u,%u,"
                "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.5g,%.5g,%.6g\n",
                name, r.seq, r.t_end_s, r.tr_s, r.rs_ohm, r.valid, imest_reason_name(r.status),
                t->tr, t->rs, r.e_i, r.pe_k1_rel, r.pe_k2_rel, r.slip_ratio, r.i_rms_a, r.n_roots,
                r.n_admissible, r.used_samples, r.flags, t->speed, t->te, t->load, t->te_ref,
                t->te_err_rms, t->psi, t->psi_ref, t->i_rms, t->temp_s, t->temp_r, t->ifoc_tr);
        j->windows++;
        if (r.valid) {
          j->valid++;
          if (j->id == IFOC_ADAPTIVE) imsim_set_ifoc_tr(&sim, r.tr_s);
          if (j->id == EXP1 && have_id < 2) {
            have_id = 2; /* first valid window */
            j->id_tr = r.tr_s;
            j->id_rs = r.rs_ohm;
            j->id_seq = (int)r.seq;
            j->id_status = r.status;
          }
        } else if (j->id == EXP1 && have_id == 0 && r.seq == 0 && r.tr_s > 0 && r.rs_ohm > 0) {
          have_id = 1; /* no valid window yet: the run-up window's estimate, flagged invalid */
          j->id_tr = r.tr_s;
          j->id_rs = r.rs_ohm;
          j->id_seq = (int)r.seq;
          j->id_status = r.status;
        }
      }
    }
    if ((k & 1023u) == 0) atomic_store(&j->done, k);
  }
  atomic_store(&j->done, total);
  free(truth);
  j->can_lines = tee.log.lines;
  j->can_failed = tee.log.failed;
  j->live_sent = tee.live_sent;
  j->live_failed = tee.live_failed;
#ifdef IMEST_DEMO_HAVE_SOCKETCAN
  if (tee.live) imest_socketcan_close(&tee.sc);
#endif
  int bad = 0;
  if (fclose(log) != 0) bad = 1;
  if (fclose(csv) != 0) bad = 1;
  if (bad) {
    snprintf(j->err, sizeof j->err, "%s: write error in %s", name, dir);
    return -1;
  }
  if (j->id == EXP1) {
    if (!have_id) {
      /* no estimate at all: still draw the run-up, with the nominal parameters */
      j->id_tr = c.tr_s;
      j->id_rs = c.rs_ohm;
      j->id_seq = -1;
    }
    FILE *f = open_out(j, dir, "exp1_identified.csv");
    if (f == NULL) return -1;
    fprintf(f, "seq,valid,status,T_R_s,R_S_ohm,source\n%d,%d,%s,%.9g,%.9g,%s\n", j->id_seq,
            have_id == 2, have_id ? imest_reason_name(j->id_status) : "none", j->id_tr, j->id_rs,
            have_id == 2   ? "first valid window"
            : have_id == 1 ? "run-up window 0, NOT valid (no valid window)"
                           : "nominal parameters (no usable estimate)");
    if (fclose(f) != 0) return -1;
    if (exp1_wave(j, dir, j->id_tr, j->id_rs) != 0) return -1;
  }
  return 0;
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
/* Main                                                                       */

static void usage(FILE *f)
{
  fprintf(f,
          "usage: imest-demo [--out DIR] [--duration S] [--exp1-duration S] [--only LIST]\n"
          "                  [--can-iface NAME] [--seed N] [--quiet]\n"
          "\n"
          "Runs the paper's experiments on the simulated motor with imest in the loop (ISR\n"
          "call per sample, background call per window, telemetry over the CAN port) and\n"
          "writes DIR/raw/<exp>.candump.log, DIR/raw/<exp>_direct.csv, DIR/raw/exp1_wave.csv.\n"
          "Experiments run in parallel threads: exp1 (run-up), exp2 (30 Hz V/f heat run),\n"
          "ifoc_fixed and ifoc_adaptive (the heat run under IFOC, controller T_R fixed at\n"
          "the cold value / taken from the estimator).\n"
          "\n"
          "  --out DIR           output folder (default results)\n"
          "  --duration S        motor time of exp2 and the IFOC runs (default 3600)\n"
          "  --exp1-duration S   motor time of exp1 (default 2)\n"
          "  --only LIST         comma-separated subset of exp1,exp2,ifoc_fixed,ifoc_adaptive\n"
          "  --can-iface NAME    also send exp2's frames on this SocketCAN interface\n"
          "  --seed N            sensor noise seed (default 1)\n"
          "  --quiet             no progress on stderr (default: progress if it is a terminal)\n"
          "\n"
          "stdout: one line per experiment, key=value pairs.\n");
}

static int parse_pos(const char *opt, const char *v, double *out)
{
  char *end = NULL;
  const double x = v ? strtod(v, &end) : (double)NAN;
  if (v == NULL || end == v || *end || !(x > 0) || !isfinite(x)) {
    fprintf(stderr, "imest-demo: %s needs a positive number\n", opt);
    return -1;
  }
  *out = x;
  return 0;
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

int main(int argc, char **argv)
{
  options_t o;
  memset(&o, 0, sizeof o);
  o.out = "results";
  o.duration_s = 3600.0;
  o.exp1_duration_s = 2.0;
  o.seed = 1;
  o.only = (1u << NEXP) - 1u;
  for (int a = 1; a < argc; ++a) {
    const char *opt = argv[a], *v = a + 1 < argc ? argv[a + 1] : NULL;
    if (!strcmp(opt, "-h") || !strcmp(opt, "--help")) {
      usage(stdout);
      return 0;
    } else if (!strcmp(opt, "--out") && v) {
      o.out = v;
      a++;
    } else if (!strcmp(opt, "--duration")) {
      if (parse_pos(opt, v, &o.duration_s)) return 2;
      a++;
    } else if (!strcmp(opt, "--exp1-duration")) {
      if (parse_pos(opt, v, &o.exp1_duration_s)) return 2;
      a++;
    } else if (!strcmp(opt, "--can-iface") && v) {
      o.can_iface = v;
      a++;
    } else if (!strcmp(opt, "--seed") && v) {
      o.seed = strtoul(v, NULL, 0);
      a++;
    } else if (!strcmp(opt, "--only") && v) {
      o.only = 0;
      char buf[256];
      snprintf(buf, sizeof buf, "%s", v);
      for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        int found = 0;
        for (int e = 0; e < NEXP; ++e)
          if (!strcmp(tok, k_exp_name[e])) {
            o.only |= 1u << e;
            found = 1;
          }
        if (!found) {
          fprintf(stderr, "imest-demo: --only: unknown experiment '%s'\n", tok);
          return 2;
        }
      }
      a++;
    } else if (!strcmp(opt, "--quiet")) {
      o.quiet = 1;
    } else {
      fprintf(stderr, "imest-demo: unknown option or missing value: '%s' (see --help)\n", opt);
      return 2;
    }
  }
  if (o.duration_s < 1.0 || o.exp1_duration_s < 1.0) {
    fprintf(stderr, "imest-demo: durations must be at least one window (1 s)\n");
    return 2;
  }
  char raw[1024];
  snprintf(raw, sizeof raw, "%.900s/raw", o.out);
  if (mkdir_p(raw) != 0) {
    fprintf(stderr, "imest-demo: cannot create %s: %s\n", raw, strerror(errno));
    return 1;
  }

  static job_t jobs[NEXP];
  pthread_t th[NEXP];
  int started[NEXP] = {0};
  const double t0 = now_s();
  for (int e = 0; e < NEXP; ++e) {
    jobs[e].id = e;
    jobs[e].opt = &o;
    jobs[e].duration_s = e == EXP1 ? o.exp1_duration_s : o.duration_s;
    jobs[e].total = (unsigned long long)llround(jobs[e].duration_s * 4000.0);
    atomic_store(&jobs[e].done, 0);
    if (!(o.only & (1u << e))) continue;
    /* the threads' simulators and estimators are thread-local statics: the
       default 8 MiB stack is plenty */
    if (pthread_create(&th[e], NULL, job_thread, &jobs[e]) != 0) {
      fprintf(stderr, "imest-demo: cannot start a thread\n");
      return 1;
    }
    started[e] = 1;
  }

  const int tty = !o.quiet && isatty(2);
  for (;;) {
    int running = 0;
    unsigned long long done = 0, total = 0;
    for (int e = 0; e < NEXP; ++e) {
      if (!started[e]) continue;
      const unsigned long long d = atomic_load(&jobs[e].done);
      done += d;
      total += jobs[e].total;
      if (d < jobs[e].total) running = 1;
    }
    if (tty) {
      const double el = now_s() - t0;
      const double frac = total ? (double)done / (double)total : 1.0;
      fprintf(stderr, "\rimest-demo: simulating %5.1f %%  (%.0f s of motor time, %.0f s elapsed",
              100.0 * frac, (double)done / 4000.0, el);
      if (frac > 0.02 && frac < 1.0) fprintf(stderr, ", ~%.0f s left", el * (1.0 - frac) / frac);
      fprintf(stderr, ")   ");
    }
    if (!running) break;
    struct timespec ts = {0, 250000000L};
    nanosleep(&ts, NULL);
  }
  int fail = 0;
  for (int e = 0; e < NEXP; ++e)
    if (started[e]) pthread_join(th[e], NULL);
  if (tty) fprintf(stderr, "\n");
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
           k_exp_name[e], j->duration_s, j->windows, j->valid, j->can_lines, j->can_failed,
           j->wall_s, j->duration_s / j->wall_s);
    if (e == EXP1)
      printf(" identified_T_R_s=%.6g identified_R_S_ohm=%.6g identified_window=%d", j->id_tr,
             j->id_rs, j->id_seq);
    if (j->live) printf(" live_sent=%lu live_failed=%lu", j->live_sent, j->live_failed);
    printf("\n");
  }
  struct rusage ru;
  double cpu = NAN;
  if (getrusage(RUSAGE_SELF, &ru) == 0)
    cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
          (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
  const long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  printf("simulate_wall_s=%.2f simulate_cpu_s=%.2f cpus=%ld\n", now_s() - t0, cpu, ncpu);
  return fail;
}
