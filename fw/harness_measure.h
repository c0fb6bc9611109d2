/* SPDX-License-Identifier: Apache-2.0 */
/* Measurement helpers shared by the firmware harnesses (harness_main.c, harness_commission.c):
 * call statistics, SysTick, and a painted stack for one call's high-water mark. Harness code
 * (not counted by the plugin). */
#ifndef FW_HARNESS_MEASURE_H
#define FW_HARNESS_MEASURE_H
#include <stdint.h>

#define SYST_CSR    (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR    (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR    (*(volatile uint32_t *)0xE000E018u)
#define STACK_PAINT 0xC5C5C5C5u

/* The counting plugin's channels open at fw_mark_bN and close at fw_mark_eN (harness_markers.S):
   0 ISR call, 1 background call with work, 2 empty bracket, 3 stand-in, 4 init, 5 idle
   background call. */
void fw_mark_b0(void);
void fw_mark_e0(void);
void fw_mark_b1(void);
void fw_mark_e1(void);
void fw_mark_b4(void);
void fw_mark_e4(void);
void fw_mark_b5(void);
void fw_mark_e5(void);
uint32_t harness_stack_used(void); /* harness_startup.c: the whole run's stack high-water mark */

typedef struct {
  uint32_t n, min, max;
  uint64_t sum;
} stat_t;

void stat_add(stat_t *s, uint32_t v);
void stat_print(const char *name, const stat_t *s); /* "name calls N min A mean B max C" */
uint32_t ticks(uint32_t before, uint32_t after);    /* SysTick ticks between two CVR reads */
void paint_stack(uint32_t bytes);                   /* paint this much stack below the caller */
uint32_t sp_now(void);
uint32_t stack_below(uint32_t sp); /* bytes used below sp since the last paint_stack() */

/* SysTick on, then the counting's validation (tools/firmware-budget checks it): an empty
   bracket (channel 2) and a stand-in of known count (channel 3), 200 calls, with their
   SysTick figures printed. */
void harness_validate_counting(void);

#endif
