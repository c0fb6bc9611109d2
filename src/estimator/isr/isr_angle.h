/* SPDX-License-Identifier: Apache-2.0 */
/* ISR stage: the encoder angle through a tracking observer (an alpha-beta-
 * gamma tracker, a type-3 loop). A quantised encoder gives the rotation and
 * the speed a sawtooth error whose beat with the sample rate can fall inside
 * the front end's band (docs/METHOD.md §8.9); the observer passes what the
 * rotor can do and attenuates faster errors. A type-3 loop has no lag at
 * constant speed or constant acceleration, so a run-up only sees the change
 * of acceleration. The observer keeps its tracking error d = th_hat -
 * th_encoder instead of th_hat, so no wrap is needed: the step between two
 * encoder angles is wrapped already.
 *
 * Any causal smoother distorts a fast change of acceleration (a direct-on-line
 * start: measured, the run-up window becomes poorly determined), so the
 * observer is engaged only while the rotor turns at a steady speed: the ISR
 * engages it after a window whose mean speed did not change and disengages
 * it after one whose speed did (isr_engage_observer, isr_sample.c). A rotor
 * can also swing inside the observer's band at a steady mean speed (a V/f
 * drive's hunting); with the encoder's counts given, a correction beyond one
 * count shows that (below), docs/METHOD.md §13.1. */
#ifndef IMEST_ISR_ANGLE_H
#define IMEST_ISR_ANGLE_H

#include "common/imest_math.h"

static inline void isr_angle_reset(imest_angle_t *o, imest_real_t dth)
{
  o->d = RL(0);
  o->dth = dth;
  o->ddth = RL(0);
}

/* One sample: dth_enc = the encoder's wrapped step since the previous sample.
 * The tracker always runs (so it has converged when it is engaged); engaged,
 * the rotation and the speed take its estimate, disengaged the encoder's.
 * Returns the correction to add to the encoder angle and the step to use
 * (the speed times T) in *step. */
static inline imest_real_t isr_angle_update(imest_angle_t *o, imest_real_t dth_enc, imest_real_t *step)
{
  const imest_real_t e = (dth_enc - o->d) - (o->dth + RL(0.5) * o->ddth); /* encoder - prediction */
  o->dth = (o->dth + o->ddth) + o->k2 * e;
  o->ddth += o->k3 * e;
  o->d = (o->k1 - RL(1)) * e;
  /* The true angle lies within one count (d_max) of the encoder's, whichever
   * way it rounds: a larger correction is the tracker's lag on a real motion
   * (a V/f drive's hunting), not quantisation. From then on until the window
   * ends, and for the next window (isr_engage_observer), the encoder's angle
   * and speed are used: a lag the tracker shows in its angle it has in its
   * speed too. The switch moves the angle by about one count. */
  o->state |= (uint32_t)(imest__abs(o->d) > o->d_max); /* IMEST_ANG_OVER */
  const int on = (o->state & (IMEST_ANG_ENGAGED | IMEST_ANG_OVER)) == IMEST_ANG_ENGAGED;
  *step = on ? o->dth : dth_enc;
  return on ? o->d : RL(0);
}

#endif
