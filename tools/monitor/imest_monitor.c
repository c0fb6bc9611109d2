/* SPDX-License-Identifier: Apache-2.0 */
/* imest-monitor: decode imest CAN telemetry live from a SocketCAN interface or
 * from a candump -L log, print a table or CSV, and report lost, repeated,
 * late and corrupted frames, estimator overruns and sender restarts (each on
 * stderr, and a summary at the end). When nothing could be decoded it says
 * what the input held and what is likely wrong, and exits 1. With
 * --temperatures it also shows each window's IMEST_TEMP frame (base + 6,
 * imest_temperature.h), matched to the window by the rolling counter.
 *
 * Exit codes: 0 windows decoded; 1 unusable input (nothing decoded, cannot
 * open or read the log, interface error); 2 usage error; 3 with
 * --require-valid, windows decoded but none valid. */
#define _GNU_SOURCE 1
#include <errno.h>
#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest/imest_temperature.h"
#include "imest_can_id.h"
#include "imest_candump.h"
#include "tool_args.h"
#ifdef IMEST_MONITOR_SOCKETCAN
#include "imest_socketcan.h"
#endif

static const char *const k_frame_name[IMEST_CAN_NFRAMES] = {"IMEST_TR",   "IMEST_RS",      "IMEST_QUAL",
                                                            "IMEST_STAT", "IMEST_VERDICT", "IMEST_BOUNDS"};
#define ALL_FRAMES ((1u << IMEST_CAN_NFRAMES) - 1u)

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
  (void)sig;
  g_stop = 1;
}

/* Identifiers that were not ours, for the diagnosis when nothing decodes. */
#define MAX_IDS 64
typedef struct {
  uint32_t id[MAX_IDS];
  unsigned long n[MAX_IDS];
  unsigned int used;
  unsigned long more; /* frames of identifiers beyond MAX_IDS distinct ones */
} id_census_t;

typedef struct {
  int csv;
  tool_require_t require; /* --require-valid */
  unsigned long n_valid;  /* windows whose required column is 1 */
  uint32_t base_id;
  unsigned long count; /* stop after this many windows (0: never) */
  unsigned long windows;
  double win_t; /* time of the last accepted frame of the open window */
  char where[128];
  imest_can_rx_t rx;
  unsigned long lines, malformed, plain_candump;
  uint32_t last_tx_failed;
  int have_tx_failed;
  id_census_t foreign;
  /* IMEST_TEMP (--temperatures): a window waits for its frame until that comes, a frame of
   * another window comes, or the input ends; a frame that came first waits for its window */
  int temps;
  int have_pending, have_temp;
  imest_can_window_t pending;
  double pending_t;
  imest_temperature_can_t temp;
  unsigned long temp_frames, temp_corrupt, temp_unmatched;
} monitor_t;

static void usage(FILE *f)
{
  fputs("usage: imest-monitor (--can-iface NAME | --log FILE|-) [--can-base-id ID] [--can-ext]\n"
        "                     [--csv] [--temperatures] [--count N] [--timeout SEC]\n"
        "                     [--require-valid[=WHICH]]\n"
        "  --can-iface NAME    read live from a SocketCAN interface (e.g. can0, vcan0);\n"
        "                      --iface NAME is the same (the older spelling)\n"
        "  --log FILE          read a candump -L log ('-' = stdin); record one with candump -L\n"
        "  --can-base-id ID    base identifier of the node (default 0x6A0); its frames are\n"
        "                      ID..ID+5. Values above 0x7FF are 29-bit extended identifiers\n"
        "                      (--base-id ID is the same, the older spelling)\n"
        "  --can-ext           the base identifier is a 29-bit extended one even if it is\n"
        "                      small (--ext is the same, the older spelling)\n"
        "  --csv               CSV instead of a table: t_s, then the columns imest-replay\n"
        "                      prints, in its order, for what the frames carry: T_R_s,R_S_ohm,\n"
        "                      E_I,valid,status,seq,pe_k1_rel,pe_k2_rel,n_roots,n_admissible,\n"
        "                      flags,tr_valid,rs_valid,tr_reason,rs_reason,span_s,windows,\n"
        "                      tr_bound_rel,rs_bound_rel; then the monitor's own: clamped,sat,\n"
        "                      tx_failed,counter,frames. t_s is the time of the window's last\n"
        "                      frame (for a log of imest-replay --candump: its t_end_s). A value\n"
        "                      the sender clamped to its field's range is printed as that\n"
        "                      limit, and its column is named in 'clamped' (';'-separated;\n"
        "                      'sat' is the same as a bit mask). Empty: its frame is missing\n"
        "  --temperatures      also the stator's and the rotor's temperatures of the frame\n"
        "                      IMEST_TEMP (ID+6, sent by firmware that runs the temperature\n"
        "                      module), matched to its window by the rolling counter: in the\n"
        "                      CSV the columns stator_c,stator_uncert_k,stator_valid,rotor_c,\n"
        "                      rotor_uncert_k,rotor_valid (imest-replay --temperatures' names,\n"
        "                      without rr_ohm) after rs_bound_rel, empty when no IMEST_TEMP\n"
        "                      came with the window, nan when it says not available; 'frames'\n"
        "                      has bit 0x40 for it. A window is shown when its IMEST_TEMP\n"
        "                      arrives, or a frame of another window, or the input ends\n"
        "  --count N           stop after N windows (N >= 1)\n"
        "  --timeout SEC       live: stop after SEC seconds without any frame (default: never)\n"
        "  --require-valid[=WHICH]  exit 3 when windows were decoded but none has WHICH = 1:\n"
        "                      valid (the default: T_R and R_S), tr (tr_valid) or rs\n"
        "                      (rs_valid); the value only as --require-valid=WHICH\n"
        "  -h, --help          this text\n"
        "  --version           the version and licence\n"
        "Options take their value as '--opt value' or '--opt=value'. Events (lost, repeated,\n"
        "corrupted frames, incomplete windows, sequence gaps, restarts) and a summary go to\n"
        "stderr. The table shows a clamped value as a bound ('>1.31068').\n"
        "Exit status: 0 windows decoded; 1 nothing decoded or an input error; 2 usage error;\n"
        "3 --require-valid given and no decoded window valid (the message names the column).\n",
        f);
}

