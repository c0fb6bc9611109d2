/* imest-monitor: decode imest CAN telemetry live from a SocketCAN interface or
 * from a candump -L log, print a table or CSV, and report lost, repeated and
 * corrupted frames (each event on stderr, and a summary at the end). */
#define _GNU_SOURCE 1
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest_candump.h"
#ifdef IMEST_MONITOR_SOCKETCAN
#include "imest_socketcan.h"
#endif

static const char *const k_frame_name[IMEST_CAN_NFRAMES] = {"IMEST_TR", "IMEST_RS", "IMEST_QUAL",
                                                            "IMEST_STAT"};

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
  (void)sig;
  g_stop = 1;
}

typedef struct {
  int csv;
  uint32_t base_id;
  unsigned long count;      /* stop after this many windows (0: never) */
  unsigned long windows;
  double win_t;             /* time of the last accepted frame of the open window */
  char where[128];
  imest_can_rx_t rx;
  unsigned long malformed;
  uint32_t last_tx_failed;
  int have_tx_failed;
} monitor_t;

static void usage(FILE *f) {
  fputs("usage: imest-monitor (--iface NAME | --log FILE|-) [--base-id ID] [--ext] [--csv]\n"
        "                     [--count N] [--timeout SEC]\n"
        "  --iface NAME   read live from a SocketCAN interface (e.g. can0, vcan0)\n"
        "  --log FILE     read a candump -L log ('-' = stdin)\n"
        "  --base-id ID   base identifier of the node (default 0x6A0); frames at ID..ID+3;\n"
        "                 values above 0x7FF are 29-bit extended identifiers\n"
        "  --ext          the base identifier is a 29-bit extended one\n"
        "  --csv          CSV (header t_s,seq,T_R_s,R_S_ohm,E_I,valid,status,...) instead of a table\n"
        "  --count N      stop after N windows\n"
        "  --timeout SEC  live: stop after SEC seconds without any frame (default: never)\n"
        "Events (lost, repeated, corrupted frames, incomplete windows, sequence gaps) and a\n"
        "summary go to stderr.\n",
        f);
}

static void fmt_or_empty(char *buf, size_t n, int have, const char *fmt, double v) {
  if (have) {
    snprintf(buf, n, fmt, v);
  } else {
    buf[0] = '\0';
  }
}

static void print_window(monitor_t *m, const imest_can_window_t *w, double t) {
  int h_tr = (w->have >> IMEST_CAN_FRAME_TR) & 1u, h_rs = (w->have >> IMEST_CAN_FRAME_RS) & 1u;
  int h_q = (w->have >> IMEST_CAN_FRAME_QUAL) & 1u, h_st = (w->have >> IMEST_CAN_FRAME_STAT) & 1u;
  char seq[16], tr[32], rs[32], ei[32], valid[8], status[32], pk1[32], pk2[32];
  char nr[8], na[8], flags[16], sat[8], txf[16];
  if (h_st) {
    snprintf(seq, sizeof seq, "%lu", (unsigned long)w->seq);
    snprintf(txf, sizeof txf, "%lu", (unsigned long)w->tx_failed);
  } else {
    seq[0] = txf[0] = '\0';
  }
  fmt_or_empty(tr, sizeof tr, h_tr, "%.9g", w->tr_s);
  fmt_or_empty(ei, sizeof ei, h_tr, "%.4f", w->e_i);
  fmt_or_empty(rs, sizeof rs, h_rs, "%.9g", w->rs_ohm);
  fmt_or_empty(pk2, sizeof pk2, h_rs, "%.5f", w->pe_k2_rel);
  fmt_or_empty(pk1, sizeof pk1, h_q, "%.5f", w->pe_k1_rel);
  if (h_q) {
    snprintf(valid, sizeof valid, "%d", w->valid);
    snprintf(status, sizeof status, "%s", imest_reason_name(w->status));
    snprintf(nr, sizeof nr, "%u", w->n_roots);
    snprintf(na, sizeof na, "%u", w->n_admissible);
    snprintf(flags, sizeof flags, "0x%04X", w->flags);
    snprintf(sat, sizeof sat, "0x%02X", w->sat);
  } else {
    valid[0] = status[0] = nr[0] = na[0] = flags[0] = sat[0] = '\0';
  }
  if (m->csv) {
    printf("%.6f,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%u,0x%X\n", t, seq, tr, rs, ei, valid, status,
           pk1, pk2, nr, na, flags, sat, txf, w->counter, w->have);
  } else {
    printf("%17.6f %8s %13s %13s %7s %8s %8s %5s %-17s %2s/%-2s %6s %5s%s\n", t, seq, tr, rs, ei, pk1,
           pk2, valid, status, na, nr, flags, txf, w->have == 0xFu ? "" : "  (incomplete)");
  }
  if (h_st) {
    m->last_tx_failed = w->tx_failed;
    m->have_tx_failed = 1;
  }
  fflush(stdout);
  m->windows++;
}

