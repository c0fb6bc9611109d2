/* SPDX-License-Identifier: Apache-2.0 */
/* Motor constants from an equivalent circuit (include/imest/imest_circuit.h). Runs once at set-up,
 * in a folder of its own: neither the estimator nor the tracker needs it, and a firmware that
 * converts its constants offline links none of it. float32, no libm. */
#include "imest/imest_circuit.h"

#include <math.h>
#include <stddef.h>

#define IMEST_CIRCUIT_TWO_PI 6.28318530717958647692f

static int positive(float x)
{
  return isfinite(x) && x > 0.0f;
}
static int non_negative(float x)
{
  return isfinite(x) && x >= 0.0f;
}

/* *k from L_S, L_R, L_m, the leakage product term (L_S L_R - L_m^2, computed without
   cancellation by the caller), R_R and R_S; IMEST_ERR_ARG if a result is not finite. */
static int fill(imest_circuit_constants_t *k, float ls, float lr, float lm, float leak, float rr, float rs)
{
  const float sigma = leak / (ls * lr), tr = lr / rr;
  if (!positive(ls) || !positive(lr) || !positive(tr) || !(sigma > 0.0f && sigma < 1.0f))
    return IMEST_ERR_ARG;
  k->ls_h = ls;
  k->lr_h = lr;
  k->lm_h = lm;
  k->sigma = sigma;
  k->tr_s = tr;
  k->rs_ohm = rs;
  return IMEST_OK;
}

int imest_circuit_from_t(const imest_circuit_t *c, imest_circuit_constants_t *k)
{
  if (c == NULL || k == NULL) return IMEST_ERR_NULL;
  if (!positive(c->lm_h) || !positive(c->lls_h) || !positive(c->llr_h) || !positive(c->rr_ohm) ||
      !non_negative(c->rs_ohm))
    return IMEST_ERR_ARG;
  const float lm = c->lm_h, a = c->lls_h, b = c->llr_h;
  /* L_S L_R - L_m^2 = L_ls L_m + L_lr L_m + L_ls L_lr */
  return fill(k, lm + a, lm + b, lm, (a + b) * lm + a * b, c->rr_ohm, c->rs_ohm);
}

int imest_circuit_from_x(const imest_circuit_x_t *x, imest_circuit_constants_t *k)
{
  if (x == NULL || k == NULL) return IMEST_ERR_NULL;
  if (!positive(x->f_hz)) return IMEST_ERR_ARG;
  const float w = IMEST_CIRCUIT_TWO_PI * x->f_hz;
  imest_circuit_t c;
  c.lm_h = x->xm_ohm / w;
  c.lls_h = x->xls_ohm / w;
  c.llr_h = x->xlr_ohm / w;
  c.rr_ohm = x->rr_ohm;
  c.rs_ohm = x->rs_ohm;
  return imest_circuit_from_t(&c, k);
}

int imest_circuit_from_inv_gamma(const imest_circuit_inv_gamma_t *g, imest_circuit_constants_t *k)
{
  if (g == NULL || k == NULL) return IMEST_ERR_NULL;
  if (!positive(g->lm_h) || !positive(g->lsig_h) || !positive(g->rr_ohm) || !non_negative(g->rs_ohm))
    return IMEST_ERR_ARG;
  const float lm = g->lm_h, ls = g->lsig_h + lm;
  /* L_R = L_m = L_M: L_S L_R - L_m^2 = L_sigma L_M */
  return fill(k, ls, lm, lm, g->lsig_h * lm, g->rr_ohm, g->rs_ohm);
}

int imest_circuit_apply(const imest_circuit_constants_t *k, imest_config_t *cfg)
{
  if (k == NULL || cfg == NULL) return IMEST_ERR_NULL;
  if (!positive(k->ls_h) || !positive(k->tr_s) || !(k->sigma > 0.0f && k->sigma < 1.0f) ||
      !non_negative(k->rs_ohm))
    return IMEST_ERR_ARG;
  cfg->ls_h = k->ls_h;
  cfg->sigma = k->sigma;
  cfg->tr_nominal_s = k->tr_s;
  cfg->tr_nominal_known = 1;
  if (k->rs_ohm > 0.0f) cfg->rs_nominal_ohm = k->rs_ohm;
  return IMEST_OK;
}