/* --- output ------------------------------------------------------------------ */

static void fmt_or_empty(char *buf, size_t n, int have, const char *fmt, double v)
{
  if (have) {
    snprintf(buf, n, fmt, v);
  } else {
    buf[0] = '\0';
  }
}

/* A value the sender clamped to its field's range is a bound, not a value. */
static void fmt_value(char *buf, size_t n, int have, const char *fmt, double v, unsigned int sat,
                      unsigned int sat_bit)
{
  if (have && (sat & sat_bit)) {
    buf[0] = v > 0.0 ? '>' : '<';
    snprintf(buf + 1, n - 1u, fmt, v);
  } else {
    fmt_or_empty(buf, n, have, fmt, v);
  }
}

/* The table's relative bounds, in percent ("n/a" when not available). */
static void fmt_percent(char *buf, size_t n, int have, double v, unsigned int sat, unsigned int sat_bit)
{
  if (have && isnan(v)) {
    snprintf(buf, n, "n/a");
  } else {
    fmt_value(buf, n, have, "%.3f%%", 100.0 * v, sat, sat_bit);
  }
}

static void fmt_reason(char *buf, size_t n, int have, int reason)
{
  if (!have) {
    buf[0] = '\0';
  } else if (reason == 255) {
    snprintf(buf, n, "out_of_range");
  } else {
    snprintf(buf, n, "%s", imest_reason_name(reason));
  }
}

/* The clamped columns, in the order of the saturation bits (IMEST_CAN_SAT_*). */
static const struct {
  unsigned int bit;
  const char *column;
} k_clamp[] = {{IMEST_CAN_SAT_TR, "T_R_s"},         {IMEST_CAN_SAT_RS, "R_S_ohm"},
               {IMEST_CAN_SAT_EI, "E_I"},           {IMEST_CAN_SAT_PEK1, "pe_k1_rel"},
               {IMEST_CAN_SAT_PEK2, "pe_k2_rel"},   {IMEST_CAN_SAT_SPAN, "span_s"},
               {IMEST_CAN_SAT_TRB, "tr_bound_rel"}, {IMEST_CAN_SAT_RSB, "rs_bound_rel"}};

/* A CSV cell: the number (a clamped one as its limit: the 'clamped' column
 * says so), empty when its frame is missing. */
static void csv_num(int have, const char *fmt, double v)
{
  putchar(',');
  if (have) printf(fmt, v);
}

static void csv_uint(int have, unsigned long v)
{
  putchar(',');
  if (have) printf("%lu", v);
}

static void csv_reason(int have, int reason)
{
  putchar(',');
  if (have) fputs(reason == 255 ? "out_of_range" : imest_reason_name(reason), stdout);
}

/* IMEST_TEMP's values and the columns named in 'clamped' when at their field's end. */
static const struct {
  unsigned int bit;
  const char *column;
} k_temp_clamp[] = {{IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C, "stator_c"},
                    {IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT, "stator_uncert_k"},
                    {IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C, "rotor_c"},
                    {IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_UNCERT, "rotor_uncert_k"}};

/* A temperature cell: empty without the frame, "nan" when not available (as imest-replay). */
static void csv_temp(const imest_temperature_can_t *tc, const char *fmt, float v)
{
  putchar(',');
  if (tc == NULL) return;
  if (isnan(v))
    fputs("nan", stdout);
  else
    printf(fmt, (double)v);
}

static void csv_temperatures(const imest_temperature_can_t *tc)
{
  csv_temp(tc, "%.2f", tc ? tc->stator_c : 0.0f);
  csv_temp(tc, "%.1f", tc ? tc->stator_uncert_k : 0.0f);
  putchar(',');
  if (tc) printf("%d", tc->stator_valid);
  csv_temp(tc, "%.2f", tc ? tc->rotor_c : 0.0f);
  csv_temp(tc, "%.1f", tc ? tc->rotor_uncert_k : 0.0f);
  putchar(',');
  if (tc) printf("%d", tc->rotor_valid);
}

/* One CSV row: imest-replay's columns and order for what the frames carry
 * (print_header lists them), then the monitor's own. temps: --temperatures (tc NULL: no
 * IMEST_TEMP came with this window). */
