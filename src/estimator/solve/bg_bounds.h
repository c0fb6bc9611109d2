/* SPDX-License-Identifier: Apache-2.0 */
/* Every iteration bound of the background solve, in one place: the loops of
 * bg_roots.c and bg_quality.c are bounded by these, out->work is bounded by
 * BG_SOLVE_WORK_BOUND, and the tests and the fuzzer check against the same
 * macros. Internal: not part of the public API. */
#ifndef IMEST_BG_BOUNDS_H
#define IMEST_BG_BOUNDS_H

/* Largest polynomial degree the root finder accepts (generic resultant: 20). */
#define BG_POLY_MAXDEG 20

/* Bounds (per polynomial domain; BG_ROOTS_DOMAINS domains per call). */
#define BG_ROOTS_MAX_DEPTH         48   /* isolation: interval halvings from (0,1] */
#define BG_ROOTS_MAX_BISECT        48   /* refinement bisections in chain precision */
#define BG_ROOTS_MAX_POLISH        40   /* safeguarded Newton/bisection steps in float64 */
#define BG_ROOTS_MAX_EXPAND        8    /* bracket expansions when float64 sees no sign change */
#define BG_ROOTS_MAX_SPLITS        1024 /* isolation halvings per domain */
#define BG_ROOTS_DOMAINS           4u   /* kappa in (0,1], (1,16], (16,256], (256,inf) */
/* float64 rescue grid of a domain (parity_rescue): cells ending at 2^-16 ..
 * 2^-1, 0.75 and the domain's top; 2 end evaluations plus one per cell, and
 * at most one bracketed Newton solve per cell. */
#define BG_ROOTS_RESCUE_POW2_CELLS 16u
#define BG_ROOTS_RESCUE_CELLS      (BG_ROOTS_RESCUE_POW2_CELLS + 2u)
/* Hard bounds per call (4 domains, <= 20 roots each), asserted by the tests. */
#define BG_ROOTS_BOUND_STURM                                                                                 \
  (BG_ROOTS_DOMAINS * (2u + BG_ROOTS_MAX_SPLITS + BG_POLY_MAXDEG * BG_ROOTS_MAX_BISECT))
#define BG_ROOTS_BOUND_BISECT (BG_ROOTS_DOMAINS * BG_POLY_MAXDEG * BG_ROOTS_MAX_BISECT)
#define BG_ROOTS_BOUND_POLISH                                                                                \
  (BG_ROOTS_DOMAINS * (BG_POLY_MAXDEG * (2u * (2u + 2u * BG_ROOTS_MAX_EXPAND + BG_ROOTS_MAX_POLISH) + 1u) +  \
                       2u + BG_ROOTS_RESCUE_CELLS + BG_ROOTS_RESCUE_CELLS * BG_ROOTS_MAX_POLISH))

/* Quality (bg_quality.c): per side of K2*, step-out probes then an Illinois
 * search for the crossing; per K1 extreme, 3 start points then parabolic or
 * outward steps. */
#define BG_PE_MAX_PROBE  80 /* step-out probes per side */
#define BG_PE_MAX_ROOT   40 /* Illinois iterations per crossing */
#define BG_PE_MAX_MIN    40 /* parabolic/outward steps per K1 extreme (after 3 start points) */
#define BG_QUALITY_BOUND (2u * (BG_PE_MAX_PROBE + BG_PE_MAX_ROOT) + 2u * (3u + BG_PE_MAX_MIN))

/* One solve: out->work = Sturm evaluations + bisection steps + float64 polish
 * evaluations + quality-profile evaluations. */
#define BG_SOLVE_WORK_BOUND                                                                                  \
  (BG_ROOTS_BOUND_STURM + BG_ROOTS_BOUND_BISECT + BG_ROOTS_BOUND_POLISH + BG_QUALITY_BOUND)

#endif /* IMEST_BG_BOUNDS_H */
