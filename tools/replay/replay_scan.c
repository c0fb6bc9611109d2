/* SPDX-License-Identifier: Apache-2.0 */
#include "replay_scan.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tool_args.h"

#define PI                3.14159265358979323846
/* Below this rate no motor log is usable (a 64-sample window, the supply
 * frequency): a lower rate from t means t is not in seconds. */
#define FS_IMPLAUSIBLE_HZ 100.0

static const char *const k_prog = "imest-replay";

static double wrap_pi(double x)
{
  return x - 2.0 * PI * floor((x + PI) / (2.0 * PI));
}

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
    if (c->run == 5)
      c->plateau += 5;
    else if (c->run > 5)
      c->plateau++;
  } else if (a == c->max_abs) {
    c->run = 1;
  } else {
    c->run = 0;
  }
  c->prev = x;
}

const csv_layout_t *replay_layout(replay_voltage_t voltage)
{
  return voltage == REPLAY_VOLTAGE_DUTY ? &CSV_DUTY : &CSV_PHASE;
}

void replay_decode(replay_voltage_t voltage, const double *v, replay_sample_t *x)
{
  x->t = v[0];
  if (voltage == REPLAY_VOLTAGE_DUTY) {
    /* the voltage a drive commands, without the zero sequence its neutral
     * does not see (for the scan's checks; the library forms its own) */
    const double mean = (v[1] + v[2] + v[3]) / 3.0;
    for (int k = 0; k < 3; ++k) {
      x->d[k] = v[1 + k];
      x->u[k] = v[4] * (v[1 + k] - mean);
      x->i[k] = v[5 + k];
    }
    x->vdc = v[4];
    x->theta = v[8];
  } else {
    for (int k = 0; k < 3; ++k) {
      x->u[k] = v[1 + k];
      x->i[k] = v[4 + k];
      x->d[k] = 0.0;
    }
    x->vdc = 0.0;
    x->theta = v[7];
  }
}

/* What the time column and the conventions look like over the whole file. */
typedef struct {
  double tprev, qprev;   /* previous t and its rounding bound */
  double dt_min, dt_max; /* raw steps */
  long line_min, line_max;
  double lo, hi; /* steps widened / narrowed by their rounding */
  long line_lo, line_hi;
  double t_hi[2];            /* t before and after the step at line_hi */
  double step;               /* the nominal step when gaps are left out (0: the record's mean) */
  long repeats, line_repeat; /* steps of exactly 0 */
  double t_repeat;
  double q_repeat, q_worst;   /* rounding of t at the first repeat, at the widest step */
  int all_unit_steps;         /* every step exactly 1 (a sample index) */
  double p_sum, s_sum;        /* sum of u.i, sum of |u||i| */
  double field_rad, mech_rad; /* net rotation of the current vector, of theta */
  double i_prev[2];
  double th_prev, th_min, th_max;
  long th_wraps;                /* steps beyond +-pi: the angle wraps somewhere */
  double d_min, d_max, vdc_min; /* duty input: the duties' and the bus's range */
  long line_d_min, line_d_max, line_vdc_min;
} tally_t;

static void tally_duty(tally_t *y, const csv_reader_t *r, const replay_sample_t *x)
{
  for (int k = 0; k < 3; ++k) {
    if (x->d[k] < y->d_min) {
      y->d_min = x->d[k];
      y->line_d_min = r->line;
    }
    if (x->d[k] > y->d_max) {
      y->d_max = x->d[k];
      y->line_d_max = r->line;
    }
  }
  if (x->vdc < y->vdc_min) {
    y->vdc_min = x->vdc;
    y->line_vdc_min = r->line;
  }
}

