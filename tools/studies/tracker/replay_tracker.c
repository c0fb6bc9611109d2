/* SPDX-License-Identifier: Apache-2.0 */
/* replay-tracker: the estimator's per-window results (imest-demo's <run>_direct.csv) fed again,
 * open loop, to one rule for the controller's T_R (the library's tracker, imest_tracker.h, or
 * every valid window as it is), with faults injected, and the T_R that rule makes the controller
 * use compared with the simulator's truth. The study tools/studies/tracker/run calls it once per
 * rule, fault and run (README.md there). Host tool (stdio). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "imest/imest.h"
#include "imest/imest_tracker.h"
#include "tool_args.h"

#define PROG "replay-tracker"

typedef struct {
  const char *in;            /* input file, "-" for stdin */
  const char *out;           /* per-window CSV, or NULL */
  int raw;                   /* rule: 0 the tracker, 1 every valid window */
  double tr_nominal_s;       /* <= 0: from the first row's trk_T_R_s */
  double fallback_rel_per_s; /* < 0: the library's default */
  double rate_rel_per_s;     /* < 0: the library's default */
  unsigned long high_every;  /* 0: none */
  double high_rel;
  double invalid_from_s; /* NAN: no invalid stretch */
  double invalid_for_s;
  double score_from_s;
} options_t;

static void usage(FILE *f)
{
  fputs("usage: " PROG " [--rule tracker|raw] [--tr-nominal S] [--fallback-rel-per-s X]\n"
        "                      [--rate-rel-per-s X] [--high-every N] [--high-rel R]\n"
        "                      [--invalid-from S] [--invalid-for S] [--score-from S]\n"
        "                      [-o FILE] FILE\n"
        "\n"
        "Feeds the per-window results of FILE ('-': stdin; a CSV with the columns t_end_s,\n"
        "T_R_s, tr_valid, tr_bound_rel and T_R_true_s, as imest-demo's <run>_direct.csv;\n"
        "other columns are ignored) to one rule for the controller's T_R, open loop, with\n"
        "faults injected, and compares the T_R the rule makes the controller use with\n"
        "T_R_true_s (the simulator's truth).\n"
        "Options take a value as '--opt VALUE' or '--opt=VALUE'.\n"
        "\n"
        "  --rule RULE            tracker (default): imest_tracker_update() on every row, the\n"
        "                         config imest_tracker_config_default() with the options below;\n"
        "                         raw: the latest valid window's T_R as it is (the nominal\n"
        "                         before the first)\n"
        "  --tr-nominal S         the nominal T_R [s] (default: the first row's trk_T_R_s,\n"
        "                         where imest-demo's own tracker is at its nominal)\n"
        "  --fallback-rel-per-s X the tracker's fallback_rel_per_s (default: the library's)\n"
        "  --rate-rel-per-s X     the tracker's rate_rel_per_s (default: the library's)\n"
        "  --high-every N         every Nth valid window (counted from the first valid one,\n"
        "                         after --invalid-from's) is made --high-rel higher, its\n"
        "                         verdict kept valid (a wrong verdict)\n"
        "  --high-rel R           default 0.10\n"
        "  --invalid-from S       the windows with t_end_s in (S, S + --invalid-for] are made\n"
        "                         not valid; their truth is kept (the load goes on)\n"
        "  --invalid-for S        default 300\n"
        "  --score-from S         only windows with t_end_s > S are scored (default 10)\n"
        "  -o, --output FILE      one row per window: t_end_s, T_R_true_s, T_R_in_s,\n"
        "                         tr_valid_in, injected (high / invalid / none), T_R_used_s,\n"
        "                         state (the tracker's; raw for --rule raw), e_rel\n"
        "  -h, --help             this text\n"
        "  --version              the version and licence\n"
        "\n"
        "stdout: one line of key=value pairs: rule, tr_nominal_s, rate_rel_per_s,\n"
        "fallback_rel_per_s, windows (scored), mean_abs_e, max_abs_e, over_1pct (scored\n"
        "windows with |e| > 1 %), injected_high, injected_invalid, accepted, rejected,\n"
        "acquisitions, stale_windows, max_rate_rel_per_s (the largest |change of the used T_R|\n"
        "/ (previous used T_R x dt) over the scored windows, acquisitions left out),\n"
        "max_stale_rate_rel_per_s (the same over the windows in state stale). e = used T_R /\n"
        "T_R_true_s - 1.\n"
        "Exit status: 0 done; 1 the input cannot be read, lacks a column, has a row that is\n"
        "not a number or goes back in time, has no scored window, or the output cannot be\n"
        "written; 2 bad option or argument.\n",
        f);
}