static void print_csv_row(const imest_can_window_t *w, double t, int h_tr, int h_rs, int h_q, int h_v,
                          int h_b, int temps, const imest_temperature_can_t *tc)
{
  const imest_result_t *r = &w->result;
  const int h_st = (int)((w->have >> IMEST_CAN_FRAME_STAT) & 1u);
  printf("%.6f", t);
  csv_num(h_tr, "%.9g", r->tr_s);
  csv_num(h_rs, "%.9g", r->rs_ohm);
  csv_num(h_tr, "%.4f", r->e_i);
  csv_uint(h_q, (unsigned long)r->valid);
  csv_reason(h_q, r->status);
  csv_uint(h_st, (unsigned long)r->seq);
  csv_num(h_q, "%.5f", r->pe_k1_rel);
  csv_num(h_rs, "%.5f", r->pe_k2_rel);
  csv_uint(h_q, r->n_roots);
  csv_uint(h_q, r->n_admissible);
  putchar(',');
  if (h_q) printf("0x%x", r->flags);
  csv_uint(h_v, (unsigned long)r->tr_valid);
  csv_uint(h_v, (unsigned long)r->rs_valid);
  csv_reason(h_v, r->tr_reason);
  csv_reason(h_v, r->rs_reason);
  csv_num(h_v, "%.3f", r->span_s);
  csv_uint(h_v, r->windows);
  csv_num(h_b, "%.5f", r->tr_bound_rel);
  csv_num(h_b, "%.5f", r->rs_bound_rel);
  if (temps) csv_temperatures(tc);
  putchar(',');
  const char *sep = "";
  for (size_t k = 0; k < sizeof k_clamp / sizeof k_clamp[0]; ++k) {
    if (w->sat & k_clamp[k].bit) {
      printf("%s%s", sep, k_clamp[k].column);
      sep = ";";
    }
  }
  for (size_t k = 0; tc != NULL && k < sizeof k_temp_clamp / sizeof k_temp_clamp[0]; ++k) {
    if (tc->clamped & k_temp_clamp[k].bit) {
      printf("%s%s", sep, k_temp_clamp[k].column);
      sep = ";";
    }
  }
  putchar(',');
  if (h_q) printf("0x%x", w->sat);
  csv_uint(h_st, (unsigned long)w->tx_failed);
  printf(",%u,0x%x\n", w->counter, w->have | (tc ? 1u << IMEST_TEMPERATURE_CAN_FRAME : 0u));
}

/* The table's temperature columns: value (a clamped one as a bound), uncertainty, verdict. */
static void fmt_temp(char *buf, size_t n, const imest_temperature_can_t *tc, float v, const char *fmt,
                     unsigned int clamp_bit)
{
  if (tc == NULL) {
    buf[0] = '\0';
  } else if (isnan(v)) {
    snprintf(buf, n, "n/a");
  } else if (tc->clamped & clamp_bit) {
    buf[0] = v > 0.0f ? '>' : '<';
    snprintf(buf + 1, n - 1u, fmt, (double)v);
  } else {
    snprintf(buf, n, fmt, (double)v);
  }
}

static void print_table_temperatures(const imest_temperature_can_t *tc)
{
  char sc[24], su[16], rc[24], ru[16];
  fmt_temp(sc, sizeof sc, tc, tc ? tc->stator_c : 0.0f, "%.2f", IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C);
  fmt_temp(su, sizeof su, tc, tc ? tc->stator_uncert_k : 0.0f, "%.1f",
           IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT);
  fmt_temp(rc, sizeof rc, tc, tc ? tc->rotor_c : 0.0f, "%.2f", IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C);
  fmt_temp(ru, sizeof ru, tc, tc ? tc->rotor_uncert_k : 0.0f, "%.1f",
           IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_UNCERT);
  printf(" %9s %5s %-2s %9s %5s %-2s", sc, su,
         tc == NULL         ? ""
         : tc->stator_valid ? "ok"
                            : "no",
         rc, ru,
         tc == NULL        ? ""
         : tc->rotor_valid ? "ok"
                           : "no");
}

/* --require-valid: whether the window has the column asked for at 1. */
static void count_valid(monitor_t *m, const imest_can_window_t *w, int h_q, int h_v)
{
  const imest_result_t *r = &w->result;
  if ((m->require == TOOL_REQUIRE_VALID && h_q && r->valid) ||
      (m->require == TOOL_REQUIRE_TR && h_v && r->tr_valid) ||
      (m->require == TOOL_REQUIRE_RS && h_v && r->rs_valid))
    m->n_valid++;
}