static void tally_row(tally_t *y, replay_scan_t *s, const csv_reader_t *r, const replay_sample_t *x,
                      replay_voltage_t voltage)
{
  /* power-invariant alpha/beta of the currents: the field's direction */
  const double ia = (2.0 * x->i[0] - x->i[1] - x->i[2]) / 3.0, ib = (x->i[1] - x->i[2]) / sqrt(3.0);
  const double u2 = x->u[0] * x->u[0] + x->u[1] * x->u[1] + x->u[2] * x->u[2];
  const double i2 = x->i[0] * x->i[0] + x->i[1] * x->i[1] + x->i[2] * x->i[2];
  y->p_sum += x->u[0] * x->i[0] + x->u[1] * x->i[1] + x->u[2] * x->i[2];
  y->s_sum += sqrt(u2 * i2);
  if (s->n == 0) {
    s->t0 = x->t;
    s->i_first = fmax(fabs(x->i[0]), fmax(fabs(x->i[1]), fabs(x->i[2])));
    y->th_min = y->th_max = x->theta;
  } else {
    const double dt = x->t - y->tprev, q = r->t_round + y->qprev;
    if (dt < y->dt_min) {
      y->dt_min = dt;
      y->line_min = r->line;
    }
    if (dt > y->dt_max) {
      y->dt_max = dt;
      y->line_max = r->line;
    }
    if (dt + q < y->lo) {
      y->lo = dt + q;
      y->line_lo = r->line;
    }
    if (dt - q > y->hi) {
      y->hi = dt - q;
      y->line_hi = r->line;
      y->t_hi[0] = y->tprev;
      y->t_hi[1] = x->t;
    }
    if (dt == y->dt_max) y->q_worst = r->t_round;
    if (dt == 0.0 && y->repeats++ == 0) {
      y->line_repeat = r->line;
      y->t_repeat = x->t;
      y->q_repeat = r->t_round;
    }
    if (dt != 1.0) y->all_unit_steps = 0;
    const double dth = x->theta - y->th_prev;
    if (fabs(dth) > PI) y->th_wraps++;
    y->mech_rad += wrap_pi(dth);
    if (s->n == 1) s->th_step1 = fabs(wrap_pi(dth));
    y->field_rad += atan2(y->i_prev[0] * ib - y->i_prev[1] * ia, y->i_prev[0] * ia + y->i_prev[1] * ib);
    y->th_min = fmin(y->th_min, x->theta);
    y->th_max = fmax(y->th_max, x->theta);
  }
  for (int k = 0; k < 3; ++k) {
    /* a voltage formed from duty cycles has no ADC that could clip */
    if (voltage == REPLAY_VOLTAGE_PHASE) clip_feed(&s->clip_u[k], x->u[k]);
    clip_feed(&s->clip_i[k], x->i[k]);
    s->i_max = fmax(s->i_max, fabs(x->i[k]));
  }
  if (voltage == REPLAY_VOLTAGE_DUTY) tally_duty(y, r, x);
  y->i_prev[0] = ia;
  y->i_prev[1] = ib;
  y->th_prev = x->theta;
  y->tprev = x->t;
  y->qprev = r->t_round;
  s->n++;
}

/* Decimals a rounding bound stands for (5e-5 -> 4). */
static int decimals(double q)
{
  return q > 0 ? (int)lround(-log10(2.0 * q)) : 0;
}

/* t is not in seconds, or not a time at all: say which, and what to do. */
static int bad_unit(const char *name, const tally_t *y, double step)
{
  if (y->all_unit_steps) {
    fprintf(stderr,
            "%s: %s: t counts samples (every step is exactly 1), it is not a time in seconds. "
            "Give the drive's sample rate with --fs HZ (t then only orders the rows), or write "
            "t in seconds.\n",
            k_prog, name);
    return TOOL_EXIT_DATA;
  }
  fprintf(stderr,
          "%s: %s: t steps by %.6g on average: %.6g Hz if t is in seconds, too slow for "
          "any motor log (the estimator needs at least several hundred Hz).",
          k_prog, name, step, 1.0 / step);
  if (1e3 / step >= FS_IMPLAUSIBLE_HZ && 1e3 / step <= 1e6)
    fprintf(stderr, " If t is in milliseconds (%.6g Hz), divide it by 1000 or give --fs %.6g.", 1e3 / step,
            1e3 / step);
  else if (1e6 / step >= FS_IMPLAUSIBLE_HZ && 1e6 / step <= 1e6)
    fprintf(stderr, " If t is in microseconds (%.6g Hz), divide it by 1e6 or give --fs %.6g.", 1e6 / step,
            1e6 / step);
  fprintf(stderr, " If t is a sample index or a timer count, give --fs with the drive's sample "
                  "rate.\n");
  return TOOL_EXIT_DATA;
}

