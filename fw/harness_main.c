/* SPDX-License-Identifier: Apache-2.0 */
/* Firmware harness: feeds recorded samples through imest_isr_abc() and
 * completes every background solve with imest_background(), bracketing each
 * call with marker functions so that the icount TCG plugin can count the
 * executed instructions exactly, and also measuring each call with SysTick
 * (plugin-free: with -icount shift=0 SysTick advances one tick per 40
 * instructions on the MPS2 boards, so that figure is good to +-40).
 *
 * Channels: 0 ISR call, 1 background call that solves a window, 2 empty
 * bracket (must count 0), 3 stand-in with a known count, 4 imest_init,
 * 5 background call with nothing to do. */
#include <stddef.h>
#include <stdint.h>

#include "harness_measure.h"
#include "harness_semihost.h"
#include "fw_samples.h"

#ifndef FW_WITH_IMEST
#define FW_WITH_IMEST 1
#endif
#if FW_WITH_IMEST
#include "imest/imest.h"
#endif

#ifndef FW_WINDOW_S
#define FW_WINDOW_S 0.4f
#endif

#if FW_WITH_IMEST
static imest_t est;
static imest_result_t res;
#endif

int main(void)
{
  int fails = 0;
  harness_validate_counting();

#if FW_WITH_IMEST
  sh_kv("sizeof_imest_t", sizeof(imest_t));
  sh_kv("sizeof_imest_result_t", sizeof(imest_result_t));
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2u;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.fs_hz = FW_FS_HZ;
  cfg.window_s = FW_WINDOW_S;
  /* The recording is in steady state and has no sensor offsets: the default
   * first-start warm-up (0.8 s for the offset tracker, cheaper calls) would
   * pull the mean below the cost of a sample in operation. 30 ms = 3/filter_hz. */
  cfg.warmup_s = 0.03f;
#ifdef FW_INPUT_DUTY
  /* a drive without voltage sensors whose recording came from an ideal
   * inverter (the path has no branches: the count does not depend on the
   * model's numbers, and the windows must come out valid) */
  cfg.inverter.uncertainty = 0.2f;
#endif
#ifdef FW_ROTOR_HF
  /* a deep-bar rotor (the 4 kW real motor's commissioned ratios) on an IGBT inverter: both
   * harmonic terms of the bounds run (their count does not depend on the windows' verdicts,
   * which this recording from an ideal inverter makes invalid) */
  cfg.rotor_hf_rr_ratio = 5.66f;
  cfg.rotor_hf_sigma_ratio = 0.557f;
  cfg.inverter.dead_time_s = 2e-6f;
  cfg.inverter.v_switch_v = 1.0f;
  cfg.inverter.v_diode_v = 0.8f;
#endif
  fw_mark_b4();
  int rc = imest_init(&est, &cfg);
  fw_mark_e4();
  if (rc != IMEST_OK) {
    sh_puts("imest_init failed\n");
    return 1;
  }
  stat_t st_isr = {0, 0, 0, 0}, st_bg = {0, 0, 0, 0};
  uint32_t stack_isr = 0u, stack_bg = 0u, n_valid = 0u;
  for (uint32_t n = 0u; n < (uint32_t)FW_N_SAMPLES; n++) {
    const float *row = fw_samples[n];
    int solve;
#ifdef FW_INPUT_DUTY
    /* the duties that give the recorded phase voltages on a 400 V bus */
    const float duty[3] = {0.5f + row[0] * (1.0f / 400.0f), 0.5f + row[1] * (1.0f / 400.0f),
                           0.5f + row[2] * (1.0f / 400.0f)};
#endif
    paint_stack(1024u);
    uint32_t sp = sp_now();
    uint32_t t0 = SYST_CVR;
    fw_mark_b0();
#ifdef FW_INPUT_DUTY
    solve = imest_isr_duty(&est, duty, 400.0f, &row[3], row[6]);
#else
    solve = imest_isr_abc(&est, &row[0], &row[3], row[6]);
#endif
    fw_mark_e0();
    uint32_t t1 = SYST_CVR;
    stat_add(&st_isr, ticks(t0, t1));
    {
      uint32_t s = stack_below(sp);
      if (s > stack_isr) stack_isr = s;
    }
    if (solve) {
      paint_stack(12u * 1024u);
      sp = sp_now();
      t0 = SYST_CVR;
      fw_mark_b1();
      int got = imest_background(&est, &res);
      fw_mark_e1();
      t1 = SYST_CVR;
      stat_add(&st_bg, ticks(t0, t1));
      uint32_t s = stack_below(sp);
      if (s > stack_bg) stack_bg = s;
      if (got != 1) {
        sh_puts("background returned no result after a completed window\n");
        fails++;
      }
      sh_puts("window seq ");
      sh_putu(res.seq);
      sh_puts(" samples ");
      sh_putu(res.samples);
      sh_puts(" used ");
      sh_putu(res.used_samples);
      sh_puts(" status ");
      sh_puts(imest_reason_name(res.status));
      sh_puts(" valid ");
      sh_putu((uint64_t)res.valid);
      sh_puts(" tr_s ");
      sh_putf(res.tr_s, 6);
      sh_puts(" rs_ohm ");
      sh_putf(res.rs_ohm, 4);
      sh_puts(" e_i ");
      sh_putf(res.e_i, 6);
      sh_puts(" n_roots ");
      sh_putu(res.n_roots);
      sh_puts("\n");
      if (res.valid) n_valid++;
    } else {
      fw_mark_b5();
      int got = imest_background(&est, &res);
      fw_mark_e5();
      if (got != 0) fails++;
    }
  }
  stat_print("isr_systick_ticks", &st_isr);
  stat_print("solve_systick_ticks", &st_bg);
  sh_kv("stack_isr_bytes", stack_isr);
  sh_kv("stack_background_bytes", stack_bg);
  sh_kv("valid_windows", n_valid);
  if (st_bg.n < 3u) {
    sh_puts("fewer than 3 solves\n");
    fails++;
  }
#endif
  sh_kv("stack_total_bytes", harness_stack_used());
  sh_puts(fails ? "harness FAILED\n" : "harness done\n");
  return fails ? 1 : 0;
}
