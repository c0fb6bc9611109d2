/* SPDX-License-Identifier: Apache-2.0 */
/* Power-invariant 3-2 transform (docs/METHOD.md §1). */
#include "imsim_internal.h"

const double IMS_AK_RE[3] = {1.0, -0.5, -0.5};
const double IMS_AK_IM[3] = {0.0, SQ3H, -SQ3H};

void imsim_abc_to_ab(const double abc[3], double ab[2])
{
  ab[0] = SQ23 * (abc[0] - 0.5 * abc[1] - 0.5 * abc[2]);
  ab[1] = SQ23 * SQ3H * (abc[1] - abc[2]);
}

void imsim_ab_to_abc(const double ab[2], double abc[3])
{
  abc[0] = SQ23 * ab[0];
  abc[1] = SQ23 * (-0.5 * ab[0] + SQ3H * ab[1]);
  abc[2] = SQ23 * (-0.5 * ab[0] - SQ3H * ab[1]);
}
