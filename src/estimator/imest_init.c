/* SPDX-License-Identifier: Apache-2.0 */
/* Configuration defaults and checks, filter design, instance initialisation.
 * Runs once, outside the ISR: float64 and <math.h> are fine here. */
#include <math.h>
#include <stddef.h>

#include "bg_flux.h"
#include "bg_validity.h" /* IMEST_WITH_ROTOR_HF */
#include "bg_noise.h"
#include "bg_transient.h"
#include "common/imest_handoff.h"
#include "common/imest_math.h"

void imest_config_default(imest_config_t *cfg)
{
  if (cfg == NULL) return;
  /* every field defined, those not named below 0 (a config on the stack held
   * garbage in tr_nominal_known: found by the verdict tests) */
  unsigned char *raw = (unsigned char *)cfg;
  for (size_t b = 0; b < sizeof *cfg; ++b) raw[b] = 0u;
  cfg->pole_pairs = 0; /* motor constants: the caller must set them */
  cfg->ls_h = 0.0f;
  cfg->sigma = 0.0f;
  cfg->ls_uncertainty = 0.1f;    /* a data sheet's L_S */
  cfg->sigma_uncertainty = 0.2f; /* a data sheet's sigma */
  cfg->fs_hz = 4000.0f;
  cfg->window_s = 1.0f;
  cfg->filter_hz = 100.0f;
  cfg->aa_hz = 0.0f;
  cfg->u_delay_s = 0.0f;
  cfg->dc_block_hz = 1.0f;
  cfg->angle_observer_hz = 0.0f;      /* auto: filter_hz / 4 */
  cfg->encoder_counts_per_rev = 0.0f; /* unknown */
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
  cfg->voltage_kind = IMEST_VOLTAGE_STAIRCASE;
  cfg->inverter.dead_time_s = 0.0f;
  cfg->inverter.v_switch_v = 0.0f;
  cfg->inverter.r_switch_ohm = 0.0f;
  cfg->inverter.v_diode_v = 0.0f;
  cfg->inverter.r_diode_ohm = 0.0f;
  cfg->inverter.i_band_a = 0.0f;
  cfg->inverter.edge_band_a = 0.0f;  /* the smooth sign (docs/METHOD.md §17.1) */
  cfg->inverter.uncertainty = -1.0f; /* unknown until the user (or commissioning) says */
  cfg->rs_tolerance = 0.05f;
  cfg->tr_tolerance = 0.02f;
  cfg->u_uncertainty_v = 0.0f;
  cfg->timing_uncertainty_s = 1.0e-6f;
  cfg->rs_nominal_ohm = 0.0f;
  cfg->rotor_hf_rr_ratio = 0.0f; /* a single cage */
  cfg->rotor_hf_sigma_ratio = 0.0f;
  cfg->inverter_vdc_v = 0.0f;
  cfg->ls_curve_points = 0u; /* no magnetising curve (the points are zero) */
}

/* The config's float fields and their ranges, checked in order by one loop
 * (a table costs a fraction of the flash of one comparison chain, and float
 * arithmetic is the FPU's: no soft-double code for a check). A row is the
 * field's name, its offset and one code: the kind and the indices of its two
 * bounds in the short tables below (41 rows of two floats each were 328 B). */
enum { C_ANY = 0, C_NONNEG = 1, C_POS = 2 };
/* |value| * (1/fs) must stay below this (0: no bound) */
enum { FS_NONE, FS_FILTER, FS_AA, FS_DC_BLOCK, FS_SPEED };
static const float k_below_fs[] = {
    [FS_NONE] = 0.0f,      /* no bound */
    [FS_FILTER] = 0.4f,    /* filter_hz */
    [FS_AA] = 0.45f,       /* aa_hz */
    [FS_DC_BLOCK] = 0.01f, /* dc_block_hz */
    [FS_SPEED] = 3.0f,     /* speed_limit_rad_s */
};
/* |value| must stay below this (0: no bound) */
enum { LIM_NONE, LIM_ONE, LIM_FS, LIM_COUNTS };
static const float k_below[] = {
    [LIM_NONE] = 0.0f,
    [LIM_ONE] = 1.0f,
    [LIM_FS] = 1.000001e6f,     /* fs_hz */
    [LIM_COUNTS] = 16777216.0f, /* encoder_counts_per_rev: exact in float32 */
};
#define CODE(kind, fs, lim) ((unsigned short)((kind) | (fs) << 2 | (lim) << 5))
#define CODE_KIND(c)        ((c)&3u)
#define CODE_FS(c)          (((c) >> 2) & 7u)
#define CODE_LIM(c)         ((c) >> 5)
typedef struct {
  const char *name;
  unsigned short offset;
  unsigned short code; /* C_* | FS_* << 2 | LIM_* << 5 */
} check_t;

