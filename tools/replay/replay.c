/* SPDX-License-Identifier: Apache-2.0 */
/* imest-replay: runs a recorded CSV (t,u_a,u_b,u_c,i_a,i_b,i_c,theta, or
 * with --voltage duty t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta; any order, more
 * columns ignored) through exactly the code a firmware runs: the float32 ISR
 * call per sample (imest_isr_abc or imest_isr_duty), the background call when
 * a window completes. Prints one CSV row per window on stdout.
 *
 * parse (replay_options.c) -> scan: time base, clipping, conventions
 * (replay_scan.c) -> configure, with advice on what the estimator refuses
 * (replay_advice.c) -> run: the drive loop (tools/common/drive_loop.c) -> the
 * alignment check of the voltage columns (replay_align.c). */
#define _POSIX_C_SOURCE 200809L /* dup, fdopen */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "csv_reader.h"
#include "drive_loop.h"
#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest/imest_temperature.h"
#include "replay_advice.h"
#include "replay_align.h"
#include "replay_options.h"
#include "replay_scan.h"
#include "tool_args.h"
#ifdef IMEST_HAVE_CANDUMP
#include "imest_candump.h"
#endif

static const char *const k_prog = "imest-replay";

/* One count of a 4096-count encoder [rad]: a first angle step this small is
 * encoder noise on a still rotor. */
#define ENCODER_COUNT_STILL_RAD (6.283185307179586 / 4096.0 * 1.0001)

/* ------------------------------------------------------------------------- */
/* configure: from the options and the scan to an estimator config            */

/* ADC saturation: explicit limits, or plateaus at the record's extreme. A
 * limit equal to the clipped value makes samples at it count as saturated. */
static double adc_limit(double given, const clip_t clip[3], char sym, const char *unit, const char *opt,
                        int quiet)
{
  if (given >= 0) return given;
  double limit = 0;
  for (int k = 0; k < 3; ++k) {
    if (clip[k].plateau >= 5 && clip[k].max_abs > 0) {
      limit = clip[k].max_abs;
      if (!quiet)
        fprintf(stderr,
                "%s: note: %c_%c looks clipped at %.6g %s (%ld samples on plateaus); windows "
                "with such samples are marked adc_saturation (%s overrides)\n",
                k_prog, sym, "abc"[k], clip[k].max_abs, unit, clip[k].plateau, opt);
    }
  }
  return limit;
}

static int configure(const replay_opts_t *o, const replay_scan_t *s, imest_config_t *cfg)
{
  *cfg = o->cfg;
  cfg->fs_hz = (float)s->fs;
  /* the angle may step by less than pi per sample: by default the config's
   * limit, lowered to 2 rad per sample for slow logs (1 kHz: 2000 rad/s) */
  cfg->speed_limit_rad_s =
      o->speed_limit > 0 ? (float)o->speed_limit : fminf(cfg->speed_limit_rad_s, (float)(2.0 * s->fs));
  cfg->i_limit_a = (float)adc_limit(o->i_limit, s->clip_i, 'i', "A", "--i-limit", o->quiet);
  cfg->u_limit_v = (float)adc_limit(o->u_limit, s->clip_u, 'u', "V", "--u-limit", o->quiet);
  /* At rest: no current and a still rotor imply a zero history for every
   * filter (no current means no flux and no voltage either). The rotor test
   * uses the first step only: a DOL start accelerates within ms. A still
   * rotor may show one count of a fine encoder (at 8 kHz one count of 16384
   * is 3 rad/s), so a step up to a 4096-count encoder's count is still. */
  const int still = s->th_step1 * s->fs < 2.0 || s->th_step1 <= ENCODER_COUNT_STILL_RAD;
  cfg->start_at_rest = o->from_rest >= 0 ? o->from_rest : (s->i_first <= 0.01 * s->i_max && still);
  const char *field = NULL;
  if (imest_config_check(cfg, &field) != IMEST_OK) return replay_explain_config(o, s, cfg, field);
  return -1;
}

/* ------------------------------------------------------------------------- */
/* CAN telemetry: the frames each window publishes, as a candump -L log       */

typedef struct {
  FILE *f;   /* NULL: no log */
  int owned; /* f is closed at the end (not the process's stdout) */
#ifdef IMEST_HAVE_CANDUMP
  imest_candump_port_t port;
  imest_can_pub_t pub; /* publishes what the background returns, as firmware would */
#endif
} can_log_t;

