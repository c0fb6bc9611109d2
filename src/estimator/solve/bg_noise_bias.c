/* SPDX-License-Identifier: Apache-2.0 */
/* Background solve stage: the sensors' white-noise bias on the window sums
 * (as window/bg_noise.c estimated it), taken out of the sums, and the
 * residual it explains at a given K (docs/METHOD.md §16). Takes sums, knows
 * no instance. */
#include <math.h>

#include "bg_noise_bias.h"
#include "isr_accumulate.h" /* IMEST_ACC_INDEX: the ISR's packed order of the bias */
#include "bg_float.h"       /* BG_FMAX...: no libm fmax on a core without VMAXNM */

const unsigned int imest__bg_k_of_col[7] = {0u, 1u, 3u, 4u, 5u, 6u, 7u};

/* The bias entry of ISR columns i, j (0..7, 7 = y). */
static float bias_f(const bg_noise_t *nz, unsigned int i, unsigned int j)
{
  const unsigned int lo = i < j ? i : j, hi = i < j ? j : i;
  return nz->bias[IMEST_ACC_INDEX(lo, hi)];
}

static double bias_at(const bg_noise_t *nz, unsigned int i, unsigned int j)
{
  return (double)bias_f(nz, i, j);
}

/* *dst -= f b, without the soft-double multiplication where the whole bias is
 * taken (whole: f = 1, the rule; x 1 is exact) */
BG_NOINLINE static void take(double *dst, double f, int whole, double b)
{
  if (whole)
    *dst -= b;
  else
    *dst -= f * b; /* as before, fused where the FPU fuses */
}
#define TAKE(dst, b) take(&(dst), f, whole, (b))

/* In float64 although B and c0 are float32: B_yy - 2 c0' B_y + c0' B c0 (the
 * noise's share of the centred residual) cancels; formed in float32 it moved
 * PE_K1 of a poorly determined window by 10 % (tools/studies/compare). */
static void apply(bg_sums_t *sm, const bg_noise_t *nz, double f, double m)
{
  const int whole = (f == 1.0);
  double c0[7];
  for (unsigned int i = 0; i < 7u; ++i) c0[i] = sm->c0[imest__bg_k_of_col[i]];
  double bwc[7]; /* B_WW c0 */
  for (unsigned int i = 0; i < 7u; ++i) {
    bwc[i] = 0.0;
    for (unsigned int j = 0; j < 7u; ++j) bwc[i] += bias_at(nz, i, j) * c0[j];
  }
  double cbc = 0.0, cby = 0.0;
  for (unsigned int i = 0; i < 7u; ++i) {
    for (unsigned int j = 0; j < 7u; ++j)
      TAKE(sm->rw[imest__bg_k_of_col[i]][imest__bg_k_of_col[j]], bias_at(nz, i, j));
    TAKE(sm->rwy[imest__bg_k_of_col[i]], bias_at(nz, i, 7u));
    TAKE(sm->rwe[imest__bg_k_of_col[i]], bias_at(nz, i, 7u) - bwc[i]);
    cbc += c0[i] * bwc[i];
    cby += c0[i] * bias_at(nz, i, 7u);
  }
  const double e_c0 = bias_at(nz, 7u, 7u) - 2.0 * cby + cbc;
  TAKE(sm->ry, bias_at(nz, 7u, 7u));
  TAKE(sm->ree, e_c0);
  sm->e_slack = 0.0;
  take(&sm->e_slack, f, whole, -e_c0); /* 0 - (-f e) = f e */
  /* column 3 is -m column 4, for the noise as for everything */
  for (unsigned int j = 0; j < 8u; ++j) sm->rw[2][j] = -m * sm->rw[3][j];
  for (unsigned int i = 0; i < 8u; ++i) sm->rw[i][2] = -m * sm->rw[i][3];
  sm->rw[2][2] = m * m * sm->rw[3][3];
  sm->rwy[2] = -m * sm->rwy[3];
  sm->rwe[2] = -m * sm->rwe[3];
}

void imest__bg_noise_subtract(bg_sums_t *sums, bg_noise_t *nz, double m)
{
  /* Where the noise would take more than 90 % of a column's energy, the
   * window is noise and the bias estimate the weakest: take only as much of
   * it as leaves every column (and y) 10 % of its energy. (R_W is nearly
   * singular at constant speed, W6 ~ a^2 W4 and W7 ~ a^2 W1, so definiteness
   * is no test: the bias has the same near-collinearity.) float32: the
   * energies are of B's magnitudes, which are float32; the share is
   * continuous where the test flips (0.9 r / b = 1 there). */
  float f = nz->steady ? 1.0f : 0.0f;
  for (unsigned int i = 0; i < 8u; ++i) {
    const float r = (float)((i < 7u) ? sums->rw[imest__bg_k_of_col[i]][imest__bg_k_of_col[i]] : sums->ry),
                b = bias_f(nz, i, i);
    if (b > 0.9f * r) f = BG_FMINF(f, r > 0.0f ? 0.9f * r / b : 0.0f);
  }
  nz->scale = (double)f;
  sums->e_slack = 0.0;
  if (f > 0.0f) apply(sums, nz, (double)f, m);
  nz->e_c0 = sums->e_slack;
}

double imest__bg_noise_e(const bg_noise_t *nz, const double k[8], double m)
{
  /* W3 K3 + W4 K4 = W4 (K4 - m K3): the 7-column coefficients. In float32
   * (the bias is float32; the result bounds and weighs, it is not
   * subtracted): a third of the soft-double work of a solve otherwise. */
  const float c[7] = {(float)k[0], (float)k[1], (float)(k[3] - m * k[2]), (float)k[4], (float)k[5],
                      (float)k[6], (float)k[7]};
  float e = bias_f(nz, 7u, 7u);
  for (unsigned int i = 0; i < 7u; ++i) {
    float row = -2.0f * bias_f(nz, i, 7u);
    for (unsigned int j = 0; j < 7u; ++j) row += c[j] * bias_f(nz, i, j);
    e += c[i] * row;
  }
  return (double)e;
}

double imest__bg_noise_e_at(const bg_noise_t *nz, double k1, double k2, double m)
{
  const double tr = BG_DIV(1.0, k2);
  const double k[8] = {k1, k2, k2 * k2, k1 * k2, tr, k1 * tr, k1 * tr * tr, tr * tr};
  return imest__bg_noise_e(nz, k, m);
}
