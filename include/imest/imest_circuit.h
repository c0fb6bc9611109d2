/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_circuit.h
 * @brief The estimator's motor constants (L_S, sigma, T_R; R_S) from an equivalent circuit per
 *        phase, as data sheets and drive parameter lists print it.
 *
 * Usage (once, at set-up; nothing here runs per sample or per window):
 *
 *     imest_circuit_t c = {.lm_h = 0.27649f, .lls_h = 0.01431f, .llr_h = 0.01431f,
 *                          .rr_ohm = 2.4233f, .rs_ohm = 5.04f};  // the paper's motor
 *     imest_circuit_constants_t k;     // L_S = L_R = 0.2908 H, sigma = 0.096, T_R = 0.12 s
 *     if (imest_circuit_from_t(&c, &k) == IMEST_OK) (void)imest_circuit_apply(&k, &cfg);
 *     // cfg.ls_h, cfg.sigma, cfg.tr_nominal_s (and tr_nominal_known), cfg.rs_nominal_ohm
 *
 * The T-equivalent circuit: stator resistance R_S, stator leakage L_ls, magnetising L_m, rotor
 * leakage L_lr and rotor resistance R_R (the rotor referred to the stator). Then
 *     L_S = L_m + L_ls,  L_R = L_m + L_lr,  sigma = 1 - L_m^2 / (L_S L_R),  T_R = L_R / R_R.
 * Motor makers' electrical data sheets print it per phase as resistances and reactances at the
 * rated frequency (R1, X1 or X1sigma, R2', X2' or X2sigma', Xh or Xm at 50 or 60 Hz);
 * so do drive parameter lists (e.g. Danfoss VLT: stator resistance Rs, rotor resistance Rr,
 * stator and rotor leakage reactances X1, X2, main reactance Xh, "line to common"). A reactance
 * is X = 2 pi f L at the frequency f it is given for: imest_circuit_from_x() takes them so.
 *
 * The inverse-Gamma circuit: R_S, a total leakage L_sigma on the stator side, a magnetising L_M
 * and a rotor resistance R_R' (Slemon, IEEE Trans. Ind. Appl. 1989). It is the T circuit with the
 * rotor referred by L_m / L_R instead of the turns ratio, which moves all leakage to the stator:
 *     L_M = L_m^2 / L_R,  L_sigma = sigma L_S,  R_R' = (L_m / L_R)^2 R_R,
 * so L_S = L_sigma + L_M, sigma = L_sigma / L_S and T_R = L_M / R_R' exactly, without knowing how
 * the leakage splits between stator and rotor. Drive identification runs (a standstill test can
 * separate only these four) and much of the control literature give it; the T circuit's split of
 * the leakage (a convention: IEEE Std 112 splits it by NEMA design class, half and half for
 * designs A and D) does not change L_S, sigma or T_R either.
 *
 * Conventions: every value is per phase of the equivalent star (Y). A resistance measured between
 * two terminals is 2 R_S for a star and 2/3 R_S(delta phase) for a delta; the per-phase
 * impedances of a delta-connected winding are 3 times those of its equivalent star. sigma and T_R
 * are ratios, the same in either; L_S and R_S are not. The estimator's L_S is per phase (its 3-2
 * transform is power invariant, docs/METHOD.md §1). T_R holds at the temperature R_R is given for:
 * data sheets give it cold (20 or 25 C) or warm (at the rated temperature rise, e.g. 95 or 115 C):
 * the nominal T_R at ambient is T_R_warm (1 + alpha (T_warm - T_amb)), alpha = 0.0039 /K.
 *
 * Numeric behaviour: float32 in and out; sigma is computed as (L_ls L_m + L_lr L_m + L_ls L_lr) /
 * (L_S L_R), which has no cancellation (1 - L_m^2/(L_S L_R) loses about log10(1/sigma) digits).
 * Results are within a few float32 ulps of the exact values. No libm call, no malloc, no stdio.
 */
#ifndef IMEST_IMEST_CIRCUIT_H
#define IMEST_IMEST_CIRCUIT_H

