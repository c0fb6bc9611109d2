/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_temperature.h
 * @brief The motor's thermal state from the estimator's results: the stator winding's temperature
 *        from R_S and the rotor cage's from T_R, each with its uncertainty in K and a verdict, by
 *        the resistance method against references taken at a known temperature.
 *
 * Usage (once per result, in the background task that calls imest_background()):
 *
 *     imest_temperature_config_t tc;
 *     // commissioning at ambient: 21.5 degC, R_S 3.20 ohm, T_R 0.121 s; L_S 0.2908 H
 *     imest_temperature_config_default(&tc, 21.5f, 3.20f, 0.121f, 0.2908f);
 *     static imest_temperature_t tmp;
 *     if (imest_temperature_init(&tmp, &tc) != IMEST_OK) { ... }
 *     ...
 *     while (imest_background(&est, &r) == 1) {
 *       (void)imest_temperature_update(&tmp, &r);
 *       if (tmp.stator_valid) derate_on_winding(tmp.stator_c);
 *     }
 *
 * The resistance method (IEC 60034-1, determination of winding temperature by the resistance
 * method; the same relation in IEEE Std 112). A metal conductor's resistance is linear in
 * temperature over the motor's range and extrapolates to zero at -k degC, so
 *     T = (R / R_ref) (k + T_ref) - k,
 * with R_ref measured at T_ref. k = 234.5 for copper of 100 % IACS conductivity (IEEE Std 112;
 * IEC 60034-1 rounds it to 235: 0.2 K at a 100 K rise) and 225 for aluminium (both standards).
 * So R_S up 39.3 % from 20 degC is (1.393 x 254.5) - 234.5 = 120 degC, a rise of 100 K. The
 * linear-alpha form R = R_ref (1 + alpha (T - T_ref)) is the same relation with
 * alpha = 1 / (k + T_ref) (0.00393 /K for copper at 20 degC). The figure is the winding's mean
 * temperature; its hottest spot is hotter (class F: 155 degC for a 105 K rise by resistance over
 * 40 degC coolant, 10 K left for the difference).
 *
 * The stator: R = R_S of the window, R_ref = rs_ref_ohm, k = stator_k_c (default 234.5, copper).
 * R_S is the phase resistance the estimator sees: the winding plus what is in series with it
 * (cables, a shunt), which does not heat with the winding: take rs_ref_ohm with the same wiring.
 * An uncompensated inverter voltage error also moves R_S (the estimator then says rs_valid = 0,
 * or reports it in rs_bound_rel).
 *
 * The rotor: R_R = L_R / T_R (lr_h, default L_S: the estimator's model takes equal leakages,
 * L_S = L_R), and its ratio to the reference is tr_ref_s / T_R: L_R cancels. k = rotor_k_c
 * (default 225: a die-cast aluminium cage; 234.5 for a copper cage). What this assumes:
 *   - L_R is constant. It is L_m + L_lr, and L_m falls with the flux as the iron saturates: a
 *     motor run at a different flux than at the reference (field weakening, a different V/f
 *     point or load) has another L_m, and T_R moves with it with no change of temperature. A
 *     relative change d of L_R reads as a rotor temperature error of d (T + k): 1 % of L_R is
 *     3.2 K at 100 degC in aluminium. Take tr_ref_s at the flux the motor runs at; the figure is
 *     for steady flux, not for field weakening.
 *   - R_R is the cage's DC resistance, times a skin-effect factor that is taken as constant.
 *     T_R is identified at slip frequency (1-5 Hz at load). For a bar of depth h and skin depth
 *     d (die-cast aluminium: 65 mm at 2 Hz, 41 mm at 5 Hz) the AC resistance exceeds the DC one
 *     by about 4 (h/d)^4 / 45: a 20-mm bar (small motors) 0.1 % at 2 Hz, 0.5 % at 5 Hz, so
 *     R_R at slip frequency is the DC value; a 40-mm deep bar 1.3 % at 2 Hz, 8 % at 5 Hz, which
 *     is not. The factor at the reference's slip is in tr_ref_s; its change with the slip reads
 *     as temperature: d (T + k), 3.3 K per 1 % at 100 degC (a 40-mm bar referenced at 2 Hz and
 *     run at 5 Hz: +6.5 %, 21 K too warm). Take tr_ref_s at the working slip. At starting
 *     (slip 1) none of this holds.
 *   - The cage is one temperature (bars and end rings together). A die-cast cage's alloy has a
 *     k of its own: 225 is for aluminium of about 62 % IACS, and an alloy of lower conductivity
 *     has a larger k (use the rotor maker's figure if known). An error dk in k reads as
 *     dk (R/R_ref - 1): 10 in k is 4 K at a 100 K rise.
 *
 * Uncertainty, first order in the relative bounds and summed as bounds (the estimator's
 * tr_bound_rel and rs_bound_rel are bounds, the references' uncertainties too):
 *     stator_uncert_k = (stator_c + k) (rs_bound_rel + rs_ref_bound_rel) + (R_S / rs_ref) t_ref_uncert_k
 *     rotor_uncert_k  = (rotor_c + k) (tr_bound_rel / (1 - tr_bound_rel) + tr_ref_bound_rel)
 *                       + (tr_ref / T_R) t_ref_uncert_k
 * (R_R is proportional to 1/T_R: a T_R bound b is a bound b / (1 - b) on R_R.) The references'
 * defaults:
 *   - t_ref_uncert_k 1 K: the winding's temperature at commissioning is ambient's only if the
 *     motor stood unpowered for hours (a few thermal time constants): a thermometer's +-0.5 K
 *     and 0.5 K left between the motor and the air.
 *   - rs_ref_bound_rel 0.003: the mean of the estimator's valid R_S over commissioning's cold
 *     minutes (or a four-wire DC measurement, IEC 60034-1's cold resistance, 0.1-0.2 %): worth
 *     1 K of the stator's 3 K at 100 degC (0.003 x 334.5).
 *   - tr_ref_bound_rel 0.005: the mean of the estimator's valid T_R over commissioning's cold
 *     minutes; 1.6 K of the rotor's 5 K at 100 degC (0.005 x 325).
 * The tolerances (the verdicts, below):
 *   - stator_tol_k 3 K: insulation life halves per 8-10 K (Montsinger's rule), so a 3 K error
 *     is a 20-30 % error in the life consumed; and 3 K is the resistance method's own
 *     accuracy, a 1 % error of R_S at 40-60 degC. With the references' defaults it leaves
 *     (3 K - 1 K x R/R_ref) / (T + k) - 0.003 for the window's R_S bound: 0.5 % at 20 degC,
 *     0.2 % at 100 degC, much stricter than rs_tolerance (5 %). The estimator's R_S bound is
 *     conservative: in the simulated heat run (tools/demo, exp2) rs_bound_rel is 1.3-1.5 %, a
 *     stated 5.5-6 K, while the stator temperature's actual error stays within 1.2 K, so no
 *     stator temperature there is valid at 3 K. Where the drive's R_S bound is known to be that
 *     conservative, a stator_tol_k of 6-7 K passes those windows (the figure is then as good as
 *     its actual error, not as its stated one).
 *   - rotor_tol_k 5 K: the rotor carries no insulation; its temperature serves T_R's correction
 *     and thermal protection, whose trip margins are 10 K or more. It leaves 1.1 % for the
 *     window's T_R bound at 20 degC, 0.6 % at 100 degC (tr_tolerance is 2 %, imest.h); in the
 *     heat run the bound is 0.06 % and the stated uncertainty 2.4-3.2 K, mostly the references'.
 *
 * Verdicts: stator_valid iff rs_valid, R_S and rs_bound_rel finite with R_S > 0 and the bound
 * >= 0, and stator_uncert_k <= stator_tol_k; rotor_valid the same with tr_valid, T_R,
 * tr_bound_rel (< 1) and rotor_tol_k. A temperature that is not valid keeps its number (NaN if it
 * could not be computed), as the estimator's results do.
 *
 * On CAN: the frame IMEST_TEMP at base + 6 (tools/imest.dbc, port/README.md), sent after the
 * window's six frames (imest_can.h) with the same rolling counter, so that a receiver can match
 * it with them (imest-monitor --temperatures does):
 *
 *     (void)imest_can_publish(&can, &r);
 *     (void)imest_temperature_update(&tmp, &r);
 *     (void)imest_temperature_can_publish(&can, &tmp);   // IMEST_TEMP, same counter as r's frames
 *
 * Optional: a firmware that does not call it sends the six frames only, and readers of the six
 * (imest_can_rx_feed(), imest_can_decode_frame()) classify base + 6 as foreign and ignore it.
 * Below: its layout, the packer, the publisher and the decoder.
 *
 * Numeric behaviour: float32 arithmetic and outputs (the result's double T_R, R_S and bounds are
 * converted to float first), no libm call but the isfinite and isnan macros, no malloc, no stdio,
 * no global state; the instance is caller-owned (CMSIS-DSP style) and used from one context (the
 * background task). Not linked by the estimator: a firmware that does not call it pays no flash
 * for it (fw/README.md states its size; a sending firmware built with --gc-sections does not link
 * the decoder either). Its CAN functions need the types of imest_can.h but no code of src/can/.
 */
#ifndef IMEST_IMEST_TEMPERATURE_H
#define IMEST_IMEST_TEMPERATURE_H

#include <stdint.h>

#include "imest/imest.h"
#include "imest/imest_can.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Configuration. Fill with imest_temperature_config_default(). */
typedef struct {
  /** the references' temperature [degC]: ambient at commissioning, the motor at rest long enough
   *  to be at ambient. In [-60, 200] */
  float t_ref_c;
  /** uncertainty of t_ref_c [K] (default 1: above). In [0, 50] */
  float t_ref_uncert_k;
  /** R_S at t_ref_c [ohm], as the estimator sees it (same wiring). > 0 and finite */
  float rs_ref_ohm;
  /** relative uncertainty of rs_ref_ohm (default 0.003: above). In [0, 0.5] */
  float rs_ref_bound_rel;
  /** T_R at t_ref_c [s]. > 0 and finite */
  float tr_ref_s;
  /** relative uncertainty of tr_ref_s (default 0.005: above). In [0, 0.5] */
  float tr_ref_bound_rel;
  /** rotor inductance L_R [H], for rr_ohm only (default: L_S given to the default, equal
   *  leakages). > 0 and finite */
  float lr_h;
  /** the stator conductor's k [degC] (default 234.5, copper; 225 aluminium). In [100, 1000] */
  float stator_k_c;
  /** the rotor cage's k [degC] (default 225, aluminium; 234.5 copper). In [100, 1000] */
  float rotor_k_c;
  /** largest stator_uncert_k of a valid stator temperature [K] (default 3: above). In (0, 1000] */
  float stator_tol_k;
  /** largest rotor_uncert_k of a valid rotor temperature [K] (default 5: above). In (0, 1000] */
  float rotor_tol_k;
} imest_temperature_config_t;

/** The module: the latest result's temperatures (read-only for the caller) and the config. */
typedef struct {
  float stator_c;        /**< stator winding's mean temperature [degC] (NaN: R_S not usable) */
  float stator_uncert_k; /**< its uncertainty [K] (above; NaN with stator_c) */
  int stator_valid;      /**< 1: stator_c can be trusted (above) */
  float rr_ohm;          /**< rotor resistance L_R / T_R [ohm] (NaN: T_R not usable) */
  float rotor_c;         /**< rotor cage's temperature [degC] (NaN: T_R not usable) */
  float rotor_uncert_k;  /**< its uncertainty [K] (above; NaN with rotor_c) */
  int rotor_valid;       /**< 1: rotor_c can be trusted (above) */
  double t_end_s;        /**< the result's t_end_s (0 before the first) */
  uint32_t updates;      /**< results taken since init */

  imest_temperature_config_t cfg;
} imest_temperature_t;

/** Fill a config with the defaults above and the given references: t_ref_c [degC], rs_ref_ohm
 *  [ohm] and tr_ref_s [s] at that temperature, and L_S [H] (lr_h = ls_h). Every field is
 *  written. Does nothing if cfg is NULL. */
void imest_temperature_config_default(imest_temperature_config_t *cfg, float t_ref_c, float rs_ref_ohm,
                                      float tr_ref_s, float ls_h);

/** Check a config.
 *  @param field  optional: receives the name of the first bad field (NULL if none)
 *  @retval IMEST_OK          the config is usable
 *  @retval IMEST_ERR_NULL    cfg is NULL
 *  @retval IMEST_ERR_CONFIG  a field is out of the range documented above (*field names it) */
int imest_temperature_config_check(const imest_temperature_config_t *cfg, const char **field);

/** Initialise (or restart): every temperature NaN and not valid, t_end_s 0, updates 0. The config
 *  is copied.
 *  @retval IMEST_OK          initialised
 *  @retval IMEST_ERR_NULL    t or cfg is NULL (t unchanged)
 *  @retval IMEST_ERR_CONFIG  a config field is out of range (t unchanged;
 *                            imest_temperature_config_check() names it) */
int imest_temperature_init(imest_temperature_t *t, const imest_temperature_config_t *cfg);

/**
 * Compute the temperatures of one result of imest_background(), valid or not (each result on its
 * own: no filtering across windows). stator_c and its uncertainty are computed iff R_S is finite
 * and > 0 and rs_bound_rel finite and >= 0, else NaN; rotor_c, rr_ohm and its uncertainty iff
 * T_R is finite and > 0 and tr_bound_rel finite and in [0, 1), else NaN. The verdicts as above.
 *
 * @retval 0..3            which temperatures are valid: bit 0 the stator, bit 1 the rotor
 * @retval IMEST_ERR_NULL  t or r is NULL (nothing changes)
 */
int imest_temperature_update(imest_temperature_t *t, const imest_result_t *r);

/* ----------------------------------------------------------------------------
 * IMEST_TEMP: the temperatures on CAN (frame index 6, identifier base + 6)
 * ------------------------------------------------------------------------- */

/** IMEST_TEMP's frame index: its identifier is base_id + 6 (29-bit: (base + 6) | IMEST_CAN_ID_EXT,
 *  as the six frames of imest_can.h). Nodes are IMEST_CAN_ID_STRIDE (8) apart, so base + 6 is
 *  free. The index is also the first octet the CRC covers. */
#define IMEST_TEMPERATURE_CAN_FRAME 6u

/** The layout (Intel byte order, DBC start bits; tools/imest.dbc, port/README.md):
 *   bits  0..15 Stator_C        int16, 0.01 degC; -327.67 .. 327.67; raw -32768 = not available
 *                               (NaN); beyond the range clamped to +-32767 (a bound: "or more")
 *   bits 16..31 Rotor_C         the same for the rotor
 *   bits 32..38 Stator_uncert_K u7, 0.2 K; 0 .. 25.0 K in raw 0..125, rounded to the nearest
 *                               0.2 K; raw 126 = 25.2 K or more (clamped); 127 = not available
 *   bit  39     Stator_valid    stator_valid
 *   bits 40..46 Rotor_uncert_K  as Stator_uncert_K
 *   bit  47     Rotor_valid     rotor_valid
 *   bits 48..55 Counter         the rolling counter of the window the temperatures come from
 *   bits 56..63 CRC             CRC-8 SAE J1850 over [6, bytes 0..6] (imest_can_crc8()) */
#define IMEST_TEMPERATURE_CAN_STATOR_C_START      0u
#define IMEST_TEMPERATURE_CAN_ROTOR_C_START       16u
#define IMEST_TEMPERATURE_CAN_C_BITS              16u
#define IMEST_TEMPERATURE_CAN_C_SCALE             100 /**< raw counts per degC */
#define IMEST_TEMPERATURE_CAN_C_NA                (-32768)
#define IMEST_TEMPERATURE_CAN_C_MAX               32767 /**< largest raw (-this: the smallest) */
#define IMEST_TEMPERATURE_CAN_STATOR_UNCERT_START 32u
#define IMEST_TEMPERATURE_CAN_STATOR_VALID_START  39u
#define IMEST_TEMPERATURE_CAN_ROTOR_UNCERT_START  40u
#define IMEST_TEMPERATURE_CAN_ROTOR_VALID_START   47u
#define IMEST_TEMPERATURE_CAN_UNCERT_BITS         7u
#define IMEST_TEMPERATURE_CAN_UNCERT_SCALE        5   /**< raw counts per K (0.2 K) */
#define IMEST_TEMPERATURE_CAN_UNCERT_NA           127 /**< not available */
#define IMEST_TEMPERATURE_CAN_UNCERT_MAX          126 /**< 25.2 K or more */

/** imest_temperature_can_t.clamped: the value was at its field's end, so it is a bound ("327.67
 *  or more", "25.2 K or more"), not a value. */
#define IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C      0x1u
#define IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT 0x2u
#define IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C       0x4u
#define IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_UNCERT  0x8u

/** One IMEST_TEMP frame, decoded. */
typedef struct {
  float stator_c;        /**< [degC], to 0.01 (NaN: not available) */
  float stator_uncert_k; /**< [K], to 0.2 (NaN: not available) */
  int stator_valid;      /**< 0 or 1 */
  float rotor_c;         /**< [degC] (NaN: not available) */
  float rotor_uncert_k;  /**< [K] (NaN: not available) */
  int rotor_valid;       /**< 0 or 1 */
  unsigned int counter;  /**< rolling counter (0..255): that of the window's six frames */
  unsigned int clamped;  /**< IMEST_TEMPERATURE_CAN_CLAMP_* of the values at their field's end */
} imest_temperature_can_t;

/**
 * Pack t's temperatures into IMEST_TEMP (id base_id + 6, dlc 8). Temperatures are rounded to the
 * nearest 0.01 degC and uncertainties to the nearest 0.2 K; NaN is sent as not available, values
 * beyond a field's range (+-inf too) as its end: +-327.67 degC, 25.2 K (a negative uncertainty,
 * which the module does not produce, as 0). A valid bit is sent as 1 iff the module's is nonzero.
 * @param counter  the rolling counter of the window t was updated from (sent mod 256): right
 *                 after imest_can_publish(pub, r), pub->counter - 1 (imest_can_publish() advances
 *                 it by one per window); imest_temperature_can_publish() does this
 * @retval IMEST_OK        *f holds the frame
 * @retval IMEST_ERR_NULL  t or f is NULL
 * @retval IMEST_ERR_ARG   base_id + 6 is not an identifier of base_id's kind (11-bit: base_id
 *                         <= 0x7F9; 29-bit: <= 0x1FFFFFF9 | IMEST_CAN_ID_EXT), or bits other than
 *                         IMEST_CAN_ID_EXT are set above the identifier
 */
int imest_temperature_can_pack(const imest_temperature_t *t, uint32_t base_id, unsigned int counter,
                               imest_can_frame_t *f);

/**
 * Send IMEST_TEMP through pub's port, with the counter of the window pub published last
 * (pub->counter - 1): call it after imest_can_publish() of the window t was updated from, before
 * the next one. Handed once to port->send (no retry); a refusal is counted in pub->tx_failed (and
 * so in the next window's IMEST_STAT). Background context only, as imest_can_publish(). Before
 * the first imest_can_publish() the counter sent is 255. tx_failed saturates as imest_can_publish()'s.
 * @retval 0               sent
 * @retval 1               the port refused it (counted)
 * @retval IMEST_ERR_NULL  pub or t is NULL, or pub was not initialised
 * @retval IMEST_ERR_ARG   pub->base_id has no base + 6 (imest_temperature_can_pack())
 */
int imest_temperature_can_publish(imest_can_pub_t *pub, const imest_temperature_t *t);

/**
 * Check one frame and decode it if it is IMEST_TEMP of the node at base_id, the conventions of
 * imest_can_decode_frame(): the identifier must be base_id + 6 of base_id's kind (anything else,
 * the six frames base..base+5 too, is foreign), then 8 data bytes, then the CRC. A not-available
 * raw value decodes as NaN; a value at its field's end sets its bit in out->clamped.
 * @retval IMEST_CAN_DEC_OK       *out holds the frame's values
 * @retval IMEST_CAN_DEC_FOREIGN  not IMEST_TEMP of this node (*out unchanged)
 * @retval IMEST_CAN_DEC_BAD_DLC  IMEST_TEMP, but not 8 data bytes (*out unchanged)
 * @retval IMEST_CAN_DEC_BAD_CRC  IMEST_TEMP, checksum mismatch (*out unchanged)
 * @retval IMEST_ERR_NULL         f or out is NULL
 * @retval IMEST_ERR_ARG          base_id has no base + 6 (as imest_temperature_can_pack())
 */
int imest_temperature_can_decode(const imest_can_frame_t *f, uint32_t base_id, imest_temperature_can_t *out);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_TEMPERATURE_H */