#define CHK(f, kind, below_fs, below)                                                                        \
  {                                                                                                          \
    .name = #f, .offset = (unsigned short)offsetof(imest_config_t, f), .code = CODE(kind, below_fs, below)   \
  }
static const check_t k_checks[] = {
    CHK(ls_h, C_POS, FS_NONE, LIM_NONE),
    CHK(sigma, C_POS, FS_NONE, LIM_ONE),
    CHK(ls_uncertainty, C_NONNEG, FS_NONE, LIM_ONE),
    CHK(sigma_uncertainty, C_NONNEG, FS_NONE, LIM_ONE),
    CHK(fs_hz, C_POS, FS_NONE, LIM_FS),
    CHK(window_s, C_POS, FS_NONE, LIM_NONE),
    CHK(filter_hz, C_POS, FS_FILTER, LIM_NONE),
    CHK(aa_hz, C_NONNEG, FS_AA, LIM_NONE),
    CHK(u_delay_s, C_ANY, FS_NONE, LIM_NONE),
    CHK(dc_block_hz, C_NONNEG, FS_DC_BLOCK, LIM_NONE),
    CHK(angle_observer_hz, C_ANY, FS_NONE, LIM_NONE),
    CHK(encoder_counts_per_rev, C_NONNEG, FS_NONE, LIM_COUNTS),
    CHK(warmup_s, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(tr_nominal_s, C_POS, FS_NONE, LIM_NONE),
    CHK(tr_min_s, C_POS, FS_NONE, LIM_NONE),
    CHK(tr_max_s, C_POS, FS_NONE, LIM_NONE),
    CHK(rs_min_ohm, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(rs_max_ohm, C_POS, FS_NONE, LIM_NONE),
    CHK(max_pe_k2_rel, C_POS, FS_NONE, LIM_NONE),
    CHK(max_ei, C_POS, FS_NONE, LIM_NONE),
    CHK(min_current_a, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(min_slip_ratio, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(i_limit_a, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(u_limit_v, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(i_absurd_a, C_POS, FS_NONE, LIM_NONE),
    CHK(u_absurd_v, C_POS, FS_NONE, LIM_NONE),
    CHK(speed_limit_rad_s, C_POS, FS_SPEED, LIM_NONE),
    CHK(pwm_hz, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.dead_time_s, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.v_switch_v, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.r_switch_ohm, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.v_diode_v, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.r_diode_ohm, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.i_band_a, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.edge_band_a, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter.uncertainty, C_ANY, FS_NONE, LIM_NONE),
    CHK(rs_tolerance, C_POS, FS_NONE, LIM_NONE),
    CHK(tr_tolerance, C_POS, FS_NONE, LIM_NONE),
    CHK(u_uncertainty_v, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(timing_uncertainty_s, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(rs_nominal_ohm, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(rotor_hf_rr_ratio, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(rotor_hf_sigma_ratio, C_NONNEG, FS_NONE, LIM_NONE),
    CHK(inverter_vdc_v, C_NONNEG, FS_NONE, LIM_NONE),
};
#undef CHK
#undef CODE

static int check_ok(const check_t *c, float x, float fs)
{
  const unsigned int kind = CODE_KIND(c->code);
  const float below_fs = k_below_fs[CODE_FS(c->code)], below = k_below[CODE_LIM(c->code)];
  if (!isfinite(x)) return 0;
  if ((kind == C_NONNEG && x < 0.0f) || (kind == C_POS && !(x > 0.0f))) return 0;
  const float ax = fabsf(x);
  if (below_fs > 0.0f && !(ax < below_fs * fs)) return 0;
  return !(below > 0.0f && !(ax < below));
}

/* The magnetising curve: 0 points (none) or 2 .. IMEST_LS_CURVE_POINTS (one
 * point is ls_h), each current and L_S finite and positive, the currents
 * strictly increasing (the interpolation's segments need a positive width);
 * none at all in a build without the stage (IMEST_WITH_FLUX 0). The name of
 * the first bad field, NULL if the curve is usable. */
static const char *check_ls_curve(const imest_config_t *cfg)
{
  const unsigned int n = cfg->ls_curve_points;
  if (n == 0u) return NULL;
  if (!IMEST_WITH_FLUX || n < 2u || n > IMEST_LS_CURVE_POINTS) return "ls_curve_points";
#if IMEST_WITH_FLUX
  for (unsigned int k = 0; k < n; ++k) {
    const float x = cfg->ls_curve_i_a[k], y = cfg->ls_curve_h[k];
    if (!(isfinite(x) && x > 0.0f) || (k > 0u && !(x > cfg->ls_curve_i_a[k - 1u]))) return "ls_curve_i_a";
    if (!(isfinite(y) && y > 0.0f)) return "ls_curve_h";
  }
#endif
  return NULL;
}

// NOLINTNEXTLINE(readability-function-cognitive-complexity): a flat else-if list, one bound per field
int imest_config_check(const imest_config_t *cfg, const char **field)
{
  if (cfg == NULL) {
    if (field) *field = "cfg";
    return IMEST_ERR_NULL;
  }
  const char *bad = NULL;
  const float fs = cfg->fs_hz, pwm = cfg->pwm_hz > 0.0f ? cfg->pwm_hz : fs;
  if (cfg->pole_pairs < 1u || cfg->pole_pairs > 64u) bad = "pole_pairs";
  for (unsigned int k = 0; bad == NULL && k < sizeof k_checks / sizeof k_checks[0]; ++k) {
    const float x = *(const float *)(const void *)((const char *)cfg + k_checks[k].offset);
    if (!check_ok(&k_checks[k], x, fs)) bad = k_checks[k].name;
  }
  /* the bounds that involve two fields */
  if (bad != NULL) {
  } else if (cfg->window_s * fs < 64.0f || cfg->window_s * fs > 4.0e8f)
    bad = "window_s";
  else if (fabsf(cfg->u_delay_s) * fs > 1.000001f)
    bad = "u_delay_s";
  else if (!(cfg->angle_observer_hz < 0.25f * fs))
    bad = "angle_observer_hz";
  else if (cfg->warmup_s > cfg->window_s * 100.0f)
    bad = "warmup_s";
  else if (!(cfg->tr_max_s > cfg->tr_min_s))
    bad = "tr_max_s";
  else if (!(cfg->rs_max_ohm > cfg->rs_min_ohm))
    bad = "rs_max_ohm";
  else if (cfg->pwm_hz != 0.0f && cfg->pwm_hz < fs * 0.999999f)
    bad = "pwm_hz";
  else if (!(cfg->pwm_timing == IMEST_PWM_NEXT_PERIOD || cfg->pwm_timing == IMEST_PWM_CENTRED ||
             cfg->pwm_timing == IMEST_PWM_LAST_PERIOD))
    bad = "pwm_timing";
  else if ((unsigned int)cfg->voltage_kind > (unsigned int)IMEST_VOLTAGE_SMOOTH)
    bad = "voltage_kind";
  else if (!(cfg->inverter.dead_time_s * pwm < 0.5f))
    bad = "inverter.dead_time_s";
  else if (!(cfg->timing_uncertainty_s * fs < 1.0f))
    bad = "timing_uncertainty_s";
  else if (cfg->rotor_hf_rr_ratio != 0.0f && !(IMEST_WITH_ROTOR_HF && cfg->rotor_hf_rr_ratio > 1.0f))
    bad = "rotor_hf_rr_ratio";
  else if (cfg->rotor_hf_rr_ratio != 0.0f &&
           !(cfg->rotor_hf_sigma_ratio > 0.0f && cfg->rotor_hf_sigma_ratio <= 1.0f))
    bad = "rotor_hf_sigma_ratio";
  else
    bad = check_ls_curve(cfg);
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

/* exp(-x) for 0 <= x <= 1.6 by its series (fixed 16 terms, float32): libm's
 * exp() would cost flash. */
static float exp_neg_small(float x)
{
  float sum = 1.0f, term = 1.0f;
  for (int k = 1; k <= 16; ++k) {
    term *= -x / (float)k;
    sum += term;
  }
  return sum;
}

/* Angle observer gains: an alpha-beta-gamma tracker with a triple pole at
 * r = exp(-w_n T): alpha = 1 - r^3, beta = 1.5 (1 - r)^2 (1 + r),
 * gamma = (1 - r)^3 (f_n < 0: never engaged). */
static void design_angle(imest_angle_t *o, float fn, float fs, float counts)
{
  /* one count: the true angle lies within it of the reading whichever way the
   * encoder rounds; unknown (0), a bound that never acts */
  o->d_max = counts > 0.0f ? 2.0f * (float)IMEST_PI_D / counts : 1.0e30f;
  const float r = exp_neg_small(2.0f * (float)IMEST_PI_D * (fn > 0.0f ? fn : 0.0f) / fs), q = 1.0f - r;
  o->k1 = 1.0f - r * r * r;
  o->k2 = 1.5f * q * q * (1.0f + r);
  o->k3 = q * q * q;
  o->state = fn >= 0.0f ? IMEST_ANG_ENABLED : 0u; /* engaged after a window at steady speed */
}

/* Duty-cycle input: the weights of the two periods around a sample
 * (pwm_timing) and the inverter model per leg (isr_duty.h). */
static void design_duty(imest_duty_model_t *d, const imest_config_t *cfg)
{
  const float fpwm = cfg->pwm_hz > 0.0f ? cfg->pwm_hz : cfg->fs_hz;
  /* NEXT_PERIOD: the previous period ends at the sample and this one starts
   * there, so their mean refers to the sample; otherwise this call's duty
   * alone (LAST_PERIOD's half-sample lag is taken up by the delay, init). */
  const int next = cfg->pwm_timing == IMEST_PWM_NEXT_PERIOD;
  d->w_prev = next ? 0.5f : 0.0f;
  const imest_inverter_t *v = &cfg->inverter;
  d->td_f_half = 0.5f * v->dead_time_s * fpwm;
  d->v_sum = v->v_switch_v + v->v_diode_v;
  d->r_mean = 0.5f * (v->r_switch_ohm + v->r_diode_ohm);
  d->dv = v->v_switch_v - v->v_diode_v;
  d->dr = v->r_switch_ohm - v->r_diode_ohm;
  /* the sign's band: the switching-instant model's is the devices' own
   * (edge_band_a) beyond the ripple at the edges; the smooth sign's i_band_a
   * alone or, at 0, per leg and sample b = |D_x| + b_0 (docs/METHOD.md §17.1):
   * s(i) = i / sqrt(i^2 + b^2) falls short of the sign by an area b, as the
   * dead time's mean over the two edges i +- D_x does by |D_x| + b_0. b_0:
   * a current that reaches 0 within the dead time loses t_d V_dc in
   * proportion (a ramp over the current's change in it, short by half of
   * it); the leg's phase voltage then is n/3 V_dc, n the other legs in the
   * opposite state, 2 over the two edges: b_0 = V_dc t_d / (6 sigma L_S). A
   * micro-ampere at least keeps 0 / 0 out of the signs at zero bus and zero
   * current. */
  const int edges = v->edge_band_a > 0.0f;
  const float band = edges ? v->edge_band_a : v->i_band_a;
  const int leg_band = !edges && !(band > 0.0f);
  d->ripple_per_v = (edges || leg_band) ? 1.0f / (2.0f * cfg->sigma * cfg->ls_h * fpwm) : 0.0f;
  d->floor_per_v = leg_band ? v->dead_time_s / (6.0f * cfg->sigma * cfg->ls_h) : 0.0f;
  d->band2 = band > 0.0f ? band * band : 1e-12f;
  d->vdc2_w = 12.0f / (cfg->u_absurd_v * cfg->u_absurd_v);
  /* the staircase's images alias into the samples when the steps' edges are
   * the sample instants (NEXT_PERIOD; docs/METHOD.md §17) */
  d->zoh = next ? 1.0f / (12.0f * cfg->fs_hz * cfg->sigma * cfg->ls_h) : 0.0f;
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

/* The ISR's constants: the sample rate's, the motor's, the limits, the
 * channels' alignment, the window length and the front end's filters. Float
 * arithmetic wherever the ISR's float32 constants come out the same (the
 * FPU's, no soft-double code); the filter design keeps float64. */
static void init_isr_constants(imest_t *s, const imest_config_t *cfg, double m)
{
  const float fs = cfg->fs_hz, sigma = cfg->sigma;
  s->fs = fs;
  s->inv2t = 0.5f * fs;
  s->invt2 = fs * fs;
  s->n = (imest_real_t)cfg->pole_pairs;
  s->m = (imest_real_t)m;
  s->inv_s = 1.0f / (sigma * cfg->ls_h);
  /* no ADC limit configured: the absurd-value limit takes its place */
  s->i_lim = cfg->i_limit_a > 0.0f ? cfg->i_limit_a : cfg->i_absurd_a;
  s->u_lim = cfg->u_limit_v > 0.0f ? cfg->u_limit_v : cfg->u_absurd_v;
  s->i_abs = cfg->i_absurd_a;
  s->u_abs = cfg->u_absurd_v;
  s->dth_max = cfg->speed_limit_rad_s / fs; /* per sample */
  {
    /* How much the voltage lags the currents: the timing scheme's own lag
     * (duty input, LAST_PERIOD: the period that ended, half a sample) plus
     * u_delay_s. A lag delays currents and angle; a lead delays the voltage. */
    const float lag = (cfg->pwm_timing == IMEST_PWM_LAST_PERIOD ? 0.5f : 0.0f) + cfg->u_delay_s * fs;
    s->dly_i = lag > 0.0f ? lag : 0.0f;
    s->dly_u = lag < 0.0f ? -lag : 0.0f;
  }
  /* an even number of samples: a regressor sample's sums take two calls
   * (isr_accumulate.h), and a window holds whole samples */
  s->window_n = 2u * (uint32_t)(cfg->window_s * fs * 0.5f + 0.5f);

  {
    const float wd = 2.0f * (float)IMEST_PI_D * cfg->dc_block_hz / fs;
    s->dcb_a = wd / (1.0f + wd); /* backward Euler: stable for any wd */
  }
  design_bw3(&s->bw, (double)cfg->filter_hz, (double)fs);
  imest__bg_noise_gains(&s->bw, fs, s->noise_g);
  design_aa(&s->aa, (double)cfg->aa_hz, (double)fs);
  s->stages = (s->dly_i != 0.0f ? IMEST_STAGE_DELAY_I : 0u) | (s->dly_u != 0.0f ? IMEST_STAGE_DELAY_U : 0u) |
              (cfg->aa_hz > 0.0f ? IMEST_STAGE_AA : 0u) |
              (cfg->inverter.edge_band_a > 0.0f ? IMEST_STAGE_DUTY_EDGES : 0u);
  const float fn = cfg->angle_observer_hz == 0.0f ? 0.25f * cfg->filter_hz : cfg->angle_observer_hz;
  design_angle(&s->obs, fn, fs, cfg->encoder_counts_per_rev);
  s->transient_k = imest__bg_transient_k(fn, (float)s->n, cfg->window_s); /* the judge's (bg_transient.c) */
  design_duty(&s->duty, cfg);
}

/* The warm-up: samples the filters settle, at the start and after a fault. */
static void init_warmup(imest_t *s, const imest_config_t *cfg)
{
  const float fs = cfg->fs_hz;
  /* warm-up: the slowest Butterworth-3 pole decays as exp(-pi fc t); 3/fc
   * leaves < 1e-4 of a start-up transient; the anti-alias model adds its own. */
  double warm_s = (double)cfg->warmup_s; /* float64: whole samples come out as intended */
  if (warm_s <= 0.0) {
    warm_s = 3.0 / (double)cfg->filter_hz;
    if (cfg->aa_hz > 0.0f) warm_s += 2.0 / (double)cfg->aa_hz;
  }
  s->warmup_fault_n = (uint32_t)(warm_s * (double)fs) + 3u; /* rounded up, +2 */
  s->warmup_n = cfg->start_at_rest ? 0u : s->warmup_fault_n;
  s->warm = s->warmup_n;
  /* At the very first start the offset tracker starts from zero: the offsets,
   * and the filter's own response to signals that were already there (a
   * record that starts mid-run), decay as exp(-t/tau). 5 tau (0.8 s at 1 Hz)
   * leaves 0.7 % of them; 2.5 tau left a 15 kW motor's first window valid
   * with R_S +4 % (measured, ideal sensors). After a fault the tracker keeps
   * its state; at rest it starts from the first currents. */
  if (!cfg->start_at_rest && cfg->warmup_s <= 0.0f && cfg->dc_block_hz > 0.0f)
    s->warm += (uint32_t)(5.0f / (2.0f * (float)IMEST_PI_D * cfg->dc_block_hz) * fs);
}

/* What the background judges by, as configured. */
static void init_background_constants(imest_t *s, const imest_config_t *cfg)
{
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
  s->rs_tolerance = cfg->rs_tolerance;
  s->tr_tolerance = cfg->tr_tolerance;
  /* the constants' errors the bounds take (bg_validity.c, systematic_bounds):
   * configured = (1 + e) x the motor's with |e| <= u puts the motor's value
   * up to u / (1 - u) from the configured one; the first-order move of that,
   * and (1 + u) for the second-order terms (measured: the move is up to u
   * larger, relative, than first order where the motor's constant is the
   * higher one) */
  s->ls_shift_e = cfg->ls_uncertainty * (1.0f + cfg->ls_uncertainty) / (1.0f - cfg->ls_uncertainty);
  s->sigma_shift_e =
      cfg->sigma_uncertainty * (1.0f + cfg->sigma_uncertainty) / (1.0f - cfg->sigma_uncertainty);
  s->u_uncertainty_v = cfg->u_uncertainty_v;
  s->timing_uncertainty_s = cfg->timing_uncertainty_s;
  s->rs_nominal_ohm = cfg->rs_nominal_ohm;
  s->rotor_hf_rr_ratio = cfg->rotor_hf_rr_ratio;
  s->rotor_hf_sigma_ratio = cfg->rotor_hf_sigma_ratio;
  s->inverter_vdc_v = cfg->inverter_vdc_v;
  s->tr_nominal_known = cfg->tr_nominal_known != 0;
  s->ls_curve_points = cfg->ls_curve_points;
  for (unsigned int k = 0; IMEST_WITH_FLUX && k < IMEST_LS_CURVE_POINTS; ++k) {
    s->ls_curve_i_a[k] = cfg->ls_curve_i_a[k];
    s->ls_curve_h[k] = cfg->ls_curve_h[k];
  }
  s->inverter = cfg->inverter;
  s->pwm_hz = cfg->pwm_hz > 0.0f ? cfg->pwm_hz : cfg->fs_hz;
  s->t_stair_s[1] = 1.0f / s->pwm_hz;
  s->t_stair_s[0] = cfg->voltage_kind == IMEST_VOLTAGE_SMOOTH ? 0.0f : s->t_stair_s[1];
}

int imest_init(imest_t *s, const imest_config_t *cfg)
{
  if (s == NULL || cfg == NULL) return IMEST_ERR_NULL;
  const int rc = imest_config_check(cfg, NULL);
  if (rc != IMEST_OK) return rc;

  /* no memset: the core does not depend on <string.h> */
  unsigned char *raw = (unsigned char *)s;
  for (size_t b = 0; b < sizeof *s; ++b) raw[b] = 0u;

  const double m = (1.0 - (double)cfg->sigma) / (double)cfg->sigma;
  init_isr_constants(s, cfg, m);
  init_warmup(s, cfg);
  init_background_constants(s, cfg);
  /* first centring: nominal T_R, and gamma with R_S = 0 (any c0 is correct;
   * a close one only improves float32 precision) */
  const imest_real_t k2 = RL(1) / (imest_real_t)cfg->tr_nominal_s;
  const imest_real_t k1 = s->m * k2;
  imest__bg_centre_from_k(s->win[0].c0, k1, k2, s->m);
  imest__bg_centre_from_k(s->win[1].c0, k1, k2, s->m);
  s->win[0].flags = s->warm ? IMEST_FLAG_WARMUP : 0u;
  return IMEST_OK;
}

uint32_t imest_overruns(const imest_t *s)
{
  return s ? IMEST_LOAD_RELAXED(&s->overruns) : 0u;
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
  case IMEST_REASON_TR_UNCERTAIN: return "tr_uncertain";
  case IMEST_REASON_CONSTANTS_UNCERTAIN: return "constants_uncertain";
  case IMEST_REASON_TRANSIENT: return "transient";
  default: return "unknown";
  }
}