/* tc: the window's IMEST_TEMP (NULL: none, or no --temperatures) */
static void print_window(monitor_t *m, const imest_can_window_t *w, double t,
                         const imest_temperature_can_t *tc)
{
  const imest_result_t *r = &w->result;
  const int h_tr = (int)((w->have >> IMEST_CAN_FRAME_TR) & 1u);
  const int h_rs = (int)((w->have >> IMEST_CAN_FRAME_RS) & 1u);
  const int h_q = (int)((w->have >> IMEST_CAN_FRAME_QUAL) & 1u);
  const int h_st = (int)((w->have >> IMEST_CAN_FRAME_STAT) & 1u);
  const int h_v = (int)((w->have >> IMEST_CAN_FRAME_VERDICT) & 1u);
  const int h_b = (int)((w->have >> IMEST_CAN_FRAME_BOUNDS) & 1u);
  const unsigned int sat = w->sat;
  char seq[16], tr[32], rs[32], ei[32], valid[8], status[32], pk1[32], pk2[32];
  char nr[8], na[8], flags[16], txf[16];
  char trv[8], rsv[8], trr[32], rsr[32], trb[32], rsb[32], span[32], nw[8];
  if (h_st) {
    snprintf(seq, sizeof seq, "%lu", (unsigned long)r->seq);
    snprintf(txf, sizeof txf, "%lu", (unsigned long)w->tx_failed);
  } else {
    seq[0] = txf[0] = '\0';
  }
  count_valid(m, w, h_q, h_v);
  fmt_value(tr, sizeof tr, h_tr, "%.9g", r->tr_s, sat, IMEST_CAN_SAT_TR);
  fmt_value(ei, sizeof ei, h_tr, "%.4f", r->e_i, sat, IMEST_CAN_SAT_EI);
  fmt_value(rs, sizeof rs, h_rs, "%.9g", r->rs_ohm, sat, IMEST_CAN_SAT_RS);
  fmt_value(pk2, sizeof pk2, h_rs, "%.5f", r->pe_k2_rel, sat, IMEST_CAN_SAT_PEK2);
  fmt_value(pk1, sizeof pk1, h_q, "%.5f", r->pe_k1_rel, sat, IMEST_CAN_SAT_PEK1);
  if (h_q) {
    snprintf(valid, sizeof valid, "%d", r->valid);
    snprintf(nr, sizeof nr, "%u", r->n_roots);
    snprintf(na, sizeof na, "%u", r->n_admissible);
    snprintf(flags, sizeof flags, "0x%04X", r->flags);
  } else {
    valid[0] = nr[0] = na[0] = flags[0] = '\0';
  }
  fmt_reason(status, sizeof status, h_q, r->status);
  trv[0] = rsv[0] = nw[0] = '\0'; /* empty without the validity group */
  if (h_v) {
    snprintf(trv, sizeof trv, "%d", r->tr_valid);
    snprintf(rsv, sizeof rsv, "%d", r->rs_valid);
    snprintf(nw, sizeof nw, "%u", r->windows);
  }
  fmt_reason(trr, sizeof trr, h_v, r->tr_reason);
  fmt_reason(rsr, sizeof rsr, h_v, r->rs_reason);
  fmt_value(span, sizeof span, h_v, "%.3f", r->span_s, sat, IMEST_CAN_SAT_SPAN);
  if (m->csv) {
    print_csv_row(w, t, h_tr, h_rs, h_q, h_v, h_b, m->temps, tc);
  } else {
    /* verdict per parameter: "ok", or why not; bounds in % */
    const char *trw = !h_v ? "" : r->tr_valid ? "ok" : trr;
    const char *rsw = !h_v ? "" : r->rs_valid ? "ok" : rsr;
    fmt_percent(trb, sizeof trb, h_b, r->tr_bound_rel, sat, IMEST_CAN_SAT_TRB);
    fmt_percent(rsb, sizeof rsb, h_b, r->rs_bound_rel, sat, IMEST_CAN_SAT_RSB);
    printf("%17.6f %8s %14s %9s %-17s %14s %9s %-17s %7s %9s %9s %8s %2s/%-2s %6s %5s", t, seq, tr, trb, trw,
           rs, rsb, rsw, ei, pk1, pk2, span, na, nr, flags, txf);
    if (m->temps) print_table_temperatures(tc);
    printf("%s\n", w->have == ALL_FRAMES ? "" : "  (incomplete)");
  }
  if (h_st) {
    m->last_tx_failed = w->tx_failed;
    m->have_tx_failed = 1;
  }
  fflush(stdout);
  m->windows++;
}

static void print_header(const monitor_t *m)
{
  if (m->csv) {
    /* imest-replay's names and order (tools/replay/replay.c), then the monitor's own */
    printf("t_s,T_R_s,R_S_ohm,E_I,valid,status,seq,pe_k1_rel,pe_k2_rel,n_roots,n_admissible,flags,"
           "tr_valid,rs_valid,tr_reason,rs_reason,span_s,windows,tr_bound_rel,rs_bound_rel,%s"
           "clamped,sat,tx_failed,counter,frames\n",
           m->temps ? "stator_c,stator_uncert_k,stator_valid,rotor_c,rotor_uncert_k,rotor_valid," : "");
  } else {
    printf("%17s %8s %14s %9s %-17s %14s %9s %-17s %7s %9s %9s %8s %5s %6s %5s", "t [s]", "seq", "T_R [s]",
           "+-T_R", "T_R verdict", "R_S [ohm]", "+-R_S", "R_S verdict", "E_I", "PE_K1", "PE_K2", "span [s]",
           "adm/r", "flags", "txf");
    if (m->temps) printf(" %9s %5s %-2s %9s %5s %-2s", "stator[C]", "+-K", "ok", "rotor[C]", "+-K", "ok");
    putchar('\n');
  }
  fflush(stdout);
}

/* --- events ------------------------------------------------------------------ */

static void report_missing(const monitor_t *m, const imest_can_window_t *w)
{
  fprintf(stderr, "imest-monitor: %s: incomplete window (counter %u", m->where, w->counter);
  if (w->have & (1u << IMEST_CAN_FRAME_STAT)) fprintf(stderr, ", seq %lu", (unsigned long)w->result.seq);
  fputs("): missing", stderr);
  for (unsigned int i = 0u; i < IMEST_CAN_NFRAMES; i++) {
    if (!(w->have & (1u << i))) fprintf(stderr, " %s", k_frame_name[i]);
  }
  fputc('\n', stderr);
}

