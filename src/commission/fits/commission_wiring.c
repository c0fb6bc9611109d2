/* SPDX-License-Identifier: Apache-2.0 */
/* Commissioning stage 2, wiring: a bipolar voltage pulse along each axis (+V then -V for the
 * same time, so the current returns to zero and the rotor flux stays ~0), doubled from 4 % of
 * the bus until the current responds. The current vector at the end of the +V half (its peak)
 * says which channel reads which leg, with which sign, and whether a phase is open; its size
 * gives a rough sigma*L_S for the current controller (high by the dead time's loss near zero
 * current, which only lowers the loop's phase margin a little).
 * ISR part float32; the analysis (imest__cm_fit_wiring) runs in the background, also float32:
 * it scores 48 assignments by sums of nine products with the measured float32 currents
 * (rounding 1e-7 of a score; the scores of different assignments differ by a share of the
 * response's size) and takes a median of three. */
#include <math.h>
#include <stddef.h>

#include "commission_internal.h"

enum { W_POS = 0u, W_NEG = 1u, W_REST = 2u, W_WAIT = 3u };

static uint32_t pulse_len(const imest_comm_t *c)
{
  const uint32_t n = (uint32_t)(1.0e-3f * c->cfg.fs_hz + 0.5f);
  return n < 4u ? 4u : n;
}

// A per-sample stage as one switch over its steps: the ISR path, its instruction count budgeted.
// NOLINTNEXTLINE(readability-function-cognitive-complexity)
void imest__cm_stage_wiring(imest_comm_t *c, const float m[3], float vdc)
{
  float u = 0.0f;
  c->cnt++;
  const float i_big = 0.5f * c->cfg.i_max_a;
  switch (c->step) {
  case W_POS:
    u = c->pulse_v;
    if (imest__abs(m[0]) > i_big || imest__abs(m[1]) > i_big || imest__abs(m[2]) > i_big ||
        c->cnt >= pulse_len(c)) {
      c->pulse_n = c->cnt;
      c->step = W_NEG;
      c->cnt = 0u;
    }
    break;
  case W_NEG:
    u = -c->pulse_v;
    if (c->cnt == 2u) /* the + half's last period has just been applied: the peak */
      for (int x = 0; x < 3; ++x) c->pulse_resp[c->axis][x] = m[x];
    if (c->cnt >= c->pulse_n) {
      c->step = W_REST;
      c->cnt = 0u;
    }
    break;
  case W_REST: {
    const float i_small = 0.02f * c->cfg.i_max_a;
    const int quiet = imest__abs(m[0]) < i_small && imest__abs(m[1]) < i_small && imest__abs(m[2]) < i_small;
    if (!((quiet && c->cnt >= 2u * c->pulse_n) || c->cnt > 50u * pulse_len(c))) break;
    const float *r = c->pulse_resp[c->axis];
    const uint32_t a = c->axis;
    const float resp = cm_axis_component(r, a);
    const float rmax = imest__abs(r[0]) + imest__abs(r[1]) + imest__abs(r[2]);
    if (rmax < 0.1f * c->cfg.i_max_a && c->pulse_v < 0.5f * c->v_lim && c->pulse_tries < 8u) {
      c->pulse_v *= 2.0f; /* too weak: twice the voltage, same axis */
      c->pulse_tries++;
    } else {
      c->pulse_vk[a] = c->pulse_v;
      c->pulse_nk[a] = c->pulse_n;
      c->pulse_ik[a] = resp;
      c->axis++;
    }
    c->step = W_POS;
    c->cnt = 0u;
    if (c->axis >= 3u) {
      c->axis = 0u;
      c->step = W_WAIT;
      c->wait = 0u;
      imest__cm_post(c, CM_JOB_WIRING, 0u);
    }
    break;
  }
  case W_WAIT:
  default:
    if (!imest__cm_job_done(c)) {
      if (++c->wait > (uint32_t)(10.0f * c->cfg.fs_hz)) imest__cm_fail(c, IMEST_COMM_REASON_BACKGROUND);
      break;
    }
    if (c->bg_fail) {
      imest__cm_fail(c, c->bg_fail);
      break;
    }
    imest__cm_set_gains(c, c->bg_sl);
    imest__cm_probe_begin(c);
    break;
  }
  imest__cm_command(c, CM_PAT_CENTRED, u, vdc);
}

static const unsigned int k_perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};

/* The response channel ch should show to a pulse on axis k under assignment (perm p, signs
   sgn): +-1 on the channel reading leg k, -+1/2 on the others. */
static float expected(int p, int sgn, int k, int ch)
{
  return (k_perms[p][ch] == (unsigned int)k ? 1.0f : -0.5f) * ((sgn >> ch) & 1 ? -1.0f : 1.0f);
}

