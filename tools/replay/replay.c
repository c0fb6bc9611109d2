/* imest-replay: runs a recorded CSV (t,u_a,u_b,u_c,i_a,i_b,i_c,theta, any
 * order, more columns ignored) through exactly the code a firmware runs: the
 * float32 ISR call per sample, the background call when a window completes.
 * Prints one CSV row per window on stdout. */
#include <errno.h>
#include <stddef.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csv_reader.h"
#include "imest/imest.h"
#include "imest/imest_can.h"
#ifdef IMEST_HAVE_CANDUMP
#include "imest_can_id.h"
#include "imest_candump.h"
#endif

#define TWO_PI 6.283185307179586476925

static void usage(FILE *o)
{
  fprintf(o,
          "usage: imest-replay --pole-pairs N --ls HENRY --sigma VALUE [options] FILE.csv\n"
          "\n"
          "Runs a recording through the estimator exactly as firmware does and prints one\n"
          "CSV row per window: t_end_s,T_R_s,R_S_ohm,E_I,valid,status,...\n"
          "FILE needs a header with t,u_a,u_b,u_c,i_a,i_b,i_c,theta (any order; other\n"
          "columns ignored): phase-to-neutral V, phase A (positive into the motor),\n"
          "mechanical angle in rad (unwrapped, increasing with the a-b-c field).\n"
          "\n"
          "options:\n"
          "  --window S          window length [s] (default 1)\n"
          "  --filter-hz HZ      front-end Butterworth-3 cut-off (default 100)\n"
          "  --aa-hz HZ          cut-off of a 2nd-order analog anti-alias filter on the\n"
          "                      electrical channels, modelled on the angle (default none)\n"
          "  --u-delay S         the voltage samples lag the currents by S seconds (e.g. 50e-6\n"
          "                      for volt-seconds of the PWM period that just ended at 10 kHz)\n"
          "  --dc-block-hz HZ    cut-off of the offset high-pass on voltages and currents\n"
          "                      (default 1; 0 = off)\n"
          "  --tr-nominal S      nominal T_R for scaling (default 0.1)\n"
          "  --tr-min S --tr-max S   admissible T_R band (default 0.001 .. 10)\n"
          "  --max-pe-k2 X       validity threshold on the relative PE index of K2 (0.1)\n"
          "  --i-limit A         |phase current| at which the ADC saturates (default: auto,\n"
          "                      detected from plateaus at the record's extreme; 0 = off)\n"
          "  --u-limit V         the same for the phase voltages (default auto)\n"
          "  --from-rest auto|yes|no  the record starts at rest (no warm-up needed);\n"
          "                      auto = current ~0 and rotor still at the first samples\n"
          "  --candump FILE      also write the published CAN frames (candump -L format)\n"
          "  --can-iface NAME    interface name in that log (default vcan0)\n"
          "  --can-id ID         base CAN identifier (default 0x6A0; above 0x7FF: 29-bit)\n"
          "  --can-ext           the base CAN identifier is 29-bit even if it is small\n"
          "  --quiet             no summary on stderr\n");
}

static int parse_num(const char *opt, const char *s, double *out)
{
  char *end = NULL;
  errno = 0;
  double x = strtod(s, &end);
  if (s == end || *end != '\0' || !isfinite(x)) {
    fprintf(stderr, "imest-replay: %s: '%s' is not a number\n", opt, s);
    return -1;
  }
  *out = x;
  return 0;
}

