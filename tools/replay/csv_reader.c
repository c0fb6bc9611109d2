/* SPDX-License-Identifier: Apache-2.0 */
#define _POSIX_C_SOURCE 200809L /* getline */
#include "csv_reader.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h> /* strcasecmp */

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

/* ------------------------------------------------------------------------- */
/* names, aliases and units                                                   */

/* The source fields beyond the layout's: line-to-line voltages. */
static const char *const k_ll_names[3] = {"u_ab", "u_bc", "u_ca"};

/* Other spellings of a column, beyond case, '_', '-' and spaces (which are
 * ignored: "I_A", "iA" and "ia" are all i_a). Small on purpose: a wrong alias
 * would read a column the user did not mean. */
static const struct {
  const char *name, *aliases; /* aliases: ", "-separated */
} k_aliases[] = {
    {"t", "time"},
    {"u_a", "v_a, u_an, v_an"},
    {"u_b", "v_b, u_bn, v_bn"},
    {"u_c", "v_c, u_cn, v_cn"},
    {"theta", "angle, pos, position, theta_m"},
    {"v_dc", "u_dc, v_bus, u_bus"},
    {"d_a", "duty_a"},
    {"d_b", "duty_b"},
    {"d_c", "duty_c"},
    {"u_ab", "v_ab"},
    {"u_bc", "v_bc"},
    {"u_ca", "v_ca"},
};

const char *csv_aliases(const char *canonical)
{
  for (size_t k = 0; k < sizeof k_aliases / sizeof k_aliases[0]; ++k)
    if (strcmp(canonical, k_aliases[k].name) == 0) return k_aliases[k].aliases;
  return "";
}

/* A name without case, '_', '-', '.' and spaces, into out[cap]. */
static void fold(const char *s, size_t len, char *out, size_t cap)
{
  size_t n = 0;
  for (size_t k = 0; k < len && s[k] && n + 1 < cap; ++k) {
    const unsigned char c = (unsigned char)s[k];
    if (c == '_' || c == '-' || c == '.' || isspace(c)) continue;
    out[n++] = (char)tolower(c);
  }
  out[n] = '\0';
}

/* Whether a header name (already folded) is the canonical column or one of its aliases. */
static int names_column(const char *folded, const char *canonical)
{
  char a[64];
  fold(canonical, strlen(canonical), a, sizeof a);
  if (strcmp(folded, a) == 0) return 1;
  const char *p = csv_aliases(canonical);
  while (*p) {
    const char *e = strchr(p, ',');
    const size_t len = e ? (size_t)(e - p) : strlen(p);
    fold(p, len, a, sizeof a);
    if (strcmp(folded, a) == 0) return 1;
    if (!e) break;
    p = e + 1;
  }
  return 0;
}

typedef struct {
  const char *unit;
  double scale; /* into the column's own unit */
} unit_t;

/* The units a drive logs, per kind of column; the first is the column's own. */
static const unit_t k_time[] = {{"s", 1.0},          {"sec", 1.0},        {"ms", 1e-3}, {"us", 1e-6},
                                {"\xC2\xB5s", 1e-6}, {"\xCE\xBCs", 1e-6}, {NULL, 0}};
static const unit_t k_current[] = {{"A", 1.0}, {"mA", 1e-3}, {NULL, 0}};
static const unit_t k_voltage[] = {{"V", 1.0}, {"mV", 1e-3}, {NULL, 0}};
static const unit_t k_angle[] = {{"rad", 1.0},
                                 {"deg", 3.14159265358979323846 / 180.0},
                                 {"\xC2\xB0", 3.14159265358979323846 / 180.0},
                                 {"rev", 2.0 * 3.14159265358979323846},
                                 {NULL, 0}};
static const unit_t k_duty[] = {{"1", 1.0}, {"-", 1.0}, {"%", 0.01}, {NULL, 0}};

static const unit_t *units_of(const char *canonical)
{
  if (strcmp(canonical, "t") == 0) return k_time;
  if (strcmp(canonical, "theta") == 0) return k_angle;
  if (canonical[0] == 'i') return k_current;
  if (canonical[0] == 'd') return k_duty;
  return k_voltage; /* u_a.., v_dc, u_ab.. */
}

