/* Configuration defaults and checks, filter design, instance initialisation.
 * Runs once, outside the ISR: float64 and <math.h> are fine here. */
#include <math.h>
#include <stddef.h>

#include "bg_window.h"

#define IMEST_PI_D    3.14159265358979323846
#define IMEST_SQRT2_D 1.41421356237309504880

void imest_config_default(imest_config_t *cfg)
{
  if (cfg == NULL) return;
  cfg->pole_pairs = 0; /* motor constants: the caller must set them */
  cfg->ls_h = 0.0f;
  cfg->sigma = 0.0f;
  cfg->fs_hz = 4000.0f;
  cfg->window_s = 1.0f;
  cfg->filter_hz = 100.0f;
  cfg->aa_hz = 0.0f;
  cfg->u_delay_s = 0.0f;
  cfg->dc_block_hz = 1.0f;
  cfg->warmup_s = 0.0f;
  cfg->start_at_rest = 0;
  cfg->tr_nominal_s = 0.1f;
  cfg->tr_min_s = 1.0e-3f;
  cfg->tr_max_s = 10.0f;
  cfg->rs_min_ohm = 0.0f;
  cfg->rs_max_ohm = 1.0e3f;
  cfg->max_pe_k2_rel = 0.1f;
  cfg->max_ei = 3.0f;
  cfg->min_current_a = 0.05f;
  cfg->min_slip_ratio = 0.1f;
  cfg->i_limit_a = 0.0f;
  cfg->u_limit_v = 0.0f;
  cfg->i_absurd_a = 1.0e4f;
  cfg->u_absurd_v = 1.0e5f;
  cfg->speed_limit_rad_s = 3000.0f;
  cfg->pwm_hz = 0.0f;
  cfg->pwm_timing = IMEST_PWM_NEXT_PERIOD;
  cfg->inverter.dead_time_s = 0.0f;
  cfg->inverter.v_switch_v = 0.0f;
  cfg->inverter.r_switch_ohm = 0.0f;
  cfg->inverter.v_diode_v = 0.0f;
  cfg->inverter.r_diode_ohm = 0.0f;
  cfg->inverter.i_band_a = 0.0f;
  cfg->inverter.uncertainty = -1.0f; /* unknown until the user (or commissioning) says */
  cfg->rs_tolerance = 0.05f;
  cfg->u_uncertainty_v = 0.0f;
  cfg->timing_uncertainty_s = 2.0e-6f;
  cfg->rs_nominal_ohm = 0.0f;
}

static int finite_pos(float x)
{
  return isfinite(x) && x > 0.0f;
}

int imest_config_check(const imest_config_t *cfg, const char **field)
{
  const char *bad = NULL;
  if (cfg == NULL) {
    if (field) *field = "cfg";
    return IMEST_ERR_NULL;
  }
  const double fs = (double)cfg->fs_hz;
  if (cfg->pole_pairs < 1u || cfg->pole_pairs > 64u)
    bad = "pole_pairs";
  else if (!finite_pos(cfg->ls_h))
    bad = "ls_h";
  else if (!(cfg->sigma > 0.0f && cfg->sigma < 1.0f))
    bad = "sigma";
  else if (!finite_pos(cfg->fs_hz) || cfg->fs_hz > 1.0e6f)
    bad = "fs_hz";
  else if (!finite_pos(cfg->window_s) || (double)cfg->window_s * fs < 64.0 ||
           (double)cfg->window_s * fs > 4.0e8)
    bad = "window_s";
  else if (!finite_pos(cfg->filter_hz) || (double)cfg->filter_hz >= 0.4 * fs)
    bad = "filter_hz";
  else if (!(cfg->aa_hz == 0.0f || (finite_pos(cfg->aa_hz) && (double)cfg->aa_hz < 0.45 * fs)))
    bad = "aa_hz";
  else if (!(isfinite(cfg->u_delay_s) && cfg->u_delay_s >= 0.0f && (double)cfg->u_delay_s * fs <= 1.0 + 1e-6))
    bad = "u_delay_s";
  else if (!(isfinite(cfg->dc_block_hz) && cfg->dc_block_hz >= 0.0f && (double)cfg->dc_block_hz < 0.01 * fs))
    bad = "dc_block_hz";
  else if (!(isfinite(cfg->warmup_s) && cfg->warmup_s >= 0.0f && cfg->warmup_s <= cfg->window_s * 100.0f))
    bad = "warmup_s";
  else if (!finite_pos(cfg->tr_nominal_s))
    bad = "tr_nominal_s";
  else if (!finite_pos(cfg->tr_min_s))
    bad = "tr_min_s";
  else if (!(finite_pos(cfg->tr_max_s) && cfg->tr_max_s > cfg->tr_min_s))
    bad = "tr_max_s";
  else if (!(isfinite(cfg->rs_min_ohm) && cfg->rs_min_ohm >= 0.0f))
    bad = "rs_min_ohm";
  else if (!(isfinite(cfg->rs_max_ohm) && cfg->rs_max_ohm > cfg->rs_min_ohm))
    bad = "rs_max_ohm";
  else if (!finite_pos(cfg->max_pe_k2_rel))
    bad = "max_pe_k2_rel";
  else if (!finite_pos(cfg->max_ei))
    bad = "max_ei";
  else if (!(isfinite(cfg->min_current_a) && cfg->min_current_a >= 0.0f))
    bad = "min_current_a";
  else if (!(isfinite(cfg->min_slip_ratio) && cfg->min_slip_ratio >= 0.0f))
    bad = "min_slip_ratio";
  else if (!(isfinite(cfg->i_limit_a) && cfg->i_limit_a >= 0.0f))
    bad = "i_limit_a";
  else if (!(isfinite(cfg->u_limit_v) && cfg->u_limit_v >= 0.0f))
    bad = "u_limit_v";
  else if (!finite_pos(cfg->i_absurd_a))
    bad = "i_absurd_a";
  else if (!finite_pos(cfg->u_absurd_v))
    bad = "u_absurd_v";
  else if (!finite_pos(cfg->speed_limit_rad_s) || (double)cfg->speed_limit_rad_s >= 3.0 * fs)
    bad = "speed_limit_rad_s";
  if (field) *field = bad;
  return bad ? IMEST_ERR_CONFIG : IMEST_OK;
}

