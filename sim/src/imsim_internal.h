/* SPDX-License-Identifier: Apache-2.0 */
/* imsim_t internals shared by the simulator's source files (not installed, not API).
 * One file per concern: config.c (defaults, exp presets), motors.c (drive presets),
 * transform.c, rng.c, thermal.c, load.c, supply.c (V/f reference), taylor.c (exact
 * propagator), rk4.c (reference), integrate.c (one step), pwm.c (inverter), drive.c
 * (firmware timing, external commands), steady.c (phasor steady state), sensors.c, ifoc.c,
 * sim.c (init/step). Internal functions carry the prefix ims_; the public ones imsim_. */
#ifndef IMSIM_INTERNAL_H
#define IMSIM_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdbool.h>
#include <stdint.h>

#include "imsim/imsim.h"

#define PI    3.14159265358979323846
#define SQ23  0.81649658092772603273 /* sqrt(2/3) */
#define SQ3H  0.86602540378443864676 /* sqrt(3)/2 */
#define SQRT2 1.41421356237309504880
#define NAN_D ((double)NAN)

/* ---- complex maths (a + jb = the alpha-beta pair) ---------------------------------------- */

typedef imsim_cpx_t cpx;

static inline cpx cx(double re, double im)
{
  cpx r;
  r.re = re;
  r.im = im;
  return r;
}
static inline cpx cmul(cpx a, cpx b)
{
  return cx(a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re);
}
static inline cpx cadd(cpx a, cpx b)
{
  return cx(a.re + b.re, a.im + b.im);
}
static inline cpx cscale(cpx a, double k)
{
  return cx(a.re * k, a.im * k);
}
static inline double cabs2(cpx a)
{
  return a.re * a.re + a.im * a.im;
}
static inline cpx cexpj(double ph)
{
  return cx(cos(ph), sin(ph));
}

/* a_k of u = sqrt(2/3) (x1 + a1 x2 + a2 x3): 1, e^{j2pi/3}, e^{-j2pi/3} (transform.c). */
extern const double IMS_AK_RE[3];
extern const double IMS_AK_IM[3];

/* 1/k! for k = 0..33 and 1/k for k = 0..32 (taylor.c). */
extern const double IMS_INV_FACT[34];
extern const double IMS_INV_K[33];

/* ---- motor model (eq. (1)) ---------------------------------------------------------------- */

/* Electromagnetic torque at (i, psi). */
static inline double ims_torque_of(const imsim_t *s, cpx i, cpx psi)
{
  return (double)s->c.pole_pairs * s->m_h / s->c.lr_h * (i.im * psi.re - i.re * psi.im);
}

/* dTe/dt along the model at state (i, psi, w) with input u. */
static inline double ims_torque_rate(const imsim_t *s, cpx i, cpx psi, double w, cpx u)
{
  const imsim_config_t *c = &s->c;
  const double nw = (double)c->pole_pairs * w;
  const cpx di = cadd(cadd(cscale(u, 1.0 / (c->sigma * c->ls_h)), cscale(i, -s->gamma)),
                      cmul(cx(s->beta / s->tr, -s->beta * nw), psi));
  const cpx dpsi = cadd(cscale(i, s->m_h / s->tr), cmul(cx(-1.0 / s->tr, nw), psi));
  return (double)c->pole_pairs * s->m_h / c->lr_h *
         (di.im * psi.re - di.re * psi.im + i.im * dpsi.re - i.re * dpsi.im);
}

/* motors.c: the industrial drive presets (on top of imsim_config_default). Returns 0, or -1
   for an unknown name. */
#define IMS_MOTOR_PRESET_NAMES "4kw|11kw|15kw|37kw|75kw"
int ims_motor_preset(imsim_config_t *c, const char *name);

/* load.c: the load profile's value at t; the torque it applies in the present state (load_kind:
   passive = friction-like, see load.c); one integration step under it: begin (returns the torque
   to hold over the step) and end (passive: holds a rotor at rest, stops one whose speed changed
   sign; records stalls). supply.c: reference of the open-loop supplies (alpha-beta amplitude =
   V_ll rms, phase, frequency). */
