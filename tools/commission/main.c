/* SPDX-License-Identifier: Apache-2.0 */
/* imest-commission: the library's self-commissioning routine run closed loop on the simulator
 * for a drive preset; prints what it identified against the simulator's truth, with the errors,
 * the time and the peak current of the routine, per stage.
 *
 *   imest-commission --preset 4kw
 *   imest-commission --preset 37kw --no-rotation --dead-time 3e-6
 *
 * Exit status: 0 the routine completed with a valid result, 1 it failed (the reason is
 * printed), 2 usage error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commission_online.h"
#include "commission_sensitivity.h"
#include "commission_sim.h"
#include "tool_args.h"

static const char *const k_prog = "imest-commission";

static void usage(FILE *f)
{
  fprintf(f,
          "usage: %s [options]\n"
          "Runs the self-commissioning routine (include/imest/imest_commission.h) closed loop on the\n"
          "simulator and prints identified vs true values.\n"
          "  --preset NAME        4kw, 11kw, 15kw, 37kw, 75kw, exp1 (the paper's 0.4 kW motor) [4kw]\n"
          "  --no-rotation        standstill only (L_S and sigma from the flux tails)\n"
          "  --no-nameplate       do not give the rated speed (n_p from the encoder's counts)\n"
          "  --speed-frac X       speed of the rotating run, fraction of rated [0.4]\n"
          "  --i-max A            current limit, peak [sqrt(2) x rated]\n"
          "  --r-series OHM       known series resistance passed to the routine [0]\n"
          "  --dead-time S        inverter dead time [2e-6]\n"
          "  --v-switch V         switch threshold [1]\n"
          "  --r-switch OHM       switch slope [0.02 x 8.2 A / rated current]\n"
          "  --v-diode V          diode threshold [0.8]\n"
          "  --r-diode OHM        diode slope [0.01 x 8.2 A / rated current]\n"
          "  --offsets A,B,C      current-sensor offsets [A] [1, -0.6, 0.4 %% of full scale]\n"
          "  --gain-errors A,B,C  current-sensor gain errors [0.01,-0.004,-0.006]\n"
          "  --ideal-sensors      exact currents and angle\n"
          "  --encoder-counts N   true counts per revolution [4096]\n"
          "  --cpr-assumed N      counts the firmware assumes [the true ones]\n"
          "  --encoder-reversed   the angle counts against the a-b-c field\n"
          "  --encoder-stuck      the angle never moves\n"
          "  --swap-sensors       current channels b and c swapped\n"
          "  --two-sensors        the firmware computes i_c = -i_a - i_b\n"
          "  --real-motor         the motor saturates, has iron loss and a double cage, at the\n"
          "                       preset's sizes (sim/README.md, Real-motor effects)\n"
          "  --saturation F       main-flux saturation: L_m at rated flux F below unsaturated [off]\n"
          "  --iron-loss F        iron loss, F x rated power at rated V/f [off]\n"
          "  --rotor single|double-cage:R  double-cage rotor, R_R at rated frequency R x DC [single]\n"
          "                       (--saturation 0, --iron-loss 0, --rotor single: that effect off,\n"
          "                       also with --real-motor, as imest-sim's flags)\n"
          "  --seed N             noise seed [1]\n"
          "  --trace FILE         per-sample CSV (t, stage, currents, duties, speed, angle)\n"
          "  --trace-decimate N   every N-th sample in the trace [1]\n"
          "  --csv                one machine-readable line instead of the table\n"
          "  --apply-args         instead of the table: what imest_comm_apply() fills, as imest-replay\n"
          "                       options: line 1 the constants (--pole-pairs, --ls, --sigma, their\n"
          "                       uncertainties, --rs, --tr-nominal, --ls-curve; no --sigma with a\n"
          "                       deep-bar rotor: give the data sheet's), line 2 the inverter model\n"
          "                       (for --voltage duty)\n"
          "  --verbose            also the per-axis fits\n"
          "  --result             instead of the table: every field of the result, one per line\n"
          "                       (name and value to 9 digits), the per-axis fits and, with\n"
          "                       --online, the online estimator's figures\n"
          "  --sensitivity        instead: the online estimator's T_R and R_S error per 1 %% error of\n"
          "                       L_S and sigma and per 0.1 V of inverter model error (preset at\n"
          "                       --load of rated torque, phase-voltage input)\n"
          "  --duty               --sensitivity with the duty-cycle input on the commissioned drive\n"
          "                       (the 0.1 V taken off the true inverter model's thresholds)\n"
          "  --load X             load for --sensitivity and --online, fraction of rated [1]\n"
          "  --online             then: the online estimator on the same drive at --load with the\n"
          "                       identified constants and inverter model (duty-cycle input),\n"
          "                       against the same with the true ones\n"
          "  -h, --help           this text\n"
          "  --version            the version and licence\n"
          "\n"
          "Exit status: 0 the routine completed with a valid result (--sensitivity: the runs\n"
          "completed); 1 it failed or its result is not valid (the reason is printed), or a run\n"
          "or the trace file failed; 2 bad option or argument.\n",
          k_prog);
}

/* --apply-args: the config imest_comm_apply() fills from r, as imest-replay options (the
   fields it leaves alone, e.g. sigma with IMEST_COMM_FLAG_ROTOR_HF and no slip-frequency
   value, are not printed). */
