/* SPDX-License-Identifier: Apache-2.0 */
/* Startup of the firmware harness: vector table, .data/.bss init, FPU enable
 * (CPACR), stack painting (to measure the stack high-water mark), main, exit
 * through semihosting. */
#include <stdint.h>

#include "harness_semihost.h"

extern uint32_t __data_start, __data_end, __data_load, __bss_start, __bss_end;
extern uint32_t __stack_bottom, __stack_top;
int main(void);
void Reset_Handler(void);
void Fault_Handler(void);

#define SCB_CPACR   (*(volatile uint32_t *)0xE000ED88u)
#define STACK_PAINT 0xC5C5C5C5u

__attribute__((naked, noreturn)) void Reset_Handler(void)
{
  /* Paint the stack below the current frame before anything uses it. */
  __asm__ volatile("ldr r0, =__stack_bottom\n"
                   "ldr r1, =__stack_top\n"
                   "sub r1, r1, #64\n"
                   "ldr r2, =0xC5C5C5C5\n"
                   "1: cmp r0, r1\n"
                   "bhs 2f\n"
                   "str r2, [r0], #4\n"
                   "b 1b\n"
                   "2: ldr r0, =__stack_top\n"
                   "mov sp, r0\n"
                   "b harness_c_start\n");
}

/* Lowest stack address ever written (stack high-water mark). */
uint32_t harness_stack_used(void);
uint32_t harness_stack_used(void)
{
  const uint32_t *p = &__stack_bottom;
  while (p < &__stack_top && *p == STACK_PAINT) p++;
  return (uint32_t)((uintptr_t)&__stack_top - (uintptr_t)p);
}

__attribute__((noreturn, used)) void harness_c_start(void);
__attribute__((noreturn, used)) void harness_c_start(void)
{
  /* volatile: keep these loops loops (not memcpy/memset calls), so that the
   * flash probe's baseline does not already contain memcpy/memset. */
  const volatile uint32_t *src = &__data_load;
  volatile uint32_t *dst = &__data_start;
  while (dst < &__data_end) *dst++ = *src++;
  for (dst = &__bss_start; dst < &__bss_end;) *dst++ = 0u;
  /* Full access to CP10 and CP11 (the FPU). */
  SCB_CPACR |= (0xFu << 20);
  __asm__ volatile("dsb\n isb" ::: "memory");
  sh_exit(main());
}

void Fault_Handler(void)
{
  sh_puts("FAULT\n");
  sh_exit(3);
}

__attribute__((section(".isr_vector"), used)) static const uintptr_t vectors[16] = {(uintptr_t)&__stack_top,
                                                                                    (uintptr_t)Reset_Handler,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    0,
                                                                                    0,
                                                                                    0,
                                                                                    0,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    0,
                                                                                    (uintptr_t)Fault_Handler,
                                                                                    (uintptr_t)Fault_Handler};
