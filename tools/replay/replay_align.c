/* SPDX-License-Identifier: Apache-2.0 */
/* imest-replay's alignment check (replay_align.h).
 *
 * Why R_S against the frequency, and not the residual: a voltage one row off
 * is, at the fundamental, a phase error of omega_e T, which the fit absorbs
 * into its parameters: R_S moves by about omega_e T X (X the motor's
 * reactance, itself about proportional to omega_e) and T_R by a few per cent,
 * while the residual E_I hardly tells (on the simulated 4 kW drive E_I even
 * falls steadily as the voltage is delayed, through the right alignment and
 * beyond). At one operating point the shift cannot be told from a different
 * R_S at all. Across operating points it can: a resistance does not depend on
 * the frequency, so the alignment under which the R_S estimates do not grow or
 * fall with omega_e^2 is the right one.
 *
 * The rule. Three passes (the voltage columns shifted by -1, 0, +1 rows
 * against the currents and the angle, rows 1 .. n-2 in each, so the windows
 * are the same). Taking part: the windows whose R_S is determined (relative
 * bound <= 0.5) in one pass at least. Each window is weighted by how much a
 * shift moves its R_S, g = (R_S(+1) - R_S(-1))^2: where the shift matters,
 * the data can tell (at low frequency or light load they cannot, and there
 * R_S carries the estimator's own bias, the same in every pass). Per pass the
 * weighted spread (standard deviation) of R_S across the windows. A shift is
 * reported when
 *   - the record spans operating points: omega_e^2 (from the current vector's
 *     rotation over the window) varies by a factor 2 or more over at least 4
 *     windows (at one operating point every window moves alike), and
 *   - the shift's spread is below half the record's as given, and below the
 *     other shift's, and
 *   - it matters: the median change of T_R exceeds the median tr_bound_rel.
 * Measured on ramps through the operating range (test/tools/test_replay_align.py):
 * the right alignment is 7 times (duty input, 4 kW drive with 2 us dead time)
 * to 140 times (measured phase voltages, the paper's motor) steadier than
 * either shift, so a factor 2 leaves a margin both ways. A real R_S trend of
 * other origin (a heating that follows a speed ramp, an uncompensated dead
 * time) has no reason to vanish under a shift of exactly one row, hence
 * "probably" in the note. */
#include "replay_align.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drive_loop.h"
#include "tool_args.h"

static const char *const k_prog = "imest-replay";

#define ALIGN_RS_BOUND_MAX 0.5 /* R_S determined well enough to take part (relative) */
#define ALIGN_MIN_WINDOWS  4
#define ALIGN_SPAN_MIN     2.0 /* max / min omega_e^2 */
#define ALIGN_SPREAD_KEEP  0.5 /* the shift at least halves R_S's spread across the windows */

typedef struct {
  double tr, rs, tr_bound, rs_bound, w2; /* w2: omega_e^2 [rad^2/s^2] */
} align_win_t;

typedef struct {
  align_win_t *w;
  long n, cap;
  double phi, prev[2]; /* the current vector's rotation in the window so far */
  long samples;
  int have_prev;
  double fs;
} align_pass_t;

static void on_window(void *ctx, const imest_result_t *r)
{
  align_pass_t *p = (align_pass_t *)ctx;
  if (p->n < p->cap) {
    const double we = p->samples > 0 ? p->phi * p->fs / (double)p->samples : 0.0;
    align_win_t *w = &p->w[p->n++];
    w->tr = r->tr_s;
    w->rs = r->rs_ohm;
    w->tr_bound = r->tr_bound_rel;
    w->rs_bound = r->rs_bound_rel;
    w->w2 = we * we;
  }
  p->phi = 0.0;
  p->samples = 0;
}

static void track_current(align_pass_t *p, const double i[3])
{
  const double ia = i[0] - 0.5 * (i[1] + i[2]), ib = 0.8660254037844386 * (i[1] - i[2]);
  if (p->have_prev) p->phi += atan2(p->prev[0] * ib - p->prev[1] * ia, p->prev[0] * ia + p->prev[1] * ib);
  p->prev[0] = ia;
  p->prev[1] = ib;
  p->have_prev = 1;
  p->samples++;
}

/* The three passes in one read of the file: row k's currents and angle with
   row k+shift's voltage columns, shift -1, 0, +1, for the rows 1 .. n-2 (the
   same rows, so the same windows, in every pass). */
