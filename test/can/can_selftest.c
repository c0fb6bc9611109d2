/* SPDX-License-Identifier: Apache-2.0 */
/* imest-can-selftest: publishes N synthetic window results through the real
 * library path (imest_can_pub_init, imest_can_publish) over a SocketCAN
 * interface (--iface) or into a candump -L log (--log). The results are a
 * deterministic function of the window number, with edge values (NaN,
 * infinity, out-of-range, saturation) mixed in, so two runs can be compared
 * after decoding. Used by the socketcan end-to-end test (qemu guest) and by
 * the DBC and monitor tests. --temperatures adds each window's IMEST_TEMP
 * frame (imest_temperature.h), synthetic too. --table prints the codec's signal
 * table, IMEST_TEMP's layout and the reason names instead (test_dbc.py compares
 * them with tools/imest.dbc). */
#define _GNU_SOURCE 1
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest/imest_temperature.h"
#include "imest_can_id.h"
#include "imest_candump.h"
#ifdef IMEST_SELFTEST_SOCKETCAN
#include "imest_socketcan.h"
#endif

/* Window k's result (also used by the tests' expectations). */
static void synth(unsigned int k, imest_result_t *r)
{
  memset(r, 0, sizeof *r);
  r->seq = k + (k >= 6u ? 2u : 0u); /* seq jumps by 3 at k = 6: two windows dropped by the estimator */
  r->samples = 4000u;
  r->used_samples = 4000u;
  r->t_end_s = 1.0 + (double)r->seq;
  r->tr_s = 0.001 * pow(10.0, 4.0 * (double)(k % 9u) / 8.0);   /* 1 ms .. 10 s */
  r->rs_ohm = 0.001 * pow(10.0, 5.0 * (double)(k % 7u) / 6.0); /* 1 mohm .. 100 ohm */
  r->e_i = 0.0123 * (double)(k % 13u);
  r->pe_k1_rel = 0.0011 * (double)(k % 11u);
  r->pe_k2_rel = 0.00037 * (double)(k % 17u);
  r->valid = 1;
  r->status = IMEST_OK;
  r->flags = IMEST_FLAG_HESSIAN_PD;
  r->n_roots = 1u + k % 5u;
  r->n_admissible = 1u;
  r->tr_valid = 1;
  r->rs_valid = 1;
  r->tr_reason = IMEST_REASON_NONE;
  r->rs_reason = IMEST_REASON_NONE;
  r->tr_bound_rel = 0.0013 * (double)(k % 7u);
  r->rs_bound_rel = k % 4u == 1u ? (double)NAN : 0.0071 * (double)(k % 5u);
  r->windows = 1u + k % 3u;
  r->span_s = 1.0 * (double)r->windows;
  switch (k % 10u) {
  case 3u: /* no candidate */
    r->tr_s = (double)NAN;
    r->rs_ohm = (double)NAN;
    r->e_i = (double)NAN;
    r->pe_k1_rel = (double)NAN;
    r->pe_k2_rel = (double)NAN;
    r->valid = 0;
    r->status = IMEST_REASON_NO_ROOT;
    r->tr_valid = r->rs_valid = 0;
    r->tr_reason = r->rs_reason = IMEST_REASON_NO_ROOT;
    r->tr_bound_rel = r->rs_bound_rel = (double)NAN;
    r->flags = IMEST_FLAG_WARMUP | IMEST_FLAG_ENCODER_FAULT;
    r->n_admissible = 0u;
    break;
  case 5u: /* saturation of every field */
    r->tr_s = 1e300;
    r->rs_ohm = -(double)INFINITY;
    r->e_i = 9.5;
    r->pe_k1_rel = (double)INFINITY;
    r->pe_k2_rel = 2.0;
    r->valid = 0;
    r->status = IMEST_REASON_HIGH_RESIDUAL;
    r->tr_valid = r->rs_valid = 0;
    r->tr_reason = IMEST_REASON_HIGH_RESIDUAL;
    r->rs_reason = 300; /* not a reason: sent as 255, out of range */
    r->tr_bound_rel = 5.0;
    r->rs_bound_rel = -1.0;
    r->span_s = 100.0;
    r->windows = 300u; /* saturates at 255 */
    r->flags = IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ADC_SAT | IMEST_FLAG_OVERRUN;
    r->n_roots = 20u;
    r->n_admissible = 17u;
    break;
  case 7u: /* T_R trusted, R_S not */
    r->valid = 0;
    r->status = IMEST_REASON_RS_OUT_OF_RANGE;
    r->rs_valid = 0;
    r->rs_reason = IMEST_REASON_RS_OUT_OF_RANGE;
    break;
  case 8u:
    r->valid = 0;
    r->status = IMEST_REASON_POORLY_DETERMINED;
    r->tr_valid = r->rs_valid = 0;
    r->tr_reason = r->rs_reason = IMEST_REASON_POORLY_DETERMINED;
    r->pe_k2_rel = 0.25;
    break;
  default: break;
  }
}