/* The config fields set by a plain numeric option. */
static float *float_option(imest_config_t *cfg, const char *opt)
{
  static const struct {
    const char *name;
    size_t offset;
  } table[] = {
      {"--window", offsetof(imest_config_t, window_s)},
      {"--filter-hz", offsetof(imest_config_t, filter_hz)},
      {"--aa-hz", offsetof(imest_config_t, aa_hz)},
      {"--u-delay", offsetof(imest_config_t, u_delay_s)},
      {"--dc-block-hz", offsetof(imest_config_t, dc_block_hz)},
      {"--tr-nominal", offsetof(imest_config_t, tr_nominal_s)},
      {"--tr-min", offsetof(imest_config_t, tr_min_s)},
      {"--tr-max", offsetof(imest_config_t, tr_max_s)},
      {"--max-pe-k2", offsetof(imest_config_t, max_pe_k2_rel)},
  };
  for (size_t k = 0; k < sizeof table / sizeof table[0]; ++k) {
    if (!strcmp(opt, table[k].name)) return (float *)(void *)((char *)cfg + table[k].offset);
  }
  return NULL;
}

static void print_row(double t0, const imest_result_t *r)
{
  printf("%.6f,%.9g,%.9g,%.6g,%d,%s,%u,%.9g,%.9g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%u,%u,%.4g,%.6g,%u,0x%x\n",
         t0 + r->t_end_s, r->tr_s, r->rs_ohm, r->e_i, r->valid, imest_reason_name(r->status),
         r->seq, r->k1, r->k2, r->pe_k1_rel, r->pe_k2_rel, r->hessian[0][0], r->hessian[0][1],
         r->hessian[1][1], (r->flags & IMEST_FLAG_HESSIAN_PD) ? 1 : 0, r->n_roots,
         r->n_admissible, r->slip_ratio, r->i_rms_a, r->used_samples, r->flags);
}

typedef struct {
  double max_abs;
  long run, plateau;
  double prev;
} clip_t;

/* Clipping signature: runs of >= 5 identical samples at the record's extreme. */
static void clip_feed(clip_t *c, double x)
{
  const double a = fabs(x);
  if (a > c->max_abs) {
    c->max_abs = a;
    c->plateau = 0;
    c->run = 1;
  } else if (a == c->max_abs && x == c->prev) {
    c->run++;
    if (c->run == 5) c->plateau += 5;
    else if (c->run > 5) c->plateau++;
  } else if (a == c->max_abs) {
    c->run = 1;
  } else {
    c->run = 0;
  }
  c->prev = x;
}