/* "ms, us" etc. for a message. */
static void unit_list(const unit_t *u, char *out, size_t cap)
{
  out[0] = '\0';
  for (int k = 0; u[k].unit; ++k) {
    strncat(out, k ? ", " : "", cap - strlen(out) - 1);
    strncat(out, u[k].unit, cap - strlen(out) - 1);
  }
}

/* A header field "name [unit]" or "name(unit)": the name's extent and the
 * unit (NUL-terminated in place; NULL when there is none). */
static void split_unit(char *text, size_t *name_len, char **unit)
{
  *unit = NULL;
  *name_len = strlen(text);
  char *open = strpbrk(text, "[(");
  if (open == NULL) return;
  char *close = strrchr(open, *open == '[' ? ']' : ')');
  if (close == NULL) return;
  for (const char *p = close + 1; *p; ++p)
    if (!isspace((unsigned char)*p)) return;
  *close = '\0';
  *name_len = (size_t)(open - text);
  *unit = trim(open + 1);
}

static const char *src_name(const csv_reader_t *r, int k)
{
  return k < r->need ? r->names[k] : k_ll_names[k - r->need];
}

static int layout_index(const csv_reader_t *r, const char *name)
{
  for (int k = 0; k < r->need; ++k)
    if (strcmp(r->names[k], name) == 0) return k;
  return -1;
}

static void note(csv_reader_t *r, const char *text)
{
  strncat(r->notes, text, sizeof r->notes - strlen(r->notes) - 1);
  strncat(r->notes, "\n", sizeof r->notes - strlen(r->notes) - 1);
}

static const char *sep_name(char sep)
{
  return sep == '\t' ? "tab" : sep == ';' ? "';'" : "','";
}

/* ------------------------------------------------------------------------- */
/* the header                                                                 */

/* What the header has, for messages: its fields as read. */
typedef struct {
  char list[400];
  int fields[CSV_NSRC][2]; /* exact and alias match: column index, -1 */
  int twice[CSV_NSRC];     /* a second alias match (ambiguous), -1 */
  char unit[CSV_NSRC][32]; /* the alias match's unit, "" none */
  char text[CSV_NSRC][48]; /* the matching fields as read */
  char text2[CSV_NSRC][48];
} header_t;

/* A comment (first non-blank character '#') or a blank line. */
static int skip_line(const char *s)
{
  while (isspace((unsigned char)*s)) s++;
  return *s == '\0' || *s == '#';
}

/* The first line that is neither blank nor a comment. Returns 0, or -1 at EOF. */
static int read_header_line(csv_reader_t *r)
{
  for (;;) {
    r->header_pos = ftell(r->f);
    if (read_line(r) < 0) return -1;
    char *p = r->buf;
    /* strip a UTF-8 byte order mark */
    if (r->line == 1 && (unsigned char)p[0] == 0xEF && (unsigned char)p[1] == 0xBB &&
        (unsigned char)p[2] == 0xBF)
      memmove(p, p + 3, strlen(p + 3) + 1);
    if (!skip_line(p)) break;
  }
  r->header_line = r->line;
  return 0;
}

/* The separator the header has most of (',' if none). */
static char detect_sep(const char *s)
{
  int n[3] = {0, 0, 0};
  for (; *s; ++s) n[0] += *s == ',', n[1] += *s == ';', n[2] += *s == '\t';
  if (n[1] > n[0] && n[1] >= n[2]) return ';';
  if (n[2] > n[0] && n[2] > n[1]) return '\t';
  return ',';
}

/* Matches one header field (column idx) against the source fields. */
static int match_field(csv_reader_t *r, header_t *h, char *tok, int idx, int nsrc)
{
  char *raw = trim(tok);
  char quoted[48];
  snprintf(quoted, sizeof quoted, "%s", raw);
  const size_t used = strlen(h->list);
  if (used + strlen(raw) + 3 < sizeof h->list)
    snprintf(h->list + used, sizeof h->list - used, "%s%s", idx ? ", " : "", raw);
  else if (used + 6 < sizeof h->list && strstr(h->list, ", ...") == NULL)
    snprintf(h->list + used, sizeof h->list - used, ", ...");
  for (int k = 0; k < nsrc; ++k) {
    if (strcmp(raw, src_name(r, k)) == 0) {
      if (h->fields[k][0] >= 0) {
        snprintf(r->err, sizeof r->err, "%s:%ld: column '%s' appears twice (columns %d and %d of the header)",
                 r->name, r->header_line, raw, h->fields[k][0] + 1, idx + 1);
        return -1;
      }
      h->fields[k][0] = idx;
      return 0;
    }
  }
  size_t name_len;
  char *unit;
  split_unit(raw, &name_len, &unit);
  char folded[64];
  fold(raw, name_len, folded, sizeof folded);
  for (int k = 0; k < nsrc; ++k) {
    if (!names_column(folded, src_name(r, k))) continue;
    if (h->fields[k][1] >= 0) {
      if (h->twice[k] < 0) {
        h->twice[k] = idx;
        snprintf(h->text2[k], sizeof h->text2[k], "%s", quoted);
      }
      return 0;
    }
    h->fields[k][1] = idx;
    snprintf(h->unit[k], sizeof h->unit[k], "%s", unit ? unit : "");
    snprintf(h->text[k], sizeof h->text[k], "%s", quoted);
    return 0;
  }
  return 0;
}