/* Sum of |response| over the channels for a pulse on axis k. */
static float response_abs(const imest_comm_t *c, int k)
{
  float a = 0.0f;
  for (int x = 0; x < 3; ++x) a += imest__abs(c->pulse_resp[k][x]);
  return a;
}

/* The assignment whose expected response correlates best with the measured one. */
static void best_assignment(const imest_comm_t *c, int *best_p, int *best_s)
{
  float best = -1.0f;
  *best_p = 0;
  *best_s = 0;
  for (int p = 0; p < 6; ++p)
    for (int sgn = 0; sgn < 8; ++sgn) {
      float dot = 0.0f;
      for (int k = 0; k < 3; ++k)
        for (int ch = 0; ch < 3; ++ch) dot += expected(p, sgn, k, ch) * c->pulse_resp[k][ch];
      if (dot > best) {
        best = dot;
        *best_p = p;
        *best_s = sgn;
      }
    }
}

/* residual of the assignment with one amplitude per axis (sum of squares) */
static float assignment_residual(const imest_comm_t *c, int p, int sgn)
{
  float res2 = 0.0f;
  for (int k = 0; k < 3; ++k) {
    float num = 0.0f;
    for (int ch = 0; ch < 3; ++ch) num += expected(p, sgn, k, ch) * c->pulse_resp[k][ch];
    const float amp = num / 1.5f; /* |e|^2 = 1.5 */
    for (int ch = 0; ch < 3; ++ch) {
      const float r = c->pulse_resp[k][ch] - amp * expected(p, sgn, k, ch);
      res2 += r * r;
    }
  }
  return res2;
}

/* rough sigma*L_S: volt-seconds of the + half over the current it drove, median of three */
static float rough_sigma_ls(const imest_comm_t *c)
{
  float sl[3];
  for (int k = 0; k < 3; ++k) {
    const float di = imest__abs(c->pulse_ik[k]);
    sl[k] = di > 0.0f ? c->pulse_vk[k] * (float)c->pulse_nk[k] * c->ts_s / di : 0.0f;
  }
  float med = sl[0];
  if ((sl[1] - sl[0]) * (sl[1] - sl[2]) <= 0.0f) med = sl[1];
  if ((sl[2] - sl[0]) * (sl[2] - sl[1]) <= 0.0f) med = sl[2];
  return med;
}

/* an axis that draws (almost) nothing (below a tenth of the largest): a leg or phase is open */
static int axis_open(const imest_comm_t *c)
{
  float amax = 0.0f;
  for (int k = 0; k < 3; ++k) {
    const float a = response_abs(c, k);
    if (a > amax) amax = a;
  }
  int open = 0;
  for (int k = 0; k < 3; ++k)
    if (!(response_abs(c, k) > 0.1f * amax) || !(amax > 0.0f)) open = 1;
  return open;
}

/* Background: which channel reads which leg. The true response of a pulse on axis k is
   c_k (1 on leg k, -1/2 on the others); channel ch reads sign_ch x leg perm(ch). Every one of the
   6 x 8 assignments is scored by its correlation with the measured 3 x 3 response; the best must
   explain it (relative residual < 0.25) and be the identity with positive signs. */
void imest__cm_fit_wiring(imest_comm_t *c)
{
  float norm2 = 0.0f;
  for (int k = 0; k < 3; ++k)
    for (int x = 0; x < 3; ++x) norm2 += c->pulse_resp[k][x] * c->pulse_resp[k][x];
  c->bg_fail = axis_open(c) ? IMEST_COMM_REASON_OPEN_PHASE : 0;
  int best_p, best_s;
  best_assignment(c, &best_p, &best_s);
  const float res2 = assignment_residual(c, best_p, best_s);
  for (int ch = 0; ch < 3; ++ch) {
    /* wiring_map[leg] = (channel + 1) * sign */
    const unsigned int leg = k_perms[best_p][ch];
    c->res.wiring_map[leg] = (ch + 1) * ((best_s >> ch) & 1 ? -1 : 1);
  }
  if (c->bg_fail == 0 && (best_p != 0 || best_s != 0)) c->bg_fail = IMEST_COMM_REASON_WIRING;
  if (c->bg_fail == 0 && !(res2 < 0.0625f * norm2)) c->bg_fail = IMEST_COMM_REASON_OPEN_PHASE;
  const float med = rough_sigma_ls(c);
  if (c->bg_fail == 0 && !(med > 0.0f && med < 10.0f)) c->bg_fail = IMEST_COMM_REASON_IMPLAUSIBLE;
  c->bg_sl = med;
}