/* to_stdout: the stream "-" writes to (the process's stdout, kept aside when
 * -o FILE took stdout for the windows' CSV). */
static int can_log_open(can_log_t *c, const replay_opts_t *o, FILE *to_stdout)
{
  memset(c, 0, sizeof *c);
  if (o->candump_path == NULL) return -1;
#ifdef IMEST_HAVE_CANDUMP
  c->owned = strcmp(o->candump_path, "-") != 0 || to_stdout != stdout;
  c->f = strcmp(o->candump_path, "-") ? fopen(o->candump_path, "w") : to_stdout;
  if (c->f == NULL) {
    fprintf(stderr, "%s: %s: %s\n", k_prog, o->candump_path, strerror(errno));
    return TOOL_EXIT_DATA;
  }
  if (imest_candump_port_open(&c->port, c->f, o->can_iface) != 0) {
    fprintf(stderr, "%s: --candump-iface '%s' is not a valid interface name\n", k_prog, o->can_iface);
    return TOOL_EXIT_USAGE;
  }
  (void)imest_can_pub_init(&c->pub, &c->port.port, o->can_id); /* checked by replay_parse */
  return -1;
#else
  (void)to_stdout;
  fprintf(stderr, "%s: built without the candump port: --candump is not available\n", k_prog);
  return TOOL_EXIT_USAGE;
#endif
}

/* The window's six frames, then (--temperatures: t not NULL) its IMEST_TEMP with the same counter,
 * as a firmware running the temperature module sends them (imest_temperature.h). */
static void can_log_publish(can_log_t *c, const imest_result_t *r, const imest_temperature_t *t)
{
#ifdef IMEST_HAVE_CANDUMP
  if (c->f == NULL) return;
  (void)imest_can_publish(&c->pub, r); /* a failed write: can_log_close() says so */
  if (t != NULL) (void)imest_temperature_can_publish(&c->pub, t);
#else
  (void)c;
  (void)r;
  (void)t;
#endif
}

/* The frames of the windows a sample completes are stamped with its time. */
static void can_log_time(can_log_t *c, double t_s)
{
#ifdef IMEST_HAVE_CANDUMP
  if (c->f) imest_candump_port_set_time(&c->port, t_s);
#else
  (void)c;
  (void)t_s;
#endif
}

static int can_log_close(can_log_t *c)
{
  if (c->f == NULL) return 0;
  if (!c->owned) return fflush(c->f) == 0 ? 0 : -1;
  return fclose(c->f) == 0 ? 0 : -1;
}

/* ------------------------------------------------------------------------- */
/* run: every sample through the ISR call, the background per window          */

/* The columns up to flags keep their places (tools/studies/accuracy reads them by
 * position); the per-parameter verdicts and bounds came later and follow. */
static void print_header(int temperatures, int ls_curve)
{
  printf("t_end_s,T_R_s,R_S_ohm,E_I,valid,status,seq,K1,K2,pe_k1_rel,pe_k2_rel,"
         "H11,H12,H22,hessian_pd,n_roots,n_admissible,slip_ratio,i_rms_a,used_samples,flags,"
         "tr_valid,rs_valid,tr_reason,rs_reason,span_s,windows,tr_bound_rel,rs_bound_rel%s%s\n",
         temperatures ? ",stator_c,stator_uncert_k,stator_valid,rr_ohm,rotor_c,rotor_uncert_k,rotor_valid"
                      : "",
         ls_curve ? ",ls_window_h" : "");
}

/* A bound that was not computed is NaN: printed as "nan" whatever its sign bit. */
static void print_bound(double x)
{
  if (isnan(x))
    printf(",nan");
  else
    printf(",%.6g", x);
}

typedef struct {
  double t0_s; /* the record's first t [s] */
  can_log_t *can;
  imest_temperature_t *temp; /* --temperatures: its columns follow the others (NULL: none) */
  int ls_curve;              /* --ls-curve: ls_window_h is the last column */
} row_ctx_t;

