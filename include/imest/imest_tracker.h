/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file imest_tracker.h
 * @brief The T_R a field-oriented controller should use, from the estimator's results: holds
 *        through windows that are not valid, rate-limits every step, ignores a single outlier,
 *        and falls back to the nominal T_R when no valid window has come for too long.
 *
 * Usage (once per result, in the background task that calls imest_background()):
 *
 *     imest_tracker_config_t tc;
 *     imest_tracker_config_default(&tc, 0.12f);      // the controller's nominal T_R [s]
 *     static imest_tracker_t trk;
 *     if (imest_tracker_init(&trk, &tc) != IMEST_OK) { ... }
 *     ...
 *     while (imest_background(&est, &r) == 1) {
 *       (void)imest_tracker_update(&trk, &r);          // every result, valid or not
 *       ifoc_set_rotor_time_constant(trk.tr_s);        // what the controller uses
 *     }
 *
 * Why not feed every valid window to the controller: a window's verdict (tr_valid) is a judgement
 * on that window's data alone. A verdict that is wrong once, in a window that looked fine, moves
 * the controller's slip gain by the window's whole error in one step; and between valid windows
 * (no load, standstill, faults) the controller needs a rule for what to use. The tracker is that
 * rule, written down once.
 *
 * The default rate limit, from physics. T_R = L_R / R_R, and R_R follows the rotor cage's
 * temperature: R_R(T) = R_R(T0) (1 + alpha (T - T0)) with alpha = 0.0039 /K for copper and
 * die-cast aluminium (0.0043 /K for pure aluminium). So |dT_R/dt| / T_R = alpha |dT/dt| /
 * (1 + alpha (T - T0)) <= alpha |dT/dt|, largest when the rotor is cold. A rotor's thermal time
 * constant is 10 min for small motors and longer for large ones, and its steady rise at rated
 * load about 100 K: it warms at 100 K / 10 min = 10 K/min at most right after a cold start at
 * rated load, a few K per minute in general; an overload raises the losses but is not kept up
 * for long. That bounds T_R's real rate of change by 0.0043 /K x 10 K/min = 7.2e-4 /s. The
 * default limit, 1e-3 /s (0.1 % per second, 6 % per minute), passes every such change with 40 %
 * margin, and moves the used T_R by at most 0.1 % per 1-s window: a window that is 10 % off
 * cannot move the controller by more than that before the next window corrects it.
 *
 * The default staleness, from the same physics: a rotor warming at 5 K/min (a motor at rated
 * load shortly after a cold start: 100 K over a 20-min time constant) moves T_R by
 * 0.0039 x 5 K/min = 3.3e-4 /s, so by the estimator's typical bound (tr_tolerance, 2 %) in 60 s.
 * A T_R older than that is no longer known to within its bound: the tracker then says so
 * (IMEST_TRACKER_STALE) and moves towards the nominal T_R at fallback_rel_per_s.
 *
 * The default fall-back rate, from the rotor's cooling. The nominal is the cold T_R, and a T_R
 * that has gone stale returns to it only as fast as the rotor can cool. A rotor cools towards
 * ambient with its thermal time constant tau_th: dT/dt = -(T - T_amb) / tau_th, fastest at the
 * start, when T - T_amb is the whole rise. So the temperature falls no faster than the rated rise
 * over tau_th, and T_R rises (towards the cold value) no faster than alpha x rise / tau_th =
 * 0.0039 /K x 80 K / 1200 s = 2.6e-4 /s (a rated rise of 80 K, a 20-min thermal time constant).
 * The default fallback_rel_per_s, 2.6e-4 /s, never moves the used T_R towards the cold nominal
 * faster than the rotor could actually cool: under load, where the rotor stays warm, a stale T_R
 * drifts a quarter as fast as at the rate limit (docs/integrating.md, "Feeding T_R to the
 * controller": after 5 loaded minutes without a valid window 8 % off, where the rate limit made it
 * 22 % off and holding 1.4 %). A small motor (tau_th 10 min) can cool twice as fast; the fall-back
 * then lags its cooling, erring towards holding (the cheaper error under load). 0 holds.
 *
 * The first estimate after init (and after staleness) may move faster than the rate limit: once
 * `confirm_windows` consecutive valid windows agree (below), the tracked T_R is set to the
 * latest at once (`acquire_jump`, default on). The nominal T_R is not a measurement: a data
 * sheet's or commissioning's T_R is for one temperature, and a motor started warm has a T_R
 * 20-30 % below its cold value (80 K x 0.0039 /K: 1 - 1/1.31 = 24 %). At the rate limit such an
 * error would take minutes to remove, with the torque off by about as much all that time; the
 * step at acquisition is a one-off change of the slip gain that the speed loop absorbs, and the
 * confirmation keeps a single bad first window from causing it. Set acquire_jump = 0 to ramp
 * from the nominal at the rate limit instead.
 *
 * Time is the estimator's: each result's t_end_s (seconds since imest_init). If the ISR is not
 * called for a while (drive disabled) that time stands still: initialise the tracker again when
 * the drive is re-enabled after a stop longer than stale_after_s (the motor may have cooled).
 *
 * Numeric behaviour: float32 state and arithmetic, times kept as double (t_end_s, so that the
 * time differences stay exact after years of running). Relative quantities are relative to the
 * reference value they are compared with. No libm call, no malloc, no stdio, no global state;
 * the instance is caller-owned (CMSIS-DSP style) and used from one context (the background task).
 */
