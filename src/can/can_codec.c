/* SPDX-License-Identifier: Apache-2.0 */
/* CAN telemetry codec: the signal table (can_signals.c) turned into frames
 * and back, the CRC, and the identifier rules.
 *
 * Bits are numbered as in a DBC file with Intel (little-endian) byte order:
 * bit k is bit (k mod 8) of payload octet k / 8. Every field is written with
 * explicit shifts into `unsigned char` elements holding one octet each, so the
 * result depends neither on struct layout nor on host endianness nor on the
 * width of char. No stdio, no malloc, no global mutable state. */
#include <float.h>
#include <stddef.h>

#include "imest/imest_can.h"

#if FLT_RADIX != 2 || FLT_MANT_DIG != 24 || FLT_MAX_EXP != 128
#error "imest CAN codec: float must be IEEE-754 binary32"
#endif

/* float <-> its binary32 bit pattern (type punning through a union is
 * defined in C11, 6.5.2.3 note 95). */
typedef union {
  float f;
  uint32_t u;
} imest_f32_bits_t;

_Static_assert(sizeof(float) == sizeof(uint32_t), "float and uint32_t differ in size");

#define F32_QNAN 0x7FC00000u

/* --- identifiers ------------------------------------------------------------ */

int imest_can_base_id_check(uint32_t base_id)
{
  const uint32_t last = (uint32_t)IMEST_CAN_NFRAMES - 1u;
  if (base_id & IMEST_CAN_ID_EXT) {
    return (base_id & ~IMEST_CAN_ID_EXT) <= IMEST_CAN_EFF_MASK - last ? IMEST_OK : IMEST_ERR_ARG;
  }
  return base_id <= IMEST_CAN_SFF_MASK - last ? IMEST_OK : IMEST_ERR_ARG;
}

/* --- bit fields (Intel byte order, start = LSB) ---------------------------- */

static void put_bits(unsigned char *d, unsigned int start, unsigned int len, uint32_t v)
{
  for (unsigned int i = 0u; i < len; i++) {
    const unsigned int k = start + i;
    const unsigned int bit = 1u << (k & 7u);
    unsigned int cur = (unsigned int)d[k >> 3] & 0xFFu;
    cur = ((v >> i) & 1u) ? (cur | bit) : (cur & ~bit & 0xFFu);
    d[k >> 3] = (unsigned char)(cur & 0xFFu);
  }
}

static uint32_t get_bits(const unsigned char *d, unsigned int start, unsigned int len)
{
  uint32_t v = 0u;
  for (unsigned int i = 0u; i < len; i++) {
    const unsigned int k = start + i;
    v |= (((uint32_t)d[k >> 3] >> (k & 7u)) & 1u) << i;
  }
  return v;
}

/* The raw value with every bit of a len-bit signal set. */
static uint32_t all_ones(unsigned int len)
{
  return len >= 32u ? 0xFFFFFFFFu : ((uint32_t)1u << len) - 1u;
}

/* --- CRC-8 SAE J1850 -------------------------------------------------------- */

static unsigned int crc8_update(unsigned int crc, unsigned int octet)
{
  crc ^= octet & 0xFFu;
  for (unsigned int b = 0u; b < 8u; b++) {
    crc = (crc & 0x80u) ? (((crc << 1) ^ 0x1Du) & 0xFFu) : ((crc << 1) & 0xFFu);
  }
  return crc;
}

unsigned int imest_can_crc8(const unsigned char *data, unsigned int n)
{
  unsigned int crc = 0xFFu;
  if (data == NULL) return 0u;
  for (unsigned int i = 0u; i < n; i++) crc = crc8_update(crc, data[i]);
  return crc ^ 0xFFu;
}

/* CRC of a frame: over the data id (frame index) then payload octets 0..6, so
 * a frame arriving under another frame's identifier fails too. */
static unsigned int frame_crc(unsigned int index, const unsigned char *d)
{
  unsigned int crc = crc8_update(0xFFu, index);
  for (unsigned int i = 0u; i < 7u; i++) crc = crc8_update(crc, d[i]);
  return crc ^ 0xFFu;
}

/* --- field access through the table's offsets ------------------------------ */

static const void *field_of(const imest_result_t *r, const imest_can_signal_t *s)
{
  return (const char *)r + s->field;
}

static void *field_in(imest_result_t *r, const imest_can_signal_t *s)
{
  return (char *)r + s->field;
}

/* --- encoding ----------------------------------------------------------------- */

/* double -> binary32 bits: NaN -> canonical quiet NaN, +-inf kept, finite
 * values beyond +-FLT_MAX clamped with the saturation bit. */
