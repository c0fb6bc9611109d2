/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 5b, sigma*L_S at slip frequency: after the square wave, at the same DC
 * current, the current loop follows two tones, f1 = CM_SLIP_X / (2 pi T_R) and 2 f1, each of
 * CM_SLIP_AMP x the DC current, so no phase current changes sign (the inverter's error stays a
 * constant plus a resistance). A square wave at fs/8 sees a deep-bar rotor's outer-cage leakage;
 * these tones see the rotor near the frequencies the estimator works at (imest_commission.h,
 * "What is measured", says why f1). Each tone starts at the phase arg(1 + j w T_R), where the
 * steady state's magnetising current equals the DC one the rotor holds, so the rotor flux has
 * no transient to settle (only what T_R's error leaves). After CM_SLIP_SETTLE T_R, the ISR
 * demodulates the current and the voltage applied over each period at both tones, one block per
 * period of f1 (whole periods of both); the background takes the impedances
 * (imest__cm_fit_axis). The phasors turn by a fixed rotation per sample, renormalised to unit
 * length each time (float32 drifts 1e-3 over 2e4 samples otherwise). ISR, float32. */
#include "commission_internal.h"

_Static_assert(CM_PLATEAUS * CM_BLK_PLATEAU + CM_HF_BLOCKS + CM_SLIP_BLOCKS <= IMEST_COMM_NBLK,
               "an axis's blocks fit the buffer");
_Static_assert(2 * CM_L_TONE <= IMEST_COMM_NSUM, "two tones' sums fit a block");

/* Both tones stay below half the current loop's crossover (fs/40): f1 <= fs/160. */
#define CM_SLIP_MIN_PERIOD 160.0f

void imest__cm_slip_begin(imest_comm_t *c)
{
  c->stage = IMEST_COMM_STAGE_SLIP;
  c->cnt = 0u;
  c->block = 0u;
  c->step = 0u;
  const float fs = c->cfg.fs_hz, tau = c->tau;
  float n = IMEST_2PI_F * tau * fs / CM_SLIP_X + 0.5f;
  if (n < CM_SLIP_MIN_PERIOD) n = CM_SLIP_MIN_PERIOD;
  c->n_slip = (uint32_t)n;
  c->n_slip_settle = (uint32_t)(CM_SLIP_SETTLE * tau * fs + 0.5f);
  /* the step of f1 per sample: whole periods in n_slip samples */
  const float th = IMEST_2PI_F / (float)c->n_slip;
  c->sl_w = th * fs;
  c->sl_bias = c->i_ref;
  c->sl_amp = CM_SLIP_AMP * c->i_ref;
  c->sl_u0 = c->integ[CM_PAT_CENTRED];
  for (uint32_t t = 0u; t < 2u; ++t) {
    /* e^{j a} by its series (a <= 4 pi / 160: the next terms are below float32's step) */
    const float a = th * (float)(t + 1u), a2 = a * a;
    c->sl_cw[t] = 1.0f - 0.5f * a2 * (1.0f - a2 / 12.0f);
    c->sl_sw[t] = a * (1.0f - a2 / 6.0f * (1.0f - a2 / 20.0f));
    const float x = c->sl_w * (float)(t + 1u) * tau, h = 1.0f / imest__sqrt(1.0f + x * x);
    c->sl_c[t] = h; /* e^{j arg(1 + j x)} */
    c->sl_s[t] = x * h;
  }
}

void imest__cm_stage_slip(imest_comm_t *c, float vdc, float i_n, float v_n)
{
  c->i_mag += (i_n - c->i_mag) * c->ts_s / c->tau;
  if (c->step == 1u) { /* the current at t_k, the voltage over [t_k, t_k+1), the phase at t_k */
    const float di = i_n - c->sl_bias, dv = v_n - c->sl_u0;
    float *s = c->cur.s;
    c->cur.n++;
    for (uint32_t t = 0u; t < 2u; ++t) {
      float *st = s + t * (uint32_t)CM_L_TONE;
      st[CM_L_IC] += di * c->sl_c[t];
      st[CM_L_IS] += di * c->sl_s[t];
      st[CM_L_VC] += dv * c->sl_c[t];
      st[CM_L_VS] += dv * c->sl_s[t];
    }
  }
  const float ref = c->sl_bias + c->sl_amp * (c->sl_s[0] + c->sl_s[1]);
  for (uint32_t t = 0u; t < 2u; ++t) {
    const float cn = c->sl_c[t] * c->sl_cw[t] - c->sl_s[t] * c->sl_sw[t];
    const float sn = c->sl_s[t] * c->sl_cw[t] + c->sl_c[t] * c->sl_sw[t];
    const float g = 1.5f - 0.5f * (cn * cn + sn * sn); /* one Newton step towards |e^{j.}| = 1 */
    c->sl_c[t] = cn * g;
    c->sl_s[t] = sn * g;
  }
  if (imest__cm_current_loop(c, CM_PAT_CENTRED, ref - i_n, vdc) != 0) return;
  c->cnt++;
  if (c->step == 0u) {
    if (c->cnt >= c->n_slip_settle) {
      c->step = 1u;
      c->cnt = 0u;
      imest__cm_block_start(c, CM_TAG(CM_KIND_SLIP, 0u, 0u));
    }
    return;
  }
  if (c->cnt < c->n_slip) return;
  imest__cm_block_flush(c);
  c->cnt = 0u;
  if (++c->block < CM_SLIP_BLOCKS) {
    imest__cm_block_start(c, CM_TAG(CM_KIND_SLIP, 0u, 0u));
    return;
  }
  imest__cm_post(c, CM_JOB_AXIS | (c->axis << 4), c->nblk);
  c->stage = IMEST_COMM_STAGE_DEMAGNETISE;
  c->step = 0u;
  c->cnt = 0u;
  c->cnt_demag = 0u;
  c->i_ref = 0.0f;
}
