/* Background stage: is this window's estimate trustworthy? The first reason
 * found, most fundamental first, becomes the status; a window is valid only
 * if none applies. Thresholds are config fields (README: "When is a window
 * valid" gives the measurements behind the defaults). */
#include <math.h>

#include "bg_internal.h"

static int first_flag_reason(unsigned int flags)
{
  if (flags & IMEST_FLAG_INPUT_FAULT) return IMEST_ST_INPUT_FAULT;
  if (flags & IMEST_FLAG_ADC_SAT) return IMEST_ST_ADC_SATURATION;
  if (flags & IMEST_FLAG_ENCODER_FAULT) return IMEST_ST_ENCODER_FAULT;
  if (flags & IMEST_FLAG_WARMUP) return IMEST_ST_WARMUP;
  return IMEST_OK;
}

void imest_judge(const imest_t *s, const imest_window_stats_t *st, const imest_solve_out_t *so,
                 imest_result_t *r)
{
  int status = first_flag_reason(r->flags);

  /* excitation: rms rotor-frame current rate against rms current / T_R. In
   * steady state it is the slip frequency times T_R; noise alone gives about
   * 0.01 with 12-bit sensors. */
  double tr = (double)s->tr_nominal_s;
  if (so->status == IMEST_OK && isfinite(so->tr_s)) tr = so->tr_s;
  r->slip_ratio = st->i_rms_a > 0.0 ? st->di_rms / st->i_rms_a * tr : 0.0;
  r->i_rms_a = st->i_rms_a;

  if (status == IMEST_OK && !(st->i_rms_a >= (double)s->min_current_a)) status = IMEST_ST_NO_CURRENT;
  if (status == IMEST_OK && !(r->slip_ratio >= (double)s->min_slip_ratio)) {
    status = (st->w_rms < 1.0) ? IMEST_ST_STANDSTILL : IMEST_ST_ZERO_SLIP;
  }
  if (status == IMEST_OK && so->status != IMEST_OK) status = so->status;
  if (status == IMEST_OK && !so->hessian_pd) status = IMEST_ST_NOT_MINIMUM;
  if (status == IMEST_OK && !(r->pe_k2_rel <= (double)s->max_pe_k2_rel))
    status = IMEST_ST_POORLY_DETERMINED;
  if (status == IMEST_OK && !(r->e_i <= (double)s->max_ei)) status = IMEST_ST_HIGH_RESIDUAL;
  if (status == IMEST_OK &&
      !(r->rs_ohm >= (double)s->rs_min_ohm && r->rs_ohm <= (double)s->rs_max_ohm))
    status = IMEST_ST_RS_OUT_OF_RANGE;
  /* never a confident non-finite number */
  if (status == IMEST_OK && !(isfinite(r->tr_s) && isfinite(r->rs_ohm) && isfinite(r->e_i)))
    status = IMEST_ST_NUMERIC;

  r->status = status;
  r->valid = (status == IMEST_OK);
}