int main(int argc, char **argv)
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  const char *path = NULL, *candump_path = NULL, *can_iface = "vcan0";
  double d;
  int have_np = 0, have_ls = 0, have_sigma = 0, quiet = 0;
  double i_limit = -1.0, u_limit = -1.0; /* -1 = auto */
  int from_rest = -1;                     /* -1 = auto */
  const char *can_id = NULL;
  int can_ext = 0;

  for (int a = 1; a < argc; ++a) {
    const char *o = argv[a];
    const char *v = (a + 1 < argc) ? argv[a + 1] : NULL;
#define NEED_VALUE                                                                           \
  do {                                                                                       \
    if (v == NULL) {                                                                         \
      fprintf(stderr, "imest-replay: %s needs a value\n", o);                                \
      return 2;                                                                              \
    }                                                                                        \
    a++;                                                                                     \
  } while (0)
    if (!strcmp(o, "-h") || !strcmp(o, "--help")) {
      usage(stdout);
      return 0;
    } else if (!strcmp(o, "--pole-pairs")) {
      NEED_VALUE;
      if (parse_num(o, v, &d) || d < 1 || d > 64 || d != floor(d)) {
        fprintf(stderr, "imest-replay: --pole-pairs must be an integer 1..64\n");
        return 2;
      }
      cfg.pole_pairs = (unsigned int)d;
      have_np = 1;
    } else if (!strcmp(o, "--ls")) {
      NEED_VALUE;
      if (parse_num(o, v, &d)) return 2;
      cfg.ls_h = (float)d;
      have_ls = 1;
    } else if (!strcmp(o, "--sigma")) {
      NEED_VALUE;
      if (parse_num(o, v, &d)) return 2;
      cfg.sigma = (float)d;
      have_sigma = 1;
    } else if (float_option(&cfg, o) != NULL) {
      NEED_VALUE;
      if (parse_num(o, v, &d)) return 2;
      *float_option(&cfg, o) = (float)d;
    } else if (!strcmp(o, "--i-limit")) {
      NEED_VALUE;
      if (strcmp(v, "auto") && parse_num(o, v, &i_limit)) return 2;
    } else if (!strcmp(o, "--u-limit")) {
      NEED_VALUE;
      if (strcmp(v, "auto") && parse_num(o, v, &u_limit)) return 2;
    } else if (!strcmp(o, "--from-rest")) {
      NEED_VALUE;
      if (!strcmp(v, "auto")) from_rest = -1;
      else if (!strcmp(v, "yes")) from_rest = 1;
      else if (!strcmp(v, "no")) from_rest = 0;
      else {
        fprintf(stderr, "imest-replay: --from-rest takes auto, yes or no\n");
        return 2;
      }
    } else if (!strcmp(o, "--candump")) {
      NEED_VALUE;
      candump_path = v;
    } else if (!strcmp(o, "--can-iface")) {
      NEED_VALUE;
      can_iface = v;
    } else if (!strcmp(o, "--can-id")) {
      NEED_VALUE;
      can_id = v;
    } else if (!strcmp(o, "--can-ext")) {
      can_ext = 1;
    } else if (!strcmp(o, "--quiet")) {
      quiet = 1;
    } else if (o[0] == '-' && o[1] != '\0') {
      fprintf(stderr, "imest-replay: unknown option '%s' (see --help)\n", o);
      return 2;
    } else if (path == NULL) {
      path = o;
    } else {
      fprintf(stderr, "imest-replay: more than one input file ('%s', '%s')\n", path, o);
      return 2;
    }
  }
  if (!have_np || !have_ls || !have_sigma) {
    fprintf(stderr, "imest-replay: --pole-pairs, --ls and --sigma are required (see --help)\n");
    return 2;
  }
  if (path == NULL) {
    fprintf(stderr, "imest-replay: no input file (see --help)\n");
    return 2;
  }
#ifdef IMEST_HAVE_CANDUMP
  uint32_t can_base = IMEST_CAN_DEFAULT_BASE_ID | (can_ext ? IMEST_CAN_ID_EXT : 0u);
  char can_err[256];
  if (can_id != NULL && imest_can_id_parse(can_id, can_ext, "--can-ext", &can_base, can_err, sizeof can_err)) {
    fprintf(stderr, "imest-replay: --can-id %s\n", can_err);
    return 2;
  }