static void report_window_events(const monitor_t *m, unsigned int e, const imest_can_rx_event_t *ev,
                                 const imest_can_window_t *w)
{
  if (e & IMEST_CAN_EV_RESTART) {
    fprintf(stderr,
            "imest-monitor: %s: sequence number went back to %lu: the sender restarted "
            "(no loss counted across the restart)\n",
            m->where, (unsigned long)w->result.seq);
  }
  if (e & IMEST_CAN_EV_LOST) {
    fprintf(stderr,
            "imest-monitor: %s: lost %lu frame(s) up to the window with counter %u (previous "
            "window: counter %u)\n",
            m->where, (unsigned long)ev->lost, w->counter, ev->prev_counter);
  }
  if (e & IMEST_CAN_EV_INCOMPLETE) report_missing(m, w);
  if (e & IMEST_CAN_EV_SEQ_GAP) {
    fprintf(stderr, "imest-monitor: %s: the estimator dropped %lu window(s) before seq %lu (overrun)\n",
            m->where, (unsigned long)ev->seq_gap, (unsigned long)w->result.seq);
  }
}

static void census_add(id_census_t *c, uint32_t id)
{
  for (unsigned int i = 0u; i < c->used; i++) {
    if (c->id[i] == id) {
      c->n[i]++;
      return;
    }
  }
  if (c->used < MAX_IDS) {
    c->id[c->used] = id;
    c->n[c->used++] = 1u;
  } else {
    c->more++;
  }
}

/* --- IMEST_TEMP: windows and their temperatures matched by the counter --------- */

/* The window waiting for its IMEST_TEMP, shown without it. */
static void flush_pending(monitor_t *m)
{
  if (!m->have_pending) return;
  m->have_pending = 0;
  print_window(m, &m->pending, m->pending_t, NULL);
}

/* A window the reader returned: shown now without --temperatures or with its IMEST_TEMP if that
 * came first; else it waits for it. */
static void deliver_window(monitor_t *m, const imest_can_window_t *w, double t)
{
  if (!m->temps) {
    print_window(m, w, t, NULL);
    return;
  }
  flush_pending(m);
  if (m->have_temp && m->temp.counter == w->counter) {
    m->have_temp = 0;
    print_window(m, w, t, &m->temp);
    return;
  }
  if (m->have_temp) m->temp_unmatched++; /* its window never came */
  m->have_temp = 0;
  m->pending = *w;
  m->pending_t = t;
  m->have_pending = 1;
}

static void handle_temp(monitor_t *m, const imest_temperature_can_t *tc)
{
  m->temp_frames++;
  if (!m->temps) {
    if (m->temp_frames == 1u)
      fprintf(stderr,
              "imest-monitor: %s: IMEST_TEMP frames (the motor's temperatures) on the bus: "
              "--temperatures shows them\n",
              m->where);
    return;
  }
  if (m->have_pending && m->pending.counter == tc->counter) {
    m->have_pending = 0;
    print_window(m, &m->pending, m->pending_t, tc);
    return;
  }
  flush_pending(m);                      /* its IMEST_TEMP was lost */
  if (m->have_temp) m->temp_unmatched++; /* a second one before its window: the first is stale */
  m->temp = *tc;                         /* for a window still being assembled */
  m->have_temp = 1;
}

static void handle_frame(monitor_t *m, const imest_can_frame_t *f, double t)
{
  imest_can_window_t w;
  imest_can_rx_event_t ev;
  imest_temperature_can_t tc;
  const double prev_t = m->win_t;
  const int td = imest_temperature_can_decode(f, m->base_id, &tc); /* < 0: the base has no ID+6 */
  if (td == IMEST_CAN_DEC_OK) {
    handle_temp(m, &tc);
    return;
  }
  if (td == IMEST_CAN_DEC_BAD_DLC || td == IMEST_CAN_DEC_BAD_CRC) {
    char tid[24];
    m->temp_corrupt++;
    fprintf(stderr, "imest-monitor: %s: corrupted frame %s (IMEST_TEMP): %s\n", m->where,
            imest_can_id_format(f->id, tid, sizeof tid),
            td == IMEST_CAN_DEC_BAD_DLC ? "not 8 data bytes" : "checksum mismatch");
    return;
  }
  const int rc = imest_can_rx_feed(&m->rx, f, &w, &ev);
  const unsigned int e = rc < 0 ? 0u : (unsigned int)rc;
  const char *name = ev.index < IMEST_CAN_NFRAMES ? k_frame_name[ev.index] : "?";
  char id[24];
  imest_can_id_format(f->id, id, sizeof id);
  if (e & IMEST_CAN_EV_FOREIGN) {
    census_add(&m->foreign, f->id);
    return;
  }
  if (e & IMEST_CAN_EV_CORRUPT) {
    if (ev.dec == IMEST_CAN_DEC_BAD_DLC) {
      fprintf(stderr, "imest-monitor: %s: corrupted frame %s (%s): %u data bytes, expected 8\n", m->where, id,
              name, f->dlc);
    } else {
      fprintf(stderr, "imest-monitor: %s: corrupted frame %s (%s): checksum mismatch\n", m->where, id, name);
    }
    return;
  }
  if (e & IMEST_CAN_EV_REPEATED) {
    fprintf(stderr, "imest-monitor: %s: repeated frame %s (%s), counter %u\n", m->where, id, name,
            ev.counter);
    return;
  }
  if (e & IMEST_CAN_EV_LATE) {
    fprintf(stderr, "imest-monitor: %s: late frame %s (%s) of the window with counter %u, already shown\n",
            m->where, id, name, ev.counter);
    return;
  }
  /* a frame of another window: the waiting one's IMEST_TEMP is not coming */
  if (m->have_pending && ev.counter != m->pending.counter) flush_pending(m);
  if (e & IMEST_CAN_EV_WINDOW) {
    report_window_events(m, e, &ev, &w);
    deliver_window(m, &w, (e & IMEST_CAN_EV_INCOMPLETE) ? prev_t : t);
  }
  m->win_t = t;
}

