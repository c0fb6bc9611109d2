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
 * octet by octet: one octet (0..255) per element, as the codec of imest_can.h. */
_Static_assert(IMEST_TEMPERATURE_CAN_STATOR_C_START == 0u && IMEST_TEMPERATURE_CAN_ROTOR_C_START == 16u &&
                   IMEST_TEMPERATURE_CAN_STATOR_UNCERT_START == 32u &&
                   IMEST_TEMPERATURE_CAN_STATOR_VALID_START == 39u &&
                   IMEST_TEMPERATURE_CAN_ROTOR_UNCERT_START == 40u &&
                   IMEST_TEMPERATURE_CAN_ROTOR_VALID_START == 47u && IMEST_CAN_COUNTER_START == 48u &&
                   IMEST_CAN_CRC_START == 56u,
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

/* CRC-8 over [frame index, octets 0..6], as every frame of imest_can.h. */
static unsigned int temp_crc(const unsigned char *d)
{
  unsigned char buf[8];
  buf[0] = (unsigned char)IMEST_TEMPERATURE_CAN_FRAME;
  for (unsigned int i = 0u; i < 7u; i++) buf[i + 1u] = d[i];
  return imest_can_crc8(buf, 8u);
}

/* degC -> raw int16 as 16 bits: nearest 0.01, clamped to +-32767, NaN -> -32768. */
static uint32_t enc_c(float c)
{
  if (isnan(c)) return 0x8000u;
  const float x = c * (float)IMEST_TEMPERATURE_CAN_C_SCALE;
  int32_t v = IMEST_TEMPERATURE_CAN_C_MAX;
  if (x < (float)-IMEST_TEMPERATURE_CAN_C_MAX)
    v = -IMEST_TEMPERATURE_CAN_C_MAX;
  else if (x < (float)IMEST_TEMPERATURE_CAN_C_MAX)
    v = (int32_t)(x >= 0.0f ? x + 0.5f : x - 0.5f);
  return (uint32_t)v & 0xFFFFu;
}

/* K -> raw u7: nearest 0.2 K, clamped to 0..126, NaN -> 127. */
static unsigned int enc_uncert(float u)
{
  if (isnan(u)) return (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_NA;
  if (!(u > 0.0f)) return 0u;
  const float x = u * (float)IMEST_TEMPERATURE_CAN_UNCERT_SCALE + 0.5f;
  if (x >= (float)IMEST_TEMPERATURE_CAN_UNCERT_MAX) return (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_MAX;
  return (unsigned int)x;
}

int imest_temperature_can_pack(const imest_temperature_t *t, uint32_t base_id, unsigned int counter,
                               imest_can_frame_t *f)
{
  uint32_t id = 0u;
  if (t == NULL || f == NULL) return IMEST_ERR_NULL;
  if (!temp_frame_id(base_id, &id)) return IMEST_ERR_ARG;
  const uint32_t sc = enc_c(t->stator_c);
  const uint32_t rc = enc_c(t->rotor_c);
  f->id = id;
  f->dlc = 8u;
  f->data[0] = (unsigned char)(sc & 0xFFu);
  f->data[1] = (unsigned char)(sc >> 8);
  f->data[2] = (unsigned char)(rc & 0xFFu);
  f->data[3] = (unsigned char)(rc >> 8);
  f->data[4] = (unsigned char)(enc_uncert(t->stator_uncert_k) | (t->stator_valid ? 0x80u : 0u));
  f->data[5] = (unsigned char)(enc_uncert(t->rotor_uncert_k) | (t->rotor_valid ? 0x80u : 0u));
  f->data[6] = (unsigned char)(counter & 0xFFu);
  f->data[7] = (unsigned char)temp_crc(f->data);
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

/* raw int16 (two octets) -> degC; NaN for -32768; *clamped |= bit at +-32767. */
static float dec_c(unsigned int lo, unsigned int hi, unsigned int *clamped, unsigned int bit)
{
  const uint32_t u = ((uint32_t)(hi & 0xFFu) << 8) | (uint32_t)(lo & 0xFFu);
  const int32_t v = (int32_t)u - ((u & 0x8000u) ? 65536 : 0);
  if (v == IMEST_TEMPERATURE_CAN_C_NA) return NAN;
  if (v == IMEST_TEMPERATURE_CAN_C_MAX || v == -IMEST_TEMPERATURE_CAN_C_MAX) *clamped |= bit;
  return (float)v / (float)IMEST_TEMPERATURE_CAN_C_SCALE;
}

/* raw u7 (the octet's low bits) -> K; NaN for 127; *clamped |= bit at 126. */
static float dec_uncert(unsigned int octet, unsigned int *clamped, unsigned int bit)
{
  const unsigned int v = octet & 0x7Fu;
  if (v == (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_NA) return NAN;
  if (v == (unsigned int)IMEST_TEMPERATURE_CAN_UNCERT_MAX) *clamped |= bit;
  return (float)v / (float)IMEST_TEMPERATURE_CAN_UNCERT_SCALE;
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
  out->stator_c = dec_c(f->data[0], f->data[1], &clamped, IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C);
  out->rotor_c = dec_c(f->data[2], f->data[3], &clamped, IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C);
  out->stator_uncert_k = dec_uncert(f->data[4], &clamped, IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT);
  out->rotor_uncert_k = dec_uncert(f->data[5], &clamped, IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_UNCERT);
  out->stator_valid = ((unsigned int)f->data[4] & 0x80u) ? 1 : 0;
  out->rotor_valid = ((unsigned int)f->data[5] & 0x80u) ? 1 : 0;
  out->counter = (unsigned int)f->data[6] & 0xFFu;
  out->clamped = clamped;
  return IMEST_CAN_DEC_OK;
}
