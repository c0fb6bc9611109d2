/* imest-sim: writes a simulated induction-motor record as CSV. A thin layer on the imsim API. */
#define _POSIX_C_SOURCE 200809L
#include "imsim_cli.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static const char HEADER[] =
    "t,u_a,u_b,u_c,i_a,i_b,i_c,theta,"
    "T_R_true_s,R_S_true_ohm,speed_rad_s,torque_nm,load_nm,psi_r_wb,temp_stator_c,temp_rotor_c,"
    "i_a_true,i_b_true,i_c_true,theta_true,u_a_true,u_b_true,u_c_true,"
    "ifoc_torque_ref_nm,ifoc_flux_ref_wb,ifoc_tr_s,ifoc_speed_ref_rad_s";

const char *imsim_cli_header(void) { return HEADER; }

static const char USAGE[] =
    "usage: imest-sim [options]\n"
    "Simulates the induction motor of Wang et al. (IEEE TCST 2007) and writes CSV:\n"
    "  t,u_a,u_b,u_c,i_a,i_b,i_c,theta (measured) followed by truth columns.\n"
    "\n"
    "  --preset exp1|exp2    experiment preset (applied before every other flag)\n"
    "  --duration S          simulated time (rows t = 0 .. S)\n"
    "  --fs HZ               sampling frequency (default 4000)\n"
    "  --out FILE            output file, '-' = stdout (default -)\n"
    "  --decimate N          write every N-th sample (default 1)\n"
    "motor:\n"
    "  --pole-pairs N --ls H --lr H --sigma X --rs OHM --tr S --j KGM2 --b NMS\n"
    "supply:\n"
    "  --supply sine|vf|pwm|ifoc   --vll V (line-line rms)   --freq HZ\n"
    "  --vf-ramp S --vf-boost V    --carrier-hz HZ --vdc V --dead-time S\n"
    "  --pwm-segments        integrate piecewise between PWM switching instants (reference accuracy,\n"
    "                        ~2.3x slower; default: one step per half carrier period, see README)\n"
    "  --start rest|steady   (steady: begin in the sinusoidal steady state, full load)\n"
    "load:\n"
    "  --load-nm NM --load-on S --load-ramp S\n"
    "IFOC:\n"
    "  --ifoc-tr S --ifoc-flux WB --ifoc-mode speed|torque --speed-ref RPM --speed-ramp S\n"
    "  --torque-ref NM --torque-limit NM --ifoc-ideal-stage\n"
    "sensors:\n"
    "  --ideal-sensors (exact samples: no quantisation, noise, clipping, AA, encoder)\n"
    "  --seed N --adc-bits N --i-range A --u-range V --noise-lsb X --encoder-counts N\n"
    "  --i-offset A,A,A --u-offset V,V,V --i-gain-err X,X,X   per-phase sensor offsets and\n"
    "                        relative gain errors (default 0)\n"
    "  --aa-hz HZ (0 = off) --vmeas auto|avg|aa|inst\n"
    "thermal:\n"
    "  --no-thermal --t-amb C --thermal-speedup X\n"
    "integrator:\n"
    "  --integrator fast|rk4 --rk4-substeps N --steps-per-sample N\n"
    "  --progress / --no-progress (default: bar on stderr when it is a terminal)\n";

static int perr(char *err, size_t n, const char *a, const char *b) {
  snprintf(err, n, "%s%s", a, b);
  return -1;
}

static int num(const char *s, double *v) {
  if (s == NULL || *s == '\0') return -1;
  char *end = NULL;
  errno = 0;
  const double d = strtod(s, &end);
  if (errno != 0 || end == s || *end != '\0' || !isfinite(d)) return -1;
  *v = d;
  return 0;
}

static int inum(const char *s, long *v) {
  if (s == NULL || *s == '\0') return -1;
  char *end = NULL;
  errno = 0;
  const long d = strtol(s, &end, 10);
  if (errno != 0 || end == s || *end != '\0') return -1;
  *v = d;
  return 0;
}

typedef enum { K_D, K_I, K_U64, K_STR } kind;

