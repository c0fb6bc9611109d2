/* SPDX-License-Identifier: Apache-2.0 */
/* CAN telemetry reader: assembles windows from frames and tells lost,
 * repeated, late and corrupted frames, estimator overruns and sender restarts
 * apart.
 *
 * Losses are counted per window, not per identifier, so that a corrupted
 * frame is not counted again as lost and a sender restart (counter and
 * sequence number start again) is not hundreds of lost frames: when a window
 * is returned, the frames expected since the previous one (the rolling
 * counter's gap in whole windows, plus this window) minus those received
 * minus those that arrived corrupted are the lost ones. A corrupted frame
 * cannot tell its window (its counter is not trusted): it is taken as the
 * open window's if that window still lacks its index and has nothing after
 * it (frames go out in index order), else as the next window's. The sequence number
 * (IMEST_STAT) tells a restart (it went back: nothing is counted across) from
 * an outage. No stdio, no malloc. */
#include <stddef.h>

#include "imest/imest_can.h"

#define ALL_FRAMES ((1u << IMEST_CAN_NFRAMES) - 1u)

int imest_can_rx_init(imest_can_rx_t *rx, uint32_t base_id)
{
  if (rx == NULL) return IMEST_ERR_NULL;
  if (imest_can_base_id_check(base_id) != IMEST_OK) return IMEST_ERR_ARG;
  unsigned char *raw = (unsigned char *)rx;
  for (size_t b = 0u; b < sizeof *rx; b++) raw[b] = 0u;
  rx->base_id = base_id;
  imest_can_window_clear(&rx->cur);
  return IMEST_OK;
}

static unsigned int popcount(unsigned int m)
{
  unsigned int n = 0u;
  for (unsigned int i = 0u; i < (unsigned int)IMEST_CAN_NFRAMES; i++) n += (m >> i) & 1u;
  return n;
}

static unsigned int lowest(unsigned int m)
{
  unsigned int i = 0u;
  while (i + 1u < (unsigned int)IMEST_CAN_NFRAMES && !((m >> i) & 1u)) i++;
  return i;
}

static unsigned int highest(unsigned int m)
{
  unsigned int i = (unsigned int)IMEST_CAN_NFRAMES - 1u;
  while (i > 0u && !((m >> i) & 1u)) i--;
  return i;
}

/* Hand out the window being assembled and account for it. at_end: the input
 * ended, so frames after its last received one may simply not be recorded. */
static unsigned int close_window(imest_can_rx_t *rx, imest_can_window_t *out, imest_can_rx_event_t *e,
                                 int at_end)
{
  const imest_can_window_t *w = &rx->cur;
  const unsigned int n = (unsigned int)IMEST_CAN_NFRAMES;
  unsigned int ev = IMEST_CAN_EV_WINDOW;
  const int have_seq = (int)((w->have >> IMEST_CAN_FRAME_STAT) & 1u);
  const uint32_t seq = w->result.seq;
  int restart = 0;

  if (have_seq && rx->have_seq && seq < rx->last_seq) {
    restart = 1;
    rx->st.restarts++;
    ev |= IMEST_CAN_EV_RESTART;
  } else if (have_seq && rx->have_seq) {
    const uint32_t g = seq - rx->last_seq;
    const uint32_t d = (uint32_t)((w->counter - rx->last_seq_ctr) & 0xFFu);
    if (g > d) {
      e->seq_gap = g - d;
      rx->st.seq_gaps += e->seq_gap;
      ev |= IMEST_CAN_EV_SEQ_GAP;
    }
  }
  if (have_seq) {
    rx->have_seq = 1;
    rx->last_seq = seq;
    rx->last_seq_ctr = w->counter;
  }

  /* frames expected from the previous window's end to this window's end */
  uint32_t expected;
  if (restart) {
    expected = n; /* the sender began anew with this window */
  } else if (rx->have_prev) {
    expected = (uint32_t)((w->counter - rx->prev_ctr - 1u) & 0xFFu) * n + n;
  } else {
    expected = n - lowest(w->have); /* the first window: joined mid-window? */
  }
  if (at_end) expected -= n - 1u - highest(w->have);
  const uint32_t accounted = (uint32_t)popcount(w->have) + rx->corrupt_cur;
  if (expected > accounted) {
    e->lost = expected - accounted;
    rx->st.lost += e->lost;
    ev |= IMEST_CAN_EV_LOST;
  }
  e->prev_counter = rx->prev_ctr;

  if (w->have != ALL_FRAMES) {
    ev |= IMEST_CAN_EV_INCOMPLETE;
    rx->st.incomplete++;
  }
  rx->st.windows++;
  if (out != NULL) *out = *w;
  rx->have_prev = 1;
  rx->prev_ctr = w->counter;
  rx->prev_have = w->have;
  rx->corrupt_cur = 0u;
  rx->open = 0;
  return ev;
}

