/* SPDX-License-Identifier: Apache-2.0 */
/* One parser for CAN base identifiers on command lines (see the header). */
#include "imest_can_id.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

const char *imest_can_id_format(uint32_t id, char *buf, size_t n)
{
  if (buf == NULL || n == 0u) return buf;
  if (id & IMEST_CAN_ID_EXT) {
    snprintf(buf, n, "0x%08lX", (unsigned long)(id & IMEST_CAN_EFF_MASK));
  } else {
    snprintf(buf, n, "0x%03lX", (unsigned long)(id & IMEST_CAN_SFF_MASK));
  }
  return buf;
}

static int fail(char *err, size_t n, const char *msg, const char *text)
{
  if (err != NULL && n > 0u) snprintf(err, n, msg, text);
  return IMEST_ERR_ARG;
}

int imest_can_id_parse(const char *text, int force_ext, const char *ext_option, uint32_t *base_id, char *err,
                       size_t n)
{
  const unsigned long last = (unsigned long)IMEST_CAN_NFRAMES - 1ul;
  char *end = NULL;
  if (err != NULL && n > 0u) err[0] = '\0';
  if (text == NULL || ext_option == NULL || base_id == NULL) return IMEST_ERR_NULL;
  const char *p = text;
  while (*p == ' ' || *p == '\t') p++;
  if (*p == '-') return fail(err, n, "'%s' is negative: an identifier is 0 .. 0x1FFFFFFF", text);
  if (*p == '+' || *p == '\0') {
    return fail(err, n, "'%s' is not an identifier (decimal, or hex with 0x, e.g. 0x6A0)", text);
  }
  errno = 0;
  unsigned long v = strtoul(p, &end, 0);
  if (end == p || *end != '\0') {
    return fail(err, n, "'%s' is not an identifier (decimal, or hex with 0x, e.g. 0x6A0)", text);
  }
  int ext = force_ext != 0;
  if (errno == ERANGE || v > 0xFFFFFFFFul) {
    return fail(err, n, "'%s' is beyond the 29-bit range (largest identifier 0x1FFFFFFF)", text);
  }
  if ((v & IMEST_CAN_ID_EXT) && (v & ~(unsigned long)IMEST_CAN_ID_EXT) <= IMEST_CAN_EFF_MASK) {
    v &= ~(unsigned long)IMEST_CAN_ID_EXT; /* CAN_EFF_FLAG | id */
    ext = 1;
  } else if (v > IMEST_CAN_EFF_MASK) {
    return fail(err, n, "'%s' is beyond the 29-bit range (largest identifier 0x1FFFFFFF)", text);
  } else if (v > IMEST_CAN_SFF_MASK) {
    ext = 1;
  }
  const unsigned long max = ext ? IMEST_CAN_EFF_MASK : IMEST_CAN_SFF_MASK;
  if (v > max - last) {
    if (err != NULL && n > 0u) {
      if (ext) {
        snprintf(err, n,
                 "'%s': the %d frames would need identifiers 0x%lX .. 0x%lX, beyond the 29-bit range "
                 "(largest base 0x%lX)",
                 text, IMEST_CAN_NFRAMES, v, v + last, max - last);
      } else {
        snprintf(err, n,
                 "'%s': the %d frames would need identifiers 0x%lX .. 0x%lX, beyond the 11-bit range "
                 "(largest base 0x%lX); use a lower base, or %s for 29-bit identifiers",
                 text, IMEST_CAN_NFRAMES, v, v + last, max - last, ext_option);
      }
    }
    return IMEST_ERR_ARG;
  }
  *base_id = (uint32_t)v | (ext ? IMEST_CAN_ID_EXT : 0u);
  return IMEST_OK;
}