/* --- when nothing was decoded: say what the input held ---------------------- */

static void explain_ids(const monitor_t *m)
{
  const id_census_t *c = &m->foreign;
  const uint32_t kind = m->base_id & IMEST_CAN_ID_EXT;
  const uint32_t base = m->base_id & IMEST_CAN_EFF_MASK;
  unsigned int order[MAX_IDS];
  char buf[24];
  /* most frequent first (insertion sort: at most MAX_IDS entries) */
  for (unsigned int i = 0u; i < c->used; i++) {
    unsigned int k = i;
    while (k > 0u && c->n[order[k - 1u]] < c->n[i]) {
      order[k] = order[k - 1u];
      k--;
    }
    order[k] = i;
  }
  fputs("; frames seen:", stderr);
  for (unsigned int i = 0u; i < c->used && i < 8u; i++) {
    fprintf(stderr, "%s %s (%lu)", i ? "," : "", imest_can_id_format(c->id[order[i]], buf, sizeof buf),
            c->n[order[i]]);
  }
  if (c->used > 8u || c->more) fputs(", ...", stderr);
  /* our numbers, but the other kind of identifier? */
  for (unsigned int i = 0u; i < c->used; i++) {
    const uint32_t id = c->id[i];
    if ((id & IMEST_CAN_ID_EXT) != kind && (id & IMEST_CAN_EFF_MASK) - base < (uint32_t)IMEST_CAN_NFRAMES) {
      fprintf(stderr, kind ? "; the log has 11-bit (standard) identifiers at that base: drop --can-ext\n"
                           : "; the log has 29-bit (extended) identifiers at that base: add --can-ext\n");
      return;
    }
  }
  /* a run of IMEST_CAN_NFRAMES consecutive identifiers of one kind: a node at another base? */
  for (unsigned int i = 0u; i < c->used; i++) {
    unsigned int run = 1u;
    for (unsigned int k = 1u; k < (unsigned int)IMEST_CAN_NFRAMES; k++) {
      for (unsigned int j = 0u; j < c->used; j++) {
        if (c->id[j] == c->id[i] + k) {
          run++;
          break;
        }
      }
    }
    if (run == (unsigned int)IMEST_CAN_NFRAMES) {
      fprintf(stderr, "; is --can-base-id right? %s .. +%d look like an imest node: --can-base-id %s\n",
              imest_can_id_format(c->id[i], buf, sizeof buf), IMEST_CAN_NFRAMES - 1,
              imest_can_id_format(c->id[i], buf, sizeof buf));
      return;
    }
  }
  fputs("; is --can-base-id right?\n", stderr);
}

/* Nothing decoded: name the likely cause. */
static void explain_nothing(const monitor_t *m, int live)
{
  const imest_can_rx_stats_t *s = &m->rx.st;
  char a[24], b[24];
  const uint32_t last =
      ((m->base_id & ~IMEST_CAN_ID_EXT) + IMEST_CAN_NFRAMES - 1u) | (m->base_id & IMEST_CAN_ID_EXT);
  imest_can_id_format(m->base_id, a, sizeof a);
  imest_can_id_format(last, b, sizeof b);
  fputs("imest-monitor: nothing decoded: ", stderr);
  if (s->frames == 0u && m->temp_frames + m->temp_corrupt > 0u) {
    fprintf(stderr, "%lu IMEST_TEMP frame(s) at %s+6, but none of the six frames %s..%s\n",
            m->temp_frames + m->temp_corrupt, a, a, b);
  } else if (s->frames == 0u) {
    if (live) {
      fputs("no frame received\n", stderr);
    } else if (m->lines == 0u) {
      fputs("the log is empty\n", stderr);
    } else if (m->plain_candump > 0u) {
      fprintf(stderr,
              "%lu line(s) read, none in candump -L format; they look like plain candump output "
              "('can0  6A0   [8]  00 11 ...'): record with 'candump -L' (or 'candump -l')\n",
              m->lines);
    } else {
      fprintf(stderr,
              "%lu line(s) read, none a candump -L frame line ('(1700000000.000000) can0 "
              "6A0#0011...'; see the malformed-line messages above)\n",
              m->lines);
    }
  } else if (s->foreign == s->frames) {
    fprintf(stderr, "%lu frame(s) %s, none with identifiers %s..%s", (unsigned long)s->frames,
            live ? "received" : "read", a, b);
    explain_ids(m);
  } else {
    fprintf(stderr,
            "%lu frame(s) at identifiers %s..%s, all corrupted (bad checksum or length): another "
            "sender at these identifiers, or another telemetry layout?\n",
            (unsigned long)(s->frames - s->foreign), a, b);
  }
}