/* The unit of an aliased column: its scale, or -1 with r->err. */
static int apply_unit(csv_reader_t *r, const header_t *h, int k)
{
  r->scale[k] = 1.0;
  if (h->unit[k][0] == '\0') return 0;
  const unit_t *u = units_of(src_name(r, k));
  for (int j = 0; u[j].unit; ++j) {
    if (strcasecmp(h->unit[k], u[j].unit) != 0) continue;
    r->scale[k] = u[j].scale;
    if (k == 0) snprintf(r->t_unit, sizeof r->t_unit, "%s", u[j].unit);
    if (u[j].scale != 1.0) {
      char text[160];
      snprintf(text, sizeof text, "%s in %s (from its header '%s'): converted to %s", src_name(r, k),
               u[j].unit, h->text[k], u[0].unit);
      note(r, text);
    }
    return 0;
  }
  char all[64];
  unit_list(u, all, sizeof all);
  snprintf(r->err, sizeof r->err,
           "%s:%ld: column '%s' (read as %s): unit '%s' is not known; expected one of %s", r->name,
           r->header_line, h->text[k], src_name(r, k), h->unit[k], all);
  return -1;
}

/* The missing column's message: what the header has and what was expected. */
static void missing(csv_reader_t *r, const header_t *h, int k, const char *hint)
{
  char all[128] = "";
  for (int j = 0; j < r->need; ++j) {
    strncat(all, j ? "," : "", sizeof all - strlen(all) - 1);
    strncat(all, r->names[j], sizeof all - strlen(all) - 1);
  }
  char other[96] = "";
  if (*csv_aliases(r->names[k]))
    snprintf(other, sizeof other, "; %s may be named %s", r->names[k], csv_aliases(r->names[k]));
  snprintf(r->err, sizeof r->err,
           "%s:%ld: missing column '%s' (the header needs %s in any order%s%s; names are "
           "case-insensitive, a unit may follow in [] or ()): the header (line %ld, separator %s) has: %s",
           r->name, r->header_line, r->names[k], all, other, hint, r->header_line, sep_name(r->sep), h->list);
}

