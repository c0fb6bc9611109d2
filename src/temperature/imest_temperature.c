/* SPDX-License-Identifier: Apache-2.0 */
/* The stator's and the rotor's temperatures from the estimator's results, by the resistance method
 * (include/imest/imest_temperature.h: the relation, its assumptions and the defaults), and their
 * CAN frame IMEST_TEMP (packer, publisher, decoder). Runs once per window in the background task:
 * -Os like the rest of the once-per-window code (src/CMakeLists.txt). float32 arithmetic, no libm. */
#include "imest/imest_temperature.h"

#include <math.h>
#include <stddef.h>

#include "common/imest_range.h"

void imest_temperature_config_default(imest_temperature_config_t *cfg, float t_ref_c, float rs_ref_ohm,
                                      float tr_ref_s, float ls_h)
{
  if (cfg == NULL) return;
  cfg->t_ref_c = t_ref_c;
  cfg->t_ref_uncert_k = 1.0f;
  cfg->rs_ref_ohm = rs_ref_ohm;
  cfg->rs_ref_bound_rel = 0.003f;
  cfg->tr_ref_s = tr_ref_s;
  cfg->tr_ref_bound_rel = 0.005f;
  cfg->lr_h = ls_h;
  cfg->stator_k_c = 234.5f;
  cfg->rotor_k_c = 225.0f;
  cfg->stator_tol_k = 3.0f;
  cfg->rotor_tol_k = 5.0f;
}

int imest_temperature_config_check(const imest_temperature_config_t *cfg, const char **field)
{
  const char *bad = NULL;
  if (cfg == NULL) {
    if (field) *field = "cfg";
    return IMEST_ERR_NULL;
  }
  if (!imest__in_range(cfg->t_ref_c, -60.0f, 0, 200.0f))
    bad = "t_ref_c";
  else if (!imest__in_range(cfg->t_ref_uncert_k, 0.0f, 0, 50.0f))
    bad = "t_ref_uncert_k";
  else if (!imest__in_range(cfg->rs_ref_ohm, 0.0f, 1, 3.0e38f))
    bad = "rs_ref_ohm";
  else if (!imest__in_range(cfg->rs_ref_bound_rel, 0.0f, 0, 0.5f))
    bad = "rs_ref_bound_rel";
  else if (!imest__in_range(cfg->tr_ref_s, 0.0f, 1, 3.0e38f))
    bad = "tr_ref_s";
  else if (!imest__in_range(cfg->tr_ref_bound_rel, 0.0f, 0, 0.5f))
    bad = "tr_ref_bound_rel";
  else if (!imest__in_range(cfg->lr_h, 0.0f, 1, 3.0e38f))
    bad = "lr_h";
  else if (!imest__in_range(cfg->stator_k_c, 100.0f, 0, 1000.0f))
    bad = "stator_k_c";
  else if (!imest__in_range(cfg->rotor_k_c, 100.0f, 0, 1000.0f))
    bad = "rotor_k_c";
  else if (!imest__in_range(cfg->stator_tol_k, 0.0f, 1, 1000.0f))
    bad = "stator_tol_k";
  else if (!imest__in_range(cfg->rotor_tol_k, 0.0f, 1, 1000.0f))
    bad = "rotor_tol_k";
  if (field) *field = bad;
  return bad == NULL ? IMEST_OK : IMEST_ERR_CONFIG;
}

int imest_temperature_init(imest_temperature_t *t, const imest_temperature_config_t *cfg)
{
  if (t == NULL || cfg == NULL) return IMEST_ERR_NULL;
  if (imest_temperature_config_check(cfg, NULL) != IMEST_OK) return IMEST_ERR_CONFIG;
  t->cfg = *cfg;
  t->stator_c = NAN;
  t->stator_uncert_k = NAN;
  t->stator_valid = 0;
  t->rr_ohm = NAN;
  t->rotor_c = NAN;
  t->rotor_uncert_k = NAN;
  t->rotor_valid = 0;
  t->t_end_s = 0.0;
  t->updates = 0u;
  return IMEST_OK;
}

/* T = ratio (k + T_ref) - k and its uncertainty (T + k) ratio_bound + ratio u_ref: the resistance
   method (the header), for a resistance ratio R / R_ref with relative bound ratio_bound. */
static float resistance_method(const imest_temperature_config_t *c, float ratio, float k, float ratio_bound,
                               float *uncert_k)
{
  const float temp_c = ratio * (k + c->t_ref_c) - k;
  *uncert_k = (temp_c + k) * ratio_bound + ratio * c->t_ref_uncert_k;
  return temp_c;
}

