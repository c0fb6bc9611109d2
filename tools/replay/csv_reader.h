/* SPDX-License-Identifier: Apache-2.0 */
/* Minimal strict CSV reader for motor recordings: a header row naming the
 * columns, then numeric rows. Errors name the line. "-" reads stdin (copied
 * to a temporary file so that it can be read twice). A malformed last line
 * (a recording cut off mid-write) ends the data with a warning instead of an
 * error. Host tool code. */
#ifndef IMEST_CSV_READER_H
#define IMEST_CSV_READER_H

#include <stdio.h>

#define CSV_NEED     8 /* the phase-voltage columns: t,u_a,u_b,u_c,i_a,i_b,i_c,theta */
#define CSV_MAX_NEED 9 /* the most columns a layout needs (duty: t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta) */

/* The columns a recording must have, in the order csv_next() returns them. */
typedef struct {
  const char *const *names;
  int n; /* at most CSV_MAX_NEED */
} csv_layout_t;

extern const csv_layout_t CSV_PHASE; /* t,u_a,u_b,u_c,i_a,i_b,i_c,theta (CSV_NAMES) */
extern const csv_layout_t CSV_DUTY;  /* t,d_a,d_b,d_c,v_dc,i_a,i_b,i_c,theta */

typedef struct {
  FILE *f;
  const char *name;
  long line;                /* line number of the last line read (1 = header) */
  int ncols;                /* columns in the header */
  const char *const *names; /* the layout's column names */
  int need;                 /* how many of them */
  int col[CSV_MAX_NEED];    /* column index of each needed field */
  char *buf;
  size_t cap;
  double t_round;      /* half a unit of the last row's t in its printed
                              decimals: "0.0003" -> 5e-5 (its rounding bound) */
  long truncated_line; /* a malformed last line that was dropped (0 = none) */
  char warn[512];      /* what was wrong with it */
  char err[512];
} csv_reader_t;

/* Open and read the header, for the phase-voltage columns (CSV_PHASE).
 * Returns 0 or -1 with r->err set. */
int csv_open(csv_reader_t *r, const char *path);
/* The same for the columns of a layout. */
int csv_open_layout(csv_reader_t *r, const char *path, const csv_layout_t *layout);
/* Read the next row into v[r->need] (the layout's order). Returns 1 row, 0
 * end of file (also after a dropped malformed last line: r->truncated_line),
 * -1 error with r->err naming the line. */
int csv_next(csv_reader_t *r, double *v);
/* Back to the first data row (for a second pass). */
int csv_rewind(csv_reader_t *r);
void csv_close(csv_reader_t *r);

extern const char *const CSV_NAMES[CSV_NEED];

#endif