/* drive_window_fn: the window's frames to the CAN log, one output row. */
static void print_row(void *ctx, const imest_result_t *r)
{
  const row_ctx_t *x = (const row_ctx_t *)ctx;
  const double t0_s = x->t0_s;
  if (x->temp != NULL) (void)imest_temperature_update(x->temp, r); /* r and x->temp are not NULL */
  can_log_publish(x->can, r, x->temp);
  printf("%.6f,%.9g,%.9g,%.6g,%d,%s,%u,%.9g,%.9g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%u,%u,%.4g,%.6g,%u,0x%x,",
         t0_s + r->t_end_s, r->tr_s, r->rs_ohm, r->e_i, r->valid, imest_reason_name(r->status), r->seq, r->k1,
         r->k2, r->pe_k1_rel, r->pe_k2_rel, r->hessian[0][0], r->hessian[0][1], r->hessian[1][1],
         (r->flags & IMEST_FLAG_HESSIAN_PD) ? 1 : 0, r->n_roots, r->n_admissible, r->slip_ratio, r->i_rms_a,
         r->used_samples, r->flags);
  printf("%d,%d,%s,%s,%.6g,%u", r->tr_valid, r->rs_valid, imest_reason_name(r->tr_reason),
         imest_reason_name(r->rs_reason), r->span_s, r->windows);
  print_bound(r->tr_bound_rel);
  print_bound(r->rs_bound_rel);
  if (x->temp != NULL) {
    const imest_temperature_t *t = x->temp;
    print_bound((double)t->stator_c);
    print_bound((double)t->stator_uncert_k);
    printf(",%d", t->stator_valid);
    print_bound((double)t->rr_ohm);
    print_bound((double)t->rotor_c);
    print_bound((double)t->rotor_uncert_k);
    printf(",%d", t->rotor_valid);
  }
  if (x->ls_curve) print_bound(r->ls_window_h);
  printf("\n");
}

/* The estimator along the record, in segments: --gaps restart starts a new
 * one at each gap in t. */
typedef struct {
  imest_t *est;
  imest_config_t cfg; /* for a restart: as configured, but warming up (the motor runs) */
  row_ctx_t *row;
  long win_n;                      /* samples per window */
  long k0;                         /* the segment's first sample */
  double t0_s;                     /* its time [s] */
  long restarts, flushed, dropped; /* at gaps: partial windows estimated, dropped */
} segment_t;

/* At a gap: the partial window before it is estimated if it has at least half
 * a window's samples (as at the record's end), else dropped; then the
 * instance is initialised again (filters, window, sequence) and output times
 * count from the sample after the gap. */
static void restart(drive_t *d, segment_t *g, const replay_scan_t *s, can_log_t *can, long k, double t_s)
{
  const long rest = (k - g->k0) % g->win_n;
  if (rest > 0 && 2 * rest >= g->win_n) {
    can_log_time(can, g->t0_s + (double)(k - g->k0 - 1) / s->fs);
    drive_flush(d);
    g->flushed++;
  } else if (rest > 0) {
    g->dropped++;
  }
  (void)imest_init(g->est, &g->cfg); /* the config was checked */
  g->k0 = k;
  g->t0_s = t_s;
  g->row->t0_s = t_s;
  g->restarts++;
}

static int run(csv_reader_t *r, const replay_opts_t *o, const replay_scan_t *s, drive_t *d, can_log_t *can,
               segment_t *g)
{
  if (csv_rewind(r) != 0) {
    fprintf(stderr, "%s: %s: cannot read the file a second time\n", k_prog, r->name);
    return TOOL_EXIT_DATA;
  }
  print_header(o->temperatures, o->cfg.ls_curve_points > 0u);
  double v[CSV_MAX_NEED], tprev = 0, qprev = 0;
  replay_sample_t x;
  long k = 0;
  int rc;
  while ((rc = csv_next(r, v)) == 1) {
    replay_decode(o->voltage, v, &x);
    if (k > 0 && s->n_gaps > 0 && replay_is_gap(s, x.t - tprev, r->t_round + qprev))
      restart(d, g, s, can, k, x.t * s->t_unit_s);
    tprev = x.t;
    qprev = r->t_round;
    can_log_time(can, g->t0_s + (double)(k - g->k0) / s->fs);
    const int n = o->voltage == REPLAY_VOLTAGE_DUTY ? drive_sample_duty(d, x.d, x.vdc, x.i, x.theta)
                                                    : drive_sample(d, x.u, x.i, x.theta);
    if (n < 0) break;
    k++;
  }
  if (rc < 0) {
    fprintf(stderr, "%s: %s\n", k_prog, r->err);
    return TOOL_EXIT_DATA;
  }
  return -1;
}

