/* SPDX-License-Identifier: Apache-2.0 */
/* Background: the motor's steady-state impedance at a window's operating
 * point, and how the estimate moves when what the fit matches (the measured
 * impedance) or what it assumes (the constants L_S and sigma) is off
 * (docs/METHOD.md §18.1). One place for the error bounds of bg_validity.c and
 * any correction of the estimate. float32: every use is a relative figure.
 * Internal: not part of the public API. */
#ifndef IMEST_BG_IMPEDANCE_H
#define IMEST_BG_IMPEDANCE_H

#include <math.h>

/* Z = R_S + j we L_S (1 + j sigma a) / (1 + j a), a = ws T_R, and
 * dZ/dT_R = we L_S ws (1 - sigma) / (1 + j a)^2. */
typedef struct {
  float zr, zi; /* Z [ohm] */
  float zm_r;   /* Re Z - R_S: the rotor's share of the real part [ohm] */
  float dr, di; /* dZ/dT_R [ohm/s] */
  float a;      /* ws T_R */
  float x_ls;   /* we L_S [ohm] */
} bg_impedance_t;

/* we: stator frequency, ws: slip frequency [rad/s] (signed alike); ls, sg:
 * the constants; tr, rs: the estimate. */
static inline void imest__bg_impedance(float we, float ws, float ls, float sg, float tr, float rs,
                                       bg_impedance_t *z)
{
  const float a = ws * tr, den = 1.0f + a * a;
  z->a = a;
  z->x_ls = we * ls;
  z->zm_r = we * ls * (a * (1.0f - sg)) / den;
  z->zr = rs + z->zm_r;
  z->zi = we * ls * (1.0f + sg * a * a) / den;
  const float k = we * ls * ws * (1.0f - sg) / (den * den);
  z->dr = k * (1.0f - a * a);
  z->di = k * (-2.0f * a);
}

/* How far the estimate moves, to first order, when the configured constants
 * are off: L_S configured (1 + e_ls) times the motor's, sigma (1 + e_sg)
 * times. The fit matches the measured Z with the configured constants, so
 * dR_S + dZ/dT_R dT_R = -(dZ/dL_S dL_S + dZ/dsigma dsigma), with
 * dZ/dL_S dL_S = (Z - R_S) e_ls and
 * dZ/dsigma dsigma = -we L_S sigma e_sg a (1 - j a) / (1 + a^2).
 * *d_tr_rel, *d_rs_rel: the signed relative moves of T_R and R_S (the
 * estimate minus the motor's, over the motor's). Checked against the exact
 * solution of the impedance equations on the 4 kW motor at 50 Hz: within
 * 25 % of the move for 10 % on L_S at a = 0.25 .. 1 (T_R at a = 1: exact
 * +10.9 / -11.9 %, first order +-11.4 %), within 3 % for 20 % on sigma. */
static inline void imest__bg_constants_shift(const bg_impedance_t *z, float sg, float e_ls, float e_sg,
                                             float tr, float rs, float *d_tr_rel, float *d_rs_rel)
{
  const float den = 1.0f + z->a * z->a;
  const float c = z->x_ls * sg * e_sg * z->a / den;
  const float dzr = z->zm_r * e_ls - c;
  const float dzi = z->zi * e_ls + c * z->a;
  /* no slip: T_R moves without bound unless nothing moves it */
  const float dt = z->di != 0.0f ? -dzi / z->di : (dzi != 0.0f ? INFINITY : 0.0f);
  *d_tr_rel = dt / tr;
  *d_rs_rel = (-dzr - z->dr * dt) / rs;
}

#endif /* IMEST_BG_IMPEDANCE_H */
