/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_can.h
 * @brief CAN telemetry of imest: signal table, frame codec, publisher and reader.
 *
 * Telemetry is separate from the estimator: imest_t holds no CAN state and
 * imest_background() sends nothing. The application owns a publisher and
 * hands it each result the background returns:
 *
 *     static imest_can_pub_t can;
 *     imest_can_pub_init(&can, &my_port, IMEST_CAN_DEFAULT_BASE_ID);
 *     ...
 *     while (imest_background(&est, &r) == 1) {
 *       (void)imest_can_publish(&can, &r);   // never blocks; refusals counted
 *       ...
 *     }
 *
 * A firmware that does not call these functions links none of this code.
 *
 * Every window is published as IMEST_CAN_NFRAMES classic CAN frames (8-byte
 * payloads) at consecutive identifiers base_id + 0 .. base_id + 5:
 *
 *   base+0 IMEST_TR       T_R [s] float32, E_I
 *   base+1 IMEST_RS       R_S [ohm] float32, relative PE index of K2
 *   base+2 IMEST_QUAL     relative PE index of K1, status, valid, saturation
 *                         bits, window flags, root counts
 *   base+3 IMEST_STAT     window sequence number, failed sends
 *   base+4 IMEST_VERDICT  T_R and R_S verdicts (valid, reason), span, windows
 *   base+5 IMEST_BOUNDS   relative error bounds of T_R and R_S
 *   every frame: bits 48..55 rolling counter (one value per window), bits
 *   56..63 CRC-8 SAE J1850 over [frame index, bytes 0..6].
 *
 * Where each signal sits is one table (imest_can_signal_table(), in
 * src/can/can_signals.c) that drives packing, decoding and the saturation bits;
 * tools/imest.dbc describes the same layout for CAN tools and test/can proves
 * the two equal, signal by signal. Layout and reasoning: port/README.md.
 *
 * Octets: a payload is `unsigned char data[8]`, each element holds one octet
 * (0..255) also on targets whose char has 16 bits (TI C2000). Packing is
 * explicit shift-and-mask arithmetic (little-endian / Intel byte order on the
 * bus), independent of struct layout and host endianness. Floats are IEEE-754
 * binary32 (checked at compile time).
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
 * Frames and identifiers
 * ------------------------------------------------------------------------- */

/** Identifier flag: set in imest_can_frame.id (and in a base id) for a
 *  29-bit extended identifier; clear for an 11-bit standard one. Same value
 *  as Linux's CAN_EFF_FLAG. */
#define IMEST_CAN_ID_EXT   0x80000000u
#define IMEST_CAN_SFF_MASK 0x000007FFu
#define IMEST_CAN_EFF_MASK 0x1FFFFFFFu

/** One classic CAN data frame. */
typedef struct imest_can_frame {
  uint32_t id;           /**< identifier, | IMEST_CAN_ID_EXT if extended */
  unsigned int dlc;      /**< data length 0..8 (imest sends 8) */
  unsigned char data[8]; /**< one octet (0..255) per element */
} imest_can_frame_t;

/** A transmit port. send() must not block: it queues the frame (or writes it)
 *  and returns 0, or returns nonzero if it cannot (queue full, bus-off, I/O
 *  error). imest_can_publish() calls it, never the ISR. */
typedef struct imest_can_port {
  int (*send)(void *ctx, const imest_can_frame_t *f);
  void *ctx;
} imest_can_port_t;

/** Frames per window, and their offsets from the base identifier. */
#define IMEST_CAN_NFRAMES       6
#define IMEST_CAN_FRAME_TR      0 /**< base+0: T_R, E_I */
#define IMEST_CAN_FRAME_RS      1 /**< base+1: R_S, relative PE index of K2 */
#define IMEST_CAN_FRAME_QUAL    2 /**< base+2: PE K1, status, valid, bits, roots */
#define IMEST_CAN_FRAME_STAT    3 /**< base+3: sequence number, failed sends */
#define IMEST_CAN_FRAME_VERDICT 4 /**< base+4: per-parameter verdicts, span, windows */
#define IMEST_CAN_FRAME_BOUNDS  5 /**< base+5: relative error bounds */

/** Suggested base identifier (free in the CANopen predefined connection set);
 *  tools/imest.dbc is written for it. Nodes are best spaced
 *  IMEST_CAN_ID_STRIDE apart (node n: 0x6A0 + 8 n), which leaves room for
 *  frames added later. */
#define IMEST_CAN_DEFAULT_BASE_ID 0x6A0u
#define IMEST_CAN_ID_STRIDE       8u

