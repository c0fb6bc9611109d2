/**
 * @file imest_can.h
 * @brief CAN telemetry of imest: frame codec, publisher and reader.
 *
 * Every window is published as IMEST_CAN_NFRAMES classic CAN frames (8-byte
 * payloads) at consecutive identifiers base_id + 0 .. base_id + 3. The layout
 * is documented in port/README.md ("CAN telemetry") and in tools/imest.dbc,
 * the single source of truth; test/can proves that this codec and the DBC
 * agree (independent decoder: python3-canmatrix).
 *
 *   base+0 IMEST_TR    T_R [s] float32, E_I u16 (x 1e-4)
 *   base+1 IMEST_RS    R_S [ohm] float32, relative PE index of K2 u16 (x 2e-5)
 *   base+2 IMEST_QUAL  relative PE index of K1 u16 (x 2e-5), status, valid,
 *                      saturation bits, window flags, root counts
 *   base+3 IMEST_STAT  window sequence number u32, failed sends u16
 *   every frame: byte 6 = rolling counter (one value per window), byte 7 =
 *   CRC-8 SAE J1850 over [frame index, bytes 0..6].
 *
 * Octets: a payload is `unsigned char data[8]`, each element holds one octet
 * (0..255) also on targets whose char has 16 bits (TI C2000). Packing is
 * explicit shift-and-mask arithmetic (little-endian / Intel byte order on the
 * bus), independent of struct layout and host endianness. Floats are IEEE-754
 * binary32 (checked at compile time).
 *
 * Publishing (imest_can_publish) runs in the background task, never in the
 * ISR; a failed send is counted (imest_t.can_tx_failed, also sent in IMEST_STAT)
 * and never retried.
 *
 * No malloc, no stdio, no global mutable state.
 */
#ifndef IMEST_IMEST_CAN_H
#define IMEST_IMEST_CAN_H

#include <stdint.h>

#include "imest/imest.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ----------------------------------------------------------------------------
 * Frames and the port
 * ------------------------------------------------------------------------- */

/** Identifier flag: set in imest_can_frame.id (and in a base id) for a
 *  29-bit extended identifier; clear for an 11-bit standard one. Same value
 *  as Linux's CAN_EFF_FLAG. */
#define IMEST_CAN_ID_EXT 0x80000000u
#define IMEST_CAN_SFF_MASK 0x000007FFu
#define IMEST_CAN_EFF_MASK 0x1FFFFFFFu

/** One classic CAN data frame. */
struct imest_can_frame {
  uint32_t id;              /**< identifier, | IMEST_CAN_ID_EXT if extended */
  unsigned int dlc;         /**< data length 0..8 (imest sends 8) */
  unsigned char data[8];    /**< one octet (0..255) per element */
};

/** A transmit port. send() must not block: it queues the frame (or writes it)
 *  and returns 0, or returns nonzero if it cannot (queue full, bus-off, I/O
 *  error). It is called from the background task only. */
struct imest_can_port {
  int (*send)(void *ctx, const struct imest_can_frame *f);
  void *ctx;
};

/** Frames per window, and their offsets from the base identifier. */
#define IMEST_CAN_NFRAMES 4
#define IMEST_CAN_FRAME_TR   0  /**< base+0: T_R, E_I */
#define IMEST_CAN_FRAME_RS   1  /**< base+1: R_S, relative PE index of K2 */
#define IMEST_CAN_FRAME_QUAL 2  /**< base+2: PE K1, status, valid, bits, roots */
#define IMEST_CAN_FRAME_STAT 3  /**< base+3: sequence number, failed sends */

/** Suggested base identifier (free in the CANopen predefined connection set);
 *  tools/imest.dbc is written for it. Node n could use 0x6A0 + 4 n. */
#define IMEST_CAN_DEFAULT_BASE_ID 0x6A0u

/** Scaling of the 16-bit fields: physical = raw * factor, raw 0..65534;
 *  raw 65535 = not available (NaN). */
#define IMEST_CAN_EI_FACTOR 1e-4   /**< E_I: 0 .. 6.5534, resolution 1e-4 */
#define IMEST_CAN_PE_FACTOR 2e-5   /**< relative PE indices: 0 .. 1.31068, resolution 2e-5 */
#define IMEST_CAN_U16_NA 0xFFFFu
#define IMEST_CAN_U16_MAX 0xFFFEu