typedef struct {
  double w0, th0; /* speed and angle at the step's start */
  double l_nm;    /* the profile's value                 */
  double tl;      /* the torque applied over the step    */
  bool held;      /* passive: the rotor is held at rest  */
} ims_load_step_t;
double ims_load_at(const imsim_t *s, double t);
double ims_load_torque(const imsim_t *s, double l_nm);
double ims_load_begin(const imsim_t *s, double l_nm, ims_load_step_t *ls);
void ims_load_end(imsim_t *s, const ims_load_step_t *ls, double t_end, double h);
void ims_vf_ref(const imsim_t *s, double t, double *amp, double *phase, double *f_hz);

/* thermal.c: present R_S, R_R, T_R and the derived gamma, beta from the temperatures; one
   sample of both first-order thermal models (then the parameters are updated). */
void ims_update_params(imsim_t *s);
void ims_thermal_step(imsim_t *s);

/* rng.c */
void ims_rng_seed(imsim_rng_t *r, uint64_t *sm);
double ims_rng_gauss(imsim_rng_t *r);

/* realmotor.c: real-motor effects (saturation, iron loss, double cage; sim/README.md).
   ims_rm_wanted: any effect configured. ims_rm_derive: the derived parameters (rm->on false
   when no effect is configured); 0, or -1 with a message. ims_rm_piece: sub-stepped RK4 over
   one constant-input piece (input as for ims_rk4_piece); ims_rm_sync: i, psi_R, T_e and the
   acceleration from the flux states. ims_rm_fill: the real-motor truth of a sample.
   ims_rm_steady: phasor steady state with the effects (fl: flux states, may be NULL). */
bool ims_rm_wanted(const imsim_config_t *c);
int ims_rm_derive(const imsim_config_t *c, imsim_real_t *rm, char *err, size_t errlen);
double ims_rm_lm_static(const imsim_real_t *rm, double psi_m_wb);
typedef struct step_input step_input_t;
void ims_rm_piece(imsim_t *s, double len, cpx u_pwm, const step_input_t *in, double tl);
void ims_rm_sync(imsim_t *s, double tl);
double ims_rm_p_rotor(const imsim_t *s);
void ims_rm_fill(imsim_t *s, imsim_sample_t *o);
/* The steady speed in (0, wsync]: where the torque surplus (motor torque - load - friction)
   changes sign, by a scan down from synchronous speed in steps of wsync/4000 and 200 bisections.
   Returns 0 and *w (wsync if the surplus there is >= 0), or -1 if the motor cannot carry the
   load at any speed. Shared by the linear and the real-motor phasor solutions. */
int ims_speed_root(double (*surplus)(const void *ctx, double w), const void *ctx, double wsync, double *w);
int ims_rm_steady(const imsim_config_t *c, const imsim_real_t *rm, double vll_v, double freq_hz,
                  double load_nm, imsim_steady_t *out, cpx fl[4]);
/* The phasor steady state at a given speed w (rad/s) and supply (u = vll + j0 at t = 0, we rad/s):
   ims_rm_steady_at with the effects, ims_steady_at either (rm NULL or off: the linear machine;
   fl: the effects' flux states, may be NULL). */
void ims_rm_steady_at(const imsim_config_t *c, const imsim_real_t *rm, double vll_v, double we, double w,
                      imsim_steady_t *out, cpx fl[4]);
void ims_steady_at(const imsim_config_t *c, const imsim_real_t *rm, double vll_v, double we, double w,
                   imsim_steady_t *out, cpx fl[4]);

/* ---- integration ---------------------------------------------------------------------------- */

/* Input of one integration step. */
struct step_input {
  bool aa, src, pwm;
  bool piecewise; /* PWM, fast path: integrate this half period piecewise (else by moments) */
  int p;          /* Taylor order */
  double we;      /* source rotation (rad/s), src only */
  cpx mom[32];    /* PWM input moments m_k = int_0^h (h-s)^k/k! u(s) ds */
};

