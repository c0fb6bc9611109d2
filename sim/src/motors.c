/* SPDX-License-Identifier: Apache-2.0 */
/* Industrial drive presets: 400 V, 50 Hz, 4-pole induction motors with public equivalent-circuit
 * data, each on the drive a user would put around it (sim/README.md, Presets).
 *
 * Motor data (R_S, R_R', L_ls = L_lr, L_m, J): the asynchronous-machine presets of
 * MATLAB/Simscape (Specialized Power Systems), as reproduced in the Modelica Buildings library
 * (records IM_5HP_400V_50Hz, IM_20HP_400V_50Hz, IM_50HP_400V_50Hz, IM_100HP_400V_50Hz of
 * Buildings.Electrical.AC.ThreePhasesBalanced.Loads.MotorDrive.InductionMotors.Data). The
 * 11 kW set is one widely used in simulation studies; its origin could not be traced to a
 * public record. Rated torque and current: typical catalogue values of IE3 motors of that
 * power. Assumed here: friction and windage 1 % of rated power at rated speed (viscous); the
 * thermal model's steady rises (80 K stator, 100 K rotor at rated copper loss) and time
 * constants (1200 s (P/4 kW)^(1/3), rotor 1.25x). */
#include <string.h>

#include "imsim_internal.h"

typedef struct {
  const char *name;
  double p_w;                /* rated shaft power                         */
  double rs, rr, lls, lm, j; /* ohm, ohm, H (stator = rotor leakage), H, kg m^2 */
  double t_nm, i_a;          /* rated torque, rated current (catalogue)   */
  double i_range_a;          /* current ADC full scale, about 2.5 x rated peak */
} motor_row;

static const motor_row MOTORS[] = {
    {"4kw", 4000.0, 1.405, 1.395, 5.839e-3, 172.2e-3, 0.0131, 26.5, 8.2, 30.0},
    {"11kw", 11000.0, 0.2761, 0.1645, 2.191e-3, 76.14e-3, 0.09, 72.0, 21.0, 75.0},
    {"15kw", 15000.0, 0.2147, 0.2205, 0.991e-3, 64.19e-3, 0.102, 98.0, 29.0, 100.0},
    {"37kw", 37000.0, 0.08233, 0.0503, 0.724e-3, 27.11e-3, 0.37, 240.0, 68.0, 250.0},
    {"75kw", 75000.0, 0.03552, 0.02092, 0.335e-3, 15.1e-3, 1.25, 485.0, 135.0, 500.0},
};