/* A last partial window of at least half the length is estimated too, and a
 * record shorter than one window (without gaps) is estimated as one shorter
 * window. */
static long run_last_window(drive_t *d, const replay_scan_t *s, const segment_t *g, can_log_t *can,
                            int *flushed)
{
  const long n = s->n - g->k0, rest = n % g->win_n;
  *flushed = rest > 0 && (2 * rest >= g->win_n || (n < g->win_n && g->restarts == 0));
  if (*flushed) {
    can_log_time(can, g->t0_s + (double)(n - 1) / s->fs);
    drive_flush(d);
  }
  return rest;
}

static void summary(const drive_t *d, const replay_scan_t *s, const imest_config_t *cfg, const segment_t *g,
                    long rest, int flushed)
{
  fprintf(stderr, "%s: %ld samples at %.6g Hz, %ld windows (%ld valid", k_prog, s->n, s->fs, d->windows,
          d->valid);
  if (d->tr_valid != d->valid || d->rs_valid != d->valid)
    fprintf(stderr, "; T_R valid in %ld, R_S in %ld", d->tr_valid, d->rs_valid);
  fprintf(stderr, ")");
  int most = 0;
  for (int k = 1; k < DRIVE_NSTATUS; ++k) {
    if (d->by_status[k]) fprintf(stderr, ", %ld %s", d->by_status[k], imest_reason_name(k));
    if (d->by_status[k] > d->by_status[most]) most = k;
  }
  if (rest && !flushed)
    fprintf(stderr, "; last %ld samples (under half a window) not used", rest);
  else if (rest)
    fprintf(stderr, "; last window has %ld samples", rest);
  fprintf(stderr, "%s", cfg->start_at_rest ? "; started at rest" : "; warm-up at start");
  if (g->restarts)
    fprintf(stderr, "; restarted at %ld gap%s (%ld partial window%s before them estimated, %ld dropped)",
            g->restarts, g->restarts == 1 ? "" : "s", g->flushed, g->flushed == 1 ? "" : "s", g->dropped);
  fprintf(stderr, "\n");
  /* nothing valid: say what the most common reason usually means */
  const char *what = d->valid == 0 && most ? replay_remedy(most) : NULL;
  if (what)
    fprintf(stderr, "%s: no window is valid, most are %s: %s (docs/feeding-logs.md)\n", k_prog,
            imest_reason_name(most), what);
  /* T_R refused for the constants' stated uncertainty in most windows: say what to do */
  if (2 * d->tr_constants > d->windows && !(what && most == IMEST_REASON_CONSTANTS_UNCERTAIN))
    fprintf(stderr, "%s: T_R is constants_uncertain in %ld of %ld windows: %s (docs/feeding-logs.md)\n",
            k_prog, d->tr_constants, d->windows, replay_remedy(IMEST_REASON_CONSTANTS_UNCERTAIN));
}

/* --require-valid: TOOL_EXIT_NOT_VALID when no window has the column asked for at 1. */
static int require_valid(const drive_t *d, tool_require_t req)
{
  const long n = req == TOOL_REQUIRE_TR ? d->tr_valid : req == TOOL_REQUIRE_RS ? d->rs_valid : d->valid;
  if (req == TOOL_REQUIRE_NONE || n > 0) return TOOL_EXIT_OK;
  fprintf(stderr, "%s: --require-valid: none of the %ld window(s) has %s = 1\n", k_prog, d->windows,
          tool_require_column(req));
  return TOOL_EXIT_NOT_VALID;
}

/* Opens the recording with the columns of the chosen input. A header that has
 * the other input's columns gets the --voltage that reads it. */
