/* Force-included (-include) into every core source of the ThreadSanitizer build
 * (test/concurrency/CMakeLists.txt); never part of the library.
 *
 * The hand-off (include/imest/imest.h, "Concurrency contract") orders the
 * window's contents against the published/released counters with
 * IMEST_BARRIER. On a multi-core host the contract asks for a full memory
 * barrier there; ThreadSanitizer models neither a compiler barrier nor a
 * stand-alone fence, so it would see no ordering at all and report every
 * access to a window buffer. Here the barrier is an acquire-release
 * read-modify-write of one shared word, which TSan does model: each barrier
 * takes over the ordering of every barrier executed before it, in either
 * context. That is stronger than the fence it stands for (a fence orders
 * only through the counter the other side then reads), so TSan can miss a
 * race through it but never invent one: what it reports is an access that no
 * barrier orders, i.e. of the other context's live state, or of a buffer the
 * accessing side does not own (a torn window). */
#ifndef IMEST_TSAN_BARRIER_H
#define IMEST_TSAN_BARRIER_H

#ifdef __cplusplus
extern "C" {
#endif
extern unsigned int imest_tsan_barrier_word; /* defined by the test */
#ifdef __cplusplus
}
#endif

#define IMEST_BARRIER() ((void)__atomic_fetch_add(&imest_tsan_barrier_word, 0u, __ATOMIC_ACQ_REL))

#endif