static uint32_t enc_f32(double x, unsigned int *sat, unsigned int bit)
{
  imest_f32_bits_t v;
  if (x != x) return F32_QNAN;
  if (x > DBL_MAX) return 0x7F800000u;
  if (x < -DBL_MAX) return 0xFF800000u;
  if (x > (double)FLT_MAX) {
    *sat |= bit;
    x = (double)FLT_MAX;
  } else if (x < -(double)FLT_MAX) {
    *sat |= bit;
    x = -(double)FLT_MAX;
  }
  v.f = (float)x;
  return v.u;
}

/* double >= 0 -> raw = round(x * scale) in 0 .. na-1; NaN -> na; negative or
 * too large (+inf too) -> clamped with the saturation bit. */
static uint32_t enc_scaled(double x, uint32_t scale, uint32_t na, unsigned int *sat, unsigned int bit)
{
  if (x != x) return na;
  if (x < 0.0) {
    *sat |= bit;
    return 0u;
  }
  const double r = x * (double)scale + 0.5;
  if (r >= (double)na) {
    *sat |= bit;
    return na - 1u;
  }
  return (uint32_t)r;
}

static uint32_t clamp_u(uint32_t v, uint32_t max)
{
  return v > max ? max : v;
}

/* Raw value of signal s. sat_all: the saturation bits of the whole window
 * (for SAT signals); *sat collects the bits this signal sets. */
static uint32_t encode(const imest_can_signal_t *s, const imest_result_t *r, uint32_t tx_failed,
                       unsigned int sat_all, unsigned int *sat)
{
  const uint32_t ones = all_ones(s->len);
  switch ((imest_can_kind_t)s->kind) {
  case IMEST_CAN_F32: return enc_f32(*(const double *)field_of(r, s), sat, s->mask);
  case IMEST_CAN_SCALED: return enc_scaled(*(const double *)field_of(r, s), s->scale, ones, sat, s->mask);
  case IMEST_CAN_COUNT: return clamp_u((uint32_t) * (const unsigned int *)field_of(r, s), ones);
  case IMEST_CAN_U32: return clamp_u(*(const uint32_t *)field_of(r, s), ones);
  case IMEST_CAN_ENUM: {
    const int v = *(const int *)field_of(r, s);
    if (v < 0) return ones;
    return clamp_u((uint32_t)v, ones); /* out of range: all ones */
  }
  case IMEST_CAN_BOOL: return *(const int *)field_of(r, s) != 0 ? 1u : 0u;
  case IMEST_CAN_FLAG: return (*(const unsigned int *)field_of(r, s) & s->mask) ? 1u : 0u;
  case IMEST_CAN_SAT: return (sat_all & s->mask) ? 1u : 0u;
  case IMEST_CAN_TXFAIL: return clamp_u(tx_failed, ones);
  }
  return 0u;
}

/* The saturation bits of every field, so each frame carries the same ones. */
static unsigned int sat_bits(const imest_result_t *r, const imest_can_signal_t *t, unsigned int n)
{
  unsigned int sat = 0u;
  for (unsigned int k = 0u; k < n; k++) {
    if (t[k].kind == IMEST_CAN_F32 || t[k].kind == IMEST_CAN_SCALED) (void)encode(&t[k], r, 0u, 0u, &sat);
  }
  return sat;
}

static uint32_t frame_id(uint32_t base_id, unsigned int index)
{
  const uint32_t ext = base_id & IMEST_CAN_ID_EXT;
  return ((base_id & ~IMEST_CAN_ID_EXT) + index) | ext;
}

int imest_can_pack(const imest_result_t *r, unsigned int index, uint32_t base_id, unsigned int counter,
                   uint32_t tx_failed, imest_can_frame_t *f)
{
  unsigned int n = 0u;
  const imest_can_signal_t *t = imest_can_signal_table(&n);
  if (r == NULL || f == NULL) return IMEST_ERR_NULL;
  if (index >= (unsigned int)IMEST_CAN_NFRAMES || imest_can_base_id_check(base_id) != IMEST_OK) {
    return IMEST_ERR_ARG;
  }
  const unsigned int sat_all = sat_bits(r, t, n);
  f->id = frame_id(base_id, index);
  f->dlc = 8u;
  for (unsigned int i = 0u; i < 8u; i++) f->data[i] = 0u;
  for (unsigned int k = 0u; k < n; k++) {
    unsigned int unused = 0u;
    if (t[k].frame == index)
      put_bits(f->data, t[k].start, t[k].len, encode(&t[k], r, tx_failed, sat_all, &unused));
  }
  put_bits(f->data, IMEST_CAN_COUNTER_START, 8u, counter & 0xFFu);
  put_bits(f->data, IMEST_CAN_CRC_START, 8u, frame_crc(index, f->data));
  return IMEST_OK;
}

