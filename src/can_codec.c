/* CAN telemetry codec: packing, CRC, decoding and the reader's loss /
 * repeat / corruption detection. Layout: port/README.md and tools/imest.dbc
 * (the single source of truth; test/can checks this file against it).
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

/* --- bit field helpers (Intel byte order, start = LSB) ------------------- */

static void put_bits(unsigned char *d, unsigned int start, unsigned int len, uint32_t v) {
  unsigned int i;
  for (i = 0u; i < len; i++) {
    unsigned int k = start + i;
    unsigned int byte = k >> 3;
    unsigned int bit = k & 7u;
    unsigned int cur = (unsigned int)d[byte] & 0xFFu;
    if ((v >> i) & 1u) {
      cur |= (1u << bit);
    } else {
      cur &= ~(1u << bit) & 0xFFu;
    }
    d[byte] = (unsigned char)cur;
  }
}

static uint32_t get_bits(const unsigned char *d, unsigned int start, unsigned int len) {
  uint32_t v = 0u;
  unsigned int i;
  for (i = 0u; i < len; i++) {
    unsigned int k = start + i;
    uint32_t b = ((uint32_t)d[k >> 3] >> (k & 7u)) & 1u;
    v |= b << i;
  }
  return v;
}

/* --- field encoders -------------------------------------------------------- */

/* double -> binary32 bits: NaN -> canonical quiet NaN, +-inf kept, finite
 * values beyond +-FLT_MAX clamped to +-FLT_MAX with the saturation bit. */