/* tan(x) for 0 < x < 1.3 by its sin and cos series (fixed 14 terms, relative
 * error < 1e-15): libm's tan() alone would cost ~4.5 KB of flash on a
 * Cortex-M4 (argument reduction tables). */
static double tan_small(double x)
{
  const double x2 = x * x;
  double s = x, c = 1.0, ts = x, tc = 1.0;
  for (int k = 1; k <= 14; ++k) {
    ts *= -x2 / (double)((2 * k) * (2 * k + 1));
    tc *= -x2 / (double)((2 * k - 1) * (2 * k));
    s += ts;
    c += tc;
  }
  return s / c;
}

/* Butterworth-3 by the bilinear transform prewarped at fc: a first-order
 * section (s + 1) and a second-order section (s^2 + s + 1). */
static void design_bw3(imest_bw3_t *f, double fc, double fs)
{
  const double k = tan_small(IMEST_PI_D * fc / fs);
  const double g1 = k / (1.0 + k);
  f->b0 = (imest_real_t)g1;
  f->a1 = (imest_real_t)((k - 1.0) / (1.0 + k));
  const double a0 = 1.0 + k + k * k;
  const double g2 = k * k / a0;
  f->c0 = (imest_real_t)g2;
  f->d1 = (imest_real_t)(2.0 * (k * k - 1.0) / a0);
  f->d2 = (imest_real_t)((1.0 - k + k * k) / a0);
}

/* 2nd-order Butterworth (Q = 1/sqrt 2) anti-alias model; fc = 0: identity. */
static void design_aa(imest_sos_t *f, double fc, double fs)
{
  if (fc <= 0.0) {
    f->c0 = 1;
    f->d1 = 0;
    f->d2 = 0;
    return;
  }
  const double k = tan_small(IMEST_PI_D * fc / fs);
  const double a0 = 1.0 + IMEST_SQRT2_D * k + k * k;
  const double g = k * k / a0;
  f->c0 = (imest_real_t)g;
  f->d1 = (imest_real_t)(2.0 * (k * k - 1.0) / a0);
  f->d2 = (imest_real_t)((1.0 - IMEST_SQRT2_D * k + k * k) / a0);
}