/** Saturation bits (imest_can_window_t.sat, and in frame IMEST_QUAL): the
 *  value was outside the field's range and was clamped to the nearest end
 *  (float32 fields: +-FLT_MAX; infinities are sent as infinities). */
#define IMEST_CAN_SAT_TR   0x01u
#define IMEST_CAN_SAT_RS   0x02u
#define IMEST_CAN_SAT_EI   0x04u
#define IMEST_CAN_SAT_PEK1 0x08u
#define IMEST_CAN_SAT_PEK2 0x10u

/* ----------------------------------------------------------------------------
 * Publisher (drive side)
 * ------------------------------------------------------------------------- */

/**
 * Attach a transmit port to an initialised instance (call after imest_init(),
 * which clears it). base_id: 11-bit standard identifier, or 29-bit extended
 * identifier | IMEST_CAN_ID_EXT; base_id + IMEST_CAN_NFRAMES - 1 must still be
 * a valid identifier. port == NULL detaches. Resets can_counter and
 * can_tx_failed. The port struct must outlive the instance's use of it.
 * @return IMEST_OK, IMEST_ERR_NULL (s NULL, or port->send NULL) or
 *         IMEST_ERR_CONFIG (identifier out of range).
 */
int imest_attach_can(imest_t *s, const struct imest_can_port *port, uint32_t base_id);

/**
 * Publish one window's result over the attached port (called by
 * imest_background()). Packs the IMEST_CAN_NFRAMES frames, calls port->send
 * once for each (no retry), counts every failed send in s->can_tx_failed,
 * and advances the rolling counter s->can_counter by one.
 * @return the number of frames that could not be sent (0: all sent, or no
 *         port attached), or IMEST_ERR_NULL if s or r is NULL.
 */
int imest_can_publish(imest_t *s, const imest_result_t *r);

/* ----------------------------------------------------------------------------
 * Codec
 * ------------------------------------------------------------------------- */

/** One window as carried on the bus (decoded). Fields of frames that did not
 *  arrive are NaN / 0 and their bit is clear in `have`. */
typedef struct {
  unsigned int have;        /**< bit i: frame base+i received and CRC-valid */
  unsigned int counter;     /**< rolling counter (0..255) */
  uint32_t seq;             /**< window sequence number (IMEST_STAT) */
  double tr_s;              /**< T_R [s] (float32 on the bus) */
  double rs_ohm;            /**< R_S [ohm] (float32 on the bus) */
  double e_i;               /**< E_I (NaN: not available) */
  double pe_k1_rel;         /**< relative parametric error index of K1 */
  double pe_k2_rel;         /**< relative parametric error index of K2 */
  int valid;                /**< 1: estimate can be trusted */
  int status;               /**< imest_status_t */
  unsigned int flags;       /**< IMEST_FLAG_* (window flags and HESSIAN_PD) */
  unsigned int sat;         /**< IMEST_CAN_SAT_* */
  unsigned int n_roots;
  unsigned int n_admissible;
  uint32_t tx_failed;       /**< sender's failed-send count (saturates at 65535) */
} imest_can_window_t;

/** CRC-8 SAE J1850 (poly 0x1D, init 0xFF, final xor 0xFF; check("123456789") = 0x4B)
 *  over n octets (only the low 8 bits of each element are used). */
unsigned int imest_can_crc8(const unsigned char *data, unsigned int n);

/** Pack frame `index` (0..3) of result r with rolling counter `counter` and
 *  failed-send count `tx_failed`. base_id as in imest_attach_can(). Returns
 *  IMEST_OK, IMEST_ERR_NULL or IMEST_ERR_CONFIG (bad index). */
int imest_can_pack(const imest_result_t *r, unsigned int index, uint32_t base_id,
                   unsigned int counter, uint32_t tx_failed, struct imest_can_frame *f);

/** Result of imest_can_decode_frame(). */
#define IMEST_CAN_DEC_OK       0  /**< decoded into the window */
#define IMEST_CAN_DEC_FOREIGN  1  /**< not one of ours (identifier outside base..base+3) */
#define IMEST_CAN_DEC_BAD_DLC  2  /**< ours, but not 8 data bytes */
#define IMEST_CAN_DEC_BAD_CRC  3  /**< ours, checksum mismatch */