static void report_missing(const monitor_t *m, const imest_can_window_t *w) {
  unsigned int i;
  fprintf(stderr, "imest-monitor: %s: incomplete window (counter %u", m->where, w->counter);
  if (w->have & (1u << IMEST_CAN_FRAME_STAT)) fprintf(stderr, ", seq %lu", (unsigned long)w->seq);
  fputs("): missing", stderr);
  for (i = 0u; i < IMEST_CAN_NFRAMES; i++) {
    if (!(w->have & (1u << i))) fprintf(stderr, " %s", k_frame_name[i]);
  }
  fputc('\n', stderr);
}

static uint32_t frame_id(const monitor_t *m, unsigned int index) {
  return ((m->base_id & IMEST_CAN_EFF_MASK) + index) & IMEST_CAN_EFF_MASK;
}

static void handle_frame(monitor_t *m, const struct imest_can_frame *f, double t) {
  imest_can_window_t w;
  imest_can_rx_event_t ev;
  double prev_t = m->win_t;
  unsigned int e = imest_can_rx_feed(&m->rx, f, &w, &ev);
  const char *name = ev.index < IMEST_CAN_NFRAMES ? k_frame_name[ev.index] : "?";
  unsigned long id = (unsigned long)frame_id(m, ev.index);
  if (e & IMEST_CAN_EV_CORRUPT) {
    if (ev.dec == IMEST_CAN_DEC_BAD_DLC) {
      fprintf(stderr, "imest-monitor: %s: corrupted frame 0x%03lX (%s): %u data bytes, expected 8\n",
              m->where, id, name, f->dlc);
    } else {
      fprintf(stderr, "imest-monitor: %s: corrupted frame 0x%03lX (%s): checksum mismatch\n", m->where,
              id, name);
    }
    return;
  }
  if (e & IMEST_CAN_EV_REPEATED) {
    fprintf(stderr, "imest-monitor: %s: repeated frame 0x%03lX (%s), counter %u\n", m->where, id, name,
            ev.counter);
    return;
  }
  if (e & IMEST_CAN_EV_LOST) {
    fprintf(stderr, "imest-monitor: %s: lost %lu frame(s) 0x%03lX (%s): counter %u -> %u\n", m->where,
            (unsigned long)ev.lost, id, name, ev.prev_counter, ev.counter);
  }
  if (e & IMEST_CAN_EV_WINDOW) {
    if (e & IMEST_CAN_EV_INCOMPLETE) {
      report_missing(m, &w);
      print_window(m, &w, prev_t);
    } else {
      print_window(m, &w, t);
    }
  }
  if (e & IMEST_CAN_EV_SEQ_GAP) {
    fprintf(stderr, "imest-monitor: %s: the estimator dropped %lu window(s) before seq %lu (overrun)\n",
            m->where, (unsigned long)ev.seq_gap, (unsigned long)m->rx.last_seq);
  }
  if (e & IMEST_CAN_EV_RESTART) {
    fprintf(stderr, "imest-monitor: %s: sequence number went back to %lu: sender restarted\n", m->where,
            (unsigned long)m->rx.last_seq);
  }
  if (!(e & IMEST_CAN_EV_FOREIGN)) {
    m->win_t = t;
  }
}