int imest_init(imest_t *s, const imest_config_t *cfg)
{
  if (s == NULL || cfg == NULL) return IMEST_ERR_NULL;
  const int rc = imest_config_check(cfg, NULL);
  if (rc != IMEST_OK) return rc;

  /* no memset: the core does not depend on <string.h> */
  unsigned char *raw = (unsigned char *)s;
  for (size_t b = 0; b < sizeof *s; ++b) raw[b] = 0u;

  const double fs = (double)cfg->fs_hz;
  const double sigma = (double)cfg->sigma, ls = (double)cfg->ls_h;
  const double m = (1.0 - sigma) / sigma;
  s->fs = (imest_real_t)fs;
  s->inv2t = (imest_real_t)(0.5 * fs);
  s->invt2 = (imest_real_t)(fs * fs);
  s->n = (imest_real_t)cfg->pole_pairs;
  s->m = (imest_real_t)m;
  s->inv_s = (imest_real_t)(1.0 / (sigma * ls));
  /* no ADC limit configured: the absurd-value limit takes its place */
  s->i_lim = (imest_real_t)(cfg->i_limit_a > 0.0f ? cfg->i_limit_a : cfg->i_absurd_a);
  s->u_lim = (imest_real_t)(cfg->u_limit_v > 0.0f ? cfg->u_limit_v : cfg->u_absurd_v);
  s->i_abs = (imest_real_t)cfg->i_absurd_a;
  s->u_abs = (imest_real_t)cfg->u_absurd_v;
  s->dth_max = (imest_real_t)((double)cfg->speed_limit_rad_s / fs); /* per sample */
  s->dly = (imest_real_t)((double)cfg->u_delay_s * fs);
  s->window_n = (uint32_t)((double)cfg->window_s * fs + 0.5);

  {
    const double wd = 2.0 * IMEST_PI_D * (double)cfg->dc_block_hz / fs;
    s->dcb_a = (imest_real_t)(wd / (1.0 + wd)); /* backward Euler: stable for any wd */
  }
  design_bw3(&s->bw, (double)cfg->filter_hz, fs);
  design_aa(&s->aa, (double)cfg->aa_hz, fs);
  s->aa_on = cfg->aa_hz > 0.0f;

  /* warm-up: the slowest Butterworth-3 pole decays as exp(-pi fc t); 3/fc
   * leaves < 1e-4 of a start-up transient; the anti-alias model adds its own. */
  double warm_s = (double)cfg->warmup_s;
  if (warm_s <= 0.0) {
    warm_s = 3.0 / (double)cfg->filter_hz;
    if (cfg->aa_hz > 0.0f) warm_s += 2.0 / (double)cfg->aa_hz;
  }
  s->warmup_n = cfg->start_at_rest ? 0u : (uint32_t)(warm_s * fs) + 3u; /* rounded up, +2 */
  s->warm = s->warmup_n;
  /* At the very first start the offset tracker starts from zero: the offsets,
   * and the filter's own response to signals that were already there (a
   * record that starts mid-run), decay as exp(-t/tau). 5 tau (0.8 s at 1 Hz)
   * leaves 0.7 % of them; 2.5 tau left a 15 kW motor's first window valid
   * with R_S +4 % (measured, ideal sensors). After a fault the tracker keeps
   * its state; at rest it starts from the first currents. */
  if (!cfg->start_at_rest && cfg->warmup_s <= 0.0f && cfg->dc_block_hz > 0.0f)
    s->warm += (uint32_t)(5.0 / (2.0 * IMEST_PI_D * (double)cfg->dc_block_hz) * fs);

  /* background constants */
  s->sigma = cfg->sigma;
  s->ls_h = cfg->ls_h;
  s->tr_nominal_s = cfg->tr_nominal_s;
  s->tr_min_s = cfg->tr_min_s;
  s->tr_max_s = cfg->tr_max_s;
  s->rs_min_ohm = cfg->rs_min_ohm;
  s->rs_max_ohm = cfg->rs_max_ohm;
  s->max_pe_k2_rel = cfg->max_pe_k2_rel;
  s->max_ei = cfg->max_ei;
  s->min_current_a = cfg->min_current_a;
  s->min_slip_ratio = cfg->min_slip_ratio;

  /* first centring: nominal T_R, and gamma with R_S = 0 (any c0 is correct;
   * a close one only improves float32 precision) */
  const double k2 = 1.0 / (double)cfg->tr_nominal_s;
  const double k1 = m * k2;
  bg_centre_from_k(s->win[0].c0, k1, k2, m);
  bg_centre_from_k(s->win[1].c0, k1, k2, m);
  s->win[0].flags = s->warm ? IMEST_FLAG_WARMUP : 0u;
  return IMEST_OK;
}

uint32_t imest_overruns(const imest_t *s)
{
  return s ? s->overruns : 0u;
}

const char *imest_err_name(int err)
{
  switch (err) {
  case IMEST_OK: return "ok";
  case IMEST_ERR_NULL: return "null_argument";
  case IMEST_ERR_CONFIG: return "bad_config";
  case IMEST_ERR_ARG: return "bad_argument";
  default: return "unknown";
  }
}

const char *imest_reason_name(int reason)
{
  switch (reason) {
  case IMEST_REASON_NONE: return "ok";
  case IMEST_REASON_WARMUP: return "warmup";
  case IMEST_REASON_INPUT_FAULT: return "input_fault";
  case IMEST_REASON_ADC_SATURATION: return "adc_saturation";
  case IMEST_REASON_ENCODER_FAULT: return "encoder_fault";
  case IMEST_REASON_NO_CURRENT: return "no_current";
  case IMEST_REASON_STANDSTILL: return "standstill";
  case IMEST_REASON_ZERO_SLIP: return "zero_slip";
  case IMEST_REASON_NUMERIC: return "numeric";
  case IMEST_REASON_NO_ROOT: return "no_root";
  case IMEST_REASON_NOT_MINIMUM: return "not_minimum";
  case IMEST_REASON_POORLY_DETERMINED: return "poorly_determined";
  case IMEST_REASON_HIGH_RESIDUAL: return "high_residual";
  case IMEST_REASON_RS_OUT_OF_RANGE: return "rs_out_of_range";
  case IMEST_REASON_WIRING_MISMATCH: return "wiring_mismatch";
  case IMEST_REASON_CONSTANTS_MISMATCH: return "constants_mismatch";
  case IMEST_REASON_RS_UNCERTAIN: return "rs_uncertain";
  case IMEST_REASON_GAIN_MISMATCH: return "gain_mismatch";
  default: return "unknown";
  }
}
