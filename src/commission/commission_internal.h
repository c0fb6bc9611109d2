/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning internals shared by the ISR stages (float32) and the
 * background fits (float64). Internal: not part of the public API. */
#ifndef IMEST_COMMISSION_INTERNAL_H
#define IMEST_COMMISSION_INTERNAL_H

#include <stddef.h>

#include "imest/imest_commission.h"
#include "common/imest_math.h" /* constants, imest__abs, imest__clarke, IMEST_BARRIER */

/* Block kinds (tag & 0xF), plateau (tag >> 4 & 0xF), pattern (tag >> 8 & 0xF). */
enum { CM_KIND_DC = 1u, CM_KIND_HF = 2u, CM_KIND_PROBE = 3u };
#define CM_TAG(kind, plateau, pattern)                                                                       \
  ((uint32_t)(kind) | ((uint32_t)(plateau) << 4) | ((uint32_t)(pattern) << 8))
#define CM_TAG_KIND(t)    ((t)&0xFu)
#define CM_TAG_PLATEAU(t) (((t) >> 4) & 0xFu)
#define CM_TAG_PATTERN(t) (((t) >> 8) & 0xFu)

/* Modulation patterns with the same axis voltage (imest_commission.h, step 4). */
enum { CM_PAT_CENTRED = 0u, CM_PAT_LOW = 1u, CM_PAT_HIGH = 2u };

/* DC block sums (s[]): axis voltage, the three measured currents, the dead-time, threshold and
   slope-difference regressors, the current step's delay (first block of a plateau), and the
   switching legs' shortest pulse as a share of the period (min(d, 1 - d)). */
enum { CM_S_V = 0, CM_S_MA = 1, CM_S_TD = 4, CM_S_VTH = 5, CM_S_DR = 6, CM_S_DELAY = 7, CM_S_PULSE = 8 };

/* The plateau where the clamped patterns alternate with the centred one: the top, where the
   switching leg's pulses are longest (at lower currents they may be shorter than the dead
   time allows, and a clamped pattern's error is then no longer the model's). */
#define CM_PLATEAU_PATTERNS 2u
/* Square-wave block sums: y = current step over a period, x1 = voltage, x2 = mean current. */
enum { CM_H_X11 = 0, CM_H_X12, CM_H_X1, CM_H_X22, CM_H_X2, CM_H_YX1, CM_H_YX2, CM_H_Y, CM_H_YY };

/* Slip-frequency block sums: per tone t (0: f1, 1: CM_SLIP_M f1) the current less the DC one
   and the voltage less the DC one, each times cos and sin of the tone's phase
   (commission_slip.c). */
enum { CM_L_IC = 0, CM_L_IS = 1, CM_L_VC = 2, CM_L_VS = 3, CM_L_TONE = 4 };
/* The test's lower tone at w T_R = CM_SLIP_X (imest_commission.h, "What is measured"); the
   upper one an odd multiple of it, CM_SLIP_M f1, so that no second-order product of a
   saturating magnetising curve (0, 2 f1, (M - 1) f1, (M + 1) f1, 2 M f1) falls on either tone;
   each tone's amplitude a share of the DC current that keeps the sum of both 0.3 of it from
   zero (no phase current changes sign); the settling before the block in T_R; the block's
   whole periods of f1. */
#define CM_SLIP_X       6.0f
#define CM_SLIP_M       3u
#define CM_SLIP_HARM(t) ((t) == 0u ? 1u : CM_SLIP_M) /* tone t's multiple of f1 */
#define CM_SLIP_AMP     0.35f
#define CM_SLIP_SETTLE  2.0f
#define CM_SLIP_PERIODS 3u
/* Each axis's slip-frequency sums stay in blk[CM_SLIP_BLK + axis] for the standstill fit, past
   the blocks an axis's staircase and square wave take (the probe's, before, may use them). */
#define CM_SLIP_BLK     (IMEST_COMM_NBLK - 3u)