/* The step of t: the record's mean, or without its gaps (--gaps restart). */
static double mean_step(const tally_t *y, const replay_scan_t *s)
{
  return y->step > 0 ? y->step : (s->t_last - s->t0) / (double)(s->n - 1);
}

/* Without --fs: t in seconds, increasing, steps fixed but for its rounding. */
static int time_base_from_t(const char *name, const tally_t *y, replay_scan_t *s, int quiet)
{
  const double step = mean_step(y, s);
  if (y->repeats) {
    if (2.0 * y->q_repeat >= 0.5 * step)
      fprintf(stderr,
              "%s: %s:%ld: t = %.9g repeats the previous row's t: t is printed with %d decimals, "
              "too few for its mean step of %.6g s (%.6g Hz). Write t with more decimals, or give "
              "--fs HZ (t then only orders the rows).\n",
              k_prog, name, y->line_repeat, y->t_repeat, decimals(y->q_repeat), step, 1.0 / step);
    else
      fprintf(stderr,
              "%s: %s:%ld: t = %.9g repeats the previous row's t (%ld times in the file): a duplicated "
              "row? If the drive did sample at a fixed rate, give --fs HZ (t then only orders "
              "the rows).\n",
              k_prog, name, y->line_repeat, y->t_repeat, y->repeats);
    return TOOL_EXIT_DATA;
  }
  if (1.0 / step < FS_IMPLAUSIBLE_HZ || y->all_unit_steps) return bad_unit(name, y, step);
  if (1.0 / step > 1e6) {
    fprintf(stderr,
            "%s: %s: t steps by %.6g s on average, %.6g Hz: is t in seconds? Write t in "
            "seconds or give --fs HZ.\n",
            k_prog, name, step, 1.0 / step);
    return TOOL_EXIT_DATA;
  }
  if (y->hi > 1.05 * step || y->lo < 0.95 * step) {
    const int gap = y->hi - 1.05 * step > 0.95 * step - y->lo;
    const long line = gap ? y->line_hi : y->line_lo;
    const double dt = gap ? y->dt_max : y->dt_min;
    const int missing = gap && dt > 1.5 * step;
    fprintf(stderr,
            "%s: %s:%ld: irregular sampling: a step of %.6g s where the record's mean step is "
            "%.6g s (%.6g Hz)%s. The estimator needs a fixed sample rate. If the drive did sample "
            "at a fixed rate and only t is inaccurate, give --fs HZ.",
            k_prog, name, line, dt, step, 1.0 / step, missing ? ": samples are missing there" : "");
    if (missing)
      fprintf(stderr,
              " t = %.9g after %.9g: about %ld sample%s missing; --gaps restart restarts the "
              "estimator at each such gap instead of refusing the file.",
              y->t_hi[1], y->t_hi[0], lround(dt / step) - 1, lround(dt / step) - 1 == 1 ? "" : "s");
    fprintf(stderr, "\n");
    return TOOL_EXIT_DATA;
  }
  s->fs = s->fs_t = 1.0 / step;
  s->t_unit_s = 1.0;
  s->t_rounded = y->dt_max > 1.05 * step || y->dt_min < 0.95 * step;
  if (s->t_rounded && !quiet)
    fprintf(stderr,
            "%s: note: t is printed with %d decimals; its steps (%.6g .. %.6g s) are read as the "
            "rounding of a fixed %.6g s step (%.6g Hz from the record's span)\n",
            k_prog, decimals(y->q_worst), y->dt_min, y->dt_max, step, s->fs);
  return -1;
}