int imest_temperature_update(imest_temperature_t *t, const imest_result_t *r)
{
  if (t == NULL || r == NULL) return IMEST_ERR_NULL;
  const imest_temperature_config_t *c = &t->cfg;
  int valid = 0;

  const float rs = (float)r->rs_ohm;
  const float rs_b = (float)r->rs_bound_rel;
  t->stator_c = NAN;
  t->stator_uncert_k = NAN;
  t->stator_valid = 0;
  if (isfinite(rs) && rs > 0.0f && isfinite(rs_b) && rs_b >= 0.0f) {
    t->stator_c = resistance_method(c, rs / c->rs_ref_ohm, c->stator_k_c, rs_b + c->rs_ref_bound_rel,
                                    &t->stator_uncert_k);
    t->stator_valid = (r->rs_valid && t->stator_uncert_k <= c->stator_tol_k) ? 1 : 0;
  }

  const float tr = (float)r->tr_s;
  const float tr_b = (float)r->tr_bound_rel;
  t->rr_ohm = NAN;
  t->rotor_c = NAN;
  t->rotor_uncert_k = NAN;
  t->rotor_valid = 0;
  if (isfinite(tr) && tr > 0.0f && isfinite(tr_b) && tr_b >= 0.0f && tr_b < 1.0f) {
    t->rr_ohm = c->lr_h / tr;
    /* R_R / R_R,ref = T_R,ref / T_R (L_R cancels); a bound b on T_R is b / (1 - b) on 1 / T_R */
    t->rotor_c = resistance_method(c, c->tr_ref_s / tr, c->rotor_k_c,
                                   tr_b / (1.0f - tr_b) + c->tr_ref_bound_rel, &t->rotor_uncert_k);
    t->rotor_valid = (r->tr_valid && t->rotor_uncert_k <= c->rotor_tol_k) ? 1 : 0;
  }

  if (t->stator_valid) valid |= 1;
  if (t->rotor_valid) valid |= 2;
  t->t_end_s = r->t_end_s;
  t->updates++;
  return valid;
}

/* --- IMEST_TEMP: the temperatures on CAN (the header's layout) --------------------------------- */

/* Every field is whole octets but the valid bits (bit 7 of octets 4 and 5), so the frame is packed
 * octet by octet: one octet (0..255) per element, as the codec of imest_can.h. The clamp bits of
 * a temperature and of its uncertainty are neighbours (dec_temp()). */
_Static_assert(IMEST_TEMPERATURE_CAN_STATOR_C_START == 0u && IMEST_TEMPERATURE_CAN_ROTOR_C_START == 16u &&
                   IMEST_TEMPERATURE_CAN_STATOR_UNCERT_START == 32u &&
                   IMEST_TEMPERATURE_CAN_STATOR_VALID_START == 39u &&
                   IMEST_TEMPERATURE_CAN_ROTOR_UNCERT_START == 40u &&
                   IMEST_TEMPERATURE_CAN_ROTOR_VALID_START == 47u && IMEST_CAN_COUNTER_START == 48u &&
                   IMEST_CAN_CRC_START == 56u &&
                   IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT == IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C << 1 &&
                   IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_UNCERT == IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C << 1,
               "IMEST_TEMP: the octets below follow the header's layout");

/* 1 iff base_id + 6 is an identifier of base_id's kind; *id receives it. */
static int temp_frame_id(uint32_t base_id, uint32_t *id)
{
  const uint32_t ext = base_id & IMEST_CAN_ID_EXT;
  const uint32_t b = base_id & ~IMEST_CAN_ID_EXT;
  const uint32_t last = ext ? IMEST_CAN_EFF_MASK : IMEST_CAN_SFF_MASK;
  if (b > last - IMEST_TEMPERATURE_CAN_FRAME) return 0;
  *id = (b + IMEST_TEMPERATURE_CAN_FRAME) | ext;
  return 1;
}

/* CRC-8 SAE J1850 (poly 0x1D, init 0xFF, xor-out 0xFF) over [frame index, octets 0..6], as every
 * frame of imest_can.h. The module's own copy of imest_can_crc8() (test/can checks the two agree),
 * so that src/temperature links without src/can, as the optional folders do. */
static unsigned int temp_crc(const unsigned char *d)
{
  unsigned int crc = 0xFFu;
  for (unsigned int i = 0u; i < 8u; i++) {
    crc ^= i == 0u ? IMEST_TEMPERATURE_CAN_FRAME : (unsigned int)d[i - 1u] & 0xFFu;
    for (unsigned int b = 0u; b < 8u; b++)
      crc = (crc & 0x80u) ? (((crc << 1) ^ 0x1Du) & 0xFFu) : ((crc << 1) & 0xFFu);
  }
  return crc ^ 0xFFu;
}

/* One temperature's field pair: degC -> raw int16 (nearest 0.01, clamped to +-32767, NaN -> -32768)
 * into octets d[0], d[1]; K -> raw u7 (nearest 0.2 K, clamped to 0..126, NaN -> 127) with the valid
 * bit on top into *u. */