#define CM_PLATEAUS     5u /* levels 1, 2, 3, 2, 1 thirds */
#define CM_BLK_PLATEAU  9u /* blocks per plateau: 3 cycles of the 3 patterns */
#define CM_HF_BLOCKS    8u
#define CM_PROBE_ROUND  6u /* probe blocks per round; block length doubles per round */
#define CM_PROBE_ROUNDS 9u
#define CM_WIRING_N     3u

/* Jobs handed to the background (job_kind). */
enum {
  CM_JOB_WIRING = 1u,
  CM_JOB_PROBE = 2u,
  CM_JOB_AXIS = 3u,
  CM_JOB_STANDSTILL = 4u,
  CM_JOB_ROTATION = 5u
};

/* Sub-steps of the rotating stage. */
enum {
  CM_ROT_MAGNETISE = 0u,
  CM_ROT_RAMP = 1u,
  CM_ROT_SETTLE = 2u,
  CM_ROT_MEASURE = 3u,
  CM_ROT_DOWN = 4u,
  CM_ROT_STOP = 5u,
  CM_ROT_NEXT = 6u /* a level measured: hold it until the background has set the next one */
};

/* Levels of the rotating run (commission_rotate.c, commission_fit_rotation.c): up to
   CM_ROT_SEARCH levels searching the current that gives the rated flux, then the curve's
   CM_ROT_CURVE lower levels, at fluxes spread evenly from rated down to CM_ROT_FLUX_MIN of it
   (with the rated point, IMEST_LS_CURVE_POINTS points). The blocks are free while the field
   turns (the standstill fits are done before it starts): blk[level].s[] holds each level's
   figures (background), blk[CM_ROT_LEVELS].s[] the search's state and the next level's current
   the background sets for the ISR (0: done). */
#define CM_ROT_SEARCH     4u
#define CM_ROT_CURVE      (IMEST_LS_CURVE_POINTS - 1u)
#define CM_ROT_LEVELS     (CM_ROT_SEARCH + CM_ROT_CURVE)
/* The curve's lowest flux, a fraction of the rated flux: field weakening to twice base speed.
   At the voltage limit the flux falls as 1/f, to half at 2x, less the R_S and leakage drops of
   the load's current, which at rated power take up to a tenth of the voltage (the envelope's
   motors at 2x and rated power: 0.46 to 0.48 of the rated flux). */
#define CM_ROT_FLUX_MIN   (0.5f * 0.9f)
/* The first level's current, a fraction of the levels' limit (commission_rotate.c). */
#define CM_ROT_FIRST_FRAC 0.8f
enum { CM_LV_I = 0, CM_LV_LS, CM_LV_ZR };
/* The rotating measurement's repeatability, relative: the least uncertainty a level's L_S
   carries (commission_fit_rotation.c). */
#define CM_ROT_LS_FLOOR 1e-3f
/* The coverage factor imest_comm_apply() puts on a value's std_rel (imest_commission.h). */
#define CM_COVERAGE     3.0f
enum { CM_LB_NEXT = 0, CM_LB_NSEARCH, CM_LB_I, CM_LB_LS, CM_LB_T, CM_LB_SETTLE };

/* rot_sum[] */
enum { CM_R_ID = 0, CM_R_IQ, CM_R_ND, CM_R_NQ, CM_R_UD, CM_R_UQ, CM_R_I2, CM_R_N, CM_R_WE, CM_R_COUNT };

/* Level of plateau p as a fraction of the top (1/3, 2/3, 1, 2/3, 1/3). */
static inline float cm_level(uint32_t p)
{
  const uint32_t q = p < 3u ? p + 1u : 5u - p;
  return (float)q * (1.0f / 3.0f);
}

/* The component of three phase values along axis a (0..2) in the power-invariant 3-2 transform
   (imest__clarke's alpha for a = 0). */
static inline float cm_axis_component(const float x[3], uint32_t a)
{
  return IMEST_SQRT2_3_F * (x[a] - 0.5f * (x[(a + 1u) % 3u] + x[(a + 2u) % 3u]));
}

