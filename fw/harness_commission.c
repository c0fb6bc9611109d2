/* SPDX-License-Identifier: Apache-2.0 */
/* Firmware harness for the self-commissioning routine (include/imest/imest_commission.h): the
 * routine runs its whole sequence closed loop against a small motor model on the target, and
 * each of its calls is bracketed by the marker functions so that the icount plugin counts it
 * exactly (the model, in this file, is harness code and is not counted).
 *
 * The model (float32, 8 Euler steps per sample): the paper's equations (docs/METHOD.md §1)
 * for a small motor with a short rotor time constant, so that the sequence takes seconds
 * (n_p = 2, L_S = 0.29 H, sigma = 0.096, R_S = 5 ohm, T_R = 30 ms, J = 1e-3 kg m^2), fed by a
 * 325 V, 8 kHz inverter with firmware timing (the duties returned at sample k apply from k+1)
 * and a sign-type dead-time error, exact currents, a 4096-count encoder. Accuracy is not the
 * point here (tools/commission measures it on the simulator): every stage must run.
 *
 * Channels: 0 ISR call, 1 background call that fits, 2 empty bracket, 3 stand-in of known
 * count, 4 imest_comm_init, 5 background call with nothing to do. */
#include <stddef.h>
#include <stdint.h>

#include "harness_measure.h"
#include "harness_semihost.h"
#include "imest/imest_commission.h"

/* ------------------------------------------------------------------------- */
/* The motor and its inverter                                                */

#define FS    8000.0f
#define VDC   325.0f
#define NSUB  8
#define SQ23  0.816496580927726f
#define HSQ3  0.866025403784439f
#define TWOPI 6.28318530717959f

typedef struct {
  float ia, ib, pa, pb, w, th; /* stator current, rotor flux (alpha/beta), speed, angle */
  float d[3];                  /* duties applied in the present period */
} plant_t;

static float fsign(float x)
{
  return x > 0.0f ? 1.0f : (x < 0.0f ? -1.0f : 0.0f);
}

static void plant_step(plant_t *p, const float d_next[3])
{
  const float np = 2.0f, ls = 0.2908f, sig = 0.096f, rs = 5.04f, tr = 0.03f, jm = 1.0e-3f, fric = 1.0e-4f;
  const float m = 0.9508f * ls; /* sqrt(1 - sigma) L_S with L_R = L_S */
  const float beta = m / (sig * ls * ls), gam = rs / (sig * ls) + (1.0f - sig) / (sig * tr);
  const float h = 1.0f / (FS * (float)NSUB);
  /* leg voltages: duties times the bus, less the dead time (2 us at 8 kHz; a clamped leg does
     not switch) and 1 V of drops */
  float ix[3], v[3];
  ix[0] = SQ23 * p->ia;
  ix[1] = SQ23 * (-0.5f * p->ia + HSQ3 * p->ib);
  ix[2] = SQ23 * (-0.5f * p->ia - HSQ3 * p->ib);
  for (int x = 0; x < 3; ++x) {
    const float td = (p->d[x] > 0.0f && p->d[x] < 1.0f) ? 2e-6f * 8000.0f * VDC : 0.0f;
    v[x] = p->d[x] * VDC - fsign(ix[x]) * (td + 1.0f);
  }
  const float ua = SQ23 * (v[0] - 0.5f * (v[1] + v[2])), ub = SQ23 * HSQ3 * (v[1] - v[2]);
  for (int k = 0; k < NSUB; ++k) {
    const float nw = np * p->w;
    const float dpa = -p->pa / tr - nw * p->pb + m / tr * p->ia;
    const float dpb = -p->pb / tr + nw * p->pa + m / tr * p->ib;
    const float dia = beta / tr * p->pa + beta * nw * p->pb - gam * p->ia + ua / (sig * ls);
    const float dib = beta / tr * p->pb - beta * nw * p->pa - gam * p->ib + ub / (sig * ls);
    const float te = np * m / ls * (p->pa * p->ib - p->pb * p->ia);
    p->pa += h * dpa;
    p->pb += h * dpb;
    p->ia += h * dia;
    p->ib += h * dib;
    p->w += h * (te - fric * p->w) / jm;
    p->th += h * p->w;
  }
  for (int x = 0; x < 3; ++x) p->d[x] = d_next[x];
}