#endif

  /* Pass 1: time base, clipping, start at rest. */
  csv_reader_t r;
  if (csv_open(&r, path) != 0) {
    fprintf(stderr, "imest-replay: %s\n", r.err);
    csv_close(&r);
    return 1;
  }
  double v[CSV_NEED], t0 = 0, tprev = 0, dtmin = INFINITY, dtmax = 0;
  long n = 0, line_dtmin = 0, line_dtmax = 0, rc;
  clip_t clip_i[3], clip_u[3];
  memset(clip_i, 0, sizeof clip_i);
  memset(clip_u, 0, sizeof clip_u);
  double i_first = 0, th_first = 0, th_step1 = 0, imax = 0;
  while ((rc = csv_next(&r, v)) == 1) {
    if (n == 0) {
      t0 = v[0];
      i_first = fmax(fabs(v[4]), fmax(fabs(v[5]), fabs(v[6])));
      th_first = v[7];
    } else {
      const double dt = v[0] - tprev;
      if (!(dt > 0)) {
        fprintf(stderr, "imest-replay: %s:%ld: t = %.9g does not increase (previous %.9g)\n", path,
                r.line, v[0], tprev);
        csv_close(&r);
        return 1;
      }
      if (dt < dtmin) { dtmin = dt; line_dtmin = r.line; }
      if (dt > dtmax) { dtmax = dt; line_dtmax = r.line; }
    }
    if (n == 1) th_step1 = fabs(v[7] - th_first);
    for (int k = 0; k < 3; ++k) {
      clip_feed(&clip_u[k], v[1 + k]);
      clip_feed(&clip_i[k], v[4 + k]);
      imax = fmax(imax, fabs(v[4 + k]));
    }
    tprev = v[0];
    n++;
  }
  if (rc < 0) {
    fprintf(stderr, "imest-replay: %s\n", r.err);
    csv_close(&r);
    return 1;
  }
  if (n < 2) {
    fprintf(stderr, "imest-replay: %s: %s\n", path,
            n == 0 ? "no data rows after the header" : "only one data row: no sample rate");
    csv_close(&r);
    return 1;
  }
  const double fs = (double)(n - 1) / (tprev - t0);
  if (dtmax * fs > 1.05 || dtmin * fs < 0.95) {
    const long bad = (dtmax * fs - 1.0 > 1.0 - dtmin * fs) ? line_dtmax : line_dtmin;
    fprintf(stderr,
            "imest-replay: %s:%ld: irregular sampling (steps from %.6g to %.6g s, mean %.6g s); "
            "the estimator needs a fixed sample rate\n",
            path, bad, dtmin, dtmax, 1.0 / fs);
    csv_close(&r);
    return 1;
  }
  cfg.fs_hz = (float)fs;

  /* ADC saturation: explicit limits, or plateaus at the extreme. */
  const char *phase = "abc";
  if (i_limit < 0) {
    i_limit = 0;
    for (int k = 0; k < 3; ++k) {
      if (clip_i[k].plateau >= 5) {
        i_limit = clip_i[k].max_abs;
        if (!quiet)
          fprintf(stderr,
                  "imest-replay: i_%c looks clipped at %.6g A (%ld samples on plateaus); "
                  "windows with such samples are marked adc_saturation (--i-limit overrides)\n",
                  phase[k], clip_i[k].max_abs, clip_i[k].plateau);
      }
    }
  }
  if (u_limit < 0) {
    u_limit = 0;
    for (int k = 0; k < 3; ++k) {
      if (clip_u[k].plateau >= 5 && clip_u[k].max_abs > 0) {
        u_limit = clip_u[k].max_abs;
        if (!quiet)
          fprintf(stderr, "imest-replay: u_%c looks clipped at %.6g V (--u-limit overrides)\n",
                  phase[k], clip_u[k].max_abs);
      }
    }
  }
  /* a limit equal to the clipped value: samples at it count as saturated */
  cfg.i_limit_a = (float)i_limit;
  cfg.u_limit_v = (float)u_limit;

  if (from_rest < 0) {
    /* At rest: no current and a still rotor imply a zero history for every
     * filter (no current means no flux and no voltage either). The rotor
     * test uses the first step only: a DOL start accelerates within ms. */
    from_rest = (i_first <= 0.01 * imax && th_step1 * fs < 2.0) ? 1 : 0;
  }
  cfg.start_at_rest = from_rest;

  const char *field = NULL;
  if (imest_config_check(&cfg, &field) != IMEST_OK) {
    fprintf(stderr, "imest-replay: invalid setting for %s (see --help)\n", field);
    csv_close(&r);
    return 2;
  }
  static imest_t est;
  imest_init(&est, &cfg);

  FILE *canlog = NULL;
#ifdef IMEST_HAVE_CANDUMP
  struct imest_candump_port cport;
  imest_can_pub_t can_pub; /* the application publishes what the background returns */
  if (candump_path) {
    canlog = strcmp(candump_path, "-") ? fopen(candump_path, "w") : stdout;
    if (canlog == NULL) {
      fprintf(stderr, "imest-replay: %s: %s\n", candump_path, strerror(errno));
      return 1;
    }
    if (imest_candump_port_open(&cport, canlog, can_iface) != 0) {
      fprintf(stderr, "imest-replay: --can-iface '%s' is not a valid interface name\n", can_iface);
      return 2;
    }
    (void)imest_can_pub_init(&can_pub, &cport.port, can_base); /* can_base was checked */
  }
