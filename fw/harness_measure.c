/* SPDX-License-Identifier: Apache-2.0 */
/* Measurement helpers shared by the firmware harnesses (harness_measure.h). */
#include "harness_measure.h"

#include <stdint.h>

#include "harness_semihost.h"

void fw_mark_b2(void);
void fw_mark_e2(void);
void fw_mark_b3(void);
void fw_mark_e3(void);
uint32_t fw_standin(uint32_t n);

extern uint32_t __stack_bottom;

void stat_add(stat_t *s, uint32_t v)
{
  if (s->n == 0u || v < s->min) s->min = v;
  if (v > s->max) s->max = v;
  s->sum += v;
  s->n++;
}

void stat_print(const char *name, const stat_t *s)
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
uint32_t ticks(uint32_t before, uint32_t after)
{
  return (before - after) & 0xFFFFFFu;
}

static uint32_t *paint_lo;

/* Paint `bytes` of unused stack below the caller's frame, to measure one call's stack. */
__attribute__((noinline)) void paint_stack(uint32_t bytes)
{
  uint32_t here;
  __asm__ volatile("mov %0, sp" : "=r"(here));
  uint32_t lo = here - 64u - bytes;
  if (lo < (uint32_t)(uintptr_t)&__stack_bottom) lo = (uint32_t)(uintptr_t)&__stack_bottom;
  paint_lo = (uint32_t *)(uintptr_t)(lo & ~3u);
  for (volatile uint32_t *p = paint_lo; (uintptr_t)p < here - 64u; p++) *p = STACK_PAINT;
}

__attribute__((noinline)) uint32_t sp_now(void)
{
  uint32_t sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  return sp;
}

/* Bytes of stack used below `sp` since the last paint_stack(). */
uint32_t stack_below(uint32_t sp)
{
  const uint32_t *p = paint_lo;
  while ((uintptr_t)p < sp && *p == STACK_PAINT) p++;
  return sp - (uint32_t)(uintptr_t)p;
}

void harness_validate_counting(void)
{
  SYST_RVR = 0xFFFFFFu;
  SYST_CVR = 0u;
  SYST_CSR = 5u; /* enable, processor clock, no interrupt */
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
}