static void plant_sense(const plant_t *p, float i[3], float *theta)
{
  i[0] = SQ23 * p->ia;
  i[1] = SQ23 * (-0.5f * p->ia + HSQ3 * p->ib);
  i[2] = SQ23 * (-0.5f * p->ia - HSQ3 * p->ib);
  float turns = p->th / TWOPI;
  turns -= (float)(int32_t)turns;
  if (turns < 0.0f) turns += 1.0f;
  *theta = (float)(int32_t)(turns * 4096.0f) * (TWOPI / 4096.0f);
}

static imest_comm_t comm;
static plant_t plant;

int main(void)
{
  int fails = 0;
  harness_validate_counting();

  sh_kv("sizeof_imest_comm_t", sizeof(imest_comm_t));
  sh_kv("sizeof_imest_comm_result_t", sizeof(imest_comm_result_t));
  imest_comm_config_t cc;
  imest_comm_config_default(&cc);
  cc.fs_hz = FS;
  cc.i_max_a = 3.0f;
  cc.encoder_cpr = 4096.0f;
  cc.allow_rotation = 1;
  cc.rated_voltage_v = 230.0f;
  cc.rated_freq_hz = 60.0f;
  cc.rated_speed_rpm = 1710.0f;
  cc.ramp_s = 0.5f;
  fw_mark_b4();
  int rc = imest_comm_init(&comm, &cc);
  fw_mark_e4();
  if (rc != IMEST_OK) {
    sh_puts("imest_comm_init failed\n");
    return 1;
  }
  stat_t st_isr = {0, 0, 0, 0}, st_bg = {0, 0, 0, 0};
  uint32_t stack_isr = 0u, stack_bg = 0u;
  const float d0[3] = {0.5f, 0.5f, 0.5f};
  for (int x = 0; x < 3; ++x) plant.d[x] = 0.5f;
  for (uint32_t n = 0u; n < (uint32_t)(60.0f * FS); n++) {
    float i[3], th, d[3];
    plant_sense(&plant, i, &th);
    paint_stack(1024u);
    uint32_t sp = sp_now();
    uint32_t t0 = SYST_CVR;
    fw_mark_b0();
    const int run = imest_comm_isr(&comm, i, VDC, th, d);
    fw_mark_e0();
    uint32_t t1 = SYST_CVR;
    stat_add(&st_isr, ticks(t0, t1));
    {
      uint32_t s = stack_below(sp);
      if (s > stack_isr) stack_isr = s;
    }
    /* the background task, every millisecond */
    if (n % 8u == 0u) {
      const uint32_t pending = comm.job != comm.done;
      paint_stack(8u * 1024u);
      sp = sp_now();
      t0 = SYST_CVR;
      if (pending) {
        fw_mark_b1();
        (void)imest_comm_background(&comm);
        fw_mark_e1();
        t1 = SYST_CVR;
        stat_add(&st_bg, ticks(t0, t1));
      } else {
        fw_mark_b5();
        (void)imest_comm_background(&comm);
        fw_mark_e5();
      }
      uint32_t s = stack_below(sp);
      if (s > stack_bg) stack_bg = s;
    }
    plant_step(&plant, run == 1 ? d : d0);
    if (run != 1 && comm.state != IMEST_COMM_RUNNING && comm.state != IMEST_COMM_COMPUTING) break;
  }
  imest_comm_result_t r;
  (void)imest_comm_result(&comm, &r);
  sh_puts("commission state ");
  sh_puts(imest_comm_state_name(r.state));
  sh_puts(" reason ");
  sh_puts(imest_comm_reason_name(r.reason));
  sh_puts(" time_s ");
  sh_putf((double)r.time_s, 2);
  sh_puts(" rs_ohm ");
  sh_putf((double)r.rs_ohm.value, 4);
  sh_puts(" sigma_ls_h ");
  sh_putf((double)r.sigma_ls_h.value, 5);
  sh_puts(" ls_h ");
  sh_putf((double)r.ls_h.value, 4);
  sh_puts(" tr_s ");
  sh_putf((double)r.tr_s.value, 4);
  sh_puts(" pole_pairs ");
  sh_putu(r.pole_pairs);
  sh_puts(" dead_time_us ");
  sh_putf(1e6 * (double)r.inverter.dead_time_s, 3);
  sh_puts("\n");
  if (r.state != IMEST_COMM_DONE) fails++;
  stat_print("isr_systick_ticks", &st_isr);
  stat_print("solve_systick_ticks", &st_bg);
  sh_kv("stack_isr_bytes", stack_isr);
  sh_kv("stack_background_bytes", stack_bg);
  sh_kv("stack_total_bytes", harness_stack_used());
  sh_puts(fails ? "harness FAILED\n" : "harness done\n");
  return fails ? 1 : 0;
}