#else
  (void)can_iface;
  (void)can_id;
  (void)can_ext;
  if (candump_path) {
    fprintf(stderr, "imest-replay: built without the candump port\n");
    return 2;
  }
#endif

  /* Pass 2: every sample through the ISR call, the background per window. */
  if (csv_rewind(&r) != 0) {
    fprintf(stderr, "imest-replay: %s: cannot read the file a second time\n", path);
    csv_close(&r);
    return 1;
  }
  printf("t_end_s,T_R_s,R_S_ohm,E_I,valid,status,seq,K1,K2,pe_k1_rel,pe_k2_rel,"
         "H11,H12,H22,hessian_pd,n_roots,n_admissible,slip_ratio,i_rms_a,used_samples,flags\n");
  long windows = 0, valid = 0;
  long by_status[32] = {0};
  imest_result_t res;
  while ((rc = csv_next(&r, v)) == 1) {
    const float u[3] = {(float)v[1], (float)v[2], (float)v[3]};
    const float i[3] = {(float)v[4], (float)v[5], (float)v[6]};
    double th = fmod(v[7], TWO_PI); /* firmware sees a wrapped encoder angle */
    if (th < 0) th += TWO_PI;
    if (imest_isr_abc(&est, u, i, (float)th)) {
#ifdef IMEST_HAVE_CANDUMP
      if (canlog) imest_candump_port_set_time(&cport, v[0]); /* log time = window end */
#endif
      while (imest_background(&est, &res) == 1) {
#ifdef IMEST_HAVE_CANDUMP
        if (canlog) (void)imest_can_publish(&can_pub, &res);
#endif
        print_row(t0, &res);
        windows++;
        valid += res.valid;
        if (res.status >= 0 && res.status < 32) by_status[res.status]++;
      }
    }
  }
  if (rc < 0) {
    fprintf(stderr, "imest-replay: %s\n", r.err);
    csv_close(&r);
    return 1;
  }
  csv_close(&r);
  /* A last partial window of at least half the length is estimated too, and
   * a record shorter than one window is estimated as one shorter window. */
  const long win_n = lround((double)cfg.window_s * fs), rest = n % win_n;
  const int flush = rest > 0 && (2 * rest >= win_n || n < win_n);
  if (flush && imest_isr_flush(&est)) {
#ifdef IMEST_HAVE_CANDUMP
    if (canlog) imest_candump_port_set_time(&cport, tprev);
#endif
    while (imest_background(&est, &res) == 1) {
#ifdef IMEST_HAVE_CANDUMP
      if (canlog) (void)imest_can_publish(&can_pub, &res);
#endif
      print_row(t0, &res);
      windows++;
      valid += res.valid;
      if (res.status >= 0 && res.status < 32) by_status[res.status]++;
    }
  }
  if (canlog && canlog != stdout) fclose(canlog);
  fflush(stdout);
  if (!quiet) {
    fprintf(stderr, "imest-replay: %ld samples at %.6g Hz, %ld windows (%ld valid)", n, fs,
            windows, valid);
    for (int k = 1; k < 32; ++k)
      if (by_status[k]) fprintf(stderr, ", %ld %s", by_status[k], imest_reason_name(k));
    if (rest && !flush)
      fprintf(stderr, "; last %ld samples (under half a window) not used", rest);
    else if (rest)
      fprintf(stderr, "; last window has %ld samples", rest);
    fprintf(stderr, "%s\n", from_rest ? "; started at rest" : "; warm-up at start");
  }
  if (windows == 0) {
    fprintf(stderr, "imest-replay: no window could be estimated\n");
    return 1;
  }
  return 0;
}
