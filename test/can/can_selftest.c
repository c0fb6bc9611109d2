/* imest-can-selftest: publishes N synthetic window results through the real
 * library path (an imest instance, imest_attach_can, imest_can_publish) over
 * a SocketCAN interface (--iface) or into a candump -L log (--log). The
 * results are a deterministic function of the window number, with edge values
 * (NaN, infinity, out-of-range, saturation) mixed in, so two runs can be
 * compared after decoding. Used by the socketcan end-to-end test (qemu guest)
 * and by the DBC and monitor tests. */
#define _GNU_SOURCE 1
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest_candump.h"
#ifdef IMEST_SELFTEST_SOCKETCAN
#include "imest_socketcan.h"
#endif

/* Window k's result (also used by the tests' expectations). */
static void synth(unsigned int k, imest_result_t *r) {
  memset(r, 0, sizeof *r);
  r->seq = k + (k >= 6u ? 2u : 0u); /* seq jumps by 3 at k = 6: two windows dropped by the estimator */
  r->samples = 4000u;
  r->used_samples = 4000u;
  r->t_end_s = 1.0 + (double)r->seq;
  r->tr_s = 0.001 * pow(10.0, 4.0 * (double)(k % 9u) / 8.0); /* 1 ms .. 10 s */
  r->rs_ohm = 0.001 * pow(10.0, 5.0 * (double)(k % 7u) / 6.0); /* 1 mohm .. 100 ohm */
  r->e_i = 0.0123 * (double)(k % 13u);
  r->pe_k1_rel = 0.0011 * (double)(k % 11u);
  r->pe_k2_rel = 0.00037 * (double)(k % 17u);
  r->valid = 1;
  r->status = IMEST_OK;
  r->flags = IMEST_FLAG_HESSIAN_PD;
  r->n_roots = 1u + k % 5u;
  r->n_admissible = 1u;
  switch (k % 10u) {
    case 3u: /* no candidate */
      r->tr_s = NAN;
      r->rs_ohm = NAN;
      r->e_i = NAN;
      r->pe_k1_rel = NAN;
      r->pe_k2_rel = NAN;
      r->valid = 0;
      r->status = IMEST_REASON_NO_ROOT;
      r->flags = IMEST_FLAG_WARMUP | IMEST_FLAG_ENCODER_FAULT;
      r->n_admissible = 0u;
      break;
    case 5u: /* saturation of every field */
      r->tr_s = 1e300;
      r->rs_ohm = -INFINITY;
      r->e_i = 9.5;
      r->pe_k1_rel = INFINITY;
      r->pe_k2_rel = 2.0;
      r->valid = 0;
      r->status = IMEST_REASON_HIGH_RESIDUAL;
      r->flags = IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ADC_SAT | IMEST_FLAG_OVERRUN;
      r->n_roots = 20u;
      r->n_admissible = 17u;
      break;
    case 8u:
      r->valid = 0;
      r->status = IMEST_REASON_POORLY_DETERMINED;
      r->pe_k2_rel = 0.25;
      break;
    default:
      break;
  }
}

static void usage(void) {
  fputs("usage: imest-can-selftest (--iface NAME | --log FILE|-) [--count N] [--period-ms MS]\n"
        "                          [--base-id ID] [--epoch SEC]\n",
        stderr);
}

int main(int argc, char **argv) {
  static imest_t est;
  imest_config_t cfg;
  const char *iface = NULL, *log = NULL;
  unsigned long count = 20u, period_ms = 0u, base = IMEST_CAN_DEFAULT_BASE_ID;
  double epoch = 1700000000.0;
  struct imest_candump_port cd;
  FILE *fp = NULL;
  unsigned int k;
  unsigned long failed = 0u;
  int i, rc;
#ifdef IMEST_SELFTEST_SOCKETCAN
  struct imest_socketcan sc;
#endif
  const struct imest_can_port *port = NULL;
  for (i = 1; i < argc; i++) {
    const char *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (v == NULL) {
      usage();
      return 1;
    }
    if (strcmp(argv[i], "--iface") == 0) iface = v;
    else if (strcmp(argv[i], "--log") == 0) log = v;
    else if (strcmp(argv[i], "--count") == 0) count = strtoul(v, NULL, 0);
    else if (strcmp(argv[i], "--period-ms") == 0) period_ms = strtoul(v, NULL, 0);
    else if (strcmp(argv[i], "--base-id") == 0) base = strtoul(v, NULL, 0);
    else if (strcmp(argv[i], "--epoch") == 0) epoch = strtod(v, NULL);
    else {
      usage();
      return 1;
    }
    i++;
  }
  if ((iface == NULL) == (log == NULL)) {
    usage();
    return 1;
  }
  imest_config_default(&cfg);
  cfg.pole_pairs = 2u;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  rc = imest_init(&est, &cfg);
  if (rc != IMEST_OK) {
    fprintf(stderr, "imest-can-selftest: imest_init failed (%d)\n", rc);
    return 2;
  }
  if (log != NULL) {
    fp = strcmp(log, "-") == 0 ? stdout : fopen(log, "w");
    if (fp == NULL || imest_candump_port_open(&cd, fp, "vcan0") != 0) {
      fprintf(stderr, "imest-can-selftest: cannot write '%s'\n", log);
      return 2;
    }
    port = &cd.port;
  } else {
#ifdef IMEST_SELFTEST_SOCKETCAN
    if (imest_socketcan_open(&sc, iface) != 0) {
      fprintf(stderr, "imest-can-selftest: %s\n", sc.err);
      return 3;
    }
    port = &sc.port;
#else
    fprintf(stderr, "imest-can-selftest: built without SocketCAN\n");
    return 2;
#endif
  }
  rc = imest_attach_can(&est, port, (uint32_t)base | (base > 0x7FFu ? IMEST_CAN_ID_EXT : 0u));
  if (rc != IMEST_OK) {
    fprintf(stderr, "imest-can-selftest: imest_attach_can(0x%lX) failed (%d)\n", base, rc);
    return 2;
  }
  for (k = 0u; k < count; k++) {
    imest_result_t r;
    int f;
    synth(k, &r);
    if (log != NULL) imest_candump_port_set_time(&cd, epoch + r.t_end_s);
    f = imest_can_publish(&est, &r);
    if (f != 0) failed += (unsigned long)f;
    if (period_ms != 0u) {
      struct timespec ts;
      ts.tv_sec = (time_t)(period_ms / 1000u);
      ts.tv_nsec = (long)(period_ms % 1000u) * 1000000L;
      nanosleep(&ts, NULL);
    }
  }
  fprintf(stderr, "imest-can-selftest: published %lu window(s), %lu failed send(s), can_tx_failed %lu\n",
          count, failed, (unsigned long)est.can_tx_failed);
#ifdef IMEST_SELFTEST_SOCKETCAN
  if (iface != NULL) imest_socketcan_close(&sc);
#endif
  if (fp != NULL && fp != stdout) fclose(fp);
  return failed != 0u ? 4 : 0;
}
