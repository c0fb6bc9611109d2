/* SPDX-License-Identifier: Apache-2.0 */
/* The online estimator's sensitivity to the constants commissioning provides (sensitivity.c).
 * Host code. */
#ifndef IMEST_COMMISSION_SENSITIVITY_H
#define IMEST_COMMISSION_SENSITIVITY_H

#include "imest/imest.h"
#include "imsim/imsim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  char preset[16];
  double load_frac;  /* of rated torque (exp2: of the paper's 2.064 N m) */
  double duration_s; /* simulated per run */
  double settle_s;   /* windows ending before this are left out */
  unsigned long seed;
  int duty; /* 1: the duty-cycle input with the true inverter model (the +-0.1 V go to
                        the model's thresholds); 0: the measured phase voltages */
} comm_sens_opts_t;

typedef struct {
  double tr_rel, rs_rel; /* mean error of the windows, relative */
  int windows, valid;
} comm_sens_run_t;

typedef struct {
  comm_sens_run_t base;              /* the true constants */
  double tr_per_ls, rs_per_ls;       /* relative error per +1 % of L_S */
  double tr_per_sigma, rs_per_sigma; /* per +1 % of sigma */
  double tr_per_dv, rs_per_dv;       /* per +0.1 V of voltage error per leg, in phase with the current */
} comm_sens_t;

/* Seven runs (true, +-1 % L_S, +-1 % sigma, +-0.1 V); central differences. 0, or -1 if a run
   failed (simulator or estimator set-up, or no window). */
int comm_sensitivity(const comm_sens_opts_t *o, comm_sens_t *out);

#ifdef __cplusplus
}
#endif

#endif
