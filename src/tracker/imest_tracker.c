/* SPDX-License-Identifier: Apache-2.0 */
/* The T_R a controller should use, from the estimator's results (include/imest/imest_tracker.h:
 * the rules and their physics). Runs once per window in the background task: -Os like the rest
 * of the once-per-window code (src/CMakeLists.txt). float32 state, double times, no libm. */
#include "imest/imest_tracker.h"

#include <math.h>
#include <stddef.h>

#include "common/imest_range.h"

/* |y - x| <= (max(bx + by, floor) + rate |dt|) x: the two values differ by no more than their
   bounds plus the drift the rate limit allows between them (imest_tracker_update()). */
static int agree(const imest_tracker_config_t *c, float x, float bx, float y, float by, float dt_s)
{
  float tol = bx + by;
  if (tol < c->gate_min_rel) tol = c->gate_min_rel;
  tol += c->rate_rel_per_s * fabsf(dt_s);
  return fabsf(y - x) <= tol * x;
}

/* One step of at most rate * dt (relative to the present value) towards the goal. */
static float slew(float x, float goal, float max_rel)
{
  const float step = max_rel * x;
  if (fabsf(goal - x) <= step) return goal;
  return goal > x ? x + step : x - step;
}

const char *imest_tracker_state_name(int state)
{
  switch (state) {
  case IMEST_TRACKER_NOMINAL: return "nominal";
  case IMEST_TRACKER_TRACKING: return "tracking";
  case IMEST_TRACKER_HOLDING: return "holding";
  case IMEST_TRACKER_STALE: return "stale";
  default: return "unknown";
  }
}

void imest_tracker_config_default(imest_tracker_config_t *cfg, float tr_nominal_s)
{
  if (cfg == NULL) return;
  cfg->tr_nominal_s = tr_nominal_s;
  cfg->nominal_bound_rel = 0.35f;
  cfg->rate_rel_per_s = 1.0e-3f;
  cfg->stale_after_s = 60.0f;
  cfg->fallback_rel_per_s = 2.6e-4f;
  cfg->gate_min_rel = 0.005f;
  cfg->confirm_windows = 2u;
  cfg->acquire_jump = 1;
}

int imest_tracker_config_check(const imest_tracker_config_t *cfg, const char **field)
{
  const char *bad = NULL;
  if (cfg == NULL) {
    if (field) *field = "cfg";
    return IMEST_ERR_NULL;
  }
  if (!imest__in_range(cfg->tr_nominal_s, 0.0f, 1, 3.0e38f))
    bad = "tr_nominal_s";
  else if (!imest__in_range(cfg->nominal_bound_rel, 0.0f, 0, 10.0f))
    bad = "nominal_bound_rel";
  else if (!imest__in_range(cfg->rate_rel_per_s, 0.0f, 1, 1.0f))
    bad = "rate_rel_per_s";
  else if (!imest__in_range(cfg->stale_after_s, 0.0f, 1, 3.0e38f))
    bad = "stale_after_s";
  else if (!imest__in_range(cfg->fallback_rel_per_s, 0.0f, 0, 1.0f))
    bad = "fallback_rel_per_s";
  else if (!imest__in_range(cfg->gate_min_rel, 0.0f, 0, 1.0f) || cfg->gate_min_rel >= 1.0f)
    bad = "gate_min_rel";
  else if (cfg->confirm_windows < 1u || cfg->confirm_windows > 16u)
    bad = "confirm_windows";
  if (field) *field = bad;
  return bad == NULL ? IMEST_OK : IMEST_ERR_CONFIG;
}

int imest_tracker_init(imest_tracker_t *t, const imest_tracker_config_t *cfg)
{
  if (t == NULL || cfg == NULL) return IMEST_ERR_NULL;
  if (imest_tracker_config_check(cfg, NULL) != IMEST_OK) return IMEST_ERR_CONFIG;
  t->cfg = *cfg;
  t->tr_s = cfg->tr_nominal_s;
  t->tr_bound_rel = cfg->nominal_bound_rel;
  t->age_s = 0.0f;
  t->state = IMEST_TRACKER_NOMINAL;
  t->accepted = 0u;
  t->rejected = 0u;
  t->pending = 0u;
  t->target_s = cfg->tr_nominal_s;
  t->target_bound_rel = cfg->nominal_bound_rel;
  t->pending_s = 0.0f;
  t->pending_bound_rel = 0.0f;
  t->t_accept_s = 0.0;
  t->t_pending_s = 0.0;
  t->t_last_s = 0.0;
  t->have_accept = 0;
  t->have_time = 0;
  return IMEST_OK;
}