static int finish(monitor_t *m, int live)
{
  imest_can_window_t w;
  imest_can_rx_event_t ev;
  const imest_can_rx_stats_t *s = &m->rx.st;
  if (m->count == 0u || m->windows < m->count) flush_pending(m);
  if (m->count == 0u || m->windows < m->count) {
    const int rc = imest_can_rx_flush(&m->rx, &w, &ev);
    if (rc > 0) {
      snprintf(m->where, sizeof m->where, "end of input");
      report_window_events(m, (unsigned int)rc, &ev, &w);
      deliver_window(m, &w, m->win_t);
      flush_pending(m);
    }
  }
  if (m->have_temp) m->temp_unmatched++;
  fprintf(stderr,
          "imest-monitor: summary: frames %lu (foreign %lu), windows %lu (incomplete %lu), "
          "lost %lu, repeated %lu, corrupted %lu, estimator gaps %lu, restarts %lu, late %lu, "
          "malformed lines %lu, sender tx_failed %s%lu\n",
          (unsigned long)s->frames, (unsigned long)s->foreign, (unsigned long)s->windows,
          (unsigned long)s->incomplete, (unsigned long)s->lost, (unsigned long)s->repeated,
          (unsigned long)s->corrupt, (unsigned long)s->seq_gaps, (unsigned long)s->restarts,
          (unsigned long)s->late, m->malformed, m->have_tx_failed ? "" : "n/a ",
          (unsigned long)m->last_tx_failed);
  if (m->temp_frames > 0u || m->temp_corrupt > 0u) {
    fprintf(stderr, "imest-monitor: IMEST_TEMP frames %lu (corrupted %lu, without their window %lu)%s\n",
            m->temp_frames, m->temp_corrupt, m->temp_unmatched,
            m->temps ? "" : ": not shown, --temperatures shows them");
  }
  if (m->windows == 0u) {
    explain_nothing(m, live);
    return TOOL_EXIT_DATA;
  }
  if (m->require != TOOL_REQUIRE_NONE && m->n_valid == 0u) {
    fprintf(stderr, "imest-monitor: --require-valid: none of the %lu window(s) decoded has %s = 1\n",
            m->windows, tool_require_column(m->require));
    return TOOL_EXIT_NOT_VALID;
  }
  return TOOL_EXIT_OK;
}

/* --- sources ------------------------------------------------------------------ */

/* "  can0  6A0   [8]  00 11 ..." : what plain candump prints (without -L). */
static int looks_like_plain_candump(const char *line)
{
  char ifn[32], id[16];
  unsigned int dlc;
  return sscanf(line, " %31s %15[0-9A-Fa-f] [%u]", ifn, id, &dlc) == 3;
}

static int run_log(monitor_t *m, const char *path)
{
  const int is_stdin = strcmp(path, "-") == 0;
  const char *label = is_stdin ? "<stdin>" : path;
  FILE *fp = is_stdin ? stdin : fopen(path, "r");
  struct stat st;
  char *line = NULL;
  size_t cap = 0u;
  ssize_t n;
  if (fp == NULL) {
    fprintf(stderr, "imest-monitor: cannot open log '%s': %s\n", path, strerror(errno));
    return TOOL_EXIT_DATA;
  }
  if (fstat(fileno(fp), &st) == 0 && S_ISDIR(st.st_mode)) {
    fprintf(stderr, "imest-monitor: cannot read log '%s': it is a directory (give a candump -L file)\n",
            path);
    if (!is_stdin) fclose(fp);
    return TOOL_EXIT_DATA;
  }
  print_header(m);
  errno = 0;
  while (!g_stop && (n = getline(&line, &cap, fp)) >= 0) {
    imest_can_frame_t f;
    double t = 0.0;
    const char *err = NULL;
    int r;
    m->lines++;
    if ((size_t)n != strlen(line)) {
      r = IMEST_CANDUMP_ERROR;
      err = "NUL byte in the line";
    } else {
      r = imest_candump_parse(line, &t, NULL, &f, &err);
    }
    if (r == IMEST_CANDUMP_EMPTY) continue;
    if (r != IMEST_CANDUMP_OK) {
      const size_t k = strcspn(line, "\r\n");
      m->malformed++;
      if (looks_like_plain_candump(line)) m->plain_candump++;
      if (m->malformed <= 20u) {
        fprintf(stderr, "imest-monitor: %s:%lu: malformed line: %s: '%.*s'\n", label, m->lines, err,
                (int)(k > 80u ? 80u : k), line);
      } else if (m->malformed == 21u) {
        fprintf(stderr, "imest-monitor: %s: more malformed lines (counted in the summary)\n", label);
      }
      continue;
    }
    snprintf(m->where, sizeof m->where, "%s:%lu", label, m->lines);
    handle_frame(m, &f, t);
    if (m->count != 0u && m->windows >= m->count) break;
  }
  const int read_error = ferror(fp);
  const int saved = errno;
  free(line);
  if (!is_stdin) fclose(fp);
  if (read_error) {
    fprintf(stderr, "imest-monitor: cannot read log '%s': %s\n", label, strerror(saved));
    (void)finish(m, 0);
    return TOOL_EXIT_DATA;
  }
  return finish(m, 0);
}

