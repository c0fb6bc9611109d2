/* SPDX-License-Identifier: Apache-2.0 */
#define _POSIX_C_SOURCE 200809L /* getline */
#include "csv_reader.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const CSV_NAMES[CSV_NEED] = {"t", "u_a", "u_b", "u_c", "i_a", "i_b", "i_c", "theta"};
static const char *const k_duty_names[] = {"t", "d_a", "d_b", "d_c", "v_dc", "i_a", "i_b", "i_c", "theta"};
const csv_layout_t CSV_PHASE = {CSV_NAMES, CSV_NEED};
const csv_layout_t CSV_DUTY = {k_duty_names, (int)(sizeof k_duty_names / sizeof k_duty_names[0])};
_Static_assert(sizeof k_duty_names / sizeof k_duty_names[0] <= CSV_MAX_NEED, "CSV_MAX_NEED too small");

/* Read one line (any length); strips \n and \r. Returns length or -1 at EOF. */
static long read_line(csv_reader_t *r)
{
  ssize_t n = getline(&r->buf, &r->cap, r->f);
  if (n < 0) return -1;
  if (n > 0 && r->buf[n - 1] == '\n') n--;
  if (n > 0 && r->buf[n - 1] == '\r') n--;
  r->buf[n] = '\0';
  r->line++;
  return (long)n;
}

static char *trim(char *s)
{
  while (isspace((unsigned char)*s)) s++;
  char *e = s + strlen(s);
  while (e > s && isspace((unsigned char)e[-1])) *--e = '\0';
  if (*s == '"' && e > s + 1 && e[-1] == '"') {
    e[-1] = '\0';
    s++;
  }
  return s;
}

/* stdin into a temporary file: the reader makes two passes. */
static FILE *copy_stdin(void)
{
  FILE *f = tmpfile();
  if (f == NULL) return NULL;
  char chunk[1 << 16];
  size_t n;
  while ((n = fread(chunk, 1, sizeof chunk, stdin)) > 0) {
    if (fwrite(chunk, 1, n, f) != n) {
      fclose(f);
      return NULL;
    }
  }
  if (ferror(stdin) || fflush(f) != 0 || fseek(f, 0, SEEK_SET) != 0) {
    fclose(f);
    return NULL;
  }
  return f;
}

int csv_open(csv_reader_t *r, const char *path)
{
  return csv_open_layout(r, path, &CSV_PHASE);
}

int csv_open_layout(csv_reader_t *r, const char *path, const csv_layout_t *layout)
{
  memset(r, 0, sizeof *r);
  r->names = layout->names;
  r->need = layout->n;
  const int from_stdin = strcmp(path, "-") == 0;
  r->name = from_stdin ? "stdin" : path;
  path = r->name;
  r->f = from_stdin ? copy_stdin() : fopen(path, "rb");
  if (r->f == NULL) {
    snprintf(r->err, sizeof r->err, "%s: cannot %s: %s", path, from_stdin ? "read" : "open", strerror(errno));
    return -1;
  }
  for (int k = 0; k < r->need; ++k) r->col[k] = -1;
  errno = 0;
  long len = read_line(r);
  if (len < 0) {
    if (ferror(r->f))
      snprintf(r->err, sizeof r->err, "%s: cannot read: %s", path, strerror(errno));
    else
      snprintf(r->err, sizeof r->err, "%s: empty file (no header row)", path);
    return -1;
  }
  /* strip a UTF-8 byte order mark */
  char *p = r->buf;
  if ((unsigned char)p[0] == 0xEF && (unsigned char)p[1] == 0xBB && (unsigned char)p[2] == 0xBF) p += 3;
  int idx = 0;
  for (char *tok = p;; ++idx) {
    char *comma = strchr(tok, ',');
    if (comma) *comma = '\0';
    const char *name = trim(tok);
    for (int k = 0; k < r->need; ++k) {
      if (strcmp(name, r->names[k]) == 0) {
        if (r->col[k] >= 0) {
          snprintf(r->err, sizeof r->err, "%s:1: column '%s' appears twice", path, name);
          return -1;
        }
        r->col[k] = idx;
      }
    }
    if (!comma) break;
    tok = comma + 1;
  }
  r->ncols = idx + 1;
  for (int k = 0; k < r->need; ++k) {
    if (r->col[k] < 0) {
      char all[128] = "";
      for (int j = 0; j < r->need; ++j) {
        strncat(all, j ? "," : "", sizeof all - strlen(all) - 1);
        strncat(all, r->names[j], sizeof all - strlen(all) - 1);
      }
      snprintf(r->err, sizeof r->err, "%s:1: missing column '%s' (the header needs %s in any order)", path,
               r->names[k], all);
      return -1;
    }
  }
  return 0;
}