/** Saturation bits (imest_can_window_t.sat; carried in IMEST_QUAL, and in
 *  IMEST_VERDICT / IMEST_BOUNDS for their own fields): the value was outside
 *  its field's range and was clamped to the nearest end (float32 fields:
 *  +-FLT_MAX; infinities are sent as infinities). A receiver must show a
 *  clamped value as a bound ("> 1.31068"), never as the value. */
#define IMEST_CAN_SAT_TR   0x01u
#define IMEST_CAN_SAT_RS   0x02u
#define IMEST_CAN_SAT_EI   0x04u
#define IMEST_CAN_SAT_PEK1 0x08u
#define IMEST_CAN_SAT_PEK2 0x10u
#define IMEST_CAN_SAT_SPAN 0x20u
#define IMEST_CAN_SAT_TRB  0x40u
#define IMEST_CAN_SAT_RSB  0x80u

/**
 * Check a base identifier: an 11-bit standard identifier, or a 29-bit extended
 * one | IMEST_CAN_ID_EXT, such that base_id + IMEST_CAN_NFRAMES - 1 is still
 * an identifier of the same kind.
 * @retval IMEST_OK       usable
 * @retval IMEST_ERR_ARG  out of range (or bits other than IMEST_CAN_ID_EXT set above the id)
 */
int imest_can_base_id_check(uint32_t base_id);

/* ----------------------------------------------------------------------------
 * The signal table: one line per signal, driving pack, decode and saturation
 * ------------------------------------------------------------------------- */

/** How a signal is coded on the bus and which C field it comes from. Raw
 *  values are unsigned, Intel byte order; "all ones" is the raw value with
 *  every bit of the signal set (65535 for 16 bits). */
typedef enum {
  IMEST_CAN_F32 = 0, /**< double field <-> IEEE-754 binary32 (32 bits). NaN and
                           +-inf are carried; finite values beyond +-FLT_MAX are
                           clamped and set the signal's saturation bit */
  IMEST_CAN_SCALED,  /**< double field >= 0 <-> raw / scale, raw 0 .. all ones - 1;
                           all ones = not available (NaN); negative or too large:
                           clamped to 0 / all ones - 1 with the saturation bit */
  IMEST_CAN_COUNT,   /**< unsigned int field (at most 16 bits), saturating at all ones */
  IMEST_CAN_U32,     /**< uint32_t field, saturating at all ones */
  IMEST_CAN_ENUM,    /**< int field holding an imest_reason_t; a value outside
                           0 .. all ones - 1 is sent as all ones (out of range) */
  IMEST_CAN_BOOL,    /**< int field, 1 bit: nonzero -> 1 */
  IMEST_CAN_FLAG,    /**< 1 bit: bit `mask` (IMEST_FLAG_*) of the unsigned int field */
  IMEST_CAN_SAT,     /**< 1 bit: saturation bit `mask` (IMEST_CAN_SAT_*) of the window */
  IMEST_CAN_TXFAIL   /**< the publisher's failed-send count, saturating at all ones */
} imest_can_kind_t;

/** One signal. The name of each signal is in tools/imest.dbc (the C side
 *  needs none); test/can matches the two by frame and start bit. */
typedef struct {
  uint32_t scale;       /**< IMEST_CAN_SCALED: raw counts per physical unit,
                                 physical = raw / scale (the DBC factor is 1/scale); else 1 */
  unsigned short field; /**< offsetof(imest_result_t, <field>) (F32 .. FLAG) */
  unsigned short mask;  /**< F32/SCALED: its IMEST_CAN_SAT_* bit; FLAG: the
                                 IMEST_FLAG_* bit; SAT: the IMEST_CAN_SAT_* bit it carries */
  unsigned char frame;  /**< IMEST_CAN_FRAME_* */
  unsigned char start;  /**< start bit (DBC numbering, Intel: bit k = bit k%8 of octet k/8) */
  unsigned char len;    /**< bits */
  unsigned char kind;   /**< imest_can_kind_t */
} imest_can_signal_t;

/** Rolling counter and CRC: the same bits in every frame. */
#define IMEST_CAN_COUNTER_START 48u
#define IMEST_CAN_CRC_START     56u

/** The signal table (counter and CRC excluded), ordered by frame and start bit.
 *  @param count  receives the number of signals (may be NULL)
 *  @return the table (static, const) */
const imest_can_signal_t *imest_can_signal_table(unsigned int *count);

/* ----------------------------------------------------------------------------
 * Publisher (drive side)
 * ------------------------------------------------------------------------- */

/** A publisher: caller-owned, one per CAN node. Fields are readable. */
typedef struct {
  const imest_can_port_t *port;
  uint32_t base_id;   /**< as given to imest_can_pub_init() */
  uint32_t counter;   /**< rolling counter of the next window (sent mod 256) */
  uint32_t tx_failed; /**< frames port->send refused since init (also sent in
                                 IMEST_STAT, saturating at 65535 there) */
} imest_can_pub_t;