static void enc_temp(float c, float k, int valid, unsigned char *d, unsigned char *u)
{
  uint32_t raw = 0x8000u;
  if (!isnan(c)) {
    const float x = c * (float)IMEST_TEMPERATURE_CAN_C_SCALE;
    int32_t v = IMEST_TEMPERATURE_CAN_C_MAX;
    if (x < (float)-IMEST_TEMPERATURE_CAN_C_MAX)
      v = -IMEST_TEMPERATURE_CAN_C_MAX;
    else if (x < (float)IMEST_TEMPERATURE_CAN_C_MAX)
      v = (int32_t)(x >= 0.0f ? x + 0.5f : x - 0.5f);
    raw = (uint32_t)v & 0xFFFFu;
  }
  d[0] = (unsigned char)(raw & 0xFFu);
  d[1] = (unsigned char)((raw >> 8) & 0xFFu);
  unsigned int r = (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_NA;
  if (!isnan(k)) {
    const float x = k * (float)IMEST_TEMPERATURE_CAN_UNCERT_SCALE + 0.5f;
    r = !(k > 0.0f)                                    ? 0u
        : x >= (float)IMEST_TEMPERATURE_CAN_UNCERT_MAX ? (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_MAX
                                                       : (unsigned int)x;
  }
  *u = (unsigned char)((r | (valid ? 0x80u : 0u)) & 0xFFu);
}

int imest_temperature_can_pack(const imest_temperature_t *t, uint32_t base_id, unsigned int counter,
                               imest_can_frame_t *f)
{
  uint32_t id = 0u;
  if (t == NULL || f == NULL) return IMEST_ERR_NULL;
  if (!temp_frame_id(base_id, &id)) return IMEST_ERR_ARG;
  f->id = id;
  f->dlc = 8u;
  enc_temp(t->stator_c, t->stator_uncert_k, t->stator_valid, &f->data[0], &f->data[4]);
  enc_temp(t->rotor_c, t->rotor_uncert_k, t->rotor_valid, &f->data[2], &f->data[5]);
  f->data[6] = (unsigned char)(counter & 0xFFu);
  f->data[7] = (unsigned char)(temp_crc(f->data) & 0xFFu);
  return IMEST_OK;
}

int imest_temperature_can_publish(imest_can_pub_t *pub, const imest_temperature_t *t)
{
  imest_can_frame_t f;
  if (pub == NULL || t == NULL || pub->port == NULL || pub->port->send == NULL) return IMEST_ERR_NULL;
  const int rc = imest_temperature_can_pack(t, pub->base_id, (unsigned int)((pub->counter - 1u) & 0xFFu), &f);
  if (rc != IMEST_OK) return rc;
  if (pub->port->send(pub->port->ctx, &f) == 0) return 0;
  if (pub->tx_failed != 0xFFFFFFFFu) pub->tx_failed++;
  return 1;
}

/* One temperature's field pair back (enc_temp()): *c, *k and *valid from octets d[0], d[1] and u;
 * NaN for not available; at a field's end the clamp bits (clamp_c, clamp_c << 1) in *clamped. */
static void dec_temp(const unsigned char *d, unsigned int u, float *c, float *k, int *valid,
                     unsigned int *clamped, unsigned int clamp_c)
{
  const uint32_t raw = ((uint32_t)(d[1] & 0xFFu) << 8) | (uint32_t)(d[0] & 0xFFu);
  const int32_t v = (int32_t)raw - ((raw & 0x8000u) ? 65536 : 0);
  const unsigned int r = u & 0x7Fu;
  *c = v == IMEST_TEMPERATURE_CAN_C_NA ? NAN : (float)v / (float)IMEST_TEMPERATURE_CAN_C_SCALE;
  if (v == IMEST_TEMPERATURE_CAN_C_MAX || v == -IMEST_TEMPERATURE_CAN_C_MAX) *clamped |= clamp_c;
  *k = r == (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_NA
           ? NAN
           : (float)r / (float)IMEST_TEMPERATURE_CAN_UNCERT_SCALE;
  if (r == (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_MAX) *clamped |= clamp_c << 1;
  *valid = (u & 0x80u) ? 1 : 0;
}

int imest_temperature_can_decode(const imest_can_frame_t *f, uint32_t base_id, imest_temperature_can_t *out)
{
  uint32_t id = 0u;
  unsigned int clamped = 0u;
  if (f == NULL || out == NULL) return IMEST_ERR_NULL;
  if (!temp_frame_id(base_id, &id)) return IMEST_ERR_ARG;
  if (f->id != id) return IMEST_CAN_DEC_FOREIGN;
  if (f->dlc != 8u) return IMEST_CAN_DEC_BAD_DLC;
  if (temp_crc(f->data) != ((unsigned int)f->data[7] & 0xFFu)) return IMEST_CAN_DEC_BAD_CRC;
  dec_temp(&f->data[0], f->data[4], &out->stator_c, &out->stator_uncert_k, &out->stator_valid, &clamped,
           IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C);
  dec_temp(&f->data[2], f->data[5], &out->rotor_c, &out->rotor_uncert_k, &out->rotor_valid, &clamped,
           IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C);
  out->counter = (unsigned int)f->data[6] & 0xFFu;
  out->clamped = clamped;
  return IMEST_CAN_DEC_OK;
}