/* Half a unit in the last printed decimal of a number's text: the bound of
 * its rounding ("0.0003" -> 5e-5, "2.5e-4" -> 5e-6, "12" -> 0.5). */
static double half_unit(const char *s)
{
  long decimals = 0;
  const char *p = s;
  while (*p && *p != '.' && *p != 'e' && *p != 'E') p++;
  if (*p == '.')
    for (++p; isdigit((unsigned char)*p); ++p) decimals++;
  if (*p == 'e' || *p == 'E') decimals -= strtol(p + 1, NULL, 10);
  return 0.5 * pow(10.0, -(double)decimals);
}

/* Nothing but blank lines up to the end of the file. */
static int at_last_line(csv_reader_t *r)
{
  long len;
  while ((len = read_line(r)) == 0) {}
  return len < 0;
}

int csv_next(csv_reader_t *r, double *v)
{
  long len;
  do {
    len = read_line(r);
    if (len < 0) return 0;
  } while (len == 0);            /* blank lines are ignored */
  int idx = 0, got = 0, cut = 0; /* cut: the line looks cut off mid-write */
  char *tok = r->buf;
  for (;; ++idx) {
    char *comma = strchr(tok, ',');
    if (comma) *comma = '\0';
    for (int k = 0; k < r->need; ++k) {
      if (r->col[k] != idx) continue;
      char *s = trim(tok), *end = NULL;
      errno = 0;
      double x = strtod(s, &end);
      if (*s == '\0' || end == s || *trim(end) != '\0') {
        snprintf(r->err, sizeof r->err, "%s:%ld: column '%s': '%.40s' is not a number", r->name, r->line,
                 r->names[k], s);
        /* cut off inside its last field: what is left of it is the start of a number */
        cut = comma == NULL && idx + 1 <= r->ncols && strspn(s, "0123456789+-.eE") == strlen(s);
        goto bad;
      }
      if (!isfinite(x)) {
        snprintf(r->err, sizeof r->err, "%s:%ld: column '%s': non-finite value '%.40s'", r->name, r->line,
                 r->names[k], s);
        return -1;
      }
      if (k == 0) r->t_round = half_unit(s);
      v[k] = x;
      got++;
    }
    if (!comma) break;
    tok = comma + 1;
  }
  if (idx + 1 != r->ncols || got != r->need) {
    snprintf(r->err, sizeof r->err, "%s:%ld: %d fields, the header has %d", r->name, r->line, idx + 1,
             r->ncols);
    cut = idx + 1 < r->ncols;
    goto bad;
  }
  return 1;
bad:
  /* A recording cut off mid-write: drop its last line, keep the rest. */
  if (cut) {
    const long line = r->line;
    if (at_last_line(r)) {
      r->truncated_line = line;
      snprintf(r->warn, sizeof r->warn, "%s", r->err);
      r->err[0] = '\0';
      return 0;
    }
    r->line = line; /* the peek read on: the error is the bad line's */
  }
  return -1;
}

int csv_rewind(csv_reader_t *r)
{
  if (fseek(r->f, 0, SEEK_SET) != 0) return -1;
  r->line = 0;
  return read_line(r) < 0 ? -1 : 0;
}

void csv_close(csv_reader_t *r)
{
  if (r->f) fclose(r->f);
  free(r->buf);
  r->f = NULL;
  r->buf = NULL;
}