/**
 * Set up a publisher. The port struct must outlive the publisher's use of it.
 * @param base_id  see imest_can_base_id_check()
 * @retval IMEST_OK        ready; counter and tx_failed are 0
 * @retval IMEST_ERR_NULL  pub, port or port->send is NULL
 * @retval IMEST_ERR_ARG   base_id out of range
 */
int imest_can_pub_init(imest_can_pub_t *pub, const imest_can_port_t *port, uint32_t base_id);

/**
 * Publish one window's result: packs the IMEST_CAN_NFRAMES frames and hands
 * each once to port->send (no retry); a refusal is counted in pub->tx_failed.
 * Advances pub->counter by one. Call it from the background context (after
 * imest_background() returned 1), never from the ISR.
 * @return the number of frames the port refused (0 .. IMEST_CAN_NFRAMES)
 * @retval IMEST_ERR_NULL  pub or r is NULL, or pub was not initialised
 * @retval IMEST_ERR_ARG   pub->base_id was changed to an invalid identifier
 */
int imest_can_publish(imest_can_pub_t *pub, const imest_result_t *r);

/* ----------------------------------------------------------------------------
 * Codec
 * ------------------------------------------------------------------------- */

/** One window as carried on the bus (decoded). `result` holds the fields of
 *  the signal table: those of frames that did not arrive are NaN (floats), -1
 *  (reasons) or 0, and their frame's bit is clear in `have`. Fields of
 *  imest_result_t that are not on the bus (k1, hessian, roots ...) are 0. */
typedef struct {
  imest_result_t result; /**< T_R, R_S, verdicts, indices, flags, seq, ... */
  unsigned int have;     /**< bit i: frame base+i received and CRC-valid */
  unsigned int counter;  /**< rolling counter (0..255) */
  unsigned int sat;      /**< IMEST_CAN_SAT_* of the frames received */
  uint32_t tx_failed;    /**< sender's failed-send count (saturates at 65535) */
} imest_can_window_t;

/** CRC-8 SAE J1850 (poly 0x1D, init 0xFF, final xor 0xFF; check("123456789") = 0x4B)
 *  over n octets (only the low 8 bits of each element are used).
 *  @return the CRC (0 if data is NULL) */
unsigned int imest_can_crc8(const unsigned char *data, unsigned int n);

/**
 * Pack frame `index` of result r with rolling counter `counter` (mod 256) and
 * failed-send count `tx_failed`.
 * @retval IMEST_OK        *f holds the frame
 * @retval IMEST_ERR_NULL  r or f is NULL
 * @retval IMEST_ERR_ARG   index >= IMEST_CAN_NFRAMES or base_id out of range
 */
int imest_can_pack(const imest_result_t *r, unsigned int index, uint32_t base_id, unsigned int counter,
                   uint32_t tx_failed, imest_can_frame_t *f);

/** Outcomes of imest_can_decode_frame() (non-negative: the call worked). */
#define IMEST_CAN_DEC_OK      0 /**< decoded into the window */
#define IMEST_CAN_DEC_FOREIGN 1 /**< not one of ours (identifier outside base..base+5) */
#define IMEST_CAN_DEC_BAD_DLC 2 /**< ours, but not 8 data bytes */
#define IMEST_CAN_DEC_BAD_CRC 3 /**< ours, checksum mismatch */

/**
 * Check one frame and decode the signals it carries into *w (sets bit `index`
 * in w->have, and w->counter). *index (optional) receives the frame index
 * 0..IMEST_CAN_NFRAMES-1 when the identifier is ours.
 * @retval IMEST_CAN_DEC_OK, IMEST_CAN_DEC_FOREIGN, IMEST_CAN_DEC_BAD_DLC,
 *         IMEST_CAN_DEC_BAD_CRC  the frame's outcome (w is written only on OK)
 * @retval IMEST_ERR_NULL  f or w is NULL
 */
int imest_can_decode_frame(const imest_can_frame_t *f, uint32_t base_id, imest_can_window_t *w,
                           unsigned int *index);

/** Clear a decoded window: have = 0, table fields NaN / -1 / 0 as above. */
void imest_can_window_clear(imest_can_window_t *w);

/* ----------------------------------------------------------------------------
 * Reader: window assembly, loss / repeat / corruption / restart detection
 * ------------------------------------------------------------------------- */

/** Event bits of imest_can_rx_feed(). */
#define IMEST_CAN_EV_FOREIGN  0x001u /**< frame not ours: ignored */
#define IMEST_CAN_EV_CORRUPT  0x002u /**< ours, bad CRC or DLC: dropped (not counted lost) */
#define IMEST_CAN_EV_REPEATED 0x004u /**< ours, same counter as the last of its id: dropped */
#define IMEST_CAN_EV_LOST                                                                                    \
  0x008u                               /**< with EV_WINDOW: ev.lost frames never arrived,
                                            up to and in the returned window */
