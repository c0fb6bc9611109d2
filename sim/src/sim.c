/* SPDX-License-Identifier: Apache-2.0 */
/* Simulator set-up (validation, initial state) and the per-sample step. */
#include <stdio.h>
#include <string.h>

#include "imsim_internal.h"

static int fail(imsim_t *s, const char *msg)
{
  snprintf(s->err, sizeof s->err, "%s", msg);
  return -1;
}

const char *imsim_error(const imsim_t *sim)
{
  return sim->err;
}

void imsim_get_pwm_stats(const imsim_t *s, imsim_pwm_stats_t *out)
{
  out->half_periods = s->pwm_half_periods;
  out->clipped_half_periods = s->pwm_clipped_half_periods;
  out->vdc_needed_v = s->pwm_vdc_needed;
}

int imsim_init(imsim_t *s, const imsim_config_t *cfg, imsim_sample_t *first)
{
  memset(s, 0, sizeof *s);
  s->c = *cfg;
  imsim_config_t *c = &s->c;
  if ((unsigned)c->supply > (unsigned)IMSIM_SUPPLY_EXT ||
      (unsigned)c->timing > (unsigned)IMSIM_TIMING_FIRMWARE ||
      (unsigned)c->modulation > (unsigned)IMSIM_MOD_SVPWM)
    return fail(s, "unknown supply, timing or modulation");
  if (c->pole_pairs < 1) return fail(s, "pole_pairs must be >= 1");
  if (!(c->ls_h > 0.0) || !(c->lr_h > 0.0)) return fail(s, "ls and lr must be > 0");
  if (!(c->sigma > 0.0 && c->sigma < 1.0)) return fail(s, "sigma must be in (0, 1)");
  if (!(c->rs_ohm > 0.0) || !(c->tr_s > 0.0)) return fail(s, "rs and tr must be > 0");
  if (!(c->j_kgm2 > 0.0) || !(c->b_nms >= 0.0)) return fail(s, "j must be > 0 and b >= 0");
  if (!(c->fs_hz > 0.0)) return fail(s, "fs must be > 0");
  if (!(c->vll_v >= 0.0) || !(c->freq_hz >= 0.0)) return fail(s, "vll and freq must be >= 0");
  if (c->thermal && (!(c->tau_stator_s > 0.0) || !(c->tau_rotor_s > 0.0) || !(c->thermal_speedup > 0.0)))
    return fail(s, "thermal time constants and speed-up must be > 0");
  if (!c->ideal_sensors) {
    if (c->adc_bits < 2 || c->adc_bits > 30) return fail(s, "adc bits must be in 2..30");
    if (!(c->i_range_a > 0.0) || !(c->u_range_v > 0.0)) return fail(s, "ADC ranges must be > 0");
    if (c->encoder_counts < 1) return fail(s, "encoder counts must be >= 1");
    if (!(c->noise_lsb >= 0.0)) return fail(s, "noise must be >= 0");
    for (int k = 0; k < 3; ++k)
      if (!isfinite(c->i_offset_a[k]) || !isfinite(c->u_offset_v[k]) || !(c->i_gain_err[k] > -1.0) ||
          !isfinite(c->i_gain_err[k]))
        return fail(s, "sensor offsets must be finite and gain errors > -1");
    if (!(c->aa_hz >= 0.0)) return fail(s, "aa cut-off must be >= 0");
  }
  if (c->rk4_substeps < 1) return fail(s, "rk4 substeps must be >= 1");
  const imsim_vmeas_t vm = ims_vmeas_of(c);
  if (vm == IMSIM_VMEAS_AVG && !ims_is_pwm_stage(c))
    return fail(s, "voltage measurement 'avg' needs a PWM stage");
  if (vm == IMSIM_VMEAS_INST && ims_is_pwm_stage(c))
    return fail(s,
                "voltage measurement 'inst' with a PWM stage would record 0 V: every sample instant is a "
                "carrier extreme, where all legs sit in a zero vector. Use 'avg' (phase voltage from the "
                "commanded duties and Vdc, what a drive knows) or 'aa' with an AA filter (measured voltage)");
  if (vm == IMSIM_VMEAS_AA && (c->ideal_sensors || !(c->aa_hz > 0.0)))
    return fail(s, "voltage measurement 'aa' needs an AA filter (aa_hz > 0, sensors not ideal)");
  s->ts_s = 1.0 / c->fs_hz;
  if (c->timing == IMSIM_TIMING_FIRMWARE && !ims_is_pwm_stage(c))
    return fail(s,
                "firmware timing needs the PWM inverter (supply pwm, ifoc without the ideal stage, or ext)");
  if (c->supply == IMSIM_SUPPLY_EXT && c->start == IMSIM_START_STEADY)
    return fail(
        s, "start 'steady' is not available with external commands: the motor starts at rest (--start rest)");
  if (ims_is_pwm_stage(c)) {
    if (!(c->carrier_hz > 0.0) || !(c->vdc_v > 0.0)) return fail(s, "carrier and vdc must be > 0");
    const double ratio = 2.0 * c->carrier_hz / c->fs_hz;
    const double k = floor(ratio + 0.5);
    if (k < 1.0 || fabs(ratio - k) > 1e-9 * ratio)
      return fail(s, "2 * carrier_hz must be an integer multiple of fs_hz (PWM-synchronous sampling)");
    if (ims_firmware_timing(c) && fmod(k, 2.0) != 0.0)
      return fail(s, "firmware timing samples at a carrier valley once every N carrier periods: carrier_hz "
                     "must be an integer multiple of fs_hz (fs = f_c / N)");
    if (c->steps_per_sample != 0 && c->steps_per_sample != (int)k)
      return fail(s, "with PWM, steps per sample is fixed to 2 f_c / fs");
    s->k_steps = (int)k;
    if (!(c->dead_time_s >= 0.0) || c->dead_time_s >= 0.5 / c->carrier_hz)
      return fail(s, "dead time must be in [0, 1/(2 f_c))");
    if (!(c->v_switch_v >= 0.0) || !(c->r_switch_ohm >= 0.0) || !(c->v_diode_v >= 0.0) ||
        !(c->r_diode_ohm >= 0.0) ||
        !isfinite(c->v_switch_v + c->r_switch_ohm + c->v_diode_v + c->r_diode_ohm))
      return fail(s, "switch and diode drops must be finite and >= 0");
    if (!c->ideal_sensors && !(c->vdc_range_v > 0.0)) return fail(s, "the DC-bus ADC range must be > 0");
  } else {
    if (c->steps_per_sample < 0) return fail(s, "steps per sample must be >= 0");
    s->k_steps = c->steps_per_sample > 0 ? c->steps_per_sample : 5;
  }
  s->h_s = s->ts_s / (double)s->k_steps;
  s->hk[0] = 1.0;
  for (int k = 1; k < 32; ++k) s->hk[k] = s->hk[k - 1] * s->h_s / (double)k;

  s->m_h = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
  s->rr0_ohm = c->lr_h / c->tr_s;
  s->temp_s = s->temp_r = c->t_amb_c;
  ims_update_params(s);
  if (ims_rm_derive(c, &s->rm, s->err, sizeof s->err) != 0) return -1;

  uint64_t sm = c->seed;
  ims_rng_seed(&s->rng, &sm);     /* phase channels: the same stream as ever */
  ims_rng_seed(&s->rng_vdc, &sm); /* DC bus: its own, so the other channels do not change */

  /* IFOC */
  s->ifoc_tr = c->ifoc_tr_s > 0.0 ? c->ifoc_tr_s : c->tr_s;
  s->speed_ref = c->speed_ref_rpm * 2.0 * PI / 60.0;
  if (c->supply == IMSIM_SUPPLY_IFOC) {
    if (c->ifoc_flux_wb > 0.0) {
      s->ifoc_flux = c->ifoc_flux_wb;
    } else {
      imsim_steady_t st;
      const bool have = c->vll_v > 0.0 && c->freq_hz > 0.0;
      if (imsim_steady_state(c, have ? c->vll_v : 230.0, have ? c->freq_hz : 60.0, c->load_nm, &st) != 0)
        return fail(s, "cannot derive the rated flux; set ifoc_flux_wb");
      s->ifoc_flux = st.psi_r_wb;
    }
  }
  s->te_ref = NAN_D;

  const bool ifoc_steady = c->start == IMSIM_START_STEADY && c->supply == IMSIM_SUPPLY_IFOC;
  if (c->start == IMSIM_START_STEADY) {
    imsim_steady_t st;
    double vll = c->vll_v, we = 2.0 * PI * c->freq_hz; /* the supply of the steady state */
    if (ifoc_steady) {
      if (ims_ifoc_steady(s, &vll, &we, &st) != 0)
        return fail(s, "steady start with IFOC needs speed mode, a positive --speed-ref and a load "
                       "within --torque-limit");
      s->c.speed_ramp_s = 0.0;
    } else {
      if (imsim_steady_state(c, c->vll_v, c->freq_hz, c->load_nm, &st) != 0)
        return fail(s, "steady start: load exceeds the breakdown torque");
      if (s->rm.on) (void)ims_rm_steady(c, &s->rm, c->vll_v, c->freq_hz, c->load_nm, &st, s->rm.fl);
    }
    s->x[0] = cx(st.i_ab[0], st.i_ab[1]);
    s->x[1] = cx(st.psi_ab[0], st.psi_ab[1]);
    s->w = st.speed_rad_s;
    /* AA filter states in sinusoidal steady state: f1 = H(j we) x, f2 = (j we / wc) f1 */
    if (c->aa_hz > 0.0 && !c->ideal_sensors) {
      const double wc = 2.0 * PI * c->aa_hz;
      const cpx den = cx(wc * wc - we * we, SQRT2 * wc * we);
      const double dd = cabs2(den);
      const cpx hh = cx(wc * wc * den.re / dd, -wc * wc * den.im / dd);
      s->x[2] = cmul(hh, s->x[0]);
      s->x[3] = cmul(cx(0.0, we / wc), s->x[2]);
      s->x[4] = cmul(hh, cx(vll, 0.0));
      s->x[5] = cmul(cx(0.0, we / wc), s->x[4]);
    }
    s->c.load_on_s = 0.0;
    s->c.load_ramp_s = 0.0;
  }
  s->te = ims_torque_of(s, s->x[0], s->x[1]);
  if (s->rm.on) ims_rm_sync(s, 0.0); /* the real motor's currents and torque from its flux state */
  s->acc = (s->te - ims_load_torque(s, ims_load_at(s, 0.0)) - c->b_nms * s->w) / c->j_kgm2;
  s->load_stuck = s->w == 0.0 && c->load_kind == IMSIM_LOAD_PASSIVE && fabs(ims_load_at(s, 0.0)) > 0.0 &&
                  fabs(s->te) <= fabs(ims_load_at(s, 0.0));
  if (c->supply == IMSIM_SUPPLY_SINE || c->supply == IMSIM_SUPPLY_VF) {
    double amp, ph, f;
    ims_vf_ref(s, 0.0, &amp, &ph, &f);
    s->u_inst[0] = amp * cos(ph);
    s->u_inst[1] = amp * sin(ph);
  }
  ims_sample_vdc(s);
  ims_drive_init(s);
  imsim_sample_t tmp;
  ims_fill_sample(s, first != NULL ? first : &tmp);
  s->th_meas_prev = s->th_meas;
  if (ifoc_steady) {
    /* the field angle from the encoder's, and its speed from the angle a sample before */
    s->slip_angle = s->rho - (double)c->pole_pairs * s->th_meas;
    s->th_meas_prev = s->th_meas - s->w * s->ts_s;
  }
  return 0;
}