/* A usable window (v, b at time now): accepted (1) or awaiting confirmation (0). acquiring: no
   accepted window, or the last one is stale, so only a confirmation accepts. */
static int judge(imest_tracker_t *t, float v, float b, double now, int acquiring)
{
  const imest_tracker_config_t *c = &t->cfg;
  if (!acquiring && agree(c, t->target_s, t->target_bound_rel, v, b, (float)(now - t->t_accept_s))) return 1;
  const float since_pending = (float)(now - t->t_pending_s);
  if (t->pending > 0u && since_pending <= c->stale_after_s &&
      agree(c, t->pending_s, t->pending_bound_rel, v, b, since_pending)) {
    t->pending++;
  } else {
    t->pending = 1u;
    t->pending_s = v;
    t->pending_bound_rel = b;
    t->t_pending_s = now;
  }
  if (t->pending >= c->confirm_windows) return 1;
  t->rejected++;
  return 0;
}

/* tr_bound_rel of the state just set (imest_tracker_update()). */
static float bound_of(const imest_tracker_t *t)
{
  const imest_tracker_config_t *c = &t->cfg;
  if (t->state == IMEST_TRACKER_NOMINAL) return c->nominal_bound_rel;
  const float a = t->target_s;
  float b = (fabsf(t->tr_s - a) + (t->target_bound_rel + c->rate_rel_per_s * t->age_s) * a) / t->tr_s;
  if (t->state == IMEST_TRACKER_STALE) {
    const float n = c->tr_nominal_s;
    const float bn = (fabsf(t->tr_s - n) + c->nominal_bound_rel * n) / t->tr_s;
    if (bn < b) b = bn;
  }
  return b;
}

int imest_tracker_update(imest_tracker_t *t, const imest_result_t *r)
{
  if (t == NULL || r == NULL) return IMEST_ERR_NULL;
  const double now = r->t_end_s;
  if (!isfinite(now) || (t->have_time && now < t->t_last_s)) return IMEST_ERR_ARG;
  const imest_tracker_config_t *c = &t->cfg;
  const float dt = t->have_time ? (float)(now - t->t_last_s) : 0.0f;
  t->t_last_s = now;
  t->have_time = 1;

  const float v = (float)r->tr_s;
  const int acquiring = !t->have_accept || (float)(now - t->t_accept_s) > c->stale_after_s;
  int accepted = 0, jump = 0;
  if (r->tr_valid && isfinite(v) && v > 0.0f) {
    float b = (float)r->tr_bound_rel;
    if (!(isfinite(b) && b >= 0.0f)) b = c->gate_min_rel;
    accepted = judge(t, v, b, now, acquiring);
    if (accepted) {
      jump = c->acquire_jump && acquiring;
      t->target_s = v;
      t->target_bound_rel = b;
      t->t_accept_s = now;
      t->have_accept = 1;
      t->pending = 0u;
      t->accepted++;
    }
  }

  t->age_s = (float)(t->have_accept ? now - t->t_accept_s : now);
  if (accepted)
    t->state = IMEST_TRACKER_TRACKING;
  else if (!t->have_accept)
    t->state = IMEST_TRACKER_NOMINAL;
  else if (t->age_s > c->stale_after_s)
    t->state = IMEST_TRACKER_STALE;
  else
    t->state = IMEST_TRACKER_HOLDING;

  const int to_nominal = t->state == IMEST_TRACKER_NOMINAL || t->state == IMEST_TRACKER_STALE;
  const float goal = to_nominal ? c->tr_nominal_s : t->target_s;
  const float rate = t->state == IMEST_TRACKER_STALE ? c->fallback_rel_per_s : c->rate_rel_per_s;
  t->tr_s = jump ? v : slew(t->tr_s, goal, rate * dt);
  t->tr_bound_rel = bound_of(t);
  return accepted;
}