#ifndef IMEST_IMEST_TRACKER_H
#define IMEST_IMEST_TRACKER_H

#include <stdint.h>

#include "imest/imest.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What the tracker's T_R is (imest_tracker_t.state). The values are stable. */
typedef enum {
  /** no window accepted since init: tr_s is the nominal T_R */
  IMEST_TRACKER_NOMINAL = 0,
  /** the latest result was accepted: tr_s moves towards it (at most the rate limit per second) */
  IMEST_TRACKER_TRACKING = 1,
  /** the latest result was not accepted (not valid, or a valid one awaiting confirmation) and the
   *  last accepted one is at most stale_after_s old: tr_s keeps moving towards the last accepted
   *  T_R (if it has not reached it yet), then holds it */
  IMEST_TRACKER_HOLDING = 2,
  /** the last accepted window is older than stale_after_s: tr_s moves towards the nominal T_R at
   *  fallback_rel_per_s (default 2.6e-4 /s: the rotor's cooling), and stays there */
  IMEST_TRACKER_STALE = 3
} imest_tracker_state_t;

/** Short lower-case name of a state ("nominal", "tracking", "holding", "stale"; "unknown"). */
const char *imest_tracker_state_name(int state);

/** Configuration. Fill with imest_tracker_config_default(). */
typedef struct {
  /** nominal T_R [s]: what the controller uses before the first estimate and falls back to (the
   *  data sheet's L_R / R_R, imest_circuit.h, or commissioning's). > 0 and finite */
  float tr_nominal_s;
  /** relative bound reported for the nominal T_R (default 0.35: a cold T_R used on a rotor 130 K
   *  warmer, 1 - 1/(1 + 0.0039 x 130)). In [0, 10] */
  float nominal_bound_rel;
  /** largest relative change of the used T_R per second of the estimator's time (default 1e-3
   *  /s: above, from the rotor's heating). In (0, 1] */
  float rate_rel_per_s;
  /** after this long without an accepted window [s], fall back to the nominal (default 60 s:
   *  above). > 0 and finite */
  float stale_after_s;
  /** largest relative change per second while falling back to the nominal (default 2.6e-4 /s:
   *  above, the fastest a rotor cools, 0.0039 /K x 80 K / 1200 s; 0: hold the last accepted T_R,
   *  the state still says STALE; rate_rel_per_s: return at the rate limit). For a motor whose
   *  rise or thermal time constant differs, alpha x (rated rise) / (thermal time constant).
   *  In [0, 1] */
  float fallback_rel_per_s;
  /** least relative tolerance of the agreement test (below), whatever the windows' bounds say
   *  (default 0.005). In [0, 1) */
  float gate_min_rel;
  /** consecutive valid windows that must agree before a value outside the tolerance, or the first
   *  one after init or staleness, is accepted (default 2; 1: every valid window is accepted, no
   *  outlier rejection). In [1, 16] */
  unsigned int confirm_windows;
  /** nonzero: a value acquired (the first accepted after init or after staleness) is taken at
   *  once, not rate-limited (default 1: above) */
  int acquire_jump;
} imest_tracker_config_t;

/** The tracker. The first block is the output, read-only for the caller; the second is private
 *  (public for static allocation). */
typedef struct {
  float tr_s;         /**< the T_R to use [s] */
  float tr_bound_rel; /**< relative bound of tr_s (below) */
  float age_s;        /**< time since the last accepted window [s] (below) */
  int state;          /**< imest_tracker_state_t */
  uint32_t accepted;  /**< results accepted since init */
  uint32_t rejected;  /**< valid results not accepted when they came (outliers, confirmations) */
  uint32_t pending;   /**< agreeing valid windows awaiting confirmation (0 .. confirm_windows-1) */

  imest_tracker_config_t cfg;
  float target_s;         /* the last accepted T_R */
  float target_bound_rel; /* its window's bound */
  float pending_s;        /* the first window awaiting confirmation, and its bound */
  float pending_bound_rel;
  double t_accept_s;  /* t_end_s of the last accepted window */
  double t_pending_s; /* t_end_s of the first window awaiting confirmation */
  double t_last_s;    /* t_end_s of the latest result */
  int have_accept;    /* a window was accepted since init */
  int have_time;      /* a result came since init */
} imest_tracker_t;