static int run_passes(csv_reader_t *r, const replay_opts_t *o, const imest_config_t *cfg, align_pass_t p[3])
{
  static imest_t est[3];
  drive_t d[3];
  if (csv_rewind(r) != 0) return -1;
  for (int s = 0; s < 3; ++s) {
    if (imest_init(&est[s], cfg) != IMEST_OK) return -1;
    drive_init(&d[s], &est[s], on_window, &p[s]);
  }
  replay_sample_t row[3]; /* rows k-1, k, k+1 */
  memset(row, 0, sizeof row);
  double v[CSV_MAX_NEED];
  long got = 0;
  int rc;
  while ((rc = csv_next(r, v)) == 1) {
    row[0] = row[1];
    row[1] = row[2];
    replay_decode(o->voltage, v, &row[2]);
    if (++got < 3) continue;
    const replay_sample_t *x = &row[1];
    for (int s = 0; s < 3; ++s) {
      const replay_sample_t *u = &row[s];
      track_current(&p[s], x->i);
      const int n = o->voltage == REPLAY_VOLTAGE_DUTY ? drive_sample_duty(&d[s], u->d, u->vdc, x->i, x->theta)
                                                      : drive_sample(&d[s], u->u, x->i, x->theta);
      if (n < 0) return -1;
    }
  }
  return rc < 0 ? -1 : 0;
}

/* Weighted mean and standard deviation of y over n windows. */
static double spread_of(const double *y, const double *wt, int n, double *mean)
{
  double sw = 0.0, sy = 0.0;
  for (int k = 0; k < n; ++k) {
    sw += wt[k];
    sy += wt[k] * y[k];
  }
  *mean = sy / sw;
  double ss = 0.0;
  for (int k = 0; k < n; ++k) ss += wt[k] * (y[k] - *mean) * (y[k] - *mean);
  return sqrt(ss / sw);
}

