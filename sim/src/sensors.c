/* SPDX-License-Identifier: Apache-2.0 */
/* Sensors: ADCs (bits, range, clipping, seeded noise, offsets, gain errors), the optional
 * analog AA filter (its states are integrated with the motor), the encoder, and the sample
 * record with its truth columns. */
#include "imsim_internal.h"

static double adc(imsim_t *s, double x, double range)
{
  const imsim_config_t *c = &s->c;
  const double lsb = 2.0 * range / ldexp(1.0, c->adc_bits);
  if (c->noise_lsb > 0.0) x += c->noise_lsb * lsb * ims_rng_gauss(&s->rng);
  double code = floor(x / lsb + 0.5);
  const double top = ldexp(1.0, c->adc_bits - 1);
  if (code > top - 1.0) code = top - 1.0;
  if (code < -top) code = -top;
  return code * lsb;
}

bool ims_is_pwm_stage(const imsim_config_t *c)
{
  return c->supply == IMSIM_SUPPLY_PWM || c->supply == IMSIM_SUPPLY_EXT ||
         (c->supply == IMSIM_SUPPLY_IFOC && !c->ifoc_ideal_stage);
}

bool ims_firmware_timing(const imsim_config_t *c)
{
  return ims_is_pwm_stage(c) && (c->timing == IMSIM_TIMING_FIRMWARE || c->supply == IMSIM_SUPPLY_EXT);
}

/* The DC bus through a unipolar ADC (0 .. vdc_range_v, same bits and noise as the others, its
   own noise stream). The bus itself is stiff: V_dc is constant. */
void ims_sample_vdc(imsim_t *s)
{
  const imsim_config_t *c = &s->c;
  if (!ims_is_pwm_stage(c)) {
    s->vdc_meas = NAN_D;
    return;
  }
  double x = c->vdc_v;
  if (c->ideal_sensors) {
    s->vdc_meas = x;
    return;
  }
  const double lsb = c->vdc_range_v / ldexp(1.0, c->adc_bits);
  if (c->noise_lsb > 0.0) x += c->noise_lsb * lsb * ims_rng_gauss(&s->rng_vdc);
  double code = floor(x / lsb + 0.5);
  const double top = ldexp(1.0, c->adc_bits);
  if (code > top - 1.0) code = top - 1.0;
  if (code < 0.0) code = 0.0;
  s->vdc_meas = code * lsb;
}

imsim_vmeas_t ims_vmeas_of(const imsim_config_t *c)
{
  if (c->vmeas != IMSIM_VMEAS_AUTO) return c->vmeas;
  return ims_is_pwm_stage(c) ? IMSIM_VMEAS_AVG : IMSIM_VMEAS_INST;
}