static uint32_t enc_f32(double x, unsigned int *sat, unsigned int bit) {
  imest_f32_bits_t v;
  if (x != x) {
    return 0x7FC00000u;
  }
  if (x > DBL_MAX) {
    return 0x7F800000u;
  }
  if (x < -DBL_MAX) {
    return 0xFF800000u;
  }
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

static double dec_f32(uint32_t u) {
  imest_f32_bits_t v;
  v.u = u;
  return (double)v.f;
}

/* double >= 0 -> raw = round(x * inv_factor) in 0..65534; NaN -> 65535;
 * negative or too large (incl. +inf) -> clamped with the saturation bit. */
static uint32_t enc_u16(double x, double inv_factor, unsigned int *sat, unsigned int bit) {
  double r;
  if (x != x) {
    return IMEST_CAN_U16_NA;
  }
  if (x < 0.0) {
    *sat |= bit;
    return 0u;
  }
  r = x * inv_factor + 0.5;
  if (r >= (double)IMEST_CAN_U16_NA) {
    *sat |= bit;
    return IMEST_CAN_U16_MAX;
  }
  return (uint32_t)r;
}

static double dec_u16(uint32_t raw, double factor) {
  if (raw == IMEST_CAN_U16_NA) {
    imest_f32_bits_t v;
    v.u = 0x7FC00000u;
    return (double)v.f;
  }
  return (double)raw * factor;
}

static double nan64(void) { return dec_f32(0x7FC00000u); }

/* --- CRC-8 SAE J1850 ------------------------------------------------------- */

static unsigned int crc8_update(unsigned int crc, unsigned int octet) {
  unsigned int b;
  crc ^= octet & 0xFFu;
  for (b = 0u; b < 8u; b++) {
    if (crc & 0x80u) {
      crc = ((crc << 1) ^ 0x1Du) & 0xFFu;
    } else {
      crc = (crc << 1) & 0xFFu;
    }
  }
  return crc;
}

unsigned int imest_can_crc8(const unsigned char *data, unsigned int n) {
  unsigned int crc = 0xFFu;
  unsigned int i;
  if (data == NULL) {
    return 0u;
  }
  for (i = 0u; i < n; i++) {
    crc = crc8_update(crc, data[i]);
  }
  return crc ^ 0xFFu;
}

/* CRC of a frame: over the data id (frame index) then payload octets 0..6. */
static unsigned int frame_crc(unsigned int index, const unsigned char *d) {
  unsigned int crc = crc8_update(0xFFu, index);
  unsigned int i;
  for (i = 0u; i < 7u; i++) {
    crc = crc8_update(crc, d[i]);
  }
  return crc ^ 0xFFu;
}

/* --- layout (keep in step with tools/imest.dbc) --------------------------- */

/* IMEST_QUAL bit positions */
#define Q_PEK1 0u        /* 16 bits */
#define Q_STATUS 16u     /* 8 bits */
#define Q_VALID 24u
#define Q_HESS 25u
#define Q_SAT 26u        /* 5 bits: TR, RS, EI, PEK1, PEK2 */
#define Q_WFLAGS 32u     /* 5 bits: WARMUP, INPUT_FAULT, ADC_SAT, ENCODER_FAULT, OVERRUN */
#define Q_NROOTS 37u     /* 5 bits */
#define Q_NADM 42u       /* 5 bits */
#define B_COUNTER 48u
#define B_CRC 56u

static uint32_t sat5(unsigned int n) { return n > 31u ? 31u : (uint32_t)n; }

/* Compute the saturation bits of all fields (so every frame agrees). */
static unsigned int sat_bits(const imest_result_t *r) {
  unsigned int sat = 0u;
  (void)enc_f32(r->tr_s, &sat, IMEST_CAN_SAT_TR);
  (void)enc_f32(r->rs_ohm, &sat, IMEST_CAN_SAT_RS);
  (void)enc_u16(r->e_i, 1e4, &sat, IMEST_CAN_SAT_EI);
  (void)enc_u16(r->pe_k1_rel, 5e4, &sat, IMEST_CAN_SAT_PEK1);
  (void)enc_u16(r->pe_k2_rel, 5e4, &sat, IMEST_CAN_SAT_PEK2);
  return sat;
}

int imest_can_pack(const imest_result_t *r, unsigned int index, uint32_t base_id,
                   unsigned int counter, uint32_t tx_failed, struct imest_can_frame *f) {
  unsigned int sat = 0u;
  unsigned int i;
  uint32_t ext;
  if (r == NULL || f == NULL) {
    return IMEST_ERR_NULL;
  }
  if (index >= IMEST_CAN_NFRAMES) {
    return IMEST_ERR_CONFIG;
  }
  ext = base_id & IMEST_CAN_ID_EXT;
  f->id = (((base_id & IMEST_CAN_EFF_MASK) + index) & (ext ? IMEST_CAN_EFF_MASK : IMEST_CAN_SFF_MASK)) | ext;
  f->dlc = 8u;
  for (i = 0u; i < 8u; i++) {
    f->data[i] = 0u;
  }
  switch (index) {
    case IMEST_CAN_FRAME_TR:
      put_bits(f->data, 0u, 32u, enc_f32(r->tr_s, &sat, IMEST_CAN_SAT_TR));
      put_bits(f->data, 32u, 16u, enc_u16(r->e_i, 1e4, &sat, IMEST_CAN_SAT_EI));
      break;
    case IMEST_CAN_FRAME_RS:
      put_bits(f->data, 0u, 32u, enc_f32(r->rs_ohm, &sat, IMEST_CAN_SAT_RS));
      put_bits(f->data, 32u, 16u, enc_u16(r->pe_k2_rel, 5e4, &sat, IMEST_CAN_SAT_PEK2));
      break;
    case IMEST_CAN_FRAME_QUAL: {
      unsigned int st = (r->status >= 0 && r->status <= 255) ? (unsigned int)r->status : 255u;
      unsigned int wf = r->flags;
      uint32_t bits = ((wf & IMEST_FLAG_WARMUP) ? 1u : 0u) | ((wf & IMEST_FLAG_INPUT_FAULT) ? 2u : 0u) |
                      ((wf & IMEST_FLAG_ADC_SAT) ? 4u : 0u) | ((wf & IMEST_FLAG_ENCODER_FAULT) ? 8u : 0u) |
                      ((wf & IMEST_FLAG_OVERRUN) ? 16u : 0u);
      put_bits(f->data, Q_PEK1, 16u, enc_u16(r->pe_k1_rel, 5e4, &sat, IMEST_CAN_SAT_PEK1));
      put_bits(f->data, Q_STATUS, 8u, st);
      put_bits(f->data, Q_VALID, 1u, r->valid ? 1u : 0u);
      put_bits(f->data, Q_HESS, 1u, (wf & IMEST_FLAG_HESSIAN_PD) ? 1u : 0u);
      put_bits(f->data, Q_SAT, 5u, sat_bits(r));
      put_bits(f->data, Q_WFLAGS, 5u, bits);
      put_bits(f->data, Q_NROOTS, 5u, sat5(r->n_roots));
      put_bits(f->data, Q_NADM, 5u, sat5(r->n_admissible));
      break;
    }
    default: /* IMEST_CAN_FRAME_STAT */
      put_bits(f->data, 0u, 32u, r->seq);
      put_bits(f->data, 32u, 16u, tx_failed > 0xFFFFu ? 0xFFFFu : tx_failed);
      break;
  }
  put_bits(f->data, B_COUNTER, 8u, counter & 0xFFu);
  put_bits(f->data, B_CRC, 8u, frame_crc(index, f->data));
  return IMEST_OK;
}

/* --- decoding -------------------------------------------------------------- */

void imest_can_window_clear(imest_can_window_t *w) {
  double nan = nan64();
  if (w == NULL) {
    return;
  }
  w->have = 0u;
  w->counter = 0u;
  w->seq = 0u;
  w->tr_s = nan;
  w->rs_ohm = nan;
  w->e_i = nan;
  w->pe_k1_rel = nan;
  w->pe_k2_rel = nan;
  w->valid = 0;
  w->status = -1;
  w->flags = 0u;
  w->sat = 0u;
  w->n_roots = 0u;
  w->n_admissible = 0u;
  w->tx_failed = 0u;
}

static int classify(const struct imest_can_frame *f, uint32_t base_id, unsigned int *index) {
  uint32_t ext = base_id & IMEST_CAN_ID_EXT;
  uint32_t mask = ext ? IMEST_CAN_EFF_MASK : IMEST_CAN_SFF_MASK;
  uint32_t base = base_id & mask;
  uint32_t id = f->id & mask;
  uint32_t off;
  if ((f->id & IMEST_CAN_ID_EXT) != ext || (f->id & ~(mask | IMEST_CAN_ID_EXT)) != 0u) {
    return IMEST_CAN_DEC_FOREIGN;
  }
  off = (id - base) & mask;
  if (off >= IMEST_CAN_NFRAMES) {
    return IMEST_CAN_DEC_FOREIGN;
  }
  *index = (unsigned int)off;
  if (f->dlc != 8u) {
    return IMEST_CAN_DEC_BAD_DLC;
  }
  if (frame_crc(*index, f->data) != ((unsigned int)f->data[7] & 0xFFu)) {
    return IMEST_CAN_DEC_BAD_CRC;
  }
  return IMEST_CAN_DEC_OK;
}

int imest_can_decode_frame(const struct imest_can_frame *f, uint32_t base_id,
                           imest_can_window_t *w, unsigned int *index) {
  unsigned int idx = 0u;
  int dec;
  const unsigned char *d;
  if (f == NULL || w == NULL) {
    return IMEST_CAN_DEC_FOREIGN;
  }
  dec = classify(f, base_id, &idx);
  if (index != NULL && dec != IMEST_CAN_DEC_FOREIGN) {
    *index = idx;
  }
  if (dec != IMEST_CAN_DEC_OK) {
    return dec;
  }
  d = f->data;
  switch (idx) {
    case IMEST_CAN_FRAME_TR:
      w->tr_s = dec_f32(get_bits(d, 0u, 32u));
      w->e_i = dec_u16(get_bits(d, 32u, 16u), IMEST_CAN_EI_FACTOR);
      break;
    case IMEST_CAN_FRAME_RS:
      w->rs_ohm = dec_f32(get_bits(d, 0u, 32u));
      w->pe_k2_rel = dec_u16(get_bits(d, 32u, 16u), IMEST_CAN_PE_FACTOR);
      break;
    case IMEST_CAN_FRAME_QUAL: {
      uint32_t wf = get_bits(d, Q_WFLAGS, 5u);
      w->pe_k1_rel = dec_u16(get_bits(d, Q_PEK1, 16u), IMEST_CAN_PE_FACTOR);
      w->status = (int)get_bits(d, Q_STATUS, 8u);
      w->valid = (int)get_bits(d, Q_VALID, 1u);
      w->sat = (unsigned int)get_bits(d, Q_SAT, 5u);
      w->flags = ((wf & 1u) ? IMEST_FLAG_WARMUP : 0u) | ((wf & 2u) ? IMEST_FLAG_INPUT_FAULT : 0u) |
                 ((wf & 4u) ? IMEST_FLAG_ADC_SAT : 0u) | ((wf & 8u) ? IMEST_FLAG_ENCODER_FAULT : 0u) |
                 ((wf & 16u) ? IMEST_FLAG_OVERRUN : 0u) |
                 (get_bits(d, Q_HESS, 1u) ? IMEST_FLAG_HESSIAN_PD : 0u);
      w->n_roots = (unsigned int)get_bits(d, Q_NROOTS, 5u);
      w->n_admissible = (unsigned int)get_bits(d, Q_NADM, 5u);
      break;
    }
    default:
      w->seq = get_bits(d, 0u, 32u);
      w->tx_failed = get_bits(d, 32u, 16u);
      break;
  }
  w->counter = (unsigned int)get_bits(d, B_COUNTER, 8u);
  w->have |= 1u << idx;
  return IMEST_CAN_DEC_OK;
}

/* --- reader ---------------------------------------------------------------- */

void imest_can_rx_init(imest_can_rx_t *rx, uint32_t base_id) {
  unsigned int i;
  if (rx == NULL) {
    return;
  }
  rx->base_id = base_id;
  rx->seen = 0u;
  for (i = 0u; i < IMEST_CAN_NFRAMES; i++) {
    rx->last_ctr[i] = 0u;
  }
  rx->open = 0;
  imest_can_window_clear(&rx->cur);
  rx->have_seq = 0;
  rx->last_seq = 0u;
  rx->last_seq_ctr = 0u;
  rx->st.frames = 0u;
  rx->st.foreign = 0u;
  rx->st.corrupt = 0u;
  rx->st.repeated = 0u;
  rx->st.lost = 0u;
  rx->st.windows = 0u;
  rx->st.incomplete = 0u;
  rx->st.seq_gaps = 0u;
  rx->st.restarts = 0u;
}

static void copy_window(imest_can_window_t *dst, const imest_can_window_t *src) {
  if (dst != NULL) {
    *dst = *src;
  }
}

unsigned int imest_can_rx_feed(imest_can_rx_t *rx, const struct imest_can_frame *f,
                               imest_can_window_t *out, imest_can_rx_event_t *ev) {
  imest_can_rx_event_t e;
  unsigned int idx = 0u;
  unsigned int ctr;
  unsigned int full = (1u << IMEST_CAN_NFRAMES) - 1u;
  imest_can_window_t probe;

  e.events = 0u;
  e.index = 0u;
  e.counter = 0u;
  e.prev_counter = 0u;
  e.lost = 0u;
  e.seq_gap = 0u;
  e.dec = IMEST_CAN_DEC_FOREIGN;
  if (rx == NULL || f == NULL) {
    if (ev != NULL) {
      *ev = e;
    }
    return 0u;
  }
  rx->st.frames++;
  imest_can_window_clear(&probe);
  e.dec = imest_can_decode_frame(f, rx->base_id, &probe, &idx);
  e.index = idx;
  if (e.dec == IMEST_CAN_DEC_FOREIGN) {
    rx->st.foreign++;
    e.events = IMEST_CAN_EV_FOREIGN;
  } else if (e.dec != IMEST_CAN_DEC_OK) {
    rx->st.corrupt++;
    e.events = IMEST_CAN_EV_CORRUPT;
  } else {
    ctr = probe.counter;
    e.counter = ctr;
    if (rx->seen & (1u << idx)) {
      unsigned int dctr = (ctr - rx->last_ctr[idx]) & 0xFFu;
      e.prev_counter = rx->last_ctr[idx];
      if (dctr == 0u) {
        rx->st.repeated++;
        e.events = IMEST_CAN_EV_REPEATED;
        if (ev != NULL) {
          *ev = e;
        }
        return e.events;
      }
      if (dctr > 1u) {
        e.lost = dctr - 1u;
        rx->st.lost += e.lost;
        e.events |= IMEST_CAN_EV_LOST;
      }
    }
    rx->seen |= 1u << idx;
    rx->last_ctr[idx] = ctr;

    if (rx->open && rx->cur.counter != ctr) {
      /* a frame of the next window: hand out the incomplete one */
      copy_window(out, &rx->cur);
      rx->open = 0;
      rx->st.windows++;
      rx->st.incomplete++;
      e.events |= IMEST_CAN_EV_WINDOW | IMEST_CAN_EV_INCOMPLETE;
    }
    if (!rx->open) {
      imest_can_window_clear(&rx->cur);
      rx->cur.counter = ctr;
      rx->open = 1;
    }
    (void)imest_can_decode_frame(f, rx->base_id, &rx->cur, NULL);

    if (idx == IMEST_CAN_FRAME_STAT) {
      uint32_t seq = rx->cur.seq;
      if (rx->have_seq) {
        uint32_t g = seq - rx->last_seq;
        uint32_t d = (ctr - rx->last_seq_ctr) & 0xFFu;
        if (g & 0x80000000u) {
          rx->st.restarts++;
          e.events |= IMEST_CAN_EV_RESTART;
        } else if (g > d) {
          e.seq_gap = g - d;
          rx->st.seq_gaps += e.seq_gap;
          e.events |= IMEST_CAN_EV_SEQ_GAP;
        }
      }
      rx->have_seq = 1;
      rx->last_seq = seq;
      rx->last_seq_ctr = ctr;
    }
    if (rx->cur.have == full) {
      /* a window just opened by this frame cannot be complete, so at most
       * one window is handed out per call */
      copy_window(out, &rx->cur);
      rx->open = 0;
      rx->st.windows++;
      e.events |= IMEST_CAN_EV_WINDOW;
    }
  }
  if (ev != NULL) {
    *ev = e;
  }
  return e.events;
}

unsigned int imest_can_rx_flush(imest_can_rx_t *rx, imest_can_window_t *out) {
  if (rx == NULL || !rx->open) {
    return 0u;
  }
  copy_window(out, &rx->cur);
  rx->open = 0;
  rx->st.windows++;
  rx->st.incomplete++;
  return IMEST_CAN_EV_WINDOW | IMEST_CAN_EV_INCOMPLETE;
}