/* A value of a number option, with a range: 0, or TOOL_EXIT_USAGE after a message. */
static int number_in(tool_args_t *a, double lo, double hi, double *out)
{
  if (tool_args_number(a, out)) return TOOL_EXIT_USAGE;
  if (*out < lo || *out > hi) {
    fprintf(stderr, PROG ": %s must be in [%g, %g]\n", a->opt, lo, hi);
    return TOOL_EXIT_USAGE;
  }
  return 0;
}

/* Returns -1 to go on, or the exit code to end with. */
static int parse_options(int argc, char **argv, options_t *o)
{
  memset(o, 0, sizeof *o);
  o->tr_nominal_s = -1.0;
  o->fallback_rel_per_s = -1.0;
  o->rate_rel_per_s = -1.0;
  o->high_rel = 0.10;
  o->invalid_from_s = (double)NAN;
  o->invalid_for_s = 300.0;
  o->score_from_s = 10.0;
  tool_args_t a;
  tool_args_init(&a, PROG, argc, argv);
  tool_arg_kind_t kind;
  double x;
  int rc;
  while ((kind = tool_args_next(&a)) != TOOL_ARG_END) {
    if (kind == TOOL_ARG_OPERAND) {
      if (o->in != NULL) {
        fprintf(stderr, PROG ": one input file only ('%s', see --help)\n", a.operand);
        return TOOL_EXIT_USAGE;
      }
      o->in = a.operand;
    } else if ((rc = tool_args_standard(&a, usage)) >= 0) {
      return rc;
    } else if (tool_args_is(&a, "--rule")) {
      const char *v = tool_args_value(&a);
      if (v == NULL) return TOOL_EXIT_USAGE;
      if (strcmp(v, "tracker") != 0 && strcmp(v, "raw") != 0) {
        fprintf(stderr, PROG ": --rule: '%s' is not tracker or raw\n", v);
        return TOOL_EXIT_USAGE;
      }
      o->raw = strcmp(v, "raw") == 0;
    } else if (tool_args_is(&a, "--tr-nominal")) {
      if ((rc = number_in(&a, 1e-9, 1e9, &o->tr_nominal_s)) != 0) return rc;
    } else if (tool_args_is(&a, "--fallback-rel-per-s")) {
      if ((rc = number_in(&a, 0.0, 1.0, &o->fallback_rel_per_s)) != 0) return rc;
    } else if (tool_args_is(&a, "--rate-rel-per-s")) {
      if ((rc = number_in(&a, 1e-12, 1.0, &o->rate_rel_per_s)) != 0) return rc;
    } else if (tool_args_is(&a, "--high-every")) {
      if ((rc = number_in(&a, 1.0, 1e9, &x)) != 0) return rc;
      if (x != floor(x)) {
        fprintf(stderr, PROG ": --high-every must be a whole number >= 1\n");
        return TOOL_EXIT_USAGE;
      }
      o->high_every = (unsigned long)x;
    } else if (tool_args_is(&a, "--high-rel")) {
      if ((rc = number_in(&a, -0.99, 100.0, &o->high_rel)) != 0) return rc;
    } else if (tool_args_is(&a, "--invalid-from")) {
      if ((rc = number_in(&a, -1e12, 1e12, &o->invalid_from_s)) != 0) return rc;
    } else if (tool_args_is(&a, "--invalid-for")) {
      if ((rc = number_in(&a, 0.0, 1e12, &o->invalid_for_s)) != 0) return rc;
    } else if (tool_args_is(&a, "--score-from")) {
      if ((rc = number_in(&a, -1e12, 1e12, &o->score_from_s)) != 0) return rc;
    } else if (tool_args_is(&a, "-o") || tool_args_is(&a, "--output")) {
      if ((o->out = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else {
      return tool_args_unknown(&a);
    }
  }
  if (o->in == NULL) {
    fprintf(stderr, PROG ": no input file (see --help)\n");
    return TOOL_EXIT_USAGE;
  }
  return -1;
}

/* ------------------------------------------------------------------------- */
/* The input                                                                  */

enum { C_T, C_TR, C_VALID, C_BOUND, C_TRUE, C_TRK, NCOL };
static const char *const k_col[NCOL] = {"t_end_s",      "T_R_s",      "tr_valid",
                                        "tr_bound_rel", "T_R_true_s", "trk_T_R_s"};

typedef struct {
  FILE *f;
  const char *name;
  int idx[NCOL]; /* field index of each column, -1 if absent (only trk_T_R_s may be) */
  long line;
  char buf[8192];
} reader_t;

/* Splits buf at commas in place (no quoting: the demo writes none), the line end cut off; the
   number of fields (at most max). */
static int split(char *buf, char **field, int max)
{
  buf[strcspn(buf, "\r\n")] = '\0';
  int n = 0;
  for (char *p = buf; n < max;) {
    field[n++] = p;
    char *c = strchr(p, ',');
    if (c == NULL) break;
    *c = '\0';
    p = c + 1;
  }
  return n;
}

enum { MAXF = 128 };

static int read_header(reader_t *r)
{
  char *field[MAXF];
  if (fgets(r->buf, sizeof r->buf, r->f) == NULL) {
    fprintf(stderr, PROG ": %s: empty\n", r->name);
    return -1;
  }
  r->line = 1;
  const int n = split(r->buf, field, MAXF);
  for (int c = 0; c < NCOL; ++c) {
    r->idx[c] = -1;
    for (int k = 0; k < n; ++k)
      if (strcmp(field[k], k_col[c]) == 0) r->idx[c] = k;
    if (r->idx[c] < 0 && c != C_TRK) {
      fprintf(stderr, PROG ": %s: no column %s\n", r->name, k_col[c]);
      return -1;
    }
  }
  return 0;
}

/* The next row's numbers (NAN where trk_T_R_s is absent): 1, 0 at the end, -1 after a message. */
static int read_row(reader_t *r, double v[NCOL])
{
  char *field[MAXF];
  do {
    if (fgets(r->buf, sizeof r->buf, r->f) == NULL) return 0;
    r->line++;
  } while (r->buf[0] == '\n' || r->buf[0] == '\r' || r->buf[0] == '#');
  const int n = split(r->buf, field, MAXF);
  for (int c = 0; c < NCOL; ++c) {
    v[c] = (double)NAN;
    if (r->idx[c] < 0) continue;
    if (r->idx[c] >= n) {
      fprintf(stderr, PROG ": %s:%ld: too few fields (no %s)\n", r->name, r->line, k_col[c]);
      return -1;
    }
    char *end;
    v[c] = strtod(field[r->idx[c]], &end);
    if (end == field[r->idx[c]] || *end != '\0') {
      fprintf(stderr, PROG ": %s:%ld: %s '%s' is not a number\n", r->name, r->line, k_col[c],
              field[r->idx[c]]);
      return -1;
    }
  }
  return 1;
}

/* ------------------------------------------------------------------------- */
/* The replay                                                                 */

typedef struct {
  unsigned long windows, over_1pct, injected_high, injected_invalid, acquisitions, stale_windows;
  unsigned long accepted, rejected; /* the tracker's counters; raw: the valid windows taken, 0 */
  double sum_abs_e, max_abs_e, max_rate, max_stale_rate;
} stats_t;

typedef struct {
  const options_t *o;
  imest_tracker_t trk;
  imest_tracker_config_t cfg;
  double used_s;       /* the T_R the controller uses */
  double prev_t_s;     /* the previous row's t_end_s */
  unsigned long valid; /* valid windows so far (after the invalid stretch) */
  int rows;
  FILE *out;
  stats_t s;
} replay_t;

/* One row: faults injected, fed to the rule, scored. 0, or -1 after a message. */
static int step(replay_t *p, const reader_t *rd, const double v[NCOL])
{
  const options_t *o = p->o;
  const double t = v[C_T];
  if (!isfinite(t) || (p->rows > 0 && t < p->prev_t_s)) {
    fprintf(stderr, PROG ": %s:%ld: t_end_s %g is not after the previous row's\n", rd->name, rd->line, t);
    return -1;
  }
  imest_result_t r;
  memset(&r, 0, sizeof r);
  r.t_end_s = t;
  r.tr_s = v[C_TR];
  r.tr_valid = v[C_VALID] != 0.0;
  r.tr_bound_rel = v[C_BOUND];
  r.tr_reason = r.tr_valid ? IMEST_REASON_NONE : IMEST_REASON_ZERO_SLIP;
  const char *injected = "none";
  if (r.tr_valid && isfinite(o->invalid_from_s) && t > o->invalid_from_s &&
      t <= o->invalid_from_s + o->invalid_for_s) {
    r.tr_valid = 0;
    r.tr_reason = IMEST_REASON_ZERO_SLIP;
    injected = "invalid";
    p->s.injected_invalid++;
  }
  if (r.tr_valid && o->high_every > 0ul && ++p->valid % o->high_every == 0ul) {
    r.tr_s *= 1.0 + o->high_rel;
    injected = "high";
    p->s.injected_high++;
  }

  const double dt = p->rows > 0 ? t - p->prev_t_s : 0.0;
  const double before = p->used_s;
  int acquired = 0;
  if (o->raw) {
    if (r.tr_valid && isfinite(r.tr_s) && r.tr_s > 0.0) {
      p->used_s = r.tr_s;
      p->s.accepted++;
    }
  } else {
    const int prev_state = p->trk.state;
    const double prev_age = (double)p->trk.age_s;
    const int acc = imest_tracker_update(&p->trk, &r);
    if (acc < 0) {
      fprintf(stderr, PROG ": %s:%ld: the tracker refused the row (%d)\n", rd->name, rd->line, acc);
      return -1;
    }
    /* an acceptance while acquiring (imest_tracker_update(): none accepted yet, or the last one
       more than stale_after_s old) is a jump with acquire_jump, not a rate-limited step */
    acquired = acc == 1 && (prev_state == IMEST_TRACKER_NOMINAL || prev_state == IMEST_TRACKER_STALE ||
                            prev_age + dt > (double)p->cfg.stale_after_s);
    if (acquired) p->s.acquisitions++;
    p->s.accepted = p->trk.accepted;
    p->s.rejected = p->trk.rejected;
    p->used_s = (double)p->trk.tr_s;
  }
  p->prev_t_s = t;
  p->rows++;

  const double e = p->used_s / v[C_TRUE] - 1.0;
  const int stale = !o->raw && p->trk.state == IMEST_TRACKER_STALE;
  if (t > o->score_from_s && isfinite(e)) {
    stats_t *s = &p->s;
    s->windows++;
    s->sum_abs_e += fabs(e);
    if (fabs(e) > s->max_abs_e) s->max_abs_e = fabs(e);
    if (fabs(e) > 0.01) s->over_1pct++;
    if (stale) s->stale_windows++;
    if (dt > 0.0 && !acquired) {
      const double rate = fabs(p->used_s - before) / (before * dt);
      if (rate > s->max_rate) s->max_rate = rate;
      if (stale && rate > s->max_stale_rate) s->max_stale_rate = rate;
    }
  }
  if (p->out)
    fprintf(p->out, "%.6f,%.9g,%.9g,%d,%s,%.9g,%s,%.6g\n", t, v[C_TRUE], r.tr_s, r.tr_valid, injected,
            p->used_s, o->raw ? "raw" : imest_tracker_state_name(p->trk.state), e);
  return 0;
}

/* The tracker's config and the starting T_R, once the nominal is known. */
static int start(replay_t *p, double nominal_s)
{
  const options_t *o = p->o;
  imest_tracker_config_default(&p->cfg, (float)nominal_s);
  if (o->fallback_rel_per_s >= 0.0) p->cfg.fallback_rel_per_s = (float)o->fallback_rel_per_s;
  if (o->rate_rel_per_s >= 0.0) p->cfg.rate_rel_per_s = (float)o->rate_rel_per_s;
  const char *field = NULL;
  if (imest_tracker_config_check(&p->cfg, &field) != IMEST_OK ||
      imest_tracker_init(&p->trk, &p->cfg) != IMEST_OK) {
    fprintf(stderr, PROG ": the tracker's config is out of range (%s)\n", field ? field : "?");
    return -1;
  }
  p->used_s = o->raw ? nominal_s : (double)p->trk.tr_s;
  return 0;
}

/* Every row of the input through the rule: 0, or -1 after a message. */
static int replay_rows(replay_t *p, reader_t *rd)
{
  const options_t *o = p->o;
  double v[NCOL];
  int got;
  while ((got = read_row(rd, v)) == 1) {
    if (p->rows == 0) {
      const double nominal = o->tr_nominal_s > 0.0 ? o->tr_nominal_s : v[C_TRK];
      if (!(isfinite(nominal) && nominal > 0.0)) {
        fprintf(stderr, PROG ": %s: no --tr-nominal and no trk_T_R_s in the first row\n", rd->name);
        return -1;
      }
      if (start(p, nominal) != 0) return -1;
    }
    if (step(p, rd, v) != 0) return -1;
  }
  if (got < 0) return -1;
  if (p->s.windows == 0) {
    fprintf(stderr, PROG ": %s: no window after t = %g s to score\n", rd->name, o->score_from_s);
    return -1;
  }
  return 0;
}

static void print_summary(const replay_t *p)
{
  const stats_t *s = &p->s;
  printf("rule=%s tr_nominal_s=%.9g", p->o->raw ? "raw" : "tracker", (double)p->cfg.tr_nominal_s);
  if (!p->o->raw)
    printf(" rate_rel_per_s=%.6g fallback_rel_per_s=%.6g", (double)p->cfg.rate_rel_per_s,
           (double)p->cfg.fallback_rel_per_s);
  printf(" windows=%lu mean_abs_e=%.6g max_abs_e=%.6g over_1pct=%lu injected_high=%lu injected_invalid=%lu "
         "accepted=%lu rejected=%lu acquisitions=%lu stale_windows=%lu max_rate_rel_per_s=%.6g "
         "max_stale_rate_rel_per_s=%.6g\n",
         s->windows, s->sum_abs_e / (double)s->windows, s->max_abs_e, s->over_1pct, s->injected_high,
         s->injected_invalid, s->accepted, s->rejected, s->acquisitions, s->stale_windows, s->max_rate,
         s->max_stale_rate);
}

static int run(const options_t *o)
{
  if (o->in == NULL) return TOOL_EXIT_USAGE; /* parse_options() said so */
  static reader_t rd;                        /* its line buffer is large */
  rd.name = o->in;
  rd.f = strcmp(o->in, "-") == 0 ? stdin : fopen(o->in, "r");
  if (rd.f == NULL) {
    fprintf(stderr, PROG ": %s: cannot open\n", o->in);
    return TOOL_EXIT_DATA;
  }
  replay_t p;
  memset(&p, 0, sizeof p);
  p.o = o;
  int ok = read_header(&rd) == 0;
  if (ok && o->out) {
    if ((p.out = fopen(o->out, "w")) == NULL) {
      fprintf(stderr, PROG ": %s: cannot write\n", o->out);
      ok = 0;
    } else {
      fprintf(p.out, "t_end_s,T_R_true_s,T_R_in_s,tr_valid_in,injected,T_R_used_s,state,e_rel\n");
    }
  }
  if (ok) ok = replay_rows(&p, &rd) == 0;
  if (p.out && fclose(p.out) != 0 && ok) {
    fprintf(stderr, PROG ": %s: write error\n", o->out);
    ok = 0;
  }
  if (rd.f != stdin) (void)fclose(rd.f);
  if (!ok) return TOOL_EXIT_DATA;
  print_summary(&p);
  return TOOL_EXIT_OK;
}

int main(int argc, char **argv)
{
  options_t o;
  const int rc = parse_options(argc, argv, &o);
  if (rc >= 0) return rc;
  return run(&o);
}