static int print_apply_args(const imest_comm_result_t *r)
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  const float tr0 = cfg.tr_nominal_s;
  if (imest_comm_apply(r, &cfg) < 0) {
    fprintf(stderr, "%s: the result is not valid (%s): nothing to apply\n", k_prog,
            imest_comm_reason_name(r->reason));
    return 1;
  }
  printf("--pole-pairs %u --ls %.9g", cfg.pole_pairs, (double)cfg.ls_h);
  if (!(r->flags & IMEST_COMM_FLAG_ROTOR_HF) || (r->flags & IMEST_COMM_FLAG_SIGMA_SLIP))
    printf(" --sigma %.9g --sigma-uncertainty %.9g", (double)cfg.sigma, (double)cfg.sigma_uncertainty);
  printf(" --ls-uncertainty %.9g --rs %.9g", (double)cfg.ls_uncertainty, (double)cfg.rs_nominal_ohm);
  if (cfg.tr_nominal_s != tr0) printf(" --tr-nominal %.9g", (double)cfg.tr_nominal_s);
  if (cfg.rotor_hf_rr_ratio > 0.0f)
    printf(" --rotor-hf-rr %.9g --rotor-hf-sigma %.9g", (double)cfg.rotor_hf_rr_ratio,
           (double)cfg.rotor_hf_sigma_ratio);
  for (unsigned int k = 0; k < cfg.ls_curve_points; ++k)
    printf("%s%.9g:%.9g", k == 0u ? " --ls-curve " : ",", (double)cfg.ls_curve_i_a[k],
           (double)cfg.ls_curve_h[k]);
  const imest_inverter_t *v = &cfg.inverter;
  printf("\n--dead-time %.9g --v-switch %.9g --r-switch %.9g --v-diode %.9g --r-diode %.9g --i-band %.9g "
         "--inverter-uncertainty %.9g",
         (double)v->dead_time_s, (double)v->v_switch_v, (double)v->r_switch_ohm, (double)v->v_diode_v,
         (double)v->r_diode_ohm, (double)v->i_band_a, (double)v->uncertainty);
  /* the bus only matters to measured phase voltages with a deep-bar rotor (the duty input has its own) */
  if (cfg.rotor_hf_rr_ratio > 0.0f) printf(" --inverter-vdc %.9g", (double)cfg.inverter_vdc_v);
  printf("\n");
  return 0;
}

static int parse3(tool_args_t *a, double v[3])
{
  const char *s = tool_args_value(a);
  if (s == NULL) return -1;
  char *end;
  for (int k = 0; k < 3; ++k) {
    v[k] = strtod(s, &end);
    if (end == s || !isfinite(v[k]) || (k < 2 && *end != ',') || (k == 2 && *end != '\0')) {
      fprintf(stderr, "%s: %s needs three numbers A,B,C\n", k_prog, a->opt);
      return -1;
    }
    s = end + 1;
  }
  return 0;
}

static double pct(double id, double tr)
{
  return 100.0 * (id - tr) / tr;
}

static void row(const char *name, double scale, double id, double tr, const char *note)
{
  printf("  %-26s %12.5g %12.5g %+9.3f %%  %s\n", name, id * scale, tr * scale, pct(id, tr),
         note ? note : "");
}

static void print_value(const char *name, const imest_comm_value_t *v)
{
  printf("%s %.9g\n%s.std_rel %.9g\n%s.spread_rel %.9g\n", name, (double)v->value, name, (double)v->std_rel,
         name, (double)v->spread_rel);
}

static void print_floats(const char *name, const float *v, unsigned int n)
{
  for (unsigned int k = 0; k < n; ++k) printf("%s[%u] %.9g\n", name, k, (double)v[k]);
}

static void print_online(const char *which, const comm_online_t *v)
{
  printf("online.%s.windows %d\nonline.%s.tr_valid %d\nonline.%s.rs_valid %d\n", which, v->windows, which,
         v->tr_valid, which, v->rs_valid);
  printf("online.%s.tr_rel %.9g\nonline.%s.rs_rel %.9g\n", which, v->tr_rel, which, v->rs_rel);
  printf("online.%s.tr_all_rel %.9g\nonline.%s.rs_all_rel %.9g\n", which, v->tr_all_rel, which,
         v->rs_all_rel);
}

