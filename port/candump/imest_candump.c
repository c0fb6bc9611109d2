/* SPDX-License-Identifier: Apache-2.0 */
/* candump -L log lines: format, parse, and a port writing them to a FILE*. */
#include "imest_candump.h"

#include <math.h>
#include <string.h>

static const char *const k_default_iface = "vcan0";

static int iface_ok(const char *s)
{
  size_t n = strlen(s);
  size_t i;
  if (n == 0u || n >= IMEST_CANDUMP_IFNAMSIZ) {
    return 0;
  }
  for (i = 0u; i < n; i++) {
    unsigned char c = (unsigned char)s[i];
    if (c <= ' ' || c == '#' || c == '(' || c == ')' || c >= 0x7Fu) {
      return 0;
    }
  }
  return 1;
}

int imest_candump_format(char *buf, size_t n, double t_s, const char *iface, const imest_can_frame_t *f)
{
  static const char hex[] = "0123456789ABCDEF";
  unsigned long long sec;
  unsigned long usec;
  char tmp[IMEST_CANDUMP_LINE_MAX];
  int len;
  unsigned int i;
  size_t pos;
  if (buf == NULL || f == NULL || f->dlc > 8u) {
    return -1;
  }
  if (iface == NULL) {
    iface = k_default_iface;
  }
  if (!iface_ok(iface)) {
    return -1;
  }
  if (!(t_s >= 0.0) || t_s > 1e15) {
    t_s = 0.0;
  }
  sec = (unsigned long long)floor(t_s);
  usec = (unsigned long)llround((t_s - (double)sec) * 1e6);
  if (usec >= 1000000ul) {
    sec += 1u;
    usec -= 1000000ul;
  }
  if (f->id & IMEST_CAN_ID_EXT) {
    if ((f->id & ~IMEST_CAN_ID_EXT) > IMEST_CAN_EFF_MASK) {
      return -1;
    }
    len = snprintf(tmp, sizeof tmp, "(%010llu.%06lu) %s %08lX#", sec, usec, iface,
                   (unsigned long)(f->id & IMEST_CAN_EFF_MASK));
  } else {
    if (f->id > IMEST_CAN_SFF_MASK) {
      return -1;
    }
    len = snprintf(tmp, sizeof tmp, "(%010llu.%06lu) %s %03lX#", sec, usec, iface, (unsigned long)f->id);
  }
  if (len < 0 || (size_t)len + 2u * f->dlc >= sizeof tmp) {
    return -1;
  }
  pos = (size_t)len;
  for (i = 0u; i < f->dlc; i++) {
    unsigned int o = (unsigned int)f->data[i] & 0xFFu;
    tmp[pos++] = hex[o >> 4];
    tmp[pos++] = hex[o & 15u];
  }
  tmp[pos] = '\0';
  if (pos + 1u > n) {
    return -1;
  }
  memcpy(buf, tmp, pos + 1u);
  return (int)pos;
}