/**
 * Check and decode one frame into the fields of *w that this frame carries
 * (sets bit `index` in w->have and w->counter). *index (optional) receives the
 * frame index 0..3 when the identifier is ours.
 * @return IMEST_CAN_DEC_* (w is only written on IMEST_CAN_DEC_OK).
 */
int imest_can_decode_frame(const struct imest_can_frame *f, uint32_t base_id,
                           imest_can_window_t *w, unsigned int *index);

/** Clear a decoded window (have = 0, values NaN or 0). */
void imest_can_window_clear(imest_can_window_t *w);

/* ----------------------------------------------------------------------------
 * Reader: loss / repeat / corruption detection and window assembly
 * ------------------------------------------------------------------------- */

/** Event bits of imest_can_rx_feed(). */
#define IMEST_CAN_EV_FOREIGN    0x001u /**< frame not ours: ignored */
#define IMEST_CAN_EV_CORRUPT    0x002u /**< ours, bad CRC or DLC: dropped */
#define IMEST_CAN_EV_REPEATED   0x004u /**< ours, same counter as the last of its id: dropped */
#define IMEST_CAN_EV_LOST       0x008u /**< counter skipped: ev.lost frames of this id missing */
#define IMEST_CAN_EV_WINDOW     0x010u /**< a window is returned in *out (complete or not) */
#define IMEST_CAN_EV_INCOMPLETE 0x020u /**< ... and it lacks frames (out->have != 0xF) */
#define IMEST_CAN_EV_SEQ_GAP    0x040u /**< the sequence number skipped ev.seq_gap more windows
                                            than the rolling counter: windows the estimator
                                            dropped (overruns), not lost on the bus */
#define IMEST_CAN_EV_RESTART    0x080u /**< the sequence number went backwards: sender restarted */

/** Details of one imest_can_rx_feed() call. */
typedef struct {
  unsigned int events;     /**< IMEST_CAN_EV_* */
  unsigned int index;      /**< frame index 0..3 (when ours) */
  unsigned int counter;    /**< its rolling counter */
  unsigned int prev_counter; /**< the previous counter of that id (EV_LOST / EV_REPEATED) */
  uint32_t lost;           /**< frames of this id lost (EV_LOST) */
  uint32_t seq_gap;        /**< windows dropped by the estimator (EV_SEQ_GAP) */
  int dec;                 /**< IMEST_CAN_DEC_* of the frame */
} imest_can_rx_event_t;

/** Running totals of a reader. */
typedef struct {
  uint32_t frames;         /**< frames fed */
  uint32_t foreign;
  uint32_t corrupt;
  uint32_t repeated;
  uint32_t lost;           /**< frames lost (counter gaps) */
  uint32_t windows;        /**< windows returned */
  uint32_t incomplete;     /**< of which incomplete */
  uint32_t seq_gaps;       /**< windows dropped by the estimator (sequence gaps
                                beyond what the counter explains) */
  uint32_t restarts;       /**< sequence number went backwards */
} imest_can_rx_stats_t;

/** Reader state (caller-owned). */
typedef struct {
  uint32_t base_id;
  unsigned int seen;                      /**< bit i: a frame of id i was seen */
  unsigned int last_ctr[IMEST_CAN_NFRAMES];
  int open;                               /**< a window is being assembled */
  imest_can_window_t cur;
  int have_seq;
  uint32_t last_seq;
  unsigned int last_seq_ctr;              /**< counter of the frame that carried last_seq */
  imest_can_rx_stats_t st;
} imest_can_rx_t;

/** Initialise a reader for the node at base_id (as in imest_attach_can()). */
void imest_can_rx_init(imest_can_rx_t *rx, uint32_t base_id);

/**
 * Feed one received frame. A window is returned in *out (EV_WINDOW) when its
 * fourth frame arrives, or, incomplete, when a frame of the next window
 * arrives first. ev (optional) receives the details.
 * @return the event bits.
 */
unsigned int imest_can_rx_feed(imest_can_rx_t *rx, const struct imest_can_frame *f,
                               imest_can_window_t *out, imest_can_rx_event_t *ev);

/** End of input: return the window still being assembled (EV_WINDOW |
 *  EV_INCOMPLETE), or 0 if none. */
unsigned int imest_can_rx_flush(imest_can_rx_t *rx, imest_can_window_t *out);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_CAN_H */