void ims_fill_sample(imsim_t *s, imsim_sample_t *o)
{
  const imsim_config_t *c = &s->c;
  const bool aa = !c->ideal_sensors && c->aa_hz > 0.0;
  o->n = s->n;
  o->t = s->t;
  /* truth */
  const double iab[2] = {s->x[0].re, s->x[0].im};
  imsim_ab_to_abc(iab, o->i_abc_true);
  o->i_ab_true[0] = iab[0];
  o->i_ab_true[1] = iab[1];
  o->psi_ab[0] = s->x[1].re;
  o->psi_ab[1] = s->x[1].im;
  o->psi_r_wb = sqrt(cabs2(s->x[1]));
  o->theta_true = s->th;
  o->speed_rad_s = s->w;
  o->torque_nm = s->te;
  o->load_nm = ims_load_torque(s, ims_load_at(s, s->t));
  o->accel_rad_s2 = (s->te - o->load_nm - c->b_nms * s->w) / c->j_kgm2;
  o->tr_s = s->tr;
  o->rs_ohm = s->rs;
  o->temp_stator_c = s->temp_s;
  o->temp_rotor_c = s->temp_r;
  const cpx ir = cscale(cadd(s->x[1], cscale(s->x[0], -s->m_h)), 1.0 / c->lr_h);
  o->p_cu_stator_w = s->rs * cabs2(s->x[0]);
  o->p_cu_rotor_w = s->rr * cabs2(ir);
  if (s->rm.on)
    ims_rm_fill(s, o);
  else
    o->psi_m_wb = o->lm_h = o->lr_eff_h = o->rr_eff_ohm = o->p_fe_w = o->w_mag_j = o->tr_ifoc_s = NAN_D;
  double utrue[2];
  const bool fw = ims_firmware_timing(c);
  if (fw) {
    /* the sample period that just ended (duties constant over it) */
    utrue[0] = s->u_sp_act[0] / (double)s->k_steps;
    utrue[1] = s->u_sp_act[1] / (double)s->k_steps;
  } else if (ims_is_pwm_stage(c)) {
    utrue[0] = 0.5 * (s->u_hp_act[0][0] + s->u_hp_act[1][0]);
    utrue[1] = 0.5 * (s->u_hp_act[0][1] + s->u_hp_act[1][1]);
  } else {
    utrue[0] = s->u_inst[0];
    utrue[1] = s->u_inst[1];
  }
  o->u_ab_true[0] = utrue[0];
  o->u_ab_true[1] = utrue[1];
  imsim_ab_to_abc(utrue, o->u_abc_true);
  if (c->supply == IMSIM_SUPPLY_IFOC) {
    o->ifoc_torque_ref_nm = s->te_ref;
    o->ifoc_flux_ref_wb = s->ifoc_flux;
    o->ifoc_tr_s = s->ifoc_tr;
    o->ifoc_speed_ref_rad_s = c->ifoc_mode == IMSIM_IFOC_SPEED ? s->speed_ref : NAN_D;
  } else {
    o->ifoc_torque_ref_nm = o->ifoc_flux_ref_wb = o->ifoc_tr_s = o->ifoc_speed_ref_rad_s = NAN_D;
  }
  for (int k = 0; k < 3; ++k) o->duty[k] = fw ? s->duty[k] : NAN_D;
  o->vdc_v = s->vdc_meas;
  o->vdc_true_v = ims_is_pwm_stage(c) ? c->vdc_v : NAN_D;

  /* measured voltage (alpha-beta, before the ADC) */
  double um[2];
  switch (ims_vmeas_of(c)) {
  case IMSIM_VMEAS_AVG:
    if (fw) {
      um[0] = s->u_sp_cmd[0] / (double)s->k_steps;
      um[1] = s->u_sp_cmd[1] / (double)s->k_steps;
    } else {
      um[0] = 0.5 * (s->u_hp_cmd[0][0] + s->u_hp_cmd[1][0]);
      um[1] = 0.5 * (s->u_hp_cmd[0][1] + s->u_hp_cmd[1][1]);
    }
    break;
  case IMSIM_VMEAS_AA:
    um[0] = s->x[4].re;
    um[1] = s->x[4].im;
    break;
  case IMSIM_VMEAS_INST:
  case IMSIM_VMEAS_AUTO:
  default:
    um[0] = s->u_inst[0];
    um[1] = s->u_inst[1];
    break;
  }
  double uabc[3], imab[2], iabc[3];
  imsim_ab_to_abc(um, uabc);
  imab[0] = aa ? s->x[2].re : s->x[0].re;
  imab[1] = aa ? s->x[2].im : s->x[0].im;
  imsim_ab_to_abc(imab, iabc);
  if (c->ideal_sensors) {
    for (int k = 0; k < 3; ++k) {
      o->u_abc[k] = uabc[k];
      o->i_abc[k] = iabc[k];
    }
    o->theta = s->th;
  } else {
    for (int k = 0; k < 3; ++k)
      o->i_abc[k] = adc(s, iabc[k] * (1.0 + c->i_gain_err[k]) + c->i_offset_a[k], c->i_range_a);
    for (int k = 0; k < 3; ++k) o->u_abc[k] = adc(s, uabc[k] + c->u_offset_v[k], c->u_range_v);
    const double cpr = (double)c->encoder_counts;
    o->theta = floor(s->th * cpr / (2.0 * PI)) * (2.0 * PI / cpr);
  }
  /* what the controller sees */
  imsim_abc_to_ab(o->i_abc, s->i_meas_ab);
  s->th_meas = o->theta;
}
