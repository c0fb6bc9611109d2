/* SPDX-License-Identifier: Apache-2.0 */
/* Properties of the host parsers (CSV reader of imest-replay, candump -L line
 * parser) on arbitrary input: shared by the seeded random test
 * (test_parsers_random.cpp) and the libFuzzer targets (fuzz/). Each returns
 * NULL if the property holds, else what is wrong. */
#ifndef IMEST_PARSER_PROPERTY_H
#define IMEST_PARSER_PROPERTY_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csv_reader.h"
#include "imest_candump.h"

/* One candump line (NUL-terminated): the result is one of the three codes; an
 * error carries a message; a frame is a valid classic CAN frame that formats
 * back to a line which parses to the same frame. */
static inline const char *imest_candump_property(const char *line)
{
  double t = -1.0;
  char iface[IMEST_CANDUMP_IFNAMSIZ];
  imest_can_frame_t f, g;
  const char *err = NULL;
  memset(iface, 'x', sizeof iface);
  const int rc = imest_candump_parse(line, &t, iface, &f, &err);
  if (rc == IMEST_CANDUMP_EMPTY) return NULL;
  if (rc == IMEST_CANDUMP_ERROR) return (err != NULL && err[0] != '\0') ? NULL : "error without a message";
  if (rc != IMEST_CANDUMP_OK) return "unknown return code";
  if (!(isfinite(t) && t >= 0.0)) return "timestamp not finite and >= 0";
  if (memchr(iface, '\0', sizeof iface) == NULL || iface[0] == '\0')
    return "interface name not terminated/empty";
  if (f.dlc > 8u) return "dlc > 8";
  if (f.id & IMEST_CAN_ID_EXT) {
    if ((f.id & ~IMEST_CAN_ID_EXT) > IMEST_CAN_EFF_MASK) return "extended id out of range";
  } else if (f.id > IMEST_CAN_SFF_MASK) {
    return "standard id out of range";
  }
  char buf[IMEST_CANDUMP_LINE_MAX];
  /* the interface may hold characters format refuses ('#', '(' ...): use the default then */
  int n = imest_candump_format(buf, sizeof buf, 0.0, iface, &f);
  if (n < 0) n = imest_candump_format(buf, sizeof buf, 0.0, NULL, &f);
  if (n < 0) return "a parsed frame does not format";
  if (imest_candump_parse(buf, NULL, NULL, &g, &err) != IMEST_CANDUMP_OK)
    return "formatted line does not parse";
  if (g.id != f.id || g.dlc != f.dlc || memcmp(g.data, f.data, f.dlc) != 0)
    return "round trip changed the frame";
  return NULL;
}

/* A CSV file at path: open, then read every row. Errors name the file and, for
 * content errors, the line ("path:LINE: ..."); rows are finite; the reader
 * stops (it reads at most one row per line of the file). */
static inline const char *imest_csv_property(const char *path, long max_lines)
{
  static char want[600];
  csv_reader_t r;
  double v[CSV_NEED];
  if (csv_open(&r, path) != 0) {
    const char *bad = NULL;
    if (r.err[0] == '\0')
      bad = "csv_open failed without a message";
    else if (strncmp(r.err, path, strlen(path)) != 0)
      bad = "csv_open error does not name the file";
    csv_close(&r);
    return bad;
  }
  long rows = 0;
  int rc;
  const char *bad = NULL;
  while ((rc = csv_next(&r, v)) == 1) {
    for (int k = 0; k < CSV_NEED; ++k)
      if (!isfinite(v[k])) bad = "a row with a non-finite value";
    if (++rows > max_lines + 1) {
      bad = "more rows than lines";
      break;
    }
  }
  if (bad == NULL && rc == -1) {
    snprintf(want, sizeof want, "%s:%ld: ", path, r.line);
    if (strncmp(r.err, want, strlen(want)) != 0)
      bad = "csv_next error does not start with path:line:";
    else if (r.line < 2 || r.line > max_lines)
      bad = "csv_next error with a line number outside the file";
  }
  if (bad == NULL && rc != -1 && rc != 0 && rc != 1) bad = "csv_next returned an unknown code";
  csv_close(&r);
  return bad;
}

#endif