/* --fs against a t in seconds: a step that disagrees by more than 1 % is named. */
static void fs_against_seconds(const char *what, double step, double fs, int quiet)
{
  if (quiet || fabs(step * fs - 1.0) <= 0.01) return;
  fprintf(stderr, "%s: note: t (%s) steps by %.6g s, %.6g Hz, where --fs says %.6g Hz (a step of %.6g s)",
          k_prog, what, step, 1.0 / step, fs, 1.0 / fs);
  const double p10 = log10(step * fs);
  if (fabs(p10 - round(p10)) < log10(1.01) && round(p10) != 0.0)
    fprintf(stderr, ": the step is 1/fs x %.0e, is t's unit right?", pow(10.0, round(p10)));
  fprintf(stderr, "; using --fs\n");
}

/* With --fs: t only orders the rows; its unit follows from its mean step, or
 * from its header. What that unit looks like is said, and a t in seconds that
 * disagrees with --fs is named. */
static int time_base_given(const csv_reader_t *r, const tally_t *y, replay_scan_t *s, double fs, int quiet)
{
  const double step = mean_step(y, s);
  const char *name = r->name;
  s->fs = fs;
  if (y->dt_min < 0) {
    /* a timer that wrapped, or no time at all: the output counts from the first row */
    if (!quiet)
      fprintf(stderr,
              "%s: note: %s:%ld: t decreases; with --fs it is not used, output times "
              "count from the first row%s\n",
              k_prog, name, y->line_min,
              s->n_gaps ? " (and gaps cannot be found: --gaps restart does nothing)" : "");
    s->t_unit_s = 0.0;
    s->n_gaps = 0;
    s->gap_step = 0.0;
    return -1;
  }
  s->fs_t = step > 0 ? 1.0 / step : 0.0;
  if (r->t_unit[0] != '\0' && step > 0) {
    /* the header says what t is in (converted to s) */
    char what[48];
    snprintf(what, sizeof what, "in %s by its header", r->t_unit);
    fs_against_seconds(what, step, fs, quiet);
    s->t_unit_s = 1.0;
  } else {
    double unit = step > 0 ? 1.0 / (fs * step) : 0.0;
    static const double k_units[] = {1.0, 1e-3, 1e-6};
    static const char *const k_unit_names[] = {"s", "ms", "us"};
    size_t k = 0;
    for (; k < sizeof k_units / sizeof k_units[0]; ++k)
      if (fabs(unit / k_units[k] - 1.0) < 0.05) break;
    if (k == 0) {
      fs_against_seconds("in s", step, fs, quiet);
      unit = 1.0;
    } else if (k < sizeof k_units / sizeof k_units[0]) {
      if (!quiet)
        fprintf(stderr, "%s: note: t steps by %.6g: in %s at --fs %.6g Hz\n", k_prog, step, k_unit_names[k],
                fs);
      unit = k_units[k];
    } else if (!quiet && step > 0) {
      if (fabs(step - 1.0) < 0.01)
        fprintf(stderr, "%s: note: t steps by %.6g: a sample index; the rate is --fs %.6g Hz\n", k_prog, step,
                fs);
      else
        fprintf(stderr,
                "%s: note: t steps by %.6g: %.6g Hz if t is in seconds, %.6g Hz if in ms, where "
                "--fs says %.6g Hz: t is read in units of %.6g s; using --fs\n",
                k_prog, step, 1.0 / step, 1e3 / step, fs, unit);
    }
    s->t_unit_s = unit;
  }
  if (step > 0 && (y->hi > 1.05 * step || y->lo < 0.95 * step) && !quiet)
    fprintf(stderr,
            "%s: note: t's steps vary from %.6g to %.6g (mean %.6g, line %ld); with --fs "
            "they are not checked: the rows are taken as samples at %.6g Hz%s\n",
            k_prog, y->dt_min, y->dt_max, step, y->hi > 1.05 * step ? y->line_hi : y->line_lo, fs,
            y->hi > 1.5 * step && !s->n_gaps
                ? " (samples missing: --gaps restart restarts the estimator at gaps)"
                : "");
  return -1;
}

