/* SPDX-License-Identifier: Apache-2.0 */
/* imest-replay's first pass over a recording: its time base (sample rate,
 * unit and rounding of t), ADC clipping, whether it starts at rest, and a
 * check of the sign conventions. Everything the run needs before the first
 * sample goes to the estimator. */
#ifndef IMEST_REPLAY_SCAN_H
#define IMEST_REPLAY_SCAN_H

#include "csv_reader.h"
#include "replay_options.h"

typedef struct {
  double max_abs, prev;
  long run, plateau;
} clip_t;

/* One row of a recording, either input. */
typedef struct {
  double t;
  double u[3];      /* phase-to-neutral voltage [V]: measured, or v_dc (d - mean d) of the duties */
  double d[3], vdc; /* duty input: the upper switches' duties (row k: [t_k, t_k+1)), bus [V] */
  double i[3];      /* phase currents [A] */
  double theta;     /* mechanical angle [rad] */
} replay_sample_t;

/* A row as csv_next() returned it (the layout of `voltage`) into *x. */
void replay_decode(replay_voltage_t voltage, const double *v, replay_sample_t *x);

/* The CSV columns of an input. */
const csv_layout_t *replay_layout(replay_voltage_t voltage);

typedef struct {
  long n;                      /* data rows */
  double t0, t_last;           /* first and last t, in the file's unit */
  double fs;                   /* the sample rate used [Hz]: --fs, or from t */
  double fs_t;                 /* the rate t implies if it is in seconds [Hz] */
  double t_unit_s;             /* seconds per unit of t (1 unless --fs says otherwise) */
  int t_rounded;               /* t's steps vary only by its printed rounding */
  clip_t clip_i[3], clip_u[3]; /* clip_u: measured phase voltages only */
  double i_first, i_max;       /* for the at-rest test */
  double th_step1;             /* |first angle step| [rad] */
  /* --gaps restart: steps of t over 1.5 x gap_step (t's unit) are gaps */
  double gap_step;  /* the median step of t (0: no gaps looked for) */
  long n_gaps;      /* how many */
  long gap_missing; /* samples missing in them, about */
  long gap_line[4]; /* the first ones: line, t before and after */
  double gap_t[4][2];
} replay_scan_t;

/* Whether a step of t (dt, with q the rounding of its two ends) is a gap
 * that --gaps restart restarts the estimator at. */
int replay_is_gap(const replay_scan_t *s, double dt, double q);

/* Reads the whole file once. Returns -1 to go on, or the exit code after a
 * message on stderr (TOOL_EXIT_DATA: the file cannot be used, with what to do). */
int replay_scan(csv_reader_t *r, const replay_opts_t *o, replay_scan_t *s);

#endif