void imsim_step(imsim_t *s, imsim_sample_t *out)
{
  const imsim_config_t *c = &s->c;
  const double ts = s->ts_s, h = s->h_s;
  /* 1. thermal: copper losses at t_n drive both first-order models (exact exponential step) */
  if (c->thermal) ims_thermal_step(s);
  /* 2. load profile, held over the sample period (value at its centre); the torque it applies
     is decided per integration step (passive load: from the speed and torque, load.c) */
  const double l_nm = ims_load_at(s, s->t + 0.5 * ts);
  /* 3. controller; with firmware timing it computes the duties of the next sample period */
  if (c->supply == IMSIM_SUPPLY_IFOC) ims_ifoc_update(s);
  const bool fw = ims_firmware_timing(c);
  if (fw) ims_drive_update(s);

  const bool aa = !c->ideal_sensors && c->aa_hz > 0.0;
  const bool pwm = ims_is_pwm_stage(c);
  step_input_t in;
  in.aa = aa;
  in.pwm = pwm;
  in.src = !pwm;
  in.we = 0.0;
  in.p = 0;
  in.piecewise = false;
  pwm_half_t ph;
  memset(&ph, 0, sizeof ph);
  for (int k = 0; k < s->k_steps; ++k) {
    const double t0 = s->t + (double)k * h;
    if (pwm) {
      in.p = ims_taylor_order(s, s->w, &in);
      double m[3];
      if (fw) {
        for (int q = 0; q < 3; ++q) m[q] = 2.0 * s->duty[q] - 1.0;
      } else {
        /* the reference at the half period's centre, modulated at once */
        const double tc = t0 + 0.5 * h;
        cpx vref;
        if (c->supply == IMSIM_SUPPLY_IFOC) {
          vref = ims_ifoc_vref(s, tc);
        } else {
          double amp, phs, f;
          ims_vf_ref(s, tc, &amp, &phs, &f);
          vref = cscale(cexpj(phs), amp);
        }
        if (ims_pwm_modulate(s, vref, c->vdc_v, m)) s->pwm_clipped_half_periods++;
      }
      s->pwm_half_periods++;
      const uint64_t g = s->n * (uint64_t)s->k_steps + (uint64_t)k;
      ims_pwm_build(s, g, m, &in, &ph);
      /* moments path: exact while no phase current changes sign in the half period */
      in.piecewise = !c->pwm_moments || ims_pwm_may_cross_zero(s, &ph);
    } else if (c->supply == IMSIM_SUPPLY_IFOC) {
      /* ideal stage: the controller's synchronous-frame voltage, rotating at its we */
      s->x[6] = ims_ifoc_vref(s, t0);
      in.we = s->we_ctrl;
      in.p = ims_taylor_order(s, s->w, &in);
    } else {
      double amp, phs, f, amp_m, phs_m, f_m;
      ims_vf_ref(s, t0, &amp, &phs, &f);
      ims_vf_ref(s, t0 + 0.5 * h, &amp_m, &phs_m, &f_m);
      s->x[6] = cscale(cexpj(phs), amp_m);
      in.we = 2.0 * PI * f_m;
      in.p = ims_taylor_order(s, s->w, &in);
    }
    ims_load_step_t ls;
    const double tl = ims_load_begin(s, l_nm, &ls);
    ims_advance(s, &in, &ph, tl);
    ims_load_end(s, &ls, t0 + h, h);
    if (pwm) {
      const int slot = s->hp_count & 1;
      s->u_hp_cmd[slot][0] = ph.cmd_avg[0];
      s->u_hp_cmd[slot][1] = ph.cmd_avg[1];
      s->u_hp_act[slot][0] = ph.act_avg[0];
      s->u_hp_act[slot][1] = ph.act_avg[1];
      s->hp_count++;
      if (fw) {
        if (k == 0) s->u_sp_cmd[0] = s->u_sp_cmd[1] = s->u_sp_act[0] = s->u_sp_act[1] = 0.0;
        s->u_sp_cmd[0] += ph.cmd_avg[0];
        s->u_sp_cmd[1] += ph.cmd_avg[1];
        s->u_sp_act[0] += ph.act_avg[0];
        s->u_sp_act[1] += ph.act_avg[1];
      }
    }
  }
  if (fw) ims_drive_advance(s);
  s->n += 1;
  s->t = (double)s->n / c->fs_hz;
  if (!pwm) {
    if (c->supply == IMSIM_SUPPLY_IFOC) {
      s->u_inst[0] = s->x[6].re;
      s->u_inst[1] = s->x[6].im;
    } else {
      double amp, phs, f;
      ims_vf_ref(s, s->t, &amp, &phs, &f);
      s->u_inst[0] = amp * cos(phs);
      s->u_inst[1] = amp * sin(phs);
    }
  }
  ims_sample_vdc(s);
  ims_fill_sample(s, out);
}