static void finish(monitor_t *m) {
  imest_can_window_t w;
  const imest_can_rx_stats_t *s = &m->rx.st;
  if ((m->count == 0u || m->windows < m->count) && imest_can_rx_flush(&m->rx, &w)) {
    snprintf(m->where, sizeof m->where, "end of input");
    report_missing(m, &w);
    print_window(m, &w, m->win_t);
  }
  fprintf(stderr,
          "imest-monitor: summary: frames %lu (foreign %lu), windows %lu (incomplete %lu), "
          "lost %lu, repeated %lu, corrupted %lu, estimator gaps %lu, restarts %lu, "
          "malformed lines %lu, sender tx_failed %s%lu\n",
          (unsigned long)s->frames, (unsigned long)s->foreign, (unsigned long)s->windows,
          (unsigned long)s->incomplete, (unsigned long)s->lost, (unsigned long)s->repeated,
          (unsigned long)s->corrupt, (unsigned long)s->seq_gaps, (unsigned long)s->restarts,
          m->malformed, m->have_tx_failed ? "" : "n/a ", (unsigned long)m->last_tx_failed);
}

static void print_header(const monitor_t *m) {
  if (m->csv) {
    puts("t_s,seq,T_R_s,R_S_ohm,E_I,valid,status,pe_k1_rel,pe_k2_rel,n_roots,n_admissible,flags,sat,"
         "tx_failed,counter,frames");
  } else {
    printf("%17s %8s %13s %13s %7s %8s %8s %5s %-17s %5s %6s %5s\n", "t [s]", "seq", "T_R [s]",
           "R_S [ohm]", "E_I", "PE_K1", "PE_K2", "valid", "status", "adm/r", "flags", "txf");
  }
  fflush(stdout);
}

static int run_log(monitor_t *m, const char *path) {
  FILE *fp = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
  const char *label = strcmp(path, "-") == 0 ? "<stdin>" : path;
  char *line = NULL;
  size_t cap = 0u;
  ssize_t n;
  unsigned long lineno = 0u;
  if (fp == NULL) {
    fprintf(stderr, "imest-monitor: cannot open log '%s': %s\n", path, strerror(errno));
    return 2;
  }
  print_header(m);
  while (!g_stop && (n = getline(&line, &cap, fp)) >= 0) {
    struct imest_can_frame f;
    double t = 0.0;
    const char *err = NULL;
    int r;
    lineno++;
    if ((size_t)n != strlen(line)) {
      r = IMEST_CANDUMP_ERROR;
      err = "NUL byte in the line";
    } else {
      r = imest_candump_parse(line, &t, NULL, &f, &err);
    }
    if (r == IMEST_CANDUMP_EMPTY) continue;
    if (r != IMEST_CANDUMP_OK) {
      size_t k = strcspn(line, "\r\n");
      m->malformed++;
      fprintf(stderr, "imest-monitor: %s:%lu: malformed line: %s: '%.*s'\n", label, lineno, err,
              (int)(k > 80u ? 80u : k), line);
      continue;
    }
    snprintf(m->where, sizeof m->where, "%s:%lu", label, lineno);
    handle_frame(m, &f, t);
    if (m->count != 0u && m->windows >= m->count) break;
  }
  free(line);
  if (fp != stdin) fclose(fp);
  finish(m);
  return 0;
}

