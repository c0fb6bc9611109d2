/* SPDX-License-Identifier: Apache-2.0 */
/* Minimal ARM semihosting: SYS_WRITE0 for output, SYS_EXIT to stop QEMU. */
#include "harness_semihost.h"

#define SYS_WRITE0                   0x04u
#define SYS_EXIT                     0x18u
#define ADP_STOPPED_APPLICATION_EXIT 0x20026u
#define ADP_STOPPED_RUNTIME_ERROR    0x20023u

static uint32_t sh_call(uint32_t op, const void *arg)
{
  register uint32_t r0 __asm__("r0") = op;
  register const void *r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

void sh_puts(const char *s)
{
  (void)sh_call(SYS_WRITE0, s);
}

void sh_putu(uint64_t v)
{
  char buf[24];
  int i = 23;
  buf[i] = '\0';
  do {
    buf[--i] = (char)('0' + (int)(v % 10u));
    v /= 10u;
  } while (v != 0u && i > 0);
  sh_puts(&buf[i]);
}

void sh_puti(int64_t v)
{
  if (v < 0) {
    sh_puts("-");
    sh_putu((uint64_t)(-v));
  } else {
    sh_putu((uint64_t)v);
  }
}

void sh_putf(double v, unsigned int dec)
{
  if (v != v) {
    sh_puts("nan");
    return;
  }
  if (v < 0.0) {
    sh_puts("-");
    v = -v;
  }
  if (v > 1e15) {
    sh_puts("inf");
    return;
  }
  double scale = 1.0;
  for (unsigned int k = 0; k < dec; k++) scale *= 10.0;
  uint64_t q = (uint64_t)(v * scale + 0.5);
  uint64_t ip = q / (uint64_t)scale, fp = q % (uint64_t)scale;
  sh_putu(ip);
  if (dec > 0u) {
    char buf[24];
    buf[dec] = '\0';
    for (unsigned int k = dec; k > 0u; k--) {
      buf[k - 1u] = (char)('0' + (int)(fp % 10u));
      fp /= 10u;
    }
    sh_puts(".");
    sh_puts(buf);
  }
}

void sh_kv(const char *key, uint64_t v)
{
  sh_puts(key);
  sh_puts(" ");
  sh_putu(v);
  sh_puts("\n");
}

void sh_exit(int code)
{
  for (;;)
    (void)sh_call(SYS_EXIT, (const void *)(uintptr_t)(code == 0 ? ADP_STOPPED_APPLICATION_EXIT
                                                                : ADP_STOPPED_RUNTIME_ERROR));
}