/* --result: every field of the result, for comparing two builds (name value per line). */
static void print_result(const imest_comm_result_t *r, const imest_comm_axis_fit_t fit[3])
{
  printf("state %d\nreason %d\nstage %d\nvalid %d\nflags %u\n", r->state, r->reason, r->stage, r->valid,
         r->flags);
  printf("time_s %.9g\ni_peak_a %.9g\nvdc_v %.9g\n", (double)r->time_s, (double)r->i_peak_a,
         (double)r->vdc_v);
  print_floats("i_offset_a", r->i_offset_a, 3u);
  print_floats("i_gain_rel", r->i_gain_rel, 3u);
  for (int k = 0; k < 3; ++k) printf("wiring_map[%d] %d\n", k, r->wiring_map[k]);
  print_value("rs_ohm", &r->rs_ohm);
  print_floats("rs_axis_ohm", r->rs_axis_ohm, 3u);
  print_value("sigma_ls_h", &r->sigma_ls_h);
  print_value("sigma_ls_hf_h", &r->sigma_ls_hf_h);
  print_value("sigma_ls_slip_h", &r->sigma_ls_slip_h);
  printf("slip_test_hz %.9g\n", (double)r->slip_test_hz);
  print_value("tr_s", &r->tr_s);
  print_value("rr_ohm", &r->rr_ohm);
  print_value("rr_hf_ohm", &r->rr_hf_ohm);
  print_value("rr_slip_ohm", &r->rr_slip_ohm);
  print_value("ls_standstill_h", &r->ls_standstill_h);
  const imest_inverter_t *inv = &r->inverter;
  printf("inverter.dead_time_s %.9g\ninverter.v_switch_v %.9g\ninverter.v_diode_v %.9g\n"
         "inverter.r_switch_ohm %.9g\ninverter.r_diode_ohm %.9g\ninverter.i_band_a %.9g\n"
         "inverter.uncertainty %.9g\n",
         (double)inv->dead_time_s, (double)inv->v_switch_v, (double)inv->v_diode_v, (double)inv->r_switch_ohm,
         (double)inv->r_diode_ohm, (double)inv->i_band_a, (double)inv->uncertainty);
  print_value("dead_time_s", &r->dead_time_s);
  print_value("v_threshold_v", &r->v_threshold_v);
  print_value("dr_ohm", &r->dr_ohm);
  printf("dc_fit_rms_v %.9g\nrotor_moved_rad %.9g\n", (double)r->dc_fit_rms_v, (double)r->rotor_moved_rad);
  print_value("ls_h", &r->ls_h);
  print_value("sigma", &r->sigma);
  printf("pole_pairs %u\nencoder_dir %d\nencoder_cpr %.9g\nspeed_ratio %.9g\nslip %.9g\nneg_seq_rel %.9g\n",
         r->pole_pairs, r->encoder_dir, (double)r->encoder_cpr, (double)r->speed_ratio, (double)r->slip,
         (double)r->neg_seq_rel);
  printf("rotating_r_ohm %.9g\nrotating_i_a %.9g\nrotating_f_hz %.9g\nls_curve_points %u\n",
         (double)r->rotating_r_ohm, (double)r->rotating_i_a, (double)r->rotating_f_hz, r->ls_curve_points);
  print_floats("ls_curve_i_a", r->ls_curve_i_a, r->ls_curve_points < 4u ? r->ls_curve_points : 4u);
  print_floats("ls_curve_h", r->ls_curve_h, r->ls_curve_points < 4u ? r->ls_curve_points : 4u);
  for (int k = 0; k < 3; ++k) {
    const imest_comm_axis_fit_t *f = &fit[k];
    const float v[] = {f->r_ohm,     f->r_std,   f->td_s,     f->td_std,  f->vth_v,  f->vth_std,
                       f->dr_ohm,    f->dr_std,  f->tau_s,    f->tau_std, f->lm_h,   f->slsig_h,
                       f->slsig_std, f->rhf_ohm, f->gain_dev, f->rms_v,   f->i_top_a};
    static const char *const names[] = {"r_ohm",     "r_std",   "td_s",     "td_std",  "vth_v",  "vth_std",
                                        "dr_ohm",    "dr_std",  "tau_s",    "tau_std", "lm_h",   "slsig_h",
                                        "slsig_std", "rhf_ohm", "gain_dev", "rms_v",   "i_top_a"};
    for (int j = 0; j < (int)(sizeof v / sizeof v[0]); ++j)
      printf("fit[%d].%s %.9g\n", k, names[j], (double)v[j]);
    printf("fit[%d].ok %d\nfit[%d].separable %d\n", k, f->ok, k, f->separable);
  }
}

