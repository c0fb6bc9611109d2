/* SPDX-License-Identifier: Apache-2.0 */
/* Commission, then estimate (online.c): the online estimator on the commissioned drive with the
 * duty-cycle input. Host code. */
#ifndef IMEST_COMMISSION_ONLINE_H
#define IMEST_COMMISSION_ONLINE_H

#include "commission_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  int windows, tr_valid, rs_valid; /* windows after the first 30 % of the run */
  double tr_rel, rs_rel;           /* mean error of the valid windows against the truth */
  double tr_all_rel, rs_all_rel;   /* mean error of every window with a number (valid or not) */
  int reason;                      /* the last window's status (imest_reason_t) */
} comm_online_t;

/* The drive of the options (commission_sim.c) in operation: V/f at its rated point (the paper's
   motor: 30 Hz, 115 V), steady, load_frac of rated torque, for duration_s; the estimator with
   the constants and inverter model of id (NULL: the true ones; sigma the preset's where
   imest_comm_apply leaves it, IMEST_COMM_FLAG_ROTOR_HF), fed the duties, the bus, the currents
   and the angle (imest_isr_duty). 0, or -1 on a set-up error. */
int comm_online_run(const comm_sim_opts_t *o, double load_frac, double duration_s,
                    const imest_comm_result_t *id, comm_online_t *out);

#ifdef __cplusplus
}
#endif

#endif
