/* SPDX-License-Identifier: Apache-2.0 */
/* Load torque. The profile: 0 before load_on_s, linear ramp over load_ramp_s, then load_nm;
 * from load_step_on_s (if finite) a second linear change to load_step_nm over load_step_ramp_s
 * (0: a step); imsim_set_load() overrides it. How it acts on the rotor (load_kind):
 *
 * ACTIVE: the profile's value, opposing positive rotation at any speed (it drives a rotor that
 * stops backwards, as a hoist's weight does).
 *
 * PASSIVE (default): friction-like, L = |profile|. Moving, it opposes the motion (+L for
 * omega > 0, -L for omega < 0); at rest it is static friction: it cancels the motor's torque
 * while |T_e| <= L (the rotor stays at rest) and, once |T_e| > L, opposes the breakaway with L.
 * The stick-slip treatment (Karnopp-style, with the rest state held exactly so that the load's
 * sign cannot flip from one integration step to the next):
 *  - each integration step is decided from the state at its start: moving (omega != 0), held
 *    (omega == 0 and |T_e| <= L, L > 0: the step is integrated, then omega and theta are put
 *    back, the rotor does not move) or breaking away (omega == 0, |T_e| > L);
 *  - a moving or breaking-away rotor whose speed comes out of a step with the sign opposite
 *    to its motion has stopped within that step: omega is set to exactly 0 (the rest state),
 *    and the next step decides between held and breakaway. The stop is placed at the step's
 *    end (an error of at most one step of the load's deceleration, L h / J in speed).
 * A rotor that turns forward with omega > 0 sees the same torque as with ACTIVE, bit for bit. */
#include "imsim_internal.h"

double ims_load_at(const imsim_t *s, double t)
{
  if (s->load_overridden) return s->load_override;
  const imsim_config_t *c = &s->c;
  if (t < c->load_on_s) return 0.0;
  if (c->load_ramp_s > 0.0 && t < c->load_on_s + c->load_ramp_s)
    return c->load_nm * (t - c->load_on_s) / c->load_ramp_s;
  if (!(t >= c->load_step_on_s)) return c->load_nm; /* INFINITY: no second change */
  if (c->load_step_ramp_s > 0.0 && t < c->load_step_on_s + c->load_step_ramp_s)
    return c->load_nm + (c->load_step_nm - c->load_nm) * (t - c->load_step_on_s) / c->load_step_ramp_s;
  return c->load_step_nm;
}

double ims_load_torque(const imsim_t *s, double l_nm)
{
  if (s->c.load_kind == IMSIM_LOAD_ACTIVE) return l_nm;
  const double mag = fabs(l_nm);
  if (!(mag > 0.0)) return l_nm; /* no load (and no -0 in the record) */
  if (s->w > 0.0) return mag;
  if (s->w < 0.0) return -mag;
  if (s->te > mag) return mag;
  if (s->te < -mag) return -mag;
  return s->te; /* static friction: cancels the motor's torque */
}

double ims_load_begin(const imsim_t *s, double l_nm, ims_load_step_t *ls)
{
  ls->w0 = s->w;
  ls->th0 = s->th;
  ls->l_nm = l_nm;
  ls->tl = ims_load_torque(s, l_nm);
  const double mag = fabs(l_nm);
  ls->held = s->c.load_kind == IMSIM_LOAD_PASSIVE && mag > 0.0 && s->w == 0.0 && fabs(s->te) <= mag;
  return ls->tl;
}

static void stall_event(imsim_t *s, double t, double l_nm)
{
  if (s->stall_events == 0u) {
    s->stall_first_t_s = t;
    s->stall_first_load_nm = fabs(l_nm);
    s->stall_first_torque_nm = s->te;
  }
  s->stall_events++;
}

void ims_load_end(imsim_t *s, const ims_load_step_t *ls, double t_end, double h)
{
  const imsim_config_t *c = &s->c;
  if (c->load_kind == IMSIM_LOAD_ACTIVE) {
    if ((ls->l_nm > 0.0 && ls->w0 > 0.0 && s->w <= 0.0) || (ls->l_nm < 0.0 && ls->w0 < 0.0 && s->w >= 0.0))
      stall_event(s, t_end, ls->l_nm);
    return;
  }
  if (ls->held) {
    s->w = 0.0;
    s->th = ls->th0;
    s->acc = 0.0;
    s->load_stuck = true;
    s->stall_held_s += h;
    return;
  }
  s->load_stuck = false;
  if (!(fabs(ls->l_nm) > 0.0)) return; /* no load: nothing to stop the rotor */
  /* the direction of motion over the step: that of the speed, or of the breakaway */
  const double dir = ls->w0 != 0.0 ? ls->w0 : ls->tl;
  if (s->w * dir < 0.0) {
    s->w = 0.0;
    s->acc = (s->te - ims_load_torque(s, ls->l_nm)) / c->j_kgm2;
    s->load_stuck = fabs(s->te) <= fabs(ls->l_nm);
    if (ls->w0 != 0.0) stall_event(s, t_end, ls->l_nm);
  }
}

void imsim_set_load(imsim_t *s, double load_nm)
{
  s->load_override = load_nm;
  s->load_overridden = true;
}

void imsim_get_stall(const imsim_t *s, imsim_stall_t *out)
{
  const bool any = s->stall_events > 0u;
  out->events = s->stall_events;
  out->first_t_s = any ? s->stall_first_t_s : NAN_D;
  out->first_load_nm = any ? s->stall_first_load_nm : NAN_D;
  out->first_torque_nm = any ? s->stall_first_torque_nm : NAN_D;
  out->held_s = s->stall_held_s;
  out->at_rest_now = s->c.load_kind == IMSIM_LOAD_PASSIVE && s->w == 0.0 && s->load_stuck;
}