/* Which columns the row's fields come from, and what is derived. */
static int resolve(csv_reader_t *r, header_t *h)
{
  for (int k = 0; k < r->need + 3; ++k) {
    if (h->fields[k][0] >= 0) {
      r->col[k] = h->fields[k][0];
      r->scale[k] = 1.0;
      continue;
    }
    r->col[k] = h->fields[k][1];
    if (r->col[k] < 0) continue;
    if (h->twice[k] >= 0) {
      snprintf(r->err, sizeof r->err, "%s:%ld: columns '%s' (%d) and '%s' (%d) both read as %s: rename one",
               r->name, r->header_line, h->text[k], r->col[k] + 1, h->text2[k], h->twice[k] + 1,
               src_name(r, k));
      return -1;
    }
    if (apply_unit(r, h, k)) return -1;
  }
  /* two currents: the third is minus their sum */
  int *ki = r->ki, *ku = r->ku;
  for (int j = 0; j < 3; ++j) {
    ki[j] = layout_index(r, (const char *[]){"i_a", "i_b", "i_c"}[j]);
    ku[j] = layout_index(r, (const char *[]){"u_a", "u_b", "u_c"}[j]);
  }
  int absent = 0, which = -1;
  for (int j = 0; j < 3; ++j)
    if (ki[j] >= 0 && r->col[ki[j]] < 0) absent++, which = j;
  if (absent == 1) {
    r->derive_i = ki[which];
    const int a = which == 0 ? 1 : 0, b = which == 2 ? 1 : 2;
    char text[160];
    snprintf(text, sizeof text,
             "%s not in the header: %s = -%s - %s (the currents of a three-wire motor sum to zero)",
             r->names[ki[which]], r->names[ki[which]], r->names[ki[a]], r->names[ki[b]]);
    note(r, text);
  }
  /* no phase voltages: line-to-line ones */
  int n_u = 0, n_ll = 0;
  for (int j = 0; j < 3; ++j) {
    n_u += ku[j] >= 0 && r->col[ku[j]] >= 0;
    n_ll += r->col[r->need + j] >= 0;
  }
  if (ku[0] >= 0 && n_u == 0 && n_ll >= 2) {
    r->derive_ll = 1;
    note(r, "line-to-line voltages converted to phase-to-neutral assuming no zero sequence: "
            "u_a = (u_ab - u_ca)/3, u_b = (u_bc - u_ab)/3, u_c = (u_ca - u_bc)/3");
  } else {
    for (int j = 0; j < 3; ++j) r->col[r->need + j] = -1; /* not read */
  }
  for (int k = 0; k < r->need; ++k) {
    if (r->col[k] >= 0 || k == r->derive_i || (r->derive_ll && (k == ku[0] || k == ku[1] || k == ku[2])))
      continue;
    const char *hint = "";
    if (k == ki[0] || k == ki[1] || k == ki[2])
      hint = "; two of i_a,i_b,i_c suffice";
    else if (ku[0] >= 0 && (k == ku[0] || k == ku[1] || k == ku[2]))
      hint = n_u ? "; phase voltages need all three (their zero sequence is not known from two)"
                 : "; or two of the line-to-line u_ab,u_bc,u_ca";
    missing(r, h, k, hint);
    return -1;
  }
  r->nsrc = 0;
  for (int k = 0; k < r->need + 3; ++k) r->nsrc += r->col[k] >= 0;
  return 0;
}

