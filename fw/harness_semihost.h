/* SPDX-License-Identifier: Apache-2.0 */
/* Minimal ARM semihosting for the firmware harness (QEMU -semihosting). */
#ifndef FW_HARNESS_SEMIHOST_H
#define FW_HARNESS_SEMIHOST_H
#include <stdint.h>

void sh_puts(const char *s);
void sh_putu(uint64_t v);
void sh_puti(int64_t v);
/* Fixed-point print of a double with `dec` decimals (no printf). */
void sh_putf(double v, unsigned int dec);
void sh_kv(const char *key, uint64_t v); /* "key v\n" */
void sh_exit(int code) __attribute__((noreturn));
#endif