/* Duties are the upper switch's share of the period, in [0, 1], and the bus
 * a positive voltage: other scales (percent, a signed modulation index, timer
 * compare counts) would pass as a wrong voltage, so they are refused with the
 * conversion. Rounding of the printed duties is tolerated. */
#define DUTY_SLACK 1e-6
static int check_duty(const tally_t *y, const char *name)
{
  if (y->d_min < -DUTY_SLACK) {
    fprintf(stderr,
            "%s: %s:%ld: a duty cycle of %.6g: duties must be the upper switch's on-time share in "
            "[0, 1].%s\n",
            k_prog, name, y->line_d_min, y->d_min,
            y->d_min >= -1.0 - DUTY_SLACK && y->d_max <= 1.0 + DUTY_SLACK
                ? " A signed modulation index m in [-1, 1] converts as d = (m + 1) / 2."
                : " Convert the log's duty scale to [0, 1].");
    return TOOL_EXIT_DATA;
  }
  if (y->d_max > 1.0 + DUTY_SLACK) {
    fprintf(stderr,
            "%s: %s:%ld: a duty cycle of %.6g: duties must be the upper switch's on-time share in "
            "[0, 1].%s\n",
            k_prog, name, y->line_d_max, y->d_max,
            y->d_max <= 100.0 + DUTY_SLACK ? " In percent? Divide by 100."
                                           : " Timer compare counts? Divide by the timer's period.");
    return TOOL_EXIT_DATA;
  }
  if (y->vdc_min < 0.0) {
    fprintf(stderr, "%s: %s:%ld: v_dc = %.6g V: the DC-bus voltage must be positive, in V\n", k_prog, name,
            y->line_vdc_min, y->vdc_min);
    return TOOL_EXIT_DATA;
  }
  return -1;
}

/* The quick tests of the conventions (docs/feeding-logs.md). A negative power
 * is a note (a braking drive draws it); theta turning against the field over
 * the whole record is an error: such data fit a motor with a far smaller T_R
 * and pass as valid (measured: T_R -97.5 %, E_I 0.007). */
static int check_conventions(const tally_t *y, const char *name, int quiet)
{
  if (!quiet && y->s_sum > 0 && y->p_sum < -0.2 * y->s_sum)
    fprintf(stderr,
            "%s: note: the mean power u.i is negative (%.3g of the apparent power): unless the "
            "motor was braking, the current sign is inverted (currents must be positive into the "
            "motor) or a voltage and a current column are of different phases\n",
            k_prog, y->p_sum / y->s_sum);
  if (fabs(y->field_rad) > 4.0 * PI && fabs(y->mech_rad) > PI && (y->field_rad > 0) != (y->mech_rad > 0)) {
    fprintf(stderr,
            "%s: %s: theta turns %s (%.3g turns) while the a-b-c current field turns %s (%.3g "
            "turns): theta must increase with the a-b-c field, else T_R comes out far too small "
            "and can look valid. Negate theta, or swap two phases of u and i alike.\n",
            k_prog, name, y->mech_rad > 0 ? "forward" : "backward", fabs(y->mech_rad) / (2 * PI),
            y->field_rad > 0 ? "forward" : "backward", fabs(y->field_rad) / (2 * PI));
    return TOOL_EXIT_DATA;
  }
  if (quiet) return -1;
  if (y->th_wraps > 0 && y->th_max - y->th_min > 2.0 * PI * 1.05)
    fprintf(stderr,
            "%s: note: theta wraps around at about %.6g; an angle in rad wraps at 2 pi = 6.283. "
            "theta must be the mechanical angle in rad, not degrees (360) or encoder counts\n",
            k_prog, y->th_max - y->th_min);
  return -1;
}