/* The inverse of imest__clarke: phase values from alpha/beta (zero sequence 0). */
static inline void cm_clarke_inv(float xa, float xb, float x[3])
{
  x[0] = IMEST_SQRT2_3_F * xa;
  x[1] = IMEST_SQRT2_3_F * (-0.5f * xa + IMEST_HALF_SQRT3_F * xb);
  x[2] = IMEST_SQRT2_3_F * (-0.5f * xa - IMEST_HALF_SQRT3_F * xb);
}

/* n chars from src to dst, or zeroes if src is NULL (commission_init.c; no memcpy). */
void imest__cm_copy(void *dst, const void *src, size_t n);

/* ISR side (commission_isr.c and the stage files). */
void imest__cm_fail(imest_comm_t *c, int reason);
void imest__cm_post(imest_comm_t *c, uint32_t kind, uint32_t nblk);
int imest__cm_job_done(const imest_comm_t *c);
void imest__cm_set_gains(imest_comm_t *c, float sl_h);
float imest__cm_pi(imest_comm_t *c, uint32_t pat, float err, int with_p);
void imest__cm_command(imest_comm_t *c, uint32_t pat, float u_n, float vdc);
int imest__cm_current_loop(imest_comm_t *c, uint32_t pat, float err, float vdc);
void imest__cm_dc_accumulate(imest_comm_t *c, const float m[3], float v_n, float vdc);
void imest__cm_block_start(imest_comm_t *c, uint32_t tag);
void imest__cm_block_flush(imest_comm_t *c);

/* Stage entries and the end of the commanding part. */
void imest__cm_probe_begin(imest_comm_t *c);
void imest__cm_staircase_begin(imest_comm_t *c, uint32_t axis);
void imest__cm_pulses_begin(imest_comm_t *c);
void imest__cm_slip_begin(imest_comm_t *c);
void imest__cm_rotate_begin(imest_comm_t *c);
void imest__cm_finish(imest_comm_t *c);

/* Stage steps: each sets c->d_next. m: the currents (offsets and gains corrected); i_n / i_p:
   axis and perpendicular currents; v_n: the axis voltage applied over the present period. */
void imest__cm_stage_offsets(imest_comm_t *c, const float m[3], float vdc);
void imest__cm_stage_wiring(imest_comm_t *c, const float m[3], float vdc);
void imest__cm_stage_probe(imest_comm_t *c, const float m[3], float vdc, float i_n, float v_n);
void imest__cm_stage_staircase(imest_comm_t *c, const float m[3], float vdc, float i_n, float v_n);
void imest__cm_stage_pulses(imest_comm_t *c, float vdc, float i_n, float v_ended);
void imest__cm_stage_slip(imest_comm_t *c, float vdc, float i_n, float v_n);
void imest__cm_stage_demagnetise(imest_comm_t *c, float vdc, float i_n);
void imest__cm_stage_rotate(imest_comm_t *c, const float m[3], float vdc);

/* Background side. */
void imest__cm_fit_wiring(imest_comm_t *c);
void imest__cm_fit_probe(imest_comm_t *c);
void imest__cm_fit_axis(imest_comm_t *c, uint32_t axis);
void imest__cm_fit_standstill(imest_comm_t *c);
void imest__cm_fit_rotation(imest_comm_t *c);

/* Small dense least squares (float64, background): solves the n x n symmetric positive
   definite system a x = b (a overwritten by its Cholesky factor, x in b). Also returns the
   inverse's diagonal in dinv if not NULL. 0 on success, -1 if not positive definite. */
#define CM_LSQ_MAX 10
int imest__cm_chol_solve(double a[CM_LSQ_MAX][CM_LSQ_MAX], double b[CM_LSQ_MAX], unsigned int n,
                         double dinv[CM_LSQ_MAX]);

#endif /* IMEST_COMMISSION_INTERNAL_H */
