/* Minimal strict CSV reader for motor recordings: a header row naming the
 * columns, then numeric rows. Errors name the line. "-" reads stdin (copied
 * to a temporary file so that it can be read twice). A malformed last line
 * (a recording cut off mid-write) ends the data with a warning instead of an
 * error. Host tool code. */
#ifndef IMEST_CSV_READER_H
#define IMEST_CSV_READER_H

#include <stdio.h>

#define CSV_NEED 8 /* t,u_a,u_b,u_c,i_a,i_b,i_c,theta */

typedef struct {
  FILE *f;
  const char *name;
  long line;         /* line number of the last line read (1 = header) */
  int ncols;         /* columns in the header */
  int col[CSV_NEED]; /* column index of each needed field */
  char *buf;
  size_t cap;
  double t_round;      /* half a unit of the last row's t in its printed
                              decimals: "0.0003" -> 5e-5 (its rounding bound) */
  long truncated_line; /* a malformed last line that was dropped (0 = none) */
  char warn[512];      /* what was wrong with it */
  char err[512];
} csv_reader_t;

/* Open and read the header. Returns 0 or -1 with r->err set. */
int csv_open(csv_reader_t *r, const char *path);
/* Read the next row into v[CSV_NEED] (order of CSV_NAMES). Returns 1 row, 0
 * end of file (also after a dropped malformed last line: r->truncated_line),
 * -1 error with r->err naming the line. */
int csv_next(csv_reader_t *r, double v[CSV_NEED]);
/* Back to the first data row (for a second pass). */
int csv_rewind(csv_reader_t *r);
void csv_close(csv_reader_t *r);

extern const char *const CSV_NAMES[CSV_NEED];

#endif