/* Window k's temperatures (--temperatures): a sweep over the fields' ranges, negative ones too,
 * with not-available and clamped values mixed in. */
static void synth_temp(unsigned int k, imest_temperature_t *t)
{
  memset(t, 0, sizeof *t);
  t->stator_c = -40.0f + 7.37f * (float)k;
  t->stator_uncert_k = 0.37f * (float)(k % 9u);
  t->stator_valid = (int)(k % 2u);
  t->rotor_c = 150.0f - 11.13f * (float)k;
  t->rotor_uncert_k = 0.71f * (float)(k % 5u);
  t->rotor_valid = k % 3u == 0u;
  switch (k % 10u) {
  case 3u: /* nothing computed (the window has no candidate) */
    t->stator_c = t->stator_uncert_k = t->rotor_c = t->rotor_uncert_k = NAN;
    t->stator_valid = t->rotor_valid = 0;
    break;
  case 5u: /* every field beyond its range */
    t->stator_c = 1.0e4f;
    t->stator_uncert_k = 100.0f;
    t->rotor_c = -INFINITY;
    t->rotor_uncert_k = INFINITY;
    break;
  case 8u: /* a temperature without its uncertainty */ t->rotor_uncert_k = NAN; break;
  default: break;
  }
}

static void usage(void)
{
  fputs("usage: imest-can-selftest (--iface NAME | --log FILE|-) [--count N] [--period-ms MS]\n"
        "                          [--base-id ID] [--ext] [--epoch SEC] [--temperatures]\n"
        "       imest-can-selftest --table\n",
        stderr);
}

/* The signal table and the reason names, one line each (test_dbc.py). */
static void print_table(void)
{
  static const char *const kind[] = {"f32",  "scaled", "count", "u32",   "enum",
                                     "bool", "flag",   "sat",   "txfail"};
  unsigned int n = 0u;
  const imest_can_signal_t *t = imest_can_signal_table(&n);
  printf("frames %d counter %u crc %u\n", IMEST_CAN_NFRAMES, IMEST_CAN_COUNTER_START, IMEST_CAN_CRC_START);
  for (unsigned int k = 0u; k < n; k++) {
    printf("signal %u %u %u %s %lu %u\n", t[k].frame, t[k].start, t[k].len, kind[t[k].kind],
           (unsigned long)t[k].scale, t[k].mask);
  }
  /* IMEST_TEMP: frame index, then its signals as above (kinds of its own) */
  printf("optional %u\n", IMEST_TEMPERATURE_CAN_FRAME);
  printf("signal %u %u %u temp_c %d 0\n", IMEST_TEMPERATURE_CAN_FRAME, IMEST_TEMPERATURE_CAN_STATOR_C_START,
         IMEST_TEMPERATURE_CAN_C_BITS, IMEST_TEMPERATURE_CAN_C_SCALE);
  printf("signal %u %u %u temp_c %d 0\n", IMEST_TEMPERATURE_CAN_FRAME, IMEST_TEMPERATURE_CAN_ROTOR_C_START,
         IMEST_TEMPERATURE_CAN_C_BITS, IMEST_TEMPERATURE_CAN_C_SCALE);
  printf("signal %u %u %u temp_k %d 0\n", IMEST_TEMPERATURE_CAN_FRAME,
         IMEST_TEMPERATURE_CAN_STATOR_UNCERT_START, IMEST_TEMPERATURE_CAN_UNCERT_BITS,
         IMEST_TEMPERATURE_CAN_UNCERT_SCALE);
  printf("signal %u %u 1 bool 1 0\n", IMEST_TEMPERATURE_CAN_FRAME, IMEST_TEMPERATURE_CAN_STATOR_VALID_START);
  printf("signal %u %u %u temp_k %d 0\n", IMEST_TEMPERATURE_CAN_FRAME,
         IMEST_TEMPERATURE_CAN_ROTOR_UNCERT_START, IMEST_TEMPERATURE_CAN_UNCERT_BITS,
         IMEST_TEMPERATURE_CAN_UNCERT_SCALE);
  printf("signal %u %u 1 bool 1 0\n", IMEST_TEMPERATURE_CAN_FRAME, IMEST_TEMPERATURE_CAN_ROTOR_VALID_START);
  for (int r = 0; r < 255; r++) {
    if (strcmp(imest_reason_name(r), "unknown") != 0) printf("reason %d %s\n", r, imest_reason_name(r));
  }
}