#include "imest/imest.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The T-equivalent circuit per phase, inductances. */
typedef struct {
  float lm_h;   /**< magnetising inductance L_m [H] (> 0) */
  float lls_h;  /**< stator leakage inductance L_ls [H] (> 0) */
  float llr_h;  /**< rotor leakage inductance L_lr, referred to the stator [H] (> 0) */
  float rr_ohm; /**< rotor resistance R_R, referred to the stator [ohm] (> 0) */
  float rs_ohm; /**< stator resistance R_S [ohm] (>= 0; 0: not given) */
} imest_circuit_t;

/** The T-equivalent circuit per phase, reactances at a frequency (as data sheets print it). */
typedef struct {
  float f_hz;    /**< the frequency the reactances are given for [Hz] (> 0; 50 or 60 usually) */
  float xm_ohm;  /**< magnetising (main) reactance X_m = 2 pi f L_m [ohm] (> 0) */
  float xls_ohm; /**< stator leakage reactance [ohm] (> 0) */
  float xlr_ohm; /**< rotor leakage reactance, referred to the stator [ohm] (> 0) */
  float rr_ohm;  /**< rotor resistance, referred to the stator [ohm] (> 0) */
  float rs_ohm;  /**< stator resistance [ohm] (>= 0; 0: not given) */
} imest_circuit_x_t;

/** The inverse-Gamma circuit per phase. */
typedef struct {
  float lm_h;   /**< magnetising inductance L_M = L_m^2 / L_R [H] (> 0) */
  float lsig_h; /**< total leakage inductance L_sigma = sigma L_S [H] (> 0) */
  float rr_ohm; /**< rotor resistance R_R' = (L_m / L_R)^2 R_R [ohm] (> 0) */
  float rs_ohm; /**< stator resistance R_S [ohm] (>= 0; 0: not given) */
} imest_circuit_inv_gamma_t;

/** What the estimator takes, and the rest of the T circuit. */
typedef struct {
  float ls_h;   /**< stator inductance L_S [H] (imest_config_t.ls_h) */
  float sigma;  /**< total leakage factor, in (0, 1) (imest_config_t.sigma) */
  float tr_s;   /**< rotor time constant T_R = L_R / R_R [s] (imest_config_t.tr_nominal_s) */
  float rs_ohm; /**< stator resistance [ohm] (0: not given) (imest_config_t.rs_nominal_ohm) */
  float lr_h;   /**< rotor inductance L_R [H] (inverse-Gamma: L_M, the rotor referred by L_m / L_R) */
  float lm_h;   /**< magnetising inductance L_m [H] (inverse-Gamma: L_M) */
} imest_circuit_constants_t;

/** From the T circuit (inductances).
 *  @retval IMEST_OK        *k filled
 *  @retval IMEST_ERR_NULL  c or k is NULL
 *  @retval IMEST_ERR_ARG   a field is not finite, or not > 0 (rs_ohm: < 0), or a result is not
 *                          finite (*k unchanged) */
int imest_circuit_from_t(const imest_circuit_t *c, imest_circuit_constants_t *k);

/** From the T circuit given as reactances at x->f_hz: L = X / (2 pi f), then as
 *  imest_circuit_from_t(). @retval as imest_circuit_from_t() (f_hz included in the checks) */
int imest_circuit_from_x(const imest_circuit_x_t *x, imest_circuit_constants_t *k);

/** From the inverse-Gamma circuit: L_S = L_sigma + L_M, sigma = L_sigma / L_S, T_R = L_M / R_R',
 *  lr_h = lm_h = L_M. @retval as imest_circuit_from_t() */
int imest_circuit_from_inv_gamma(const imest_circuit_inv_gamma_t *g, imest_circuit_constants_t *k);

/** Fill an estimator config: ls_h, sigma, tr_nominal_s with tr_nominal_known = 1 (the motor's own
 *  T_R, imest.h), and rs_nominal_ohm if k->rs_ohm > 0 (pass the R_S at ambient temperature). The
 *  other fields stay as they are; imest_config_check() still judges the whole.
 *  @retval IMEST_OK        filled
 *  @retval IMEST_ERR_NULL  k or cfg is NULL
 *  @retval IMEST_ERR_ARG   k's ls_h or tr_s is not finite and > 0, sigma not in (0, 1), or rs_ohm
 *                          < 0 or not finite: nothing filled */
int imest_circuit_apply(const imest_circuit_constants_t *k, imest_config_t *cfg);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_CIRCUIT_H */