static void event_clear(imest_can_rx_event_t *e)
{
  e->events = 0u;
  e->index = 0u;
  e->counter = 0u;
  e->prev_counter = 0u;
  e->lost = 0u;
  e->seq_gap = 0u;
  e->dec = IMEST_CAN_DEC_FOREIGN;
}

int imest_can_rx_feed(imest_can_rx_t *rx, const imest_can_frame_t *f, imest_can_window_t *out,
                      imest_can_rx_event_t *ev)
{
  imest_can_rx_event_t e;
  imest_can_window_t probe;
  unsigned int idx = 0u;
  event_clear(&e);
  if (ev != NULL) *ev = e;
  if (rx == NULL || f == NULL) return IMEST_ERR_NULL;
  rx->st.frames++;
  imest_can_window_clear(&probe);
  e.dec = imest_can_decode_frame(f, rx->base_id, &probe, &idx);
  e.index = idx;
  const unsigned int ctr = probe.counter;
  const unsigned int bit = 1u << idx;
  if (e.dec == IMEST_CAN_DEC_FOREIGN) {
    rx->st.foreign++;
    e.events = IMEST_CAN_EV_FOREIGN;
  } else if (e.dec != IMEST_CAN_DEC_OK) {
    rx->st.corrupt++;
    if (rx->open && !(rx->cur.have & bit) && (rx->cur.have >> idx) == 0u) {
      rx->corrupt_cur++;
    } else {
      rx->corrupt_next++;
    }
    e.events = IMEST_CAN_EV_CORRUPT;
  } else if ((rx->seen & bit) && rx->last_ctr[idx] == ctr) {
    e.counter = ctr;
    e.prev_counter = ctr;
    rx->st.repeated++;
    e.events = IMEST_CAN_EV_REPEATED;
  } else if (rx->have_prev && ctr == rx->prev_ctr && !(rx->prev_have & bit) &&
             !(rx->open && rx->cur.counter == ctr)) {
    /* e.g. a controller that sends by identifier priority from several
     * mailboxes: the frame arrived after the next window's first one */
    e.counter = ctr;
    rx->st.late++;
    if (rx->st.lost > 0u) rx->st.lost--; /* it was counted lost with its window */
    e.events = IMEST_CAN_EV_LATE;
  } else {
    e.counter = ctr;
    rx->seen |= bit;
    rx->last_ctr[idx] = ctr;
    if (rx->open && rx->cur.counter != ctr) {
      /* a frame of the next window: hand out the incomplete one */
      e.events |= close_window(rx, out, &e, 0);
    }
    if (!rx->open) {
      imest_can_window_clear(&rx->cur);
      rx->cur.counter = ctr;
      rx->open = 1;
      rx->corrupt_cur = rx->corrupt_next;
      rx->corrupt_next = 0u;
    }
    (void)imest_can_decode_frame(f, rx->base_id, &rx->cur, NULL);
    /* a window just opened by this frame cannot be complete unless it is
     * the only frame, so at most one window is handed out per call */
    if (rx->cur.have == ALL_FRAMES && !(e.events & IMEST_CAN_EV_WINDOW)) {
      e.events |= close_window(rx, out, &e, 0);
    }
  }
  if (ev != NULL) *ev = e;
  return (int)e.events;
}

int imest_can_rx_flush(imest_can_rx_t *rx, imest_can_window_t *out, imest_can_rx_event_t *ev)
{
  imest_can_rx_event_t e;
  event_clear(&e);
  if (ev != NULL) *ev = e;
  if (rx == NULL) return IMEST_ERR_NULL;
  if (!rx->open) return 0;
  e.events = close_window(rx, out, &e, 1);
  e.counter = rx->prev_ctr;
  if (ev != NULL) *ev = e;
  return (int)e.events;
}