int imsim_cli_parse(int argc, char **argv, imsim_config *c, imsim_cli_opts *o, char *err, size_t errlen) {
  o->out = "-";
  o->decimate = 1;
  o->progress = -1;
  o->help = 0;
  err[0] = '\0';
  /* pass 1: preset */
  imsim_config_default(c);
  for (int a = 1; a < argc; ++a) {
    const char *arg = argv[a];
    const char *val = NULL;
    if (strncmp(arg, "--preset=", 9) == 0) val = arg + 9;
    else if (strcmp(arg, "--preset") == 0) {
      if (a + 1 >= argc) return perr(err, errlen, "missing value for ", arg);
      val = argv[a + 1];
    }
    if (val != NULL && imsim_config_preset(c, val) != 0)
      return perr(err, errlen, "unknown preset (exp1|exp2): ", val);
  }
  /* pass 2: everything */
  for (int a = 1; a < argc; ++a) {
    char name[64];
    const char *arg = argv[a];
    const char *val = NULL;
    if (strncmp(arg, "--", 2) != 0) return perr(err, errlen, "unexpected argument: ", arg);
    const char *eq = strchr(arg, '=');
    size_t len = eq != NULL ? (size_t)(eq - arg) : strlen(arg);
    if (len >= sizeof name) return perr(err, errlen, "unknown flag: ", arg);
    memcpy(name, arg, len);
    name[len] = '\0';
    if (eq != NULL) val = eq + 1;

    /* flags without values */
    if (strcmp(name, "--help") == 0 || strcmp(name, "--ideal-sensors") == 0 || strcmp(name, "--no-thermal") == 0 ||
        strcmp(name, "--ifoc-ideal-stage") == 0 || strcmp(name, "--progress") == 0 ||
        strcmp(name, "--pwm-segments") == 0 ||
        strcmp(name, "--no-progress") == 0) {
      if (eq != NULL) return perr(err, errlen, "flag takes no value: ", name);
      if (strcmp(name, "--help") == 0) o->help = 1;
      else if (strcmp(name, "--ideal-sensors") == 0) c->ideal_sensors = true;
      else if (strcmp(name, "--no-thermal") == 0) c->thermal = false;
      else if (strcmp(name, "--ifoc-ideal-stage") == 0) c->ifoc_ideal_stage = true;
      else if (strcmp(name, "--progress") == 0) o->progress = 1;
      else if (strcmp(name, "--pwm-segments") == 0) c->pwm_moments = false;
      else o->progress = 0;
      continue;
    }
    if (val == NULL) {
      if (a + 1 >= argc) return perr(err, errlen, "missing value for ", name);
      val = argv[++a];
    }
    double d = 0.0;
    long l = 0;
#define DBL(flag, field, cond, what)                                                        \
  if (strcmp(name, flag) == 0) {                                                            \
    if (num(val, &d) != 0 || !(cond)) {                                                      \
      snprintf(err, errlen, "invalid value for %s: '%s' (%s)", flag, val, what);           \
      return -1;                                                                            \
    }                                                                                       \
    field = d;                                                                              \
    continue;                                                                               \
  }
#define INT(flag, field, lo, hi)                                                            \
  if (strcmp(name, flag) == 0) {                                                            \
    if (inum(val, &l) != 0 || l < (lo) || l > (hi)) {                                        \
      snprintf(err, errlen, "invalid value for %s: '%s' (integer %ld..%ld)", flag, val,     \
               (long)(lo), (long)(hi));                                                     \
      return -1;                                                                            \
    }                                                                                       \
    field = (int)l;                                                                         \
    continue;                                                                               \
  }
    if (strcmp(name, "--preset") == 0) continue; /* done in pass 1 */
    if (strcmp(name, "--out") == 0) {
      if (val[0] == '\0') return perr(err, errlen, "empty value for ", name);
      o->out = val;
      continue;
    }
    if (strcmp(name, "--decimate") == 0) {
      if (inum(val, &l) != 0 || l < 1) return perr(err, errlen, "invalid value for --decimate (integer >= 1): ", val);
      o->decimate = l;
      continue;
    }
    if (strcmp(name, "--seed") == 0) {
      char *end = NULL;
      errno = 0;
      const unsigned long long u = strtoull(val, &end, 10);
      if (errno != 0 || end == val || *end != '\0' || val[0] == '-')
        return perr(err, errlen, "invalid value for --seed (unsigned integer): ", val);
      c->seed = (uint64_t)u;
      continue;
    }
    double *per_phase = strcmp(name, "--i-offset") == 0   ? c->i_offset_a
                        : strcmp(name, "--u-offset") == 0   ? c->u_offset_v
                        : strcmp(name, "--i-gain-err") == 0 ? c->i_gain_err
                                                            : NULL;
    if (per_phase != NULL) {
      const char *p = val;
      for (int k = 0; k < 3; ++k) {
        char *end = NULL;
        const double x = strtod(p, &end);
        if (end == p || !isfinite(x) || (k < 2 ? *end != ',' : *end != '\0'))
          return perr(err, errlen, "expected three comma-separated numbers (phases a,b,c) for ", name);
        per_phase[k] = x;
        p = end + 1;
      }
      continue;
    }
    if (strcmp(name, "--supply") == 0) {
      if (strcmp(val, "sine") == 0) c->supply = IMSIM_SUPPLY_SINE;
      else if (strcmp(val, "vf") == 0) c->supply = IMSIM_SUPPLY_VF;
      else if (strcmp(val, "pwm") == 0) c->supply = IMSIM_SUPPLY_PWM;
      else if (strcmp(val, "ifoc") == 0) c->supply = IMSIM_SUPPLY_IFOC;
      else return perr(err, errlen, "invalid value for --supply (sine|vf|pwm|ifoc): ", val);
      continue;
    }
    if (strcmp(name, "--vmeas") == 0) {
      if (strcmp(val, "auto") == 0) c->vmeas = IMSIM_VMEAS_AUTO;
      else if (strcmp(val, "avg") == 0) c->vmeas = IMSIM_VMEAS_AVG;
      else if (strcmp(val, "aa") == 0) c->vmeas = IMSIM_VMEAS_AA;
      else if (strcmp(val, "inst") == 0) c->vmeas = IMSIM_VMEAS_INST;
      else return perr(err, errlen, "invalid value for --vmeas (auto|avg|aa|inst): ", val);
      continue;
    }
    if (strcmp(name, "--start") == 0) {
      if (strcmp(val, "rest") == 0) c->start = IMSIM_START_REST;
      else if (strcmp(val, "steady") == 0) c->start = IMSIM_START_STEADY;
      else return perr(err, errlen, "invalid value for --start (rest|steady): ", val);
      continue;
    }
    if (strcmp(name, "--ifoc-mode") == 0) {
      if (strcmp(val, "speed") == 0) c->ifoc_mode = IMSIM_IFOC_SPEED;
      else if (strcmp(val, "torque") == 0) c->ifoc_mode = IMSIM_IFOC_TORQUE;
      else return perr(err, errlen, "invalid value for --ifoc-mode (speed|torque): ", val);
      continue;
    }
    if (strcmp(name, "--integrator") == 0) {
      if (strcmp(val, "fast") == 0) c->integrator = IMSIM_INTEGRATOR_FAST;
      else if (strcmp(val, "rk4") == 0) c->integrator = IMSIM_INTEGRATOR_RK4;
      else return perr(err, errlen, "invalid value for --integrator (fast|rk4): ", val);
      continue;
    }
    DBL("--duration", c->duration_s, d >= 0.0, ">= 0 s")
    DBL("--fs", c->fs_hz, d > 0.0, "> 0 Hz")
    INT("--pole-pairs", c->pole_pairs, 1, 64)
    DBL("--ls", c->ls_h, d > 0.0, "> 0 H")
    DBL("--lr", c->lr_h, d > 0.0, "> 0 H")
    DBL("--sigma", c->sigma, d > 0.0 && d < 1.0, "0 < sigma < 1")
    DBL("--rs", c->rs_ohm, d > 0.0, "> 0 ohm")
    DBL("--tr", c->tr_s, d > 0.0, "> 0 s")
    DBL("--j", c->j_kgm2, d > 0.0, "> 0 kg m^2")
    DBL("--b", c->b_nms, d >= 0.0, ">= 0 N m s")
    DBL("--vll", c->vll_v, d >= 0.0, ">= 0 V")
    DBL("--freq", c->freq_hz, d >= 0.0, ">= 0 Hz")
    DBL("--vf-ramp", c->vf_ramp_s, d >= 0.0, ">= 0 s")
    DBL("--vf-boost", c->vf_boost_v, d >= 0.0, ">= 0 V")
    DBL("--load-nm", c->load_nm, 1, "N m")
    DBL("--load-on", c->load_on_s, d >= 0.0, ">= 0 s")
    DBL("--load-ramp", c->load_ramp_s, d >= 0.0, ">= 0 s")
    DBL("--carrier-hz", c->carrier_hz, d > 0.0, "> 0 Hz")
    DBL("--vdc", c->vdc_v, d > 0.0, "> 0 V")
    DBL("--dead-time", c->dead_time_s, d >= 0.0, ">= 0 s")
    DBL("--ifoc-tr", c->ifoc_tr_s, d > 0.0, "> 0 s")
    DBL("--ifoc-flux", c->ifoc_flux_wb, d > 0.0, "> 0 Wb")
    DBL("--speed-ref", c->speed_ref_rpm, 1, "rpm")
    DBL("--speed-ramp", c->speed_ramp_s, d >= 0.0, ">= 0 s")
    DBL("--torque-ref", c->torque_ref_nm, 1, "N m")
    DBL("--torque-limit", c->torque_limit_nm, d > 0.0, "> 0 N m")
    INT("--adc-bits", c->adc_bits, 2, 30)
    DBL("--i-range", c->i_range_a, d > 0.0, "> 0 A")
    DBL("--u-range", c->u_range_v, d > 0.0, "> 0 V")
    DBL("--noise-lsb", c->noise_lsb, d >= 0.0, ">= 0 LSB")
    INT("--encoder-counts", c->encoder_counts, 1, 1000000000)
    DBL("--aa-hz", c->aa_hz, d >= 0.0, ">= 0 Hz (0 = off)")
    DBL("--t-amb", c->t_amb_c, d > -273.15, "degC")
    DBL("--thermal-speedup", c->thermal_speedup, d > 0.0, "> 0")
    INT("--rk4-substeps", c->rk4_substeps, 1, 100000)
    INT("--steps-per-sample", c->steps_per_sample, 0, 100000)
#undef DBL
#undef INT
    return perr(err, errlen, "unknown flag: ", name);
  }
  return 0;
}