#define IMEST_CAN_EV_WINDOW     0x010u /**< a window is returned in *out (complete or not) */
#define IMEST_CAN_EV_INCOMPLETE 0x020u /**< ... and it lacks frames */
#define IMEST_CAN_EV_SEQ_GAP                                                                                 \
  0x040u /**< with EV_WINDOW: the sequence number skipped
                                            ev.seq_gap more windows than the rolling counter:
                                            windows the estimator dropped (overruns), not
                                            lost on the bus */
#define IMEST_CAN_EV_RESTART                                                                                 \
  0x080u /**< with EV_WINDOW: its sequence number went back:
                                            the sender restarted (no loss counted across) */
#define IMEST_CAN_EV_LATE                                                                                    \
  0x100u /**< ours, a frame of the window already returned
                                            incomplete (sent out of order): dropped */

/** Details of one imest_can_rx_feed() call. */
typedef struct {
  unsigned int events;       /**< IMEST_CAN_EV_* */
  unsigned int index;        /**< frame index (when ours) */
  unsigned int counter;      /**< its rolling counter (when decoded) */
  unsigned int prev_counter; /**< counter of the window returned before (EV_LOST) */
  uint32_t lost;             /**< EV_LOST: frames lost */
  uint32_t seq_gap;          /**< EV_SEQ_GAP: windows dropped by the estimator */
  int dec;                   /**< IMEST_CAN_DEC_* of the frame */
} imest_can_rx_event_t;

/** Running totals of a reader. */
typedef struct {
  uint32_t frames; /**< frames fed */
  uint32_t foreign;
  uint32_t corrupt; /**< bad CRC or DLC (not also counted as lost) */
  uint32_t repeated;
  uint32_t late;
  uint32_t lost;       /**< frames that never arrived (rolling-counter accounting;
                                not across a sender restart) */
  uint32_t windows;    /**< windows returned */
  uint32_t incomplete; /**< of which incomplete */
  uint32_t seq_gaps;   /**< windows dropped by the estimator (sequence gaps
                                beyond what the counter explains) */
  uint32_t restarts;   /**< sequence number went backwards */
} imest_can_rx_stats_t;

/** Reader state (caller-owned; fields private except `st`). */
typedef struct {
  uint32_t base_id;
  unsigned int seen; /* bit i: a frame of id i was seen */
  unsigned int last_ctr[IMEST_CAN_NFRAMES];
  int open; /* a window is being assembled */
  imest_can_window_t cur;
  int have_prev;                    /* a window was returned before */
  unsigned int prev_ctr, prev_have; /* its counter and frames */
  uint32_t corrupt_cur;             /* corrupt frames in place of the open window's */
  uint32_t corrupt_next;            /* ... and of the window that opens next */
  int have_seq;
  uint32_t last_seq;
  unsigned int last_seq_ctr; /* counter of the window that carried last_seq */
  imest_can_rx_stats_t st;   /**< running totals */
} imest_can_rx_t;

/**
 * Initialise a reader for the node at base_id.
 * @retval IMEST_OK        ready
 * @retval IMEST_ERR_NULL  rx is NULL
 * @retval IMEST_ERR_ARG   base_id out of range (imest_can_base_id_check())
 */
int imest_can_rx_init(imest_can_rx_t *rx, uint32_t base_id);

/**
 * Feed one received frame. A window is returned in *out (EV_WINDOW) when its
 * last frame arrives, or, incomplete, when a frame of the next window arrives
 * first. Losses are counted per returned window from the rolling counter:
 * frames expected since the previous window minus frames received minus
 * corrupted ones; none across a sender restart (the sequence number went
 * back), none before the first frame of the first window.
 * @param out  (optional) receives the window on EV_WINDOW
 * @param ev   (optional) receives the details
 * @return the event bits (>= 0)
 * @retval IMEST_ERR_NULL  rx or f is NULL
 */
int imest_can_rx_feed(imest_can_rx_t *rx, const imest_can_frame_t *f, imest_can_window_t *out,
                      imest_can_rx_event_t *ev);

/**
 * End of input: return the window still being assembled (frames missing after
 * its last received frame are not counted as lost: the capture ended).
 * @return EV_WINDOW | EV_INCOMPLETE (| EV_LOST ...), or 0 if no window was open
 * @retval IMEST_ERR_NULL  rx is NULL
 */
int imest_can_rx_flush(imest_can_rx_t *rx, imest_can_window_t *out, imest_can_rx_event_t *ev);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_CAN_H */
