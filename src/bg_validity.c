/* Background stage: is this window's estimate trustworthy? The first reason
 * found, most fundamental first, becomes the status; a window is valid only
 * if none applies. Thresholds are config fields (README: "When is a window
 * valid" gives the measurements behind the defaults). */
#include <math.h>

#include "bg_validity.h"

static int first_flag_reason(unsigned int flags, uint32_t used, uint32_t samples)
{
  if (flags & IMEST_FLAG_INPUT_FAULT) return IMEST_REASON_INPUT_FAULT;
  if (flags & IMEST_FLAG_ADC_SAT) return IMEST_REASON_ADC_SATURATION;
  if (flags & IMEST_FLAG_ENCODER_FAULT) return IMEST_REASON_ENCODER_FAULT;
  /* warm-up samples are not accumulated; the rest of the window is clean
   * data, so warm-up invalidates a window only when it took half of it */
  if ((flags & IMEST_FLAG_WARMUP) && 2u * used < samples) return IMEST_REASON_WARMUP;
  return IMEST_REASON_NONE;
}

void bg_judge(const imest_t *s, const bg_window_stats_t *st, const bg_solve_out_t *so, imest_result_t *r)
{
  int status = first_flag_reason(r->flags, r->used_samples, r->samples);

  /* Excitation: the mean rotation rate of the rotor-frame current vector
   * (sum of i x di/dt over sum of |i|^2) times the nominal T_R. In steady
   * state it is slip frequency x T_R, the ratio of rotor to magnetising
   * current; noise averages out of it (0.004..0.008 at no load with 12-bit
   * sensors, 0.05 at 5 % load, 1.1 at rated load). Below 0.1 T_R is weakly
   * observable: a small systematic error (an uncompensated voltage lag)
   * moved it by 20 % in the validity study without raising the PE index.
   * The nominal T_R, not the estimate, so that a wrong estimate cannot make
   * the window look excited. */
  r->slip_ratio = fabs(st->slip_rate) * (double)s->tr_nominal_s;
  r->i_rms_a = st->i_rms_a;

  if (status == IMEST_REASON_NONE && !(st->i_rms_a >= (double)s->min_current_a)) {
    /* i_rms_a is what passed the offset high-pass. A DC current it removed
     * (magnetising at rest) is in the tracked means: that rotor is at rest
     * with excitation, not without current. */
    const double ia = (double)s->off_ia, ib = (double)s->off_ib;
    const int dc = sqrt(ia * ia + ib * ib) >= (double)s->min_current_a;
    status = (dc && fabs(st->w_mean) < 1.0) ? IMEST_REASON_STANDSTILL : IMEST_REASON_NO_CURRENT;
  }
  if (status == IMEST_REASON_NONE && !(r->slip_ratio >= (double)s->min_slip_ratio)) {
    /* about 10 rpm: an encoder toggling by a count averages to zero here */
    status = (fabs(st->w_mean) < 1.0) ? IMEST_REASON_STANDSTILL : IMEST_REASON_ZERO_SLIP;
  }
  if (status == IMEST_REASON_NONE && so->status != IMEST_OK) status = so->status; /* NUMERIC or NO_ROOT */
  if (status == IMEST_REASON_NONE && !so->hessian_pd) status = IMEST_REASON_NOT_MINIMUM;
  if (status == IMEST_REASON_NONE && !(r->pe_k2_rel <= (double)s->max_pe_k2_rel))
    status = IMEST_REASON_POORLY_DETERMINED;
  if (status == IMEST_REASON_NONE && !(r->e_i <= (double)s->max_ei)) status = IMEST_REASON_HIGH_RESIDUAL;
  if (status == IMEST_REASON_NONE &&
      !(r->rs_ohm >= (double)s->rs_min_ohm && r->rs_ohm <= (double)s->rs_max_ohm))
    status = IMEST_REASON_RS_OUT_OF_RANGE;
  /* never a confident non-finite number */
  if (status == IMEST_REASON_NONE && !(isfinite(r->tr_s) && isfinite(r->rs_ohm) && isfinite(r->e_i)))
    status = IMEST_REASON_NUMERIC;

  /* One verdict for both parameters until the per-parameter evidence (voltage
   * error, timing, gain mismatch) bounds R_S separately. */
  r->status = status;
  r->valid = (status == IMEST_REASON_NONE);
  r->tr_reason = status;
  r->tr_valid = r->valid;
  r->rs_reason = status;
  r->rs_valid = r->valid;
}