int main(int argc, char **argv)
{
  const char *iface = NULL, *log = NULL, *base_text = NULL;
  unsigned long count = 20u, period_ms = 0u;
  uint32_t base = IMEST_CAN_DEFAULT_BASE_ID;
  int ext = 0, temps = 0;
  double epoch = 1700000000.0;
  imest_candump_port_t cd;
  FILE *fp = NULL;
  unsigned long failed = 0u;
  imest_can_pub_t pub;
  char err[256];
#ifdef IMEST_SELFTEST_SOCKETCAN
  imest_socketcan_t sc;
#endif
  const imest_can_port_t *port = NULL;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--table") == 0) {
      print_table();
      return 0;
    }
    if (strcmp(argv[i], "--ext") == 0) {
      ext = 1;
      continue;
    }
    if (strcmp(argv[i], "--temperatures") == 0) {
      temps = 1;
      continue;
    }
    const char *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (v == NULL) {
      usage();
      return 2;
    }
    if (strcmp(argv[i], "--iface") == 0)
      iface = v;
    else if (strcmp(argv[i], "--log") == 0)
      log = v;
    else if (strcmp(argv[i], "--count") == 0)
      count = strtoul(v, NULL, 0);
    else if (strcmp(argv[i], "--period-ms") == 0)
      period_ms = strtoul(v, NULL, 0);
    else if (strcmp(argv[i], "--base-id") == 0)
      base_text = v;
    else if (strcmp(argv[i], "--epoch") == 0)
      epoch = strtod(v, NULL);
    else {
      usage();
      return 2;
    }
    i++;
  }
  if ((iface == NULL) == (log == NULL)) {
    usage();
    return 2;
  }
  if (base_text != NULL && imest_can_id_parse(base_text, ext, "--ext", &base, err, sizeof err) != IMEST_OK) {
    fprintf(stderr, "imest-can-selftest: --base-id %s\n", err);
    return 2;
  }
  if (log != NULL) {
    fp = strcmp(log, "-") == 0 ? stdout : fopen(log, "w");
    if (fp == NULL || imest_candump_port_open(&cd, fp, "vcan0") != 0) {
      fprintf(stderr, "imest-can-selftest: cannot write '%s'\n", log);
      return 1;
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
  const int rc = imest_can_pub_init(&pub, port, base);
  if (rc != IMEST_OK) {
    fprintf(stderr, "imest-can-selftest: imest_can_pub_init(0x%lX) failed (%s)\n", (unsigned long)base,
            imest_err_name(rc));
    return 2;
  }
  for (unsigned int k = 0u; k < count; k++) {
    imest_result_t r;
    synth(k, &r);
    if (log != NULL) imest_candump_port_set_time(&cd, epoch + r.t_end_s);
    const int f = imest_can_publish(&pub, &r);
    if (f > 0) failed += (unsigned long)f;
    if (temps) {
      imest_temperature_t t;
      synth_temp(k, &t);
      if (imest_temperature_can_publish(&pub, &t) != 0) failed++;
    }
    if (period_ms != 0u) {
      struct timespec ts;
      ts.tv_sec = (time_t)(period_ms / 1000u);
      ts.tv_nsec = (long)(period_ms % 1000u) * 1000000L;
      nanosleep(&ts, NULL);
    }
  }
  fprintf(stderr, "imest-can-selftest: published %lu window(s), %lu failed send(s), tx_failed %lu\n", count,
          failed, (unsigned long)pub.tx_failed);
#ifdef IMEST_SELFTEST_SOCKETCAN
  if (iface != NULL) imest_socketcan_close(&sc);
#endif
  if (fp != NULL && fp != stdout) fclose(fp);
  return failed != 0u ? 4 : 0;
}