static int cmp_double(const void *a, const void *b)
{
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double median(double *v, int n)
{
  qsort(v, (size_t)n, sizeof *v, cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int finite_win(const align_win_t *w)
{
  return isfinite(w->tr) && isfinite(w->rs) && w->w2 > 0.0;
}

/* The decision from the three passes (index 0: shift -1, 1: as given, 2: +1). */
static void decide(align_pass_t p[3], replay_align_t *out)
{
  long n = p[0].n;
  for (int k = 1; k < 3; ++k) n = p[k].n < n ? p[k].n : n;
  double *buf = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1) * 5u);
  char *sel = calloc((size_t)(n > 0 ? n : 1), 1);
  if (buf == NULL || sel == NULL) {
    free(buf);
    free(sel);
    out->why = "out of memory";
    return;
  }
  double *wt = buf, *y[3] = {buf + n, buf + 2 * n, buf + 3 * n}, *t = buf + 4 * n;
  /* taking part: R_S determined (relative bound within ALIGN_RS_BOUND_MAX) in one pass at
     least (a relative bound grows where a shift drives R_S towards 0) */
  int m = 0;
  double wmin = HUGE_VAL, wmax = 0.0;
  for (long k = 0; k < n; ++k) {
    const align_win_t *a = &p[0].w[k], *g = &p[1].w[k], *c = &p[2].w[k];
    if (!finite_win(a) || !finite_win(g) || !finite_win(c)) continue;
    const double ub = fmin(fmin(a->rs_bound, g->rs_bound), c->rs_bound);
    if (!(ub <= ALIGN_RS_BOUND_MAX) || !(ub > 0.0)) continue;
    wt[m] = (c->rs - a->rs) * (c->rs - a->rs);
    y[0][m] = a->rs;
    y[1][m] = g->rs;
    y[2][m] = c->rs;
    t[m] = g->tr_bound;
    wmin = fmin(wmin, g->w2);
    wmax = fmax(wmax, g->w2);
    sel[k] = 1;
    m++;
  }
  out->windows = m;
  if (m < ALIGN_MIN_WINDOWS) {
    out->why = "too few windows with a determined R_S";
  } else if (!(wmax >= ALIGN_SPAN_MIN * wmin)) {
    out->why = "one operating point: a one-row shift cannot be told from a different R_S";
  } else {
    for (int s = 0; s < 3; ++s) out->spread[s] = spread_of(y[s], wt, m, &out->rs_mean[s]);
    const int best = out->spread[0] < out->spread[2] ? 0 : 2;
    out->tr_bound = median(t, m);
    if (!(out->spread[best] < ALIGN_SPREAD_KEEP * out->spread[1])) {
      out->why = ""; /* as given fits best, or no shift clearly better */
    } else {
      int q = 0;
      for (long k = 0; k < n; ++k)
        if (sel[k]) t[q++] = fabs(p[best].w[k].tr / p[1].w[k].tr - 1.0);
      out->tr_change = median(t, q);
      if (out->tr_change > out->tr_bound)
        out->shift = best - 1;
      else
        out->why = "a shift would make R_S more constant but changes T_R only within its bound";
    }
  }
  free(buf);
  free(sel);
}

/* The option that would fix the record, written into fix[]. */
static void remedy(const replay_opts_t *o, const imest_config_t *cfg, double fs, int shift, char *fix,
                   size_t n)
{
  const double T = 1.0 / fs;
  const double ud = (double)cfg->u_delay_s + (shift > 0 ? T : -T);
  const char *cols = o->voltage == REPLAY_VOLTAGE_DUTY ? "duty and v_dc" : "voltage";
  if (o->voltage == REPLAY_VOLTAGE_DUTY && shift > 0 && cfg->pwm_timing == IMEST_PWM_NEXT_PERIOD &&
      cfg->u_delay_s == 0.0f)
    snprintf(fix, n, "--pwm-timing last (row k's duties applied during [t_k-1, t_k))");
  else if (o->voltage == REPLAY_VOLTAGE_DUTY && shift < 0 && cfg->pwm_timing == IMEST_PWM_LAST_PERIOD &&
           cfg->u_delay_s == 0.0f)
    snprintf(fix, n, "--pwm-timing next (row k's duties applied during [t_k, t_k+1))");
  else if (fabs(ud) <= T * (1.0 + 1e-6))
    snprintf(
        fix, n,
        "--u-delay %.6g (the voltage %s the currents by one more sample), or the %s columns moved %s one row",
        ud, shift > 0 ? "lags" : "leads", cols, shift > 0 ? "up" : "down");
  else
    snprintf(fix, n, "the %s columns moved %s one row (--u-delay would exceed 1/fs)", cols,
             shift > 0 ? "up" : "down");
}

int replay_align_check(csv_reader_t *r, const replay_opts_t *o, const replay_scan_t *s,
                       const imest_config_t *cfg, replay_align_t *out)
{
  memset(out, 0, sizeof *out);
  out->why = "";
  if (s->n_gaps > 0) {
    out->why = "the record has gaps";
    return -1;
  }
  const long win_n = lround((double)cfg->window_s * s->fs);
  const long cap = (win_n > 0 ? s->n / win_n : 0) + 2;
  align_pass_t p[3];
  memset(p, 0, sizeof p);
  int rc = -1;
  for (int k = 0; k < 3; ++k) {
    p[k].w = calloc((size_t)cap, sizeof(align_win_t));
    p[k].cap = cap;
    p[k].fs = s->fs;
    if (p[k].w == NULL) goto done;
  }
  if (run_passes(r, o, cfg, p) != 0) {
    fprintf(stderr, "%s: %s: alignment check: cannot read the file again\n", k_prog, r->name);
    rc = TOOL_EXIT_DATA;
    goto done;
  }
  decide(p, out);
  if (out->shift != 0) {
    char fix[192];
    remedy(o, cfg, s->fs, out->shift, fix, sizeof fix);
    const int i = out->shift + 1;
    fprintf(stderr,
            "%s: note: alignment: the %s columns probably sit one row %s against the currents and the "
            "angle: as given, R_S varies with the operating point (%.3g ohm rms across %d windows, mean "
            "%.4g ohm); with row k's voltage taken from row k%+d it is %.2g times as steady (%.3g ohm rms, "
            "mean %.4g ohm) and T_R changes by %.2g %% (its bound %.2g %%). Nothing was changed; if the "
            "firmware confirms it, fix it with %s (docs/feeding-logs.md, section 3, alignment check; "
            "--no-align-check "
            "skips this check)\n",
            k_prog, o->voltage == REPLAY_VOLTAGE_DUTY ? "duty and v_dc" : "voltage",
            out->shift < 0 ? "early" : "late", out->spread[1], out->windows, out->rs_mean[1], out->shift,
            out->spread[1] / out->spread[i], out->spread[i], out->rs_mean[i], 100.0 * out->tr_change,
            100.0 * out->tr_bound, fix);
  }
done:
  for (int k = 0; k < 3; ++k) free(p[k].w);
  return rc;
}