/* %.9g is exact to ~1e-9 relative, which is what the spec asks for. */
void imsim_cli_write_row(FILE *f, const imsim_sample *s) {
  fprintf(f,
          "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,"
          "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n",
          s->t, s->u_abc[0], s->u_abc[1], s->u_abc[2], s->i_abc[0], s->i_abc[1], s->i_abc[2], s->theta,
          s->tr_s, s->rs_ohm, s->speed_rad_s, s->torque_nm, s->load_nm, s->psi_r_wb, s->temp_stator_c,
          s->temp_rotor_c, s->i_abc_true[0], s->i_abc_true[1], s->i_abc_true[2], s->theta_true,
          s->u_abc_true[0], s->u_abc_true[1], s->u_abc_true[2], s->ifoc_torque_ref_nm, s->ifoc_flux_ref_wb,
          s->ifoc_tr_s, s->ifoc_speed_ref_rad_s);
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int imsim_cli_main(int argc, char **argv) {
  imsim_config c;
  imsim_cli_opts o;
  char err[256];
  if (imsim_cli_parse(argc, argv, &c, &o, err, sizeof err) != 0) {
    fprintf(stderr, "imest-sim: %s\n(try --help)\n", err);
    return 2;
  }
  if (o.help) {
    fputs(USAGE, stdout);
    return 0;
  }
  static imsim sim;
  imsim_sample smp;
  if (imsim_init(&sim, &c, &smp) != 0) {
    fprintf(stderr, "imest-sim: %s\n", imsim_error(&sim));
    return 2;
  }
  FILE *f = stdout;
  if (strcmp(o.out, "-") != 0) {
    f = fopen(o.out, "w");
    if (f == NULL) {
      fprintf(stderr, "imest-sim: cannot open '%s': %s\n", o.out, strerror(errno));
      return 1;
    }
  }
  static char buf[1 << 20];
  setvbuf(f, buf, _IOFBF, sizeof buf);
  const uint64_t total = (uint64_t)llround(c.duration_s * c.fs_hz);
  const int bar = o.progress < 0 ? isatty(STDERR_FILENO) : o.progress;
  const double t0 = now_s();
  uint64_t next_bar = 0;
  const uint64_t bar_step = total / 200u + 1u;
  fprintf(f, "%s\n", HEADER);
  imsim_cli_write_row(f, &smp);
  for (uint64_t n = 1; n <= total; ++n) {
    imsim_step(&sim, &smp);
    if ((n % (uint64_t)o.decimate) == 0u) imsim_cli_write_row(f, &smp);
    if (bar && n >= next_bar) {
      next_bar = n + bar_step;
      const double frac = (double)n / (double)total;
      const int w = (int)(frac * 40.0);
      char line[48];
      for (int k = 0; k < 40; ++k) line[k] = k < w ? '#' : ' ';
      line[40] = '\0';
      const double el = now_s() - t0;
      fprintf(stderr, "\r[%s] %5.1f%%  %.1f/%.1f s motor  %.1f s wall  ", line, 100.0 * frac, smp.t, c.duration_s, el);
      fflush(stderr);
    }
  }
  if (bar) fprintf(stderr, "\n");
  int rc = 0;
  if (fflush(f) != 0 || ferror(f)) {
    fprintf(stderr, "imest-sim: write error\n");
    rc = 1;
  }
  if (f != stdout) {
    if (fclose(f) != 0) rc = 1;
  }
  return rc;
}
