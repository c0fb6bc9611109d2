/* SPDX-License-Identifier: Apache-2.0 */
/*
 * icount: a QEMU TCG plugin (QEMU 7.2 plugin API, version 1) that counts the
 * guest instructions executed between marker functions of the firmware
 * harness, exactly, and keeps a per-address execution profile.
 *
 * Debian's qemu-system-arm 7.2 loads plugins but ships no <qemu-plugin.h>, so
 * the handful of API declarations used here are written out below from the
 * documented plugin API of QEMU 7.2 (docs/devel/tcg-plugins.rst).
 *
 * Arguments (-plugin ./libicount.so,key=value,...):
 *   bN=ADDR, eN=ADDR  begin/end marker addresses of channel N (0..5)
 *   hlo=ADDR,hhi=ADDR instructions in [hlo, hhi) (the harness) are not counted
 *                     in a channel: a channel counts only what the measured
 *                     call executes, from its first instruction to its return
 *   out=FILE          per-channel statistics
 *   prof=FILE         per-channel per-address execution counts
 *
 * out format, one line per channel with calls:  "chan N calls C min X max Y sum S"
 * then for every call (up to 16384 per channel):  "call N VALUE"
 */
#include <inttypes.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- QEMU 7.2 plugin API (declarations) ---------------------------------- */
typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
typedef struct qemu_info_t qemu_info_t; /* contents not used */
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *insn);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn, qemu_plugin_vcpu_udata_cb_t cb,
                                            enum qemu_plugin_cb_flags flags, void *userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void *userdata);
void qemu_plugin_outs(const char *string);
#define PLUGIN_EXPORT __attribute__((visibility("default")))
PLUGIN_EXPORT int qemu_plugin_version = 1;
/* -------------------------------------------------------------------------- */

#define NCHAN      6
#define MAXCALLS   16384
#define CODE_LIMIT 0x00400000u /* profile addresses below 4 MiB (code memory) */

static uint64_t mark_b[NCHAN], mark_e[NCHAN];
static uint64_t hlo, hhi;
static char *out_path, *prof_path;

static uint64_t counted;   /* instructions outside the harness, since start */
static int open_chan = -1; /* channel currently open */
static uint64_t open_at;
static uint64_t calls[NCHAN], vmin[NCHAN], vmax[NCHAN], vsum[NCHAN];
static uint64_t callv[NCHAN][MAXCALLS];
static uint32_t *prof[NCHAN + 1]; /* per halfword address; [NCHAN] = outside channels */

static void on_insn(unsigned int vcpu, void *ud)
{
  (void)vcpu;
  uint64_t pc = (uint64_t)(uintptr_t)ud;
  int c = open_chan < 0 ? NCHAN : open_chan;
  if (pc < CODE_LIMIT) prof[c][pc >> 1]++;
  if (pc >= hlo && pc < hhi) return;
  counted++;
}

static void on_mark(unsigned int vcpu, void *ud)
{
  (void)vcpu;
  uint64_t pc = (uint64_t)(uintptr_t)ud;
  for (int c = 0; c < NCHAN; c++) {
    if (pc == mark_b[c]) {
      open_chan = c;
      open_at = counted;
    } else if (pc == mark_e[c] && open_chan == c) {
      uint64_t v = counted - open_at;
      if (calls[c] == 0 || v < vmin[c]) vmin[c] = v;
      if (v > vmax[c]) vmax[c] = v;
      vsum[c] += v;
      if (calls[c] < MAXCALLS) callv[c][calls[c]] = v;
      calls[c]++;
      open_chan = -1;
    }
  }
}

static bool is_mark(uint64_t pc)
{
  for (int c = 0; c < NCHAN; c++)
    if ((mark_b[c] && pc == mark_b[c]) || (mark_e[c] && pc == mark_e[c])) return true;
  return false;
}

static void tb_trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
  (void)id;
  size_t n = qemu_plugin_tb_n_insns(tb);
  for (size_t i = 0; i < n; i++) {
    struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
    uint64_t pc = qemu_plugin_insn_vaddr(insn);
    /* A marker's callback runs before its own instruction is counted. */
    if (is_mark(pc))
      qemu_plugin_register_vcpu_insn_exec_cb(insn, on_mark, QEMU_PLUGIN_CB_NO_REGS, (void *)(uintptr_t)pc);
    qemu_plugin_register_vcpu_insn_exec_cb(insn, on_insn, QEMU_PLUGIN_CB_NO_REGS, (void *)(uintptr_t)pc);
  }
}

static void at_exit(qemu_plugin_id_t id, void *ud)
{
  (void)id;
  (void)ud;
  FILE *f = out_path ? fopen(out_path, "w") : NULL;
  if (!f) {
    qemu_plugin_outs("icount: no out= file\n");
  } else {
    for (int c = 0; c < NCHAN; c++) {
      if (!calls[c]) continue;
      fprintf(f, "chan %d calls %" PRIu64 " min %" PRIu64 " max %" PRIu64 " sum %" PRIu64 "\n", c, calls[c],
              vmin[c], vmax[c], vsum[c]);
    }
    for (int c = 0; c < NCHAN; c++)
      for (uint64_t k = 0; k < calls[c] && k < MAXCALLS; k++)
        fprintf(f, "call %d %" PRIu64 "\n", c, callv[c][k]);
    fprintf(f, "total %" PRIu64 "\n", counted);
    fclose(f);
  }
  if (prof_path) {
    FILE *p = fopen(prof_path, "w");
    if (p) {
      for (int c = 0; c <= NCHAN; c++)
        for (uint32_t a = 0; a < CODE_LIMIT / 2; a++)
          if (prof[c][a]) fprintf(p, "%d 0x%08" PRIx32 " %" PRIu32 "\n", c, a * 2u, prof[c][a]);
      fclose(p);
    }
  }
}

static uint64_t num(const char *s)
{
  return strtoull(s, NULL, 0);
}

PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc, char **argv)
{
  (void)info;
  for (int i = 0; i < argc; i++) {
    char *eq = strchr(argv[i], '=');
    if (!eq) continue;
    *eq = '\0';
    const char *k = argv[i], *v = eq + 1;
    if ((k[0] == 'b' || k[0] == 'e') && k[1] >= '0' && k[1] < '0' + NCHAN && !k[2]) {
      (k[0] == 'b' ? mark_b : mark_e)[k[1] - '0'] = num(v) & ~1ull; /* drop the Thumb bit */
    } else if (!strcmp(k, "hlo")) {
      hlo = num(v);
    } else if (!strcmp(k, "hhi")) {
      hhi = num(v);
    } else if (!strcmp(k, "out")) {
      out_path = strdup(v);
    } else if (!strcmp(k, "prof")) {
      prof_path = strdup(v);
    } else {
      fprintf(stderr, "icount: unknown argument %s\n", k);
      return -1;
    }
  }
  for (int c = 0; c <= NCHAN; c++) {
    prof[c] = calloc(CODE_LIMIT / 2, sizeof(uint32_t));
    if (!prof[c]) return -1;
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, tb_trans);
  qemu_plugin_register_atexit_cb(id, at_exit, NULL);
  return 0;
}