/** Fill a config with the defaults above and the given nominal T_R [s]; every field is written.
 *  Does nothing if cfg is NULL. */
void imest_tracker_config_default(imest_tracker_config_t *cfg, float tr_nominal_s);

/** Check a config.
 *  @param field  optional: receives the name of the first bad field (NULL if none)
 *  @retval IMEST_OK          the config is usable
 *  @retval IMEST_ERR_NULL    cfg is NULL
 *  @retval IMEST_ERR_CONFIG  a field is out of the range documented above (*field names it) */
int imest_tracker_config_check(const imest_tracker_config_t *cfg, const char **field);

/** Initialise (or restart) a tracker: tr_s = tr_nominal_s, tr_bound_rel = nominal_bound_rel,
 *  age_s = 0, state NOMINAL, counters 0. The config is copied.
 *  @retval IMEST_OK          initialised
 *  @retval IMEST_ERR_NULL    t or cfg is NULL (t unchanged)
 *  @retval IMEST_ERR_CONFIG  a config field is out of range (t unchanged; imest_tracker_config_check()
 *                            names it) */
int imest_tracker_init(imest_tracker_t *t, const imest_tracker_config_t *cfg);

/**
 * Feed one result of imest_background(), valid or not, in the order they come.
 *
 * Let t = r->t_end_s, dt = t minus the previous result's t_end_s (0 for the first), and for a
 * valid window v = r->tr_s, b = r->tr_bound_rel (gate_min_rel if that is not finite or negative).
 * Two values x (bound bx, time tx) and y (bound by, time ty) agree iff
 *     |y - x| <= (max(bx + by, gate_min_rel) + rate_rel_per_s * |ty - tx|) * x,
 * i.e. they differ by no more than their bounds plus the drift the rate limit allows between them.
 *
 * A result is usable iff tr_valid is nonzero and tr_s is finite and > 0; others change nothing
 * but the time. The tracker is acquiring iff no window was accepted since init or the last
 * accepted one is more than stale_after_s older than t. A usable result is accepted iff
 *   - the tracker is not acquiring, and the result agrees with the last accepted window; or
 *   - it agrees with the window awaiting confirmation and is the confirm_windows-th consecutive
 *     usable window to do so (with confirm_windows = 1: always).
 * Otherwise it is counted in `rejected` and, unless it agrees with the window already awaiting
 * confirmation (then `pending` counts up), starts a new confirmation. A window awaits confirmation
 * for stale_after_s at most; results that are not usable do not break a confirmation.
 *
 * After the result: age_s = t - (t_end_s of the last accepted window), or t if none was accepted.
 * state = TRACKING if this result was accepted; else NOMINAL if none was ever accepted; else STALE
 * if age_s > stale_after_s; else HOLDING. The goal is the last accepted T_R in TRACKING and
 * HOLDING, the nominal in NOMINAL and STALE. tr_s moves towards the goal by at most
 * rate_rel_per_s * dt * tr_s (in STALE fallback_rel_per_s * dt * tr_s), and stops on it; except that an acceptance while acquiring, with
 * acquire_jump, sets tr_s to the accepted value at once.
 * tr_bound_rel = nominal_bound_rel in NOMINAL; otherwise, with a the last accepted T_R and ba its
 * bound, (|tr_s - a| + (ba + rate_rel_per_s * age_s) * a) / tr_s: a bound on |T_R - tr_s| / tr_s as
 * long as T_R changes no faster than the rate limit; in STALE at most
 * (|tr_s - nominal| + nominal_bound_rel * nominal) / tr_s.
 *
 * @retval 1               r was accepted (its T_R is the goal now)
 * @retval 0               r was not accepted (not usable, or awaiting confirmation)
 * @retval IMEST_ERR_NULL  t or r is NULL (nothing changes)
 * @retval IMEST_ERR_ARG   r->t_end_s is not finite, or earlier than the previous result's (the
 *                         estimator was initialised again: initialise the tracker too); nothing changes
 */
int imest_tracker_update(imest_tracker_t *t, const imest_result_t *r);

#ifdef __cplusplus
}
#endif

#endif /* IMEST_IMEST_TRACKER_H */