#ifdef IMEST_MONITOR_SOCKETCAN
static int run_iface(monitor_t *m, const char *ifname, double timeout_s)
{
  imest_socketcan_t sc;
  double idle = 0.0;
  char id[24];
  if (imest_socketcan_open(&sc, ifname) != 0) {
    fprintf(stderr, "imest-monitor: %s\n", sc.err);
    return TOOL_EXIT_DATA;
  }
  print_header(m);
  fprintf(stderr, "imest-monitor: listening on %s (base id %s)\n", ifname,
          imest_can_id_format(m->base_id, id, sizeof id));
  while (!g_stop) {
    imest_can_frame_t f;
    double t = 0.0;
    const int r = imest_socketcan_recv(&sc, &f, 200, &t);
    if (r < 0) {
      fprintf(stderr, "imest-monitor: %s\n", sc.err);
      imest_socketcan_close(&sc);
      (void)finish(m, 1);
      return TOOL_EXIT_DATA;
    }
    if (r == 0) {
      idle += 0.2;
      if (timeout_s > 0.0 && idle >= timeout_s) {
        fprintf(stderr, "imest-monitor: no frame for %.1f s on %s: stopping\n", timeout_s, ifname);
        break;
      }
      continue;
    }
    idle = 0.0;
    snprintf(m->where, sizeof m->where, "%s t=%.6f", ifname, t);
    handle_frame(m, &f, t);
    if (m->count != 0u && m->windows >= m->count) break;
  }
  imest_socketcan_close(&sc);
  return finish(m, 1);
}
#endif

/* --- options ------------------------------------------------------------------ */

/* A count of windows: 1, 2, ... (no sign, no zero). */
static int parse_count(const char *v, unsigned long *out)
{
  char *end = NULL;
  if (v[0] < '0' || v[0] > '9') return -1;
  errno = 0;
  const unsigned long c = strtoul(v, &end, 10);
  if (errno != 0 || *end != '\0' || c == 0u) return -1;
  *out = c;
  return 0;
}

int main(int argc, char **argv)
{
  static monitor_t m;
  const char *iface = NULL, *log = NULL, *base_text = NULL, *v;
  int ext = 0;
  double timeout_s = 0.0;
  tool_args_t a;
  tool_arg_kind_t kind;
  memset(&m, 0, sizeof m);
  tool_args_init(&a, "imest-monitor", argc, argv);
  int std_rc;
  while ((kind = tool_args_next(&a)) != TOOL_ARG_END) {
    if (kind == TOOL_ARG_OPERAND) {
      fprintf(stderr, "imest-monitor: unexpected argument '%s' (a log is given with --log; see --help)\n",
              a.operand);
      return TOOL_EXIT_USAGE;
    } else if ((std_rc = tool_args_standard(&a, usage)) >= 0) {
      return std_rc;
    } else if (tool_args_is(&a, "--csv")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      m.csv = 1;
    } else if (tool_args_is(&a, "--temperatures")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      m.temps = 1;
    } else if (tool_args_is(&a, "--require-valid")) {
      if (tool_args_require_valid(&a, &m.require)) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-ext") || tool_args_is(&a, "--ext")) {
      if (tool_args_flag(&a)) return TOOL_EXIT_USAGE;
      ext = 1;
    } else if (tool_args_is(&a, "--can-iface") || tool_args_is(&a, "--iface")) {
      if ((iface = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--log")) {
      if ((log = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--can-base-id") || tool_args_is(&a, "--base-id")) {
      if ((base_text = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
    } else if (tool_args_is(&a, "--count")) {
      if ((v = tool_args_value(&a)) == NULL) return TOOL_EXIT_USAGE;
      if (parse_count(v, &m.count) != 0) {
        fprintf(stderr, "imest-monitor: bad --count '%s': give a number of windows >= 1\n", v);
        return TOOL_EXIT_USAGE;
      }
    } else if (tool_args_is(&a, "--timeout")) {
      if (tool_args_number(&a, &timeout_s)) return TOOL_EXIT_USAGE;
      if (!(timeout_s >= 0.0)) {
        fprintf(stderr, "imest-monitor: bad --timeout %g: give seconds >= 0\n", timeout_s);
        return TOOL_EXIT_USAGE;
      }
    } else {
      return tool_args_unknown(&a);
    }
  }
  if ((iface == NULL) == (log == NULL)) {
    fprintf(stderr, "imest-monitor: give exactly one of --can-iface NAME or --log FILE (see --help)\n");
    return TOOL_EXIT_USAGE;
  }
  m.base_id = IMEST_CAN_DEFAULT_BASE_ID | (ext ? IMEST_CAN_ID_EXT : 0u);
  if (base_text != NULL) {
    char err[256];
    if (imest_can_id_parse(base_text, ext, "--can-ext", &m.base_id, err, sizeof err) != IMEST_OK) {
      fprintf(stderr, "imest-monitor: bad --can-base-id %s\n", err);
      return TOOL_EXIT_USAGE;
    }
  }
  imest_can_rx_init(&m.rx, m.base_id);
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  if (log != NULL) return run_log(&m, log);
#ifdef IMEST_MONITOR_SOCKETCAN
  return run_iface(&m, iface, timeout_s);
#else
  (void)timeout_s;
  fprintf(stderr, "imest-monitor: built without SocketCAN support: use --log\n");
  return TOOL_EXIT_USAGE;
#endif
}