int replay_is_gap(const replay_scan_t *s, double dt, double q)
{
  return s->gap_step > 0 && dt - q > 1.5 * s->gap_step;
}

static int cmp_double(const void *a, const void *b)
{
  const double x = *(const double *)a, z = *(const double *)b;
  return (x > z) - (x < z);
}

/* --gaps restart: a second pass over t. Steps of more than 1.5 x the median
 * are gaps; without them the steps are tallied again and the nominal step is
 * the mean of the others. Returns -1 to go on, or an exit code. */
static int find_gaps(csv_reader_t *r, const replay_opts_t *o, tally_t *y, replay_scan_t *s)
{
  double *dt = malloc(sizeof *dt * (size_t)(s->n - 1)), *q = malloc(sizeof *q * (size_t)(s->n - 1));
  if (dt == NULL || q == NULL || csv_rewind(r) != 0) {
    free(dt);
    free(q);
    fprintf(stderr, "%s: %s: cannot read the file a second time\n", k_prog, r->name);
    return TOOL_EXIT_DATA;
  }
  double v[CSV_MAX_NEED], tprev = 0, qprev = 0;
  replay_sample_t x;
  long k = 0;
  while (csv_next(r, v) == 1 && k < s->n) {
    replay_decode(o->voltage, v, &x);
    if (k > 0) {
      dt[k - 1] = x.t - tprev;
      q[k - 1] = r->t_round + qprev;
    }
    tprev = x.t;
    qprev = r->t_round;
    k++;
  }
  const long m = k - 1;
  double *sorted = malloc(sizeof *sorted * (size_t)(m > 0 ? m : 1));
  if (sorted == NULL || m < 1) {
    free(dt);
    free(q);
    free(sorted);
    return -1;
  }
  memcpy(sorted, dt, sizeof *dt * (size_t)m);
  qsort(sorted, (size_t)m, sizeof *sorted, cmp_double);
  s->gap_step = sorted[m / 2];
  free(sorted);
  double span_gaps = 0;
  for (long j = 0; j < m; ++j) {
    if (!replay_is_gap(s, dt[j], q[j])) continue;
    span_gaps += dt[j];
    s->gap_missing += lround(dt[j] / s->gap_step) - 1;
    s->n_gaps++;
  }
  if (s->n_gaps == 0 || s->gap_step <= 0) {
    s->gap_step = 0;
    free(dt);
    free(q);
    return -1;
  }
  /* the steps again, without the gaps */
  y->step = (s->t_last - s->t0 - span_gaps) / (double)(m - s->n_gaps);
  y->dt_min = y->lo = (double)INFINITY;
  y->dt_max = y->hi = -(double)INFINITY;
  free(dt);
  free(q);
  /* a third pass: the gaps' lines, the other steps' extremes */
  if (csv_rewind(r) != 0) return TOOL_EXIT_DATA;
  long g = 0;
  k = 0;
  while (csv_next(r, v) == 1 && k < s->n) {
    replay_decode(o->voltage, v, &x);
    if (k > 0) {
      const double d = x.t - tprev, qq = r->t_round + qprev;
      if (replay_is_gap(s, d, qq)) {
        if (g < 4) {
          s->gap_line[g] = r->line;
          s->gap_t[g][0] = tprev;
          s->gap_t[g][1] = x.t;
        }
        g++;
      } else {
        if (d < y->dt_min) y->dt_min = d, y->line_min = r->line;
        if (d > y->dt_max) y->dt_max = d, y->line_max = r->line, y->q_worst = r->t_round;
        if (d + qq < y->lo) y->lo = d + qq, y->line_lo = r->line;
        if (d - qq > y->hi) y->hi = d - qq, y->line_hi = r->line, y->t_hi[0] = tprev, y->t_hi[1] = x.t;
      }
    }
    tprev = x.t;
    qprev = r->t_round;
    k++;
  }
  return -1;
}

