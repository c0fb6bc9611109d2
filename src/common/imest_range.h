/* SPDX-License-Identifier: Apache-2.0 */
/* The range test the optional modules' config checks share (the T_R tracker,
 * the temperatures). Internal: not part of the public API. */
#ifndef IMEST_COMMON_RANGE_H
#define IMEST_COMMON_RANGE_H

#include <math.h>

/* 1 iff x is finite and lo <= x <= hi (lo_open: lo < x). */
static inline int imest__in_range(float x, float lo, int lo_open, float hi)
{
  if (!isfinite(x) || x > hi) return 0;
  return lo_open ? x > lo : x >= lo;
}

#endif /* IMEST_COMMON_RANGE_H */
