/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 5b, sigma*L_S at slip frequency: after the square wave, at the same DC
 * current, the current loop follows two tones, f1 = CM_SLIP_X / (2 pi T_R) and CM_SLIP_M f1,
 * each of CM_SLIP_AMP x the DC current, so no phase current changes sign (the inverter's error
 * stays a constant plus a resistance). A square wave at fs/8 sees a deep-bar rotor's outer-cage
 * leakage; these tones see the rotor near the frequencies the estimator works at
 * (imest_commission.h, "What is measured", says why f1 and why the upper tone is an odd
 * multiple of it). Each tone starts at the phase arg(1 + j w T_R), where the steady state's
 * magnetising current equals the DC one the rotor holds, so the rotor flux has no transient to
 * settle (only what T_R's error leaves). After CM_SLIP_SETTLE T_R, the ISR demodulates the
 * current and the voltage applied over each period at both tones over CM_SLIP_PERIODS whole
 * periods of f1, into the axis's own block (CM_SLIP_BLK + axis); the standstill fit takes the
 * impedances (imest__cm_fit_standstill). The phasors turn by a fixed rotation per sample; their
 * length drifts by float32's rounding of that rotation (1e-3 over 5e4 samples), which the
 * voltage and the current share, so their ratio, the impedance, does not see it. ISR, float32. */
#include "commission_internal.h"

_Static_assert(CM_PLATEAUS *CM_BLK_PLATEAU + CM_HF_BLOCKS <= CM_SLIP_BLK,
               "an axis's blocks leave the slip-frequency sums alone");
_Static_assert(2 * CM_L_TONE <= IMEST_COMM_NSUM, "two tones' sums fit a block");

/* Both tones stay below half the current loop's crossover (fs/40): CM_SLIP_M f1 <= fs/80. */
#define CM_SLIP_MIN_PERIOD (80.0f * (float)CM_SLIP_M)

void imest__cm_slip_begin(imest_comm_t *c)
{
  c->stage = IMEST_COMM_STAGE_SLIP;
  c->cnt = 0u;
  c->step = 0u;
  const float fs = c->cfg.fs_hz, tau = c->tau;
  float n = IMEST_2PI_F * tau * fs / CM_SLIP_X + 0.5f;
  if (n < CM_SLIP_MIN_PERIOD) n = CM_SLIP_MIN_PERIOD;
  const float period = (float)(uint32_t)n; /* whole samples: whole periods in the block */
  c->n_slip = (uint32_t)period * CM_SLIP_PERIODS;
  c->n_slip_settle = (uint32_t)(CM_SLIP_SETTLE * tau * fs + 0.5f);
  const float th = IMEST_2PI_F / period; /* f1's step per sample */
  c->sl_w = th * fs;
  c->sl_bias = c->i_ref;
  c->sl_amp = CM_SLIP_AMP * c->i_ref;
  c->sl_u0 = c->integ[CM_PAT_CENTRED];
  for (uint32_t t = 0u; t < 2u; ++t) {
    /* e^{j a} by its series (a <= 2 pi / 80: the next terms are below float32's step) */
    const float a = th * (float)CM_SLIP_HARM(t), a2 = a * a;
    c->sl_cw[t] = 1.0f - 0.5f * a2 * (1.0f - a2 / 12.0f);
    c->sl_sw[t] = a * (1.0f - a2 / 6.0f * (1.0f - a2 / 20.0f));
    const float x = c->sl_w * (float)CM_SLIP_HARM(t) * tau, h = 1.0f / imest__sqrt(1.0f + x * x);
    c->sl_c[t] = h; /* e^{j arg(1 + j x)} */
    c->sl_s[t] = x * h;
  }
}

void imest__cm_stage_slip(imest_comm_t *c, float vdc, float i_n, float v_n)
{
  c->i_mag += (i_n - c->i_mag) * c->ts_s / c->tau;
  /* the current at t_k, the voltage over [t_k, t_k+1), the phase at t_k (summed while settling
     too: the measurement clears the sums when it starts) */
  const float di = i_n - c->sl_bias, dv = v_n - c->sl_u0;
  float ref = c->sl_bias;
  imest_comm_block_t *b = &c->blk[CM_SLIP_BLK + c->axis];
  for (uint32_t t = 0u; t < 2u; ++t) {
    float *st = b->s + (size_t)t * (size_t)CM_L_TONE;
    const float cs = c->sl_c[t], sn = c->sl_s[t];
    st[CM_L_IC] += di * cs;
    st[CM_L_IS] += di * sn;
    st[CM_L_VC] += dv * cs;
    st[CM_L_VS] += dv * sn;
    ref += c->sl_amp * sn;
    c->sl_c[t] = cs * c->sl_cw[t] - sn * c->sl_sw[t];
    c->sl_s[t] = sn * c->sl_cw[t] + cs * c->sl_sw[t];
  }
  b->n++;
  if (imest__cm_current_loop(c, CM_PAT_CENTRED, ref - i_n, vdc) != 0) return;
  c->cnt++;
  if (c->step == 0u) {
    if (c->cnt >= c->n_slip_settle) {
      c->step = 1u;
      c->cnt = 0u;
      b->n = 0u;
      imest__zero_f32(b->s, IMEST_COMM_NSUM);
    }
    return;
  }
  if (c->cnt < c->n_slip) return;
  imest__cm_post(c, CM_JOB_AXIS | (c->axis << 4), c->nblk);
  c->stage = IMEST_COMM_STAGE_DEMAGNETISE;
  c->step = 0u;
  c->cnt = 0u;
  c->cnt_demag = 0u;
  c->i_ref = 0.0f;
}
