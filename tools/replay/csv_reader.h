/* SPDX-License-Identifier: Apache-2.0 */
/* CSV reader for motor recordings as drives log them: a header row naming
 * the columns, then numeric rows. Errors name the line and quote what was
 * read. "-" reads stdin (copied to a temporary file so that it can be read
 * twice). A malformed last line (a recording cut off mid-write) ends the data
 * with a warning instead of an error.
 *
 * What the header may look like (docs/feeding-logs.md, section 1.1):
 *   - separator ',', ';' or tab: the one the header line has most of;
 *   - lines starting with '#' and blank lines are skipped anywhere (also
 *     before the header); a UTF-8 byte order mark is skipped;
 *   - names case-insensitive, '_', '-' and spaces inside them ignored, and a
 *     few aliases (time for t, va/van for u_a, vdc/udc for v_dc, ...):
 *     csv_aliases();
 *   - a unit in brackets or parentheses after the name ("t [ms]", "i_a(A)"):
 *     a known one is converted to the column's unit, an unknown one refused;
 *   - with ';' or tab as separator a decimal comma is read ("0,25");
 *   - two of the three currents: the third is minus their sum; no phase
 *     voltages but two or three line-to-line ones (u_ab, u_bc, u_ca): the
 *     phase-to-neutral set without a zero sequence (--voltage phase only).
 * The header exactly as the canonical names (t,u_a,...) reads as before:
 * an exact name wins over an alias, and such columns are not scaled.
 * Host tool code. */
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

#define CSV_NSRC (CSV_MAX_NEED + 3) /* the layout's columns and u_ab,u_bc,u_ca */

typedef struct {
  FILE *f;
  const char *name;
  long line;                /* line number of the last line read */
  long header_line;         /* the header's line number (1 unless comments precede it) */
  long header_pos;          /* its offset in the file (for csv_rewind) */
  char sep;                 /* ',', ';' or '\t' */
  int ncols;                /* columns in the header */
  const char *const *names; /* the layout's column names */
  int need;                 /* how many of them */
  int col[CSV_NSRC];        /* column index of each source field (layout's, then u_ab,u_bc,u_ca); -1 none */
  double scale[CSV_NSRC];   /* the header's unit into the column's (1 = as read) */
  int nsrc;                 /* source fields a row must have */
  int derive_i;             /* layout index of the current that is minus the other two (-1 none) */
  int derive_ll;            /* phase voltages from line-to-line ones */
  int ki[3], ku[3];         /* layout index of i_a,i_b,i_c and u_a,u_b,u_c (-1: not in the layout) */
  long decimal_comma_line;  /* first line with a decimal comma read (0 = none) */
  char t_unit[16];          /* t's unit as its header states it ("" = none stated; t is then in s) */
  char *buf;
  size_t cap;
  double t_round;      /* half a unit of the last row's t in its printed
                              decimals: "0.0003" -> 5e-5 (its rounding bound), in s if converted */
  long truncated_line; /* a malformed last line that was dropped (0 = none) */
  char warn[1024];     /* what was wrong with it */
  char notes[1024];    /* what the header made the reader do, one line each ("" = nothing) */
  char err[1024];
} csv_reader_t;

/* Open and read the header, for the phase-voltage columns (CSV_PHASE).
 * Returns 0 or -1 with r->err set. */
int csv_open(csv_reader_t *r, const char *path);
/* The same for the columns of a layout. */
int csv_open_layout(csv_reader_t *r, const char *path, const csv_layout_t *layout);
/* Read the next row into v[r->need] (the layout's order, in the columns'
 * units). Returns 1 row, 0 end of file (also after a dropped malformed last
 * line: r->truncated_line), -1 error with r->err naming the line. */
int csv_next(csv_reader_t *r, double *v);
/* Back to the first data row (for a second pass). */
int csv_rewind(csv_reader_t *r);
void csv_close(csv_reader_t *r);

/* The other spellings of a canonical column name ("t" -> "time"), for
 * messages and --help; "" when it has none. */
const char *csv_aliases(const char *canonical);

extern const char *const CSV_NAMES[CSV_NEED];

#endif