static int hexval(char c)
{
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

#define FAIL(msg)                                                                                            \
  do {                                                                                                       \
    if (err != NULL) {                                                                                       \
      *err = (msg);                                                                                          \
    }                                                                                                        \
    return IMEST_CANDUMP_ERROR;                                                                              \
  } while (0)

int imest_candump_parse(const char *line, double *t_s, char iface[IMEST_CANDUMP_IFNAMSIZ],
                        imest_can_frame_t *f, const char **err)
{
  const char *p = line;
  const char *q;
  double sec = 0.0;
  double frac = 0.0;
  double scale = 0.1;
  int nd;
  size_t ni;
  uint32_t id = 0u;
  unsigned int ndig;
  unsigned int nbytes = 0u;
  imest_can_frame_t fr;
  if (line == NULL || f == NULL) {
    FAIL("internal: NULL argument");
  }
  while (*p == ' ' || *p == '\t') p++;
  if (*p == '\0' || *p == '\n' || *p == '\r') {
    return IMEST_CANDUMP_EMPTY;
  }
  /* (seconds.micro) */
  if (*p != '(') FAIL("expected '(' and a timestamp at the start of the line");
  p++;
  nd = 0;
  while (*p >= '0' && *p <= '9') {
    if (nd < 20) sec = sec * 10.0 + (double)(*p - '0');
    nd++;
    p++;
  }
  if (nd == 0 || nd > 19) FAIL("bad timestamp: expected (seconds.fraction)");
  if (*p != '.') FAIL("bad timestamp: expected '.' after the seconds");
  p++;
  nd = 0;
  while (*p >= '0' && *p <= '9') {
    if (nd < 9) {
      frac += scale * (double)(*p - '0');
      scale *= 0.1;
    }
    nd++;
    p++;
  }
  if (nd == 0) FAIL("bad timestamp: no digits after '.'");
  if (*p != ')') FAIL("bad timestamp: expected ')'");
  p++;
  if (*p != ' ' && *p != '\t') FAIL("expected a blank after the timestamp");
  while (*p == ' ' || *p == '\t') p++;
  /* interface */
  q = p;
  while (*q != '\0' && *q != ' ' && *q != '\t' && *q != '\n' && *q != '\r') q++;
  ni = (size_t)(q - p);
  if (ni == 0u) FAIL("missing interface name");
  if (ni >= IMEST_CANDUMP_IFNAMSIZ) FAIL("interface name longer than 15 characters");
  if (*q != ' ' && *q != '\t') FAIL("missing frame after the interface name (truncated line?)");
  if (iface != NULL) {
    memcpy(iface, p, ni);
    iface[ni] = '\0';
  }
  p = q;
  while (*p == ' ' || *p == '\t') p++;
  /* identifier */
  ndig = 0u;
  while (hexval(*p) >= 0) {
    if (ndig < 9u) id = (id << 4) | (uint32_t)hexval(*p);
    ndig++;
    p++;
  }
  if (*p != '#') {
    if (ndig == 0u) FAIL("missing frame (expected ID#DATA)");
    FAIL("bad identifier: expected hex digits followed by '#'");
  }
  if (ndig == 3u) {
    fr.id = id; /* at most 0xFFF: check below */
    if (id > IMEST_CAN_SFF_MASK) FAIL("standard identifier above 0x7FF");
  } else if (ndig == 8u) {
    if (id > IMEST_CAN_EFF_MASK) FAIL("error frame or identifier above 0x1FFFFFFF (not a data frame)");
    fr.id = id | IMEST_CAN_ID_EXT;
  } else {
    FAIL("identifier must have 3 (standard) or 8 (extended) hex digits");
  }
  p++;
  if (*p == '#') FAIL("CAN FD frame (ID##...): only classic CAN is supported");
  if (*p == 'R' || *p == 'r') FAIL("remote frame (ID#R): not a data frame");
  while (hexval(p[0]) >= 0) {
    if (hexval(p[1]) < 0) FAIL("odd number of hex digits in the data");
    if (nbytes >= 8u) FAIL("more than 8 data bytes (classic CAN)");
    fr.data[nbytes++] = (unsigned char)((hexval(p[0]) << 4) | hexval(p[1]));
    p += 2;
  }
  while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') p++;
  if (*p != '\0') FAIL("unexpected characters after the data");
  fr.dlc = nbytes;
  {
    unsigned int i;
    for (i = nbytes; i < 8u; i++) fr.data[i] = 0u;
  }
  *f = fr;
  if (t_s != NULL) *t_s = sec + frac;
  return IMEST_CANDUMP_OK;
}

static int candump_send(void *ctx, const imest_can_frame_t *f)
{
  imest_candump_port_t *p = (imest_candump_port_t *)ctx;
  char buf[IMEST_CANDUMP_LINE_MAX];
  if (p == NULL || p->fp == NULL || imest_candump_format(buf, sizeof buf, p->t_s, p->iface, f) < 0 ||
      fputs(buf, p->fp) == EOF || fputc('\n', p->fp) == EOF || ferror(p->fp)) {
    if (p != NULL) p->failed++;
    return -1;
  }
  p->lines++;
  return 0;
}

int imest_candump_port_open(imest_candump_port_t *p, FILE *fp, const char *iface)
{
  if (p == NULL || fp == NULL) {
    return -1;
  }
  if (iface == NULL) {
    iface = k_default_iface;
  }
  if (!iface_ok(iface)) {
    return -1;
  }
  memset(p, 0, sizeof *p);
  strcpy(p->iface, iface); // NOLINT(clang-analyzer-security.insecureAPI.strcpy): length checked by iface_ok()
  p->fp = fp;
  p->t_s = 0.0;
  p->port.send = candump_send;
  p->port.ctx = p;
  return 0;
}

void imest_candump_port_set_time(imest_candump_port_t *p, double t_s)
{
  if (p != NULL) {
    p->t_s = t_s;
  }
}