#ifdef IMEST_MONITOR_SOCKETCAN
static int run_iface(monitor_t *m, const char *ifname, double timeout_s) {
  struct imest_socketcan sc;
  struct timespec ts;
  double idle = 0.0;
  if (imest_socketcan_open(&sc, ifname) != 0) {
    fprintf(stderr, "imest-monitor: %s\n", sc.err);
    return 2;
  }
  print_header(m);
  fprintf(stderr, "imest-monitor: listening on %s (base id 0x%lX%s)\n", ifname,
          (unsigned long)(m->base_id & IMEST_CAN_EFF_MASK), (m->base_id & IMEST_CAN_ID_EXT) ? ", extended" : "");
  while (!g_stop) {
    struct imest_can_frame f;
    double t = 0.0;
    int r = imest_socketcan_recv(&sc, &f, 200, &t);
    if (r < 0) {
      fprintf(stderr, "imest-monitor: %s\n", sc.err);
      imest_socketcan_close(&sc);
      finish(m);
      return 2;
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
    clock_gettime(CLOCK_REALTIME, &ts);
    snprintf(m->where, sizeof m->where, "%s t=%.6f", ifname, t);
    handle_frame(m, &f, t);
    if (m->count != 0u && m->windows >= m->count) break;
  }
  imest_socketcan_close(&sc);
  finish(m);
  return 0;
}
#endif

int main(int argc, char **argv) {
  static monitor_t m;
  const char *iface = NULL;
  const char *log = NULL;
  unsigned long base = IMEST_CAN_DEFAULT_BASE_ID;
  int ext = 0;
  double timeout_s = 0.0;
  int i;
  memset(&m, 0, sizeof m);
  for (i = 1; i < argc; i++) {
    const char *a = argv[i];
    const char *v = i + 1 < argc ? argv[i + 1] : NULL;
    char *end = NULL;
    if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
      usage(stdout);
      return 0;
    } else if (strcmp(a, "--csv") == 0) {
      m.csv = 1;
    } else if (strcmp(a, "--ext") == 0) {
      ext = 1;
    } else if (v != NULL && strcmp(a, "--iface") == 0) {
      iface = v;
      i++;
    } else if (v != NULL && strcmp(a, "--log") == 0) {
      log = v;
      i++;
    } else if (v != NULL && strcmp(a, "--base-id") == 0) {
      errno = 0;
      base = strtoul(v, &end, 0);
      if (errno != 0 || end == v || *end != '\0') {
        fprintf(stderr, "imest-monitor: bad --base-id '%s'\n", v);
        return 1;
      }
      i++;
    } else if (v != NULL && strcmp(a, "--count") == 0) {
      m.count = strtoul(v, &end, 0);
      if (end == v || *end != '\0') {
        fprintf(stderr, "imest-monitor: bad --count '%s'\n", v);
        return 1;
      }
      i++;
    } else if (v != NULL && strcmp(a, "--timeout") == 0) {
      timeout_s = strtod(v, &end);
      if (end == v || *end != '\0' || !(timeout_s >= 0.0)) {
        fprintf(stderr, "imest-monitor: bad --timeout '%s'\n", v);
        return 1;
      }
      i++;
    } else {
      fprintf(stderr, "imest-monitor: unknown or incomplete option '%s'\n", a);
      usage(stderr);
      return 1;
    }
  }
  if ((iface == NULL) == (log == NULL)) {
    fprintf(stderr, "imest-monitor: give exactly one of --iface NAME or --log FILE\n");
    usage(stderr);
    return 1;
  }
  if (base > 0x7FFul) ext = 1;
  if ((ext && base > IMEST_CAN_EFF_MASK - (IMEST_CAN_NFRAMES - 1u)) ||
      (!ext && base > IMEST_CAN_SFF_MASK - (IMEST_CAN_NFRAMES - 1u))) {
    fprintf(stderr, "imest-monitor: --base-id 0x%lX out of range (base+%d must be a valid identifier)\n",
            base, IMEST_CAN_NFRAMES - 1);
    return 1;
  }
  m.base_id = (uint32_t)base | (ext ? IMEST_CAN_ID_EXT : 0u);
  imest_can_rx_init(&m.rx, m.base_id);
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  if (log != NULL) return run_log(&m, log);
#ifdef IMEST_MONITOR_SOCKETCAN
  return run_iface(&m, iface, timeout_s);
#else
  (void)timeout_s;
  fprintf(stderr, "imest-monitor: built without SocketCAN support: use --log\n");
  return 2;
#endif
}