int main(int argc, char **argv)
{
  comm_sim_opts_t o;
  const char *preset = "4kw";
  for (int k = 1; k + 1 < argc; ++k)
    if (strcmp(argv[k], "--preset") == 0) preset = argv[k + 1];
  for (int k = 1; k < argc; ++k)
    if (strncmp(argv[k], "--preset=", 9) == 0) preset = argv[k] + 9;
  if (comm_sim_defaults(&o, preset) != 0) {
    fprintf(stderr, "%s: unknown preset '%s' (%s)\n", k_prog, preset, imsim_preset_names());
    return 2;
  }
  int csv = 0, apply_args = 0, result = 0, verbose = 0, sensitivity = 0, online = 0, duty_input = 0;
  double load = 1.0;
  const char *trace = NULL;
  tool_args_t a;
  tool_args_init(&a, k_prog, argc, argv);
  tool_arg_kind_t kind;
  while ((kind = tool_args_next(&a)) != TOOL_ARG_END) {
    if (kind == TOOL_ARG_OPERAND) {
      fprintf(stderr, "%s: unexpected argument '%s' (see --help)\n", k_prog, a.operand);
      return 2;
    }
    double v;
    const int std_rc = tool_args_standard(&a, usage);
    if (std_rc >= 0) {
      return std_rc;
    } else if (tool_args_is(&a, "--preset")) {
      if (tool_args_value(&a) == NULL) return 2;
    } else if (tool_args_is(&a, "--no-rotation")) {
      if (tool_args_flag(&a)) return 2;
      o.allow_rotation = 0;
    } else if (tool_args_is(&a, "--no-nameplate")) {
      if (tool_args_flag(&a)) return 2;
      o.nameplate_speed = 0;
    } else if (tool_args_is(&a, "--ideal-sensors")) {
      if (tool_args_flag(&a)) return 2;
      o.ideal_sensors = 1;
    } else if (tool_args_is(&a, "--encoder-reversed")) {
      if (tool_args_flag(&a)) return 2;
      o.encoder_reversed = 1;
    } else if (tool_args_is(&a, "--swap-sensors")) {
      if (tool_args_flag(&a)) return 2;
      o.swap_sensors_bc = 1;
    } else if (tool_args_is(&a, "--encoder-stuck")) {
      if (tool_args_flag(&a)) return 2;
      o.encoder_stuck = 1;
    } else if (tool_args_is(&a, "--two-sensors")) {
      if (tool_args_flag(&a)) return 2;
      o.two_sensors = 1;
    } else if (tool_args_is(&a, "--verbose")) {
      if (tool_args_flag(&a)) return 2;
      verbose = 1;
    } else if (tool_args_is(&a, "--duty")) {
      if (tool_args_flag(&a)) return 2;
      duty_input = 1;
    } else if (tool_args_is(&a, "--online")) {
      if (tool_args_flag(&a)) return 2;
      online = 1;
    } else if (tool_args_is(&a, "--sensitivity")) {
      if (tool_args_flag(&a)) return 2;
      sensitivity = 1;
    } else if (tool_args_is(&a, "--load")) {
      if (tool_args_number(&a, &load) || load < 0.0 || load > 2.0) {
        fprintf(stderr, "%s: --load needs a fraction of rated torque in [0, 2]\n", k_prog);
        return 2;
      }
    } else if (tool_args_is(&a, "--real-motor")) {
      if (tool_args_flag(&a)) return 2;
      o.real_motor = 1;
    } else if (tool_args_is(&a, "--saturation")) {
      if (tool_args_number(&a, &o.sat_fraction) || !(o.sat_fraction >= 0.0 && o.sat_fraction < 0.6)) {
        fprintf(stderr, "%s: --saturation needs a fraction in [0, 0.6)\n", k_prog);
        return 2;
      }
      o.real_off = o.sat_fraction > 0.0 ? o.real_off & ~(unsigned)COMM_SIM_OFF_SATURATION
                                        : o.real_off | COMM_SIM_OFF_SATURATION;
    } else if (tool_args_is(&a, "--iron-loss")) {
      if (tool_args_number(&a, &o.iron_loss_fraction) ||
          !(o.iron_loss_fraction >= 0.0 && o.iron_loss_fraction < 0.2)) {
        fprintf(stderr, "%s: --iron-loss needs a fraction in [0, 0.2)\n", k_prog);
        return 2;
      }
      o.real_off = o.iron_loss_fraction > 0.0 ? o.real_off & ~(unsigned)COMM_SIM_OFF_IRON_LOSS
                                              : o.real_off | COMM_SIM_OFF_IRON_LOSS;
    } else if (tool_args_is(&a, "--rotor")) {
      const char *rv = tool_args_value(&a);
      if (rv == NULL) return 2;
      char *end = NULL;
      const int single = strcmp(rv, "single") == 0;
      o.rotor_cage_ratio = strncmp(rv, "double-cage:", 12) == 0 ? strtod(rv + 12, &end) : 0.0;
      if (!single &&
          (end == NULL || *end != '\0' || !(o.rotor_cage_ratio > 1.0 && o.rotor_cage_ratio <= 4.0))) {
        fprintf(stderr, "%s: --rotor needs single or double-cage:RATIO with RATIO in (1, 4]\n", k_prog);
        return 2;
      }
      o.real_off =
          single ? o.real_off | COMM_SIM_OFF_DOUBLE_CAGE : o.real_off & ~(unsigned)COMM_SIM_OFF_DOUBLE_CAGE;
    } else if (tool_args_is(&a, "--result")) {
      if (tool_args_flag(&a)) return 2;
      result = 1;
    } else if (tool_args_is(&a, "--csv")) {
      if (tool_args_flag(&a)) return 2;
      csv = 1;
    } else if (tool_args_is(&a, "--apply-args")) {
      if (tool_args_flag(&a)) return 2;
      apply_args = 1;
    } else if (tool_args_is(&a, "--trace")) {
      if ((trace = tool_args_value(&a)) == NULL) return 2;
    } else if (tool_args_is(&a, "--offsets")) {
      if (parse3(&a, o.i_offset_a)) return 2;
    } else if (tool_args_is(&a, "--gain-errors")) {
      if (parse3(&a, o.i_gain_err)) return 2;
    } else {
      static const char *const num[] = {
          "--speed-frac", "--i-max",   "--r-series", "--dead-time",      "--v-switch",    "--r-switch",
          "--v-diode",    "--r-diode", "--seed",     "--encoder-counts", "--cpr-assumed", "--trace-decimate"};
      int which = -1;
      for (int k = 0; k < (int)(sizeof num / sizeof num[0]); ++k)
        if (tool_args_is(&a, num[k])) which = k;
      if (which < 0) return tool_args_unknown(&a);
      if (tool_args_number(&a, &v)) return 2;
      if (v < 0.0 || (which == 0 && (v < 0.05 || v > 1.0))) {
        fprintf(stderr, "%s: %s out of range\n", k_prog, num[which]);
        return 2;
      }
      switch (which) {
      case 0: o.speed_frac = v; break;
      case 1: o.i_max_a = v; break;
      case 2: o.r_series_ohm = v; break;
      case 3: o.dead_time_s = v; break;
      case 4: o.v_switch_v = v; break;
      case 5: o.r_switch_ohm = v; break;
      case 6: o.v_diode_v = v; break;
      case 7: o.r_diode_ohm = v; break;
      case 8: o.seed = (unsigned long)v; break;
      case 9: o.encoder_counts = (int)v; break;
      case 10: o.cpr_assumed = v; break;
      default: o.trace_decimate = v >= 1.0 ? (unsigned int)v : 1u; break;
      }
    }
  }
  if (sensitivity) {
    comm_sens_opts_t so;
    memset(&so, 0, sizeof so);
    snprintf(so.preset, sizeof so.preset, "%s", o.preset);
    so.load_frac = load;
    so.duration_s = 14.0;
    so.settle_s = 4.0;
    so.seed = o.seed;
    so.duty = duty_input;
    comm_sens_t r;
    if (comm_sensitivity(&so, &r) != 0) {
      fprintf(stderr, "%s: the sensitivity runs failed for %s\n", k_prog, o.preset);
      return 1;
    }
    if (csv) {
      printf("preset,load,tr_base_pct,rs_base_pct,valid,windows,tr_per_ls_pct,rs_per_ls_pct,tr_per_sigma_pct,"
             "rs_per_sigma_pct,tr_per_0p1v_pct,rs_per_0p1v_pct\n");
      printf("%s,%.2f,%.3f,%.3f,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", o.preset, load, 100.0 * r.base.tr_rel,
             100.0 * r.base.rs_rel, r.base.valid, r.base.windows, 100.0 * r.tr_per_ls, 100.0 * r.rs_per_ls,
             100.0 * r.tr_per_sigma, 100.0 * r.rs_per_sigma, 100.0 * r.tr_per_dv, 100.0 * r.rs_per_dv);
    } else {
      printf(
          "%s: preset %s at %.0f %% of rated torque, phase-voltage input, true constants: T_R %+.3f %%, R_S "
          "%+.3f %% (%d of %d windows valid)\n",
          k_prog, o.preset, 100.0 * load, 100.0 * r.base.tr_rel, 100.0 * r.base.rs_rel, r.base.valid,
          r.base.windows);
      printf("  error per +1 %% of L_S:    T_R %+.3f %%, R_S %+.3f %%\n", 100.0 * r.tr_per_ls,
             100.0 * r.rs_per_ls);
      printf("  error per +1 %% of sigma:  T_R %+.3f %%, R_S %+.3f %%\n", 100.0 * r.tr_per_sigma,
             100.0 * r.rs_per_sigma);
      printf("  error per +0.1 V per leg: T_R %+.3f %%, R_S %+.3f %%\n", 100.0 * r.tr_per_dv,
             100.0 * r.rs_per_dv);
    }
    return 0;
  }
  if (trace) {
    o.trace = strcmp(trace, "-") == 0 ? stdout : fopen(trace, "w");
    if (o.trace == NULL) {
      fprintf(stderr, "%s: cannot write %s\n", k_prog, trace);
      return 1;
    }
  }
  static comm_sim_out_t out;
  if (comm_sim_run(&o, &out) != 0) return 1;
  if (o.trace && o.trace != stdout) fclose(o.trace);
  const imest_comm_result_t *r = &out.r;
  const imsim_config_t *sc = &out.sim;
  if (apply_args) return print_apply_args(r);
  comm_online_t on_id, on_true;
  if (online && r->valid) {
    if (comm_online_run(&o, load, 20.0, r, &on_id) != 0 ||
        comm_online_run(&o, load, 20.0, NULL, &on_true) != 0) {
      fprintf(stderr, "%s: the online run failed\n", k_prog);
      return 1;
    }
  }
  if (result) {
    print_result(r, out.fit);
    if (online && r->valid) {
      print_online("identified", &on_id);
      print_online("true", &on_true);
    }
    return r->valid ? 0 : 1;
  }
  if (csv) {
    printf(
        "preset,state,reason,valid,time_s,i_peak_a,rs_err_pct,rs_winding_err_pct,sigma_ls_err_pct,ls_err_pct,"
        "sigma_err_pct,tr_err_pct,np,np_true,encoder_dir,dead_time_err_us,inv_err_model_v,inv_err_total_v\n");
    printf("%s,%s,%s,%d,%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%u,%u,%d,%.4f,%.4f,%.4f\n", o.preset,
           imest_comm_state_name(r->state), imest_comm_reason_name(r->reason), r->valid, (double)r->time_s,
           out.i_peak_true_a, pct((double)r->rs_ohm.value, out.rs_identifiable_ohm),
           pct((double)r->rs_ohm.value, out.rs_ohm), pct((double)r->sigma_ls_h.value, out.sigma_ls_h),
           pct((double)r->ls_h.value, out.ls_h), pct((double)r->sigma.value, out.sigma),
           pct((double)r->tr_s.value, out.tr_s), r->pole_pairs, out.pole_pairs, r->encoder_dir,
           ((double)r->inverter.dead_time_s - sc->dead_time_s) * 1e6, out.inv_err_model_v,
           out.inv_err_total_v);
    return r->valid ? 0 : 1;
  }
  printf(
      "%s: preset %s, %.0f V bus, %.0f kHz PWM, dead time %.2g us, switch %.2g V + %.4g ohm, diode %.2g V + "
      "%.4g ohm\n",
      k_prog, o.preset, sc->vdc_v, sc->carrier_hz / 1000.0, sc->dead_time_s * 1e6, sc->v_switch_v,
      sc->r_switch_ohm, sc->v_diode_v, sc->r_diode_ohm);
  printf("state %s%s%s, %s, %.2f s (simulated %.2f s), peak phase current %.3f A (limit %.3f A)\n",
         imest_comm_state_name(r->state), r->reason ? ": " : "",
         r->reason ? imest_comm_reason_name(r->reason) : "", r->valid ? "valid" : "not valid",
         (double)r->time_s, out.sim_time_s, out.i_peak_true_a, (double)out.cc.i_max_a);
  printf("stages: ");
  for (int k = 0; k < IMEST_COMM_STAGE_END; ++k)
    if (out.stage_s[k] > 0.0)
      printf("%s %.2f s (%.2f A)  ", imest_comm_stage_name(k), out.stage_s[k], out.stage_ipk_a[k]);
  printf("\n\n  %-26s %12s %12s %10s\n", "quantity", "identified", "true", "error");
  char note[160];
  snprintf(note, sizeof note, "true = winding %.5g + min(r_sw, r_d) %.4g; vs winding %+.3f %%", out.rs_ohm,
           out.rs_identifiable_ohm - out.rs_ohm, pct((double)r->rs_ohm.value, out.rs_ohm));
  row("R_S [ohm]", 1.0, (double)r->rs_ohm.value, out.rs_identifiable_ohm, note);
  snprintf(note, sizeof note, "axes %.5g %.5g %.5g, spread %.2g %%", (double)r->rs_axis_ohm[0],
           (double)r->rs_axis_ohm[1], (double)r->rs_axis_ohm[2], 100.0 * (double)r->rs_ohm.spread_rel);
  printf("  %-26s %s\n", "", note);
  snprintf(note, sizeof note, "spread %.2g %%", 100.0 * (double)r->sigma_ls_h.spread_rel);
  row("sigma*L_S [mH]", 1e3, (double)r->sigma_ls_h.value, out.sigma_ls_h, note);
  snprintf(note, sizeof note, "square wave at fs/8; spread %.2g %%",
           100.0 * (double)r->sigma_ls_hf_h.spread_rel);
  row("  at fs/8", 1e3, (double)r->sigma_ls_hf_h.value, out.sigma_ls_h, note);
  snprintf(note, sizeof note, "tones %.3g and %.3g Hz; spread %.2g %%", (double)r->slip_test_hz,
           3.0 * (double)r->slip_test_hz, 100.0 * (double)r->sigma_ls_slip_h.spread_rel);
  row("  at slip frequency", 1e3, (double)r->sigma_ls_slip_h.value, out.sigma_ls_h, note);
  snprintf(note, sizeof note, "%s; standstill %.5g mH (%+.2f %%)",
           (r->flags & IMEST_COMM_FLAG_LS_STANDSTILL) ? "standstill" : "rotating",
           1e3 * (double)r->ls_standstill_h.value, pct((double)r->ls_standstill_h.value, out.ls_h));
  row("L_S [mH]", 1e3, (double)r->ls_h.value, out.ls_h, note);
  if (fabs(out.ls_preset_h - out.ls_h) > 1e-9 * out.ls_h)
    printf("  %-26s %s %.5g mH (the preset's, at rated load's main flux)\n", "",
           "true values at the rated flux at no load; L_S", 1e3 * out.ls_preset_h);
  row("sigma", 1.0, (double)r->sigma.value, out.sigma,
      (r->flags & IMEST_COMM_FLAG_SIGMA_SLIP) ? "rotor_hf: sigma*L_S from the slip-frequency test"
      : (r->flags & IMEST_COMM_FLAG_ROTOR_HF)
          ? "rotor_hf: sigma*L_S at fs/8 is the rotor's high-frequency one"
          : NULL);
  row("T_R [ms]", 1e3, (double)r->tr_s.value, out.tr_s, "flux tails");
  row("R_R' [ohm]", 1.0, (double)r->rr_ohm.value, out.rr_ohm, "(1-sigma) L_S / T_R");
  {
    /* with the firmware's counts assumed right, n_p x the firmware's angle is what must match */
    const double cpr_fw = o.cpr_assumed > 0.0 ? o.cpr_assumed : (double)sc->encoder_counts;
    const double np_equiv = (double)r->pole_pairs * (double)sc->encoder_counts / cpr_fw;
    const char *verdict = r->pole_pairs == out.pole_pairs                  ? "ok"
                          : fabs(np_equiv - (double)out.pole_pairs) < 1e-9 ? "ok x angle"
                                                                           : "WRONG";
    printf("  %-26s %12u %12u %9s   %s\n", "n_p", r->pole_pairs, out.pole_pairs, verdict,
           (r->flags & IMEST_COMM_FLAG_NP_NAMEPLATE)
               ? "from the rated speed"
               : "from the speed ratio (n_p x the firmware's angle is what counts)");
  }
  const int dir_true = o.encoder_reversed ? -1 : 1;
  printf("  %-26s %12d %12d %9s   speed ratio %.5f\n", "encoder direction", r->encoder_dir, dir_true,
         r->encoder_dir == dir_true ? "ok" : "WRONG", (double)r->speed_ratio);
  printf("  %-26s %12.6g %12d %9s\n", "encoder counts/rev", (double)r->encoder_cpr, sc->encoder_counts,
         (double)r->encoder_cpr == sc->encoder_counts ? "ok" : "differs");
  printf("  %-26s %12.4f %12.4f %+9.3f us\n", "dead time [us]", 1e6 * (double)r->inverter.dead_time_s,
         1e6 * sc->dead_time_s, 1e6 * ((double)r->inverter.dead_time_s - sc->dead_time_s));
  printf("  %-26s %12.4f %12.4f %+9.4f V\n", "(V_sw0 + V_d0)/2 [V]", (double)r->v_threshold_v.value,
         0.5 * (sc->v_switch_v + sc->v_diode_v),
         (double)r->v_threshold_v.value - 0.5 * (sc->v_switch_v + sc->v_diode_v));
  printf("  %-26s %12.5f %12.5f %+9.5f ohm\n", "r_sw - r_d [ohm]", (double)r->dr_ohm.value,
         sc->r_switch_ohm - sc->r_diode_ohm, (double)r->dr_ohm.value - (sc->r_switch_ohm - sc->r_diode_ohm));
  printf("  %-26s %12.4f (0: per leg from the duties; ripple peak V_dc / (8 sigma L_S f_pwm) %.4f A), model "
         "uncertainty %.3f\n",
         "i_band [A]", (double)r->inverter.i_band_a, out.ripple_peak_a, (double)r->inverter.uncertainty);
  printf("  inverter per-leg voltage error, |i| in [2 ripple, i_max], duty 0.05..0.95: model vs devices "
         "(common slope\n"
         "  in R_S) max %.3f V; model + R_S vs devices + winding max %.3f V, rms %.3f V\n",
         out.inv_err_model_v, out.inv_err_total_v, out.inv_err_rms_v);
  printf("  %-26s", "sensor gains (rel. mean)");
  for (int x = 0; x < 3; ++x) {
    const double gm = (o.i_gain_err[0] + o.i_gain_err[1] + o.i_gain_err[2]) / 3.0;
    printf(" %.5f (true %.5f)", (double)r->i_gain_rel[x], (1.0 + o.i_gain_err[x]) / (1.0 + gm));
  }
  printf("\n  %-26s", "sensor offsets [A]");
  for (int x = 0; x < 3; ++x) printf(" %.4f (true %.4f)", (double)r->i_offset_a[x], o.i_offset_a[x]);
  if (verbose)
    for (int k = 0; k < 3; ++k) {
      const imest_comm_axis_fit_t *f = &out.fit[k];
      printf("\n  axis %d: R %.5f (%.2g) td %.4f us (%.2g) vth %.4f (%.2g) dr %.5f (%.2g) tau %.5f (%.2g) lm "
             "%.5f sl %.6f (%.2g) "
             "rhf %.4f gain %.5f rms %.4f",
             k, (double)f->r_ohm, (double)f->r_std, (double)f->td_s * 1e6, (double)f->td_std * 1e6,
             (double)f->vth_v, (double)f->vth_std, (double)f->dr_ohm, (double)f->dr_std, (double)f->tau_s,
             (double)f->tau_std, (double)f->lm_h, (double)f->slsig_h, (double)f->slsig_std,
             (double)f->rhf_ohm, (double)f->gain_dev, (double)f->rms_v);
    }
  if (online && r->valid) {
    const comm_online_t *v[2] = {&on_id, &on_true};
    printf("\n  online estimator on this drive, %.0f %% load, duty-cycle input, windows after 6 s of 20 s:",
           100.0 * load);
    for (int k = 0; k < 2; ++k)
      printf("\n    %-10s constants: T_R %+.3f %% (all windows), %+.3f %% (valid: %d of %d); R_S %+.3f %% "
             "(all), %+.3f "
             "%% (valid: %d); status %s",
             k == 0 ? "identified" : "true", 100.0 * v[k]->tr_all_rel, 100.0 * v[k]->tr_rel, v[k]->tr_valid,
             v[k]->windows, 100.0 * v[k]->rs_all_rel, 100.0 * v[k]->rs_rel, v[k]->rs_valid,
             imest_reason_name(v[k]->reason));
  }
  if (r->ls_curve_points > 0u) {
    printf("\n  magnetising curve (no load; true L_S at each current):");
    for (unsigned int j = 0u; j < r->ls_curve_points && j < 4u; ++j) {
      double ls_t = out.ls_h;
      (void)comm_sim_true_at(sc, (double)r->ls_curve_i_a[j], &ls_t, NULL, NULL);
      printf("\n    %8.4f A  %9.5g mH  true %9.5g mH  %+7.3f %%", (double)r->ls_curve_i_a[j],
             1e3 * (double)r->ls_curve_h[j], 1e3 * ls_t, pct((double)r->ls_curve_h[j], ls_t));
    }
    printf("\n    points' uncertainty %.2g %%; L_S over the curve %.2g %% (its flux dependence); rated flux "
           "at %.4f A (true %.4f A)",
           100.0 * (double)r->ls_h.std_rel, 100.0 * (double)r->ls_h.spread_rel, (double)r->rotating_i_a,
           out.i_rated_flux_a);
  }
  printf(
      "\n  rotor travel at standstill %.2g rad; rotating run %.2f Hz, %.3f A, slip %.2g, negative sequence "
      "%.3g; flags "
      "0x%04x\n",
      out.theta_max_standstill_rad, (double)r->rotating_f_hz, (double)r->rotating_i_a, (double)r->slip,
      (double)r->neg_seq_rel, r->flags);
  return r->valid ? 0 : 1;
}
