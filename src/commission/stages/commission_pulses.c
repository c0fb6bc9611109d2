/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 5, sigma*L_S: at the staircase's last plateau (1/3 of the top level) a
 * square-wave voltage of period 8 samples is added along the axis, with the current loop held
 * (its voltage frozen: the plant is passive, the DC current drifts only by the small remaining
 * flux tail). The DC bias keeps every phase current away from zero, so the inverter's error
 * stays on one branch. Per period the background regresses the current step on the voltage
 * applied during it, the mean current and a constant (imest__cm_fit_axis): di = T/(sigma L_S)
 * (v - R i - c). The voltage is known exactly (it is what the routine commanded), the current
 * step's noise only enters at the ends of each half wave. Then the slip-frequency test at the
 * same bias (commission_slip.c). ISR, float32. */
#include "commission_internal.h"

void imest__cm_pulses_begin(imest_comm_t *c)
{
  c->stage = IMEST_COMM_STAGE_PULSES;
  c->cnt = 0u;
  c->block = 0u;
  c->step = 0u;
  /* current ripple of 30 % of the bias, peak to peak, with the present sigma*L_S */
  float v = 0.3f * c->i_ref * c->sl_rough / ((float)c->n_hf_half * c->ts_s);
  if (v > 0.3f * c->v_lim) v = 0.3f * c->v_lim;
  c->v_hf = v;
}

void imest__cm_stage_pulses(imest_comm_t *c, float vdc, float i_n, float v_ended)
{
  c->cnt++;
  c->i_mag += (i_n - c->i_mag) * c->ts_s / c->tau;
  float u = c->integ[CM_PAT_CENTRED];
  if (c->step == 0u) {
    /* back to the centred pattern at the bias, loop closed, before the loop is held */
    u = imest__cm_pi(c, CM_PAT_CENTRED, c->i_ref - i_n, 1);
    if (c->cnt >= c->n_disc_level) {
      c->step = 1u;
      c->cnt = 0u;
      imest__cm_block_start(c, CM_TAG(CM_KIND_HF, 0u, 0u));
    }
  } else {
    { /* the current step over the period that just ended, and the voltage applied during it */
      const float y = i_n - c->i_prev, x1 = v_ended, x2 = 0.5f * (i_n + c->i_prev);
      float *s = c->cur.s;
      c->cur.n++;
      s[CM_H_X11] += x1 * x1;
      s[CM_H_X12] += x1 * x2;
      s[CM_H_X1] += x1;
      s[CM_H_X22] += x2 * x2;
      s[CM_H_X2] += x2;
      s[CM_H_YX1] += y * x1;
      s[CM_H_YX2] += y * x2;
      s[CM_H_Y] += y;
      s[CM_H_YY] += y * y;
    }
    const uint32_t half = (c->cnt - 1u) / c->n_hf_half;
    u += (half & 1u) ? -c->v_hf : c->v_hf;
    if (c->cnt >= c->n_hf_blk) {
      imest__cm_block_flush(c);
      c->cnt = 0u;
      if (++c->block < CM_HF_BLOCKS) {
        imest__cm_block_start(c, CM_TAG(CM_KIND_HF, 0u, 0u));
      } else {
        /* the current loop's integrator holds the bias voltage the next stage starts from */
        imest__cm_command(c, CM_PAT_CENTRED, c->integ[CM_PAT_CENTRED], vdc);
        imest__cm_slip_begin(c);
        return;
      }
    }
  }
  imest__cm_command(c, CM_PAT_CENTRED, u, vdc);
}