/* --- decoding ----------------------------------------------------------------- */

static double nan64(void)
{
  imest_f32_bits_t v;
  v.u = F32_QNAN;
  return (double)v.f;
}

static double dec_f32(uint32_t u)
{
  imest_f32_bits_t v;
  v.u = u;
  return (double)v.f;
}

static void set_bit(unsigned int *word, unsigned int mask, uint32_t on)
{
  *word = on ? (*word | mask) : (*word & ~mask);
}

static void decode(const imest_can_signal_t *s, uint32_t raw, imest_can_window_t *w)
{
  void *p = field_in(&w->result, s);
  switch ((imest_can_kind_t)s->kind) {
  case IMEST_CAN_F32: *(double *)p = dec_f32(raw); break;
  case IMEST_CAN_SCALED:
    *(double *)p = raw == all_ones(s->len) ? nan64() : (double)raw / (double)s->scale;
    break;
  case IMEST_CAN_COUNT: *(unsigned int *)p = (unsigned int)raw; break;
  case IMEST_CAN_U32: *(uint32_t *)p = raw; break;
  case IMEST_CAN_ENUM:
  case IMEST_CAN_BOOL: *(int *)p = (int)raw; break;
  case IMEST_CAN_FLAG: set_bit((unsigned int *)p, s->mask, raw); break;
  case IMEST_CAN_SAT: set_bit(&w->sat, s->mask, raw); break;
  case IMEST_CAN_TXFAIL: w->tx_failed = raw; break;
  }
}

void imest_can_window_clear(imest_can_window_t *w)
{
  unsigned int n = 0u;
  const imest_can_signal_t *t = imest_can_signal_table(&n);
  if (w == NULL) return;
  unsigned char *raw = (unsigned char *)w;
  for (size_t b = 0u; b < sizeof *w; b++) raw[b] = 0u;
  for (unsigned int k = 0u; k < n; k++) {
    void *p = field_in(&w->result, &t[k]);
    if (t[k].kind == IMEST_CAN_F32 || t[k].kind == IMEST_CAN_SCALED) *(double *)p = nan64();
    if (t[k].kind == IMEST_CAN_ENUM) *(int *)p = -1;
  }
}

/* Ours? Then which frame, and is it intact? */
static int classify(const imest_can_frame_t *f, uint32_t base_id, unsigned int *index)
{
  const uint32_t ext = base_id & IMEST_CAN_ID_EXT;
  const uint32_t mask = ext ? IMEST_CAN_EFF_MASK : IMEST_CAN_SFF_MASK;
  if ((f->id & IMEST_CAN_ID_EXT) != ext || (f->id & ~(mask | IMEST_CAN_ID_EXT)) != 0u) {
    return IMEST_CAN_DEC_FOREIGN;
  }
  const uint32_t off = ((f->id & mask) - (base_id & mask)) & mask;
  if (off >= (uint32_t)IMEST_CAN_NFRAMES) return IMEST_CAN_DEC_FOREIGN;
  *index = (unsigned int)off;
  if (f->dlc != 8u) return IMEST_CAN_DEC_BAD_DLC;
  if (frame_crc(*index, f->data) != ((unsigned int)f->data[7] & 0xFFu)) return IMEST_CAN_DEC_BAD_CRC;
  return IMEST_CAN_DEC_OK;
}

int imest_can_decode_frame(const imest_can_frame_t *f, uint32_t base_id, imest_can_window_t *w,
                           unsigned int *index)
{
  unsigned int idx = 0u;
  unsigned int n = 0u;
  const imest_can_signal_t *t = imest_can_signal_table(&n);
  if (f == NULL || w == NULL) return IMEST_ERR_NULL;
  const int dec = classify(f, base_id, &idx);
  if (index != NULL && dec != IMEST_CAN_DEC_FOREIGN) *index = idx;
  if (dec != IMEST_CAN_DEC_OK) return dec;
  for (unsigned int k = 0u; k < n; k++) {
    if (t[k].frame == idx) decode(&t[k], get_bits(f->data, t[k].start, t[k].len), w);
  }
  w->counter = (unsigned int)get_bits(f->data, IMEST_CAN_COUNTER_START, 8u);
  w->have |= 1u << idx;
  return IMEST_CAN_DEC_OK;
}