/* Where the gaps are, and what --gaps restart does at them. */
static void say_gaps(const csv_reader_t *r, const replay_scan_t *s, double step)
{
  fprintf(stderr, "%s: note: %s: %ld gap%s in t (--gaps restart), about %ld sample%s missing:", k_prog,
          r->name, s->n_gaps, s->n_gaps == 1 ? "" : "s", s->gap_missing, s->gap_missing == 1 ? "" : "s");
  for (long g = 0; g < s->n_gaps && g < 4; ++g)
    fprintf(stderr, "%s line %ld (t = %.9g after %.9g, a step of %.6g where %.6g is expected)", g ? ";" : "",
            s->gap_line[g], s->gap_t[g][1], s->gap_t[g][0], s->gap_t[g][1] - s->gap_t[g][0], step);
  fprintf(stderr,
          "%s. The estimator restarts at each: the window before the gap is estimated if it has at least "
          "half a window's samples, else dropped; the filters warm up again\n",
          s->n_gaps > 4 ? "; ..." : "");
}

int replay_scan(csv_reader_t *r, const replay_opts_t *o, replay_scan_t *s)
{
  memset(s, 0, sizeof *s);
  tally_t y;
  memset(&y, 0, sizeof y);
  y.dt_min = y.lo = (double)INFINITY;
  y.dt_max = y.hi = -(double)INFINITY;
  y.all_unit_steps = 1;
  y.d_min = y.vdc_min = (double)INFINITY;
  y.d_max = -(double)INFINITY;
  double v[CSV_MAX_NEED];
  replay_sample_t x;
  int rc;
  while ((rc = csv_next(r, v)) == 1) {
    replay_decode(o->voltage, v, &x);
    if (s->n > 0 && x.t < y.tprev && o->fs_hz <= 0) {
      fprintf(stderr,
              "%s: %s:%ld: t = %.9g does not increase (previous %.9g): rows out of "
              "order, or a timer that wrapped (then give --fs HZ)\n",
              k_prog, r->name, r->line, x.t, y.tprev);
      return TOOL_EXIT_DATA;
    }
    tally_row(&y, s, r, &x, o->voltage);
  }
  if (rc < 0) {
    fprintf(stderr, "%s: %s\n", k_prog, r->err);
    return TOOL_EXIT_DATA;
  }
  if (r->truncated_line && !o->quiet)
    fprintf(stderr,
            "%s: warning: %s: the last line looks cut off; it is left out and the "
            "%ld rows before it are used\n",
            k_prog, r->warn, s->n);
  if (s->n < 2) {
    fprintf(stderr, "%s: %s: %s\n", k_prog, r->name,
            s->n == 0 ? "no data rows after the header" : "only one data row: no sample rate");
    return TOOL_EXIT_DATA;
  }
  s->t_last = y.tprev;
  if (o->gaps_restart && (rc = find_gaps(r, o, &y, s)) >= 0) return rc;
  rc = o->fs_hz > 0 ? time_base_given(r, &y, s, o->fs_hz, o->quiet)
                    : time_base_from_t(r->name, &y, s, o->quiet);
  if (rc >= 0) return rc;
  if (s->n_gaps && !o->quiet) say_gaps(r, s, mean_step(&y, s));
  if (r->decimal_comma_line && !o->quiet)
    fprintf(stderr, "%s: note: %s: numbers with a decimal comma (first on line %ld) read as decimal points\n",
            k_prog, r->name, r->decimal_comma_line);
  if (o->voltage == REPLAY_VOLTAGE_DUTY && (rc = check_duty(&y, r->name)) >= 0) return rc;
  return check_conventions(&y, r->name, o->quiet);
}