int ims_motor_preset(imsim_config_t *c, const char *name)
{
  const motor_row *m = NULL;
  for (size_t k = 0; k < sizeof MOTORS / sizeof MOTORS[0]; ++k)
    if (strcmp(name, MOTORS[k].name) == 0) m = &MOTORS[k];
  if (m == NULL) return -1;
  imsim_config_default(c);
  /* motor: T-equivalent circuit -> the paper's parameters */
  const double l = m->lm + m->lls;
  c->pole_pairs = 2;
  c->ls_h = l;
  c->lr_h = l;
  c->sigma = 1.0 - m->lm * m->lm / (l * l);
  c->rs_ohm = m->rs;
  c->tr_s = l / m->rr;
  c->j_kgm2 = m->j;
  c->rated_voltage_v = 400.0;
  c->rated_freq_hz = 50.0;
  c->rated_power_w = m->p_w;
  c->rated_torque_nm = m->t_nm;
  c->rated_speed_rpm = m->p_w / m->t_nm * 60.0 / (2.0 * PI);
  c->rated_current_a = m->i_a;
  const double wn = m->p_w / m->t_nm;
  c->b_nms = 0.01 * m->p_w / (wn * wn);

  /* drive: 560 V bus (400 V rectified), 8 kHz, space-vector modulation, firmware timing with
     one sample per PWM period. 560 V reaches at most 396 V line-to-line: 390 V at 50 Hz. */
  c->supply = IMSIM_SUPPLY_PWM;
  c->vdc_v = 560.0;
  c->carrier_hz = 8000.0;
  c->modulation = IMSIM_MOD_SVPWM;
  c->timing = IMSIM_TIMING_FIRMWARE;
  c->fs_hz = 8000.0;
  c->vll_v = 390.0;
  c->freq_hz = 50.0;
  c->vf_ramp_s = 2.0; /* --start rest: ramp, then the load (below) */
  c->start = IMSIM_START_STEADY;
  c->load_nm = m->t_nm;
  c->load_on_s = 2.5;
  c->load_ramp_s = 1.0;
  c->duration_s = 10.0;

  /* sensors: 12 bit; phase voltage +-400 V covers +-2/3 V_dc; bus ADC 0..800 V; encoder */
  c->i_range_a = m->i_range_a;
  c->u_range_v = 400.0;
  c->vdc_range_v = 800.0;
  c->encoder_counts = 16384;

  /* IFOC (--supply ifoc): rated speed, twice rated torque */
  c->speed_ref_rpm = c->rated_speed_rpm;
  c->speed_ramp_s = 2.0;
  c->torque_limit_nm = 2.0 * m->t_nm;

  /* thermal: R_th from the rated copper losses of the phasor solution */
  imsim_steady_t st;
  if (imsim_steady_state(c, c->vll_v, c->freq_hz, c->load_nm, &st) == 0) {
    const double m_h = sqrt((1.0 - c->sigma) * c->ls_h * c->lr_h);
    const cpx i = cx(st.i_ab[0], st.i_ab[1]), psi = cx(st.psi_ab[0], st.psi_ab[1]);
    const cpx ir = cscale(cadd(psi, cscale(i, -m_h)), 1.0 / c->lr_h);
    const double ps = c->rs_ohm * cabs2(i), pr = c->lr_h / c->tr_s * cabs2(ir);
    c->rth_stator_k_per_w = 80.0 / ps;
    c->rth_rotor_k_per_w = 100.0 / pr;
  }
  c->tau_stator_s = 1200.0 * cbrt(m->p_w / 4000.0);
  c->tau_rotor_s = 1.25 * c->tau_stator_s;
  return 0;
}

/* Realistic sizes of the real-motor effects (sim/README.md, Real-motor effects): saturation
   (static L_m at rated flux below unsaturated), iron loss (share of rated power at rated V/f),
   double cage (R_R at rated frequency / DC). Smaller motors saturate more and lose a larger share
   in the core; larger ones have deeper bars. */
typedef struct {
  double p_w, sat, fe, cage;
} real_row;

static const real_row REAL[] = {
    {4000.0, 0.25, 0.035, 1.3}, {11000.0, 0.22, 0.03, 1.6},  {15000.0, 0.20, 0.025, 1.5},
    {37000.0, 0.18, 0.02, 1.8}, {75000.0, 0.15, 0.015, 2.0},
};

void imsim_config_real_motor(imsim_config_t *c)
{
  real_row r = {0.0, 0.25, 0.04, 1.5}; /* the paper's (small) motor */
  if (!(c->rated_power_w > 0.0)) {
    /* the paper's motor has no nameplate in the preset: its rated point (docs/METHOD.md §9),
       230 V 60 Hz 2.064 N m at 1760.8 rpm, 1.625 A, sizes the effects */
    c->rated_voltage_v = 230.0;
    c->rated_freq_hz = 60.0;
    c->rated_torque_nm = 2.064;
    c->rated_speed_rpm = 1760.8;
    c->rated_power_w = 2.064 * 1760.8 * 2.0 * PI / 60.0;
    c->rated_current_a = 1.625;
  }
  for (size_t k = 0; k < sizeof REAL / sizeof REAL[0]; ++k)
    if (c->rated_power_w == REAL[k].p_w) r = REAL[k];
  c->sat_fraction = r.sat;
  c->iron_loss_fraction = r.fe;
  c->rotor_cage_ratio = r.cage;
}