int csv_open_layout(csv_reader_t *r, const char *path, const csv_layout_t *layout)
{
  memset(r, 0, sizeof *r);
  r->names = layout->names;
  r->need = layout->n;
  r->derive_i = -1;
  const int from_stdin = strcmp(path, "-") == 0;
  r->name = from_stdin ? "stdin" : path;
  path = r->name;
  r->f = from_stdin ? copy_stdin() : fopen(path, "rb");
  if (r->f == NULL) {
    snprintf(r->err, sizeof r->err, "%s: cannot %s: %s", path, from_stdin ? "read" : "open", strerror(errno));
    return -1;
  }
  for (int k = 0; k < CSV_NSRC; ++k) {
    r->col[k] = -1;
    r->scale[k] = 1.0;
  }
  errno = 0;
  if (read_header_line(r) < 0) {
    if (ferror(r->f))
      snprintf(r->err, sizeof r->err, "%s: cannot read: %s", path, strerror(errno));
    else
      snprintf(r->err, sizeof r->err, "%s: empty file (no header row)", path);
    return -1;
  }
  r->sep = detect_sep(r->buf);
  if (r->sep != ',') {
    char text[96];
    snprintf(text, sizeof text, "the header (line %ld) is separated by %s", r->header_line, sep_name(r->sep));
    note(r, text);
  }
  header_t h;
  memset(&h, 0, sizeof h);
  for (int k = 0; k < CSV_NSRC; ++k) h.fields[k][0] = h.fields[k][1] = h.twice[k] = -1;
  int idx = 0;
  for (char *tok = r->buf;; ++idx) {
    char *end = strchr(tok, r->sep);
    if (end) *end = '\0';
    if (match_field(r, &h, tok, idx, r->need + 3)) return -1;
    if (!end) break;
    tok = end + 1;
  }
  r->ncols = idx + 1;
  return resolve(r, &h);
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

/* Nothing but blank lines and comments up to the end of the file. */
static int at_last_line(csv_reader_t *r)
{
  long len;
  while ((len = read_line(r)) >= 0 && skip_line(r->buf)) {}
  return len < 0;
}

/* One field as a number into *x: a decimal comma is read when the separator
 * is not ','. Returns 0, 1 not a number (r->err set; *cut: it may be the
 * start of a number), -1 non-finite (r->err set). */
static int parse_field(csv_reader_t *r, int k, char *tok, int last, double *x, int *cut)
{
  char *s = trim(tok), *end = NULL;
  char *comma = strchr(s, ',');
  if (comma != NULL) {
    if (strchr(comma + 1, ',') != NULL || strchr(s, '.') != NULL) {
      snprintf(r->err, sizeof r->err,
               "%s:%ld: column '%s': '%.40s' is not a number (expected one decimal separator, '.' or a "
               "decimal ',' with separator %s)",
               r->name, r->line, src_name(r, k), s, sep_name(r->sep));
      *cut = 0;
      return 1;
    }
    *comma = '.';
    if (r->decimal_comma_line == 0) r->decimal_comma_line = r->line;
  }
  errno = 0;
  *x = strtod(s, &end);
  if (*s == '\0' || end == s || *trim(end) != '\0') {
    snprintf(r->err, sizeof r->err, "%s:%ld: column '%s': '%.40s' is not a number", r->name, r->line,
             src_name(r, k), s);
    /* cut off inside its last field: what is left of it is the start of a number */
    *cut = last && strspn(s, "0123456789+-.eE") == strlen(s);
    return 1;
  }
  if (!isfinite(*x)) {
    snprintf(r->err, sizeof r->err, "%s:%ld: column '%s': non-finite value '%.40s'", r->name, r->line,
             src_name(r, k), s);
    return -1;
  }
  if (k == 0) r->t_round = half_unit(s) * r->scale[0];
  return 0;
}

/* The columns the header did not have, from those it had. */
static void derive(const csv_reader_t *r, double *v, const double *src)
{
  if (r->derive_i >= 0) {
    const int *ki = r->ki, which = r->derive_i == ki[0] ? 0 : r->derive_i == ki[1] ? 1 : 2;
    const int a = which == 0 ? 1 : 0, b = which == 2 ? 1 : 2;
    v[ki[which]] = -v[ki[a]] - v[ki[b]];
  }
  if (r->derive_ll) {
    double ll[3];
    for (int j = 0; j < 3; ++j)
      ll[j] = r->col[r->need + j] >= 0 ? src[r->need + j] * r->scale[r->need + j] : 0.0;
    /* the one not logged from the other two: u_ab + u_bc + u_ca = 0 */
    for (int j = 0; j < 3; ++j)
      if (r->col[r->need + j] < 0) ll[j] = -ll[(j + 1) % 3] - ll[(j + 2) % 3];
    v[r->ku[0]] = (ll[0] - ll[2]) / 3.0;
    v[r->ku[1]] = (ll[1] - ll[0]) / 3.0;
    v[r->ku[2]] = (ll[2] - ll[1]) / 3.0;
  }
}

int csv_next(csv_reader_t *r, double *v)
{
  long len;
  do {
    len = read_line(r);
    if (len < 0) return 0;
  } while (skip_line(r->buf)); /* blank lines and comments are ignored */
  double src[CSV_NSRC] = {0};
  int idx = 0, got = 0, cut = 0; /* cut: the line looks cut off mid-write */
  char *tok = r->buf;
  for (;; ++idx) {
    char *sep = strchr(tok, r->sep);
    if (sep) *sep = '\0';
    for (int k = 0; k < r->need + 3; ++k) {
      if (r->col[k] != idx) continue;
      const int bad = parse_field(r, k, tok, sep == NULL && idx + 1 <= r->ncols, &src[k], &cut);
      if (bad < 0) return -1;
      if (bad) goto bad;
      got++;
    }
    if (!sep) break;
    tok = sep + 1;
  }
  if (idx + 1 != r->ncols || got != r->nsrc) {
    snprintf(r->err, sizeof r->err, "%s:%ld: %d fields, the header (line %ld) has %d", r->name, r->line,
             idx + 1, r->header_line, r->ncols);
    cut = idx + 1 < r->ncols;
    goto bad;
  }
  for (int k = 0; k < r->need; ++k) v[k] = r->col[k] >= 0 ? src[k] * r->scale[k] : 0.0;
  derive(r, v, src);
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
  if (fseek(r->f, r->header_pos, SEEK_SET) != 0) return -1;
  r->line = r->header_line - 1;
  return read_line(r) < 0 ? -1 : 0;
}

void csv_close(csv_reader_t *r)
{
  if (r->f) fclose(r->f);
  free(r->buf);
  r->f = NULL;
  r->buf = NULL;
}
