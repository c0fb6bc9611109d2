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

void fw_mark_b0(void);
void fw_mark_e0(void);
void fw_mark_b1(void);
void fw_mark_e1(void);
void fw_mark_b2(void);
void fw_mark_e2(void);
void fw_mark_b3(void);
void fw_mark_e3(void);
void fw_mark_b4(void);
void fw_mark_e4(void);
void fw_mark_b5(void);
void fw_mark_e5(void);
uint32_t fw_standin(uint32_t n);
uint32_t harness_stack_used(void);

#define SYST_CSR    (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR    (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR    (*(volatile uint32_t *)0xE000E018u)
#define STACK_PAINT 0xC5C5C5C5u
extern uint32_t __stack_bottom;

typedef struct {
  uint32_t n, min, max;
  uint64_t sum;
} stat_t;

static void stat_add(stat_t *s, uint32_t v)
{
  if (s->n == 0u || v < s->min) s->min = v;
  if (v > s->max) s->max = v;
  s->sum += v;
  s->n++;
}

static void stat_print(const char *name, const stat_t *s)
{
  sh_puts(name);
  sh_puts(" calls ");
  sh_putu(s->n);
  sh_puts(" min ");
  sh_putu(s->min);
  sh_puts(" mean ");
  sh_putu(s->n ? (s->sum + s->n / 2u) / s->n : 0u);
  sh_puts(" max ");
  sh_putu(s->max);
  sh_puts("\n");
}

/* SysTick ticks elapsed between two CVR reads (down-counter, 24 bit). */
static uint32_t ticks(uint32_t before, uint32_t after)
{
  return (before - after) & 0xFFFFFFu;
}

#if FW_WITH_IMEST
static uint32_t *paint_lo;

/* Paint `bytes` of unused stack below the caller's frame, to measure one call's stack. */
static __attribute__((noinline)) void paint_stack(uint32_t bytes)
{
  uint32_t here;
  __asm__ volatile("mov %0, sp" : "=r"(here));
  uint32_t lo = here - 64u - bytes;
  if (lo < (uint32_t)(uintptr_t)&__stack_bottom) lo = (uint32_t)(uintptr_t)&__stack_bottom;
  paint_lo = (uint32_t *)(uintptr_t)(lo & ~3u);
  for (volatile uint32_t *p = paint_lo; (uintptr_t)p < here - 64u; p++) *p = STACK_PAINT;
}

static uint32_t sp_now(void)
{
  uint32_t sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  return sp;
}

/* Bytes of stack used below `sp` since the last paint_stack(). */
static uint32_t stack_below(uint32_t sp)
{
  const uint32_t *p = paint_lo;
  while ((uintptr_t)p < sp && *p == STACK_PAINT) p++;
  return sp - (uint32_t)(uintptr_t)p;
}
#endif

#if FW_WITH_IMEST
static imest_t est;
static imest_result_t res;
#endif

int main(void)
{
  int fails = 0;
  SYST_RVR = 0xFFFFFFu;
  SYST_CVR = 0u;
  SYST_CSR = 5u; /* enable, processor clock, no interrupt */

  /* Validation of the counting: an empty bracket and a stand-in of known count. */
  fw_mark_b2();
  fw_mark_e2();
  volatile uint32_t sink = 0u;
  stat_t st_standin = {0, 0, 0, 0};
  for (uint32_t k = 1u; k <= 200u; k++) {
    uint32_t t0 = SYST_CVR;
    fw_mark_b3();
    sink += fw_standin(k * 50u);
    fw_mark_e3();
    uint32_t t1 = SYST_CVR;
    stat_add(&st_standin, ticks(t0, t1));
  }
  (void)sink;
  sh_puts("standin_expected calls 200 min 153 mean 15078 max 30003\n");
  stat_print("standin_systick_ticks", &st_standin);

#if FW_WITH_IMEST
  sh_kv("sizeof_imest_t", sizeof(imest_t));
  sh_kv("sizeof_imest_result_t", sizeof(imest_result_t));
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2u;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
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
