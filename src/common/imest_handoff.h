/* SPDX-License-Identifier: Apache-2.0 */
/* The estimator's hand-off between its two contexts (imest.h, concurrency
 * contract): the ISR publishes a finished window by a store-release of its
 * index, the background sees it by a load-acquire, and releases the buffer
 * the same way back. Acquire/release orders the window's contents against the
 * index on any core, single or multi, cached or not (on a Cortex-M it is one
 * DMB each, at the window's end), and tools such as ThreadSanitizer see the
 * ordering. Counters read by the other context for information only
 * (overruns) are relaxed atomics: whole words, never torn. Internal: not part
 * of the public API. */
#ifndef IMEST_COMMON_HANDOFF_H
#define IMEST_COMMON_HANDOFF_H

#include "common/imest_math.h" /* IMEST_BARRIER */

#if defined(__GNUC__) || defined(__clang__)
#define IMEST_LOAD_ACQUIRE(p)     __atomic_load_n((p), __ATOMIC_ACQUIRE)
#define IMEST_STORE_RELEASE(p, v) __atomic_store_n((p), (v), __ATOMIC_RELEASE)
#define IMEST_LOAD_RELAXED(p)     __atomic_load_n((p), __ATOMIC_RELAXED)
#define IMEST_STORE_RELAXED(p, v) __atomic_store_n((p), (v), __ATOMIC_RELAXED)
#else
/* Other compilers: volatile words and IMEST_BARRIER on the side that orders
 * (define IMEST_BARRIER to a full memory barrier on a multi-core or cached
 * system, e.g. -DIMEST_BARRIER=__DMB()). */
#define IMEST_LOAD_ACQUIRE(p)     imest__load_acquire(p)
#define IMEST_STORE_RELEASE(p, v) imest__store_release((p), (v))
#define IMEST_LOAD_RELAXED(p)     (*(p))
#define IMEST_STORE_RELAXED(p, v) ((void)(*(p) = (v)))
static inline uint32_t imest__load_acquire(const volatile uint32_t *p)
{
  const uint32_t v = *p;
  IMEST_BARRIER();
  return v;
}
static inline void imest__store_release(volatile uint32_t *p, uint32_t v)
{
  IMEST_BARRIER();
  *p = v;
}
#endif

#endif /* IMEST_COMMON_HANDOFF_H */