/* One PWM half carrier period (time from its start). */
typedef struct {
  bool rising;       /* carrier rising: each leg high before its edge, low after; falling: the reverse */
  double e_cmd[3];   /* commanded edge of each leg */
  bool has_edge[3];  /* 0 < e_cmd < h (else the leg does not switch) */
  double td;         /* dead time */
  double cmd_avg[2]; /* commanded average voltage (alpha-beta) */
  double act_avg[2]; /* actual average voltage (alpha-beta, dead time and drops) */
} pwm_half_t;

/* taylor.c: Taylor order for ||A h|| = rho; norm bound of the augmented A (per second);
   order for the step h_s; exact propagation of the linear electrical part over one step. */
int ims_taylor_order_rho(double rho);
double ims_a_norm(const imsim_t *s, double w, const step_input_t *in);
int ims_taylor_order(const imsim_t *s, double w, const step_input_t *in);
void ims_fast_step(imsim_t *s, const double *hkv, double w_mid, double nwdot, const step_input_t *in);

/* rk4.c: the reference integrator's state and one constant-input piece. */
typedef struct {
  cpx x[7];
  double w, th;
} ims_full_state_t;
void ims_rk4_piece(const imsim_t *s, ims_full_state_t *X, double len, cpx u_pwm, const step_input_t *in,
                   double tl);

/* integrate.c: one integration step of length h_s with input in (fast or RK4). With PWM on the
   piecewise paths and a non-ideal inverter it sets ph->act_avg from the pieces. */
void ims_advance(imsim_t *s, const step_input_t *in, pwm_half_t *ph, double tl);

/* pwm.c: whether the inverter has device drops / is ideal (no dead time, no drops);
   reference (alpha-beta) -> leg modulation m in [-1, 1] (duty (1 + m)/2) for a bus vdc, true if
   it clipped; one half period g from m: edges, input moments, average voltages (dead time and
   drops decided by the currents at its start); the piecewise path's break points (returns
   their number, <= 8) and the voltage on the piece around tm from the currents at its start. */
bool ims_inverter_has_drops(const imsim_config_t *c);
bool ims_inverter_is_ideal(const imsim_config_t *c);
bool ims_pwm_modulate(imsim_t *s, cpx vref, double vdc, double m[3]);
void ims_pwm_build(imsim_t *s, uint64_t g, const double m[3], step_input_t *in, pwm_half_t *ph);
int ims_pwm_breaks(const pwm_half_t *ph, double h, double b[8]);
cpx ims_pwm_piece_voltage(const imsim_t *s, const pwm_half_t *ph, double tm, const double i_abc[3]);
bool ims_pwm_may_cross_zero(const imsim_t *s, const pwm_half_t *ph);

/* sensors.c: PWM inverter present; firmware timing in force; the DC-bus sample at t. */
bool ims_is_pwm_stage(const imsim_config_t *c);
bool ims_firmware_timing(const imsim_config_t *c);
void ims_sample_vdc(imsim_t *s);
imsim_vmeas_t ims_vmeas_of(const imsim_config_t *c);
void ims_fill_sample(imsim_t *s, imsim_sample_t *o);

/* drive.c (firmware timing): duties for [t_0, t_1) at init; the duties of the next sample
   period computed from the present sample (V/f or IFOC; ext: the caller's); the switch to
   them at the end of the step. */
void ims_drive_init(imsim_t *s);
void ims_drive_update(imsim_t *s);
void ims_drive_advance(imsim_t *s);

/* ifoc.c */
void ims_ifoc_update(imsim_t *s);
cpx ims_ifoc_vref(const imsim_t *s, double t);
/* --start steady with IFOC (speed mode): the operating point its loops hold at the speed
   reference and the load (the slip where the imposed current's torque meets the load, the
   supply vll_v / we that drives that current), the machine's phasors there (st, and the real
   motor's flux states), and the controller's state at it. -1: torque mode, no positive speed
   reference, or a load beyond the torque limit. */
int ims_ifoc_steady(imsim_t *s, double *vll_v, double *we, imsim_steady_t *st);

#endif /* IMSIM_INTERNAL_H */