static int open_recording(csv_reader_t *r, const replay_opts_t *o)
{
  if (csv_open_layout(r, o->path, replay_layout(o->voltage)) == 0) {
    /* what the header made the reader do: said once */
    for (const char *p = r->notes; *p && !o->quiet;) {
      const char *e = strchr(p, '\n');
      fprintf(stderr, "%s: note: %.*s\n", k_prog, (int)(e - p), p);
      p = e + 1;
    }
    return 0;
  }
  fprintf(stderr, "%s: %s", k_prog, r->err);
  const replay_voltage_t other =
      o->voltage == REPLAY_VOLTAGE_DUTY ? REPLAY_VOLTAGE_PHASE : REPLAY_VOLTAGE_DUTY;
  csv_reader_t alt;
  memset(&alt, 0, sizeof alt);
  if (strstr(r->err, "missing column") != NULL && strcmp(o->path, "-") != 0 &&
      csv_open_layout(&alt, o->path, replay_layout(other)) == 0)
    fprintf(stderr, "; it has the columns of --voltage %s", other == REPLAY_VOLTAGE_DUTY ? "duty" : "phase");
  csv_close(&alt);
  fprintf(stderr, "\n");
  return -1;
}

/* -o FILE: the windows' CSV into FILE (stdout is reopened on it, so the rows
 * are written as without -o); *to_stdout: where "--candump -" then goes. */
static int open_output(const replay_opts_t *o, FILE **to_stdout)
{
  *to_stdout = stdout;
  if (o->output_path == NULL || strcmp(o->output_path, "-") == 0) return -1;
  if (o->candump_path != NULL && strcmp(o->candump_path, "-") == 0) {
    const int fd = dup(STDOUT_FILENO);
    *to_stdout = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (*to_stdout == NULL) {
      fprintf(stderr, "%s: stdout for --candump -: %s\n", k_prog, strerror(errno));
      return TOOL_EXIT_DATA;
    }
  }
  if (freopen(o->output_path, "w", stdout) == NULL) {
    fprintf(stderr, "%s: -o %s: cannot write: %s\n", k_prog, o->output_path, strerror(errno));
    return TOOL_EXIT_DATA;
  }
  return -1;
}

int main(int argc, char **argv)
{
  replay_opts_t o;
  int rc = replay_parse(argc, argv, &o);
  if (rc >= 0) return rc;

  csv_reader_t r;
  if (open_recording(&r, &o) != 0) {
    csv_close(&r);
    return TOOL_EXIT_DATA;
  }
  replay_scan_t s;
  imest_config_t cfg;
  static imest_t est;
  can_log_t can;
  drive_t d;
  static imest_temperature_t temp;
  row_ctx_t row = {0, &can, NULL, o.cfg.ls_curve_points > 0u};
  if (o.temperatures) {
    (void)imest_temperature_init(&temp, &o.temp_cfg); /* checked by replay_parse() */
    row.temp = &temp;
  }
  if ((rc = replay_scan(&r, &o, &s)) >= 0 || (rc = configure(&o, &s, &cfg)) >= 0) goto done;
  imest_init(&est, &cfg);
  FILE *to_stdout = stdout;
  if ((rc = open_output(&o, &to_stdout)) >= 0 || (rc = can_log_open(&can, &o, to_stdout)) >= 0) goto done;
  row.t0_s = s.t0 * s.t_unit_s;
  drive_init(&d, &est, print_row, &row);
  segment_t seg = {&est, cfg, &row, lround((double)cfg.window_s * s.fs), 0, row.t0_s, 0, 0, 0};
  seg.cfg.start_at_rest = 0;
  if ((rc = run(&r, &o, &s, &d, &can, &seg)) >= 0) goto done;
  int flushed;
  const long rest = run_last_window(&d, &s, &seg, &can, &flushed);
  if (can_log_close(&can) != 0 || fflush(stdout) != 0) {
    fprintf(stderr, "%s: write error\n", k_prog);
    rc = TOOL_EXIT_DATA;
    goto done;
  }
  if (!o.quiet) summary(&d, &s, &cfg, &seg, rest, flushed);
  /* the voltage columns one row off: a note, nothing changed (replay_align.c) */
  replay_align_t al;
  if (!o.quiet && o.align_check && !d.error && d.windows > 0 &&
      (rc = replay_align_check(&r, &o, &s, &cfg, &al)) >= 0)
    goto done;
  if (d.error) {
    fprintf(stderr, "%s: imest_background failed: %s\n", k_prog, imest_err_name(d.error));
    rc = TOOL_EXIT_DATA;
  } else if (d.windows == 0) {
    fprintf(stderr, "%s: no window could be estimated\n", k_prog);
    rc = TOOL_EXIT_DATA;
  } else {
    rc = require_valid(&d, (tool_require_t)o.require);
  }
done:
  csv_close(&r);
  return rc;
}
