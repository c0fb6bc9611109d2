/* SPDX-License-Identifier: Apache-2.0 */
/* The Python module's entry point into the core: a flat interface of plain
 * doubles, ints and strings, so that the module (python/imest/, ctypes)
 * mirrors no C struct. The config travels as one double per field, in the
 * order of the table below (names and defaults read from here, filled from
 * imest_config_default()); each window comes back as one row of doubles in
 * the order of the column table (imest-replay's CSV columns first, then a few
 * more of imest_result_t). The run is tools/common/drive_loop.c, the loop
 * imest-replay runs, with replay's rule for the last partial window.
 *
 * Compiled only into the host shared library (CMake target imest_shared,
 * libimest.so), never into the firmware's static library. Host code: it may
 * use libm, but keeps the core's rules (no malloc, no global mutable state). */
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "drive_loop.h"
#include "imest/imest.h"

/* Bumped whenever a signature or a table's meaning changes: the module
 * refuses a library of another ABI (a stale build). */
#define IMEST_PY_ABI 1

/* The kinds of a config field and of a result column (the module's dtypes). */
enum { KIND_FLOAT = 0, KIND_INT = 1, KIND_UINT = 2, KIND_PWM_TIMING = 3, KIND_REASON = 4 };

/* Every field of imest_config_t, by its C name (a nested field as
 * "inverter.dead_time_s", the name imest_config_check() reports; an array's
 * element as "ls_curve_h[1]"). */
#define IMEST_PY_CONFIG_FIELDS(X)                                                                            \
  X(pole_pairs, KIND_UINT)                                                                                   \
  X(ls_h, KIND_FLOAT)                                                                                        \
  X(sigma, KIND_FLOAT)                                                                                       \
  X(ls_uncertainty, KIND_FLOAT)                                                                              \
  X(sigma_uncertainty, KIND_FLOAT)                                                                           \
  X(fs_hz, KIND_FLOAT)                                                                                       \
  X(window_s, KIND_FLOAT)                                                                                    \
  X(filter_hz, KIND_FLOAT)                                                                                   \
  X(aa_hz, KIND_FLOAT)                                                                                       \
  X(u_delay_s, KIND_FLOAT)                                                                                   \
  X(angle_observer_hz, KIND_FLOAT)                                                                           \
  X(encoder_counts_per_rev, KIND_FLOAT)                                                                      \
  X(dc_block_hz, KIND_FLOAT)                                                                                 \
  X(warmup_s, KIND_FLOAT)                                                                                    \
  X(start_at_rest, KIND_INT)                                                                                 \
  X(pwm_hz, KIND_FLOAT)                                                                                      \
  X(pwm_timing, KIND_PWM_TIMING)                                                                             \
  X(voltage_kind, KIND_INT)                                                                                  \
  X(inverter.dead_time_s, KIND_FLOAT)                                                                        \
  X(inverter.v_switch_v, KIND_FLOAT)                                                                         \
  X(inverter.r_switch_ohm, KIND_FLOAT)                                                                       \
  X(inverter.v_diode_v, KIND_FLOAT)                                                                          \
  X(inverter.r_diode_ohm, KIND_FLOAT)                                                                        \
  X(inverter.i_band_a, KIND_FLOAT)                                                                           \
  X(inverter.edge_band_a, KIND_FLOAT)                                                                        \
  X(inverter.uncertainty, KIND_FLOAT)                                                                        \
  X(tr_nominal_s, KIND_FLOAT)                                                                                \
  X(tr_nominal_known, KIND_INT)                                                                              \
  X(tr_min_s, KIND_FLOAT)                                                                                    \
  X(tr_max_s, KIND_FLOAT)                                                                                    \
  X(rs_min_ohm, KIND_FLOAT)                                                                                  \
  X(rs_max_ohm, KIND_FLOAT)                                                                                  \
  X(max_pe_k2_rel, KIND_FLOAT)                                                                               \
  X(max_ei, KIND_FLOAT)                                                                                      \
  X(min_current_a, KIND_FLOAT)                                                                               \
  X(min_slip_ratio, KIND_FLOAT)                                                                              \
  X(rs_tolerance, KIND_FLOAT)                                                                                \
  X(tr_tolerance, KIND_FLOAT)                                                                                \
  X(u_uncertainty_v, KIND_FLOAT)                                                                             \
  X(timing_uncertainty_s, KIND_FLOAT)                                                                        \
  X(rs_nominal_ohm, KIND_FLOAT)                                                                              \
  X(rotor_hf_rr_ratio, KIND_FLOAT)                                                                           \
  X(rotor_hf_sigma_ratio, KIND_FLOAT)                                                                        \
  X(inverter_vdc_v, KIND_FLOAT)                                                                              \
  X(ls_curve_i_a[0], KIND_FLOAT)                                                                             \
  X(ls_curve_i_a[1], KIND_FLOAT)                                                                             \
  X(ls_curve_i_a[2], KIND_FLOAT)                                                                             \
  X(ls_curve_i_a[3], KIND_FLOAT)                                                                             \
  X(ls_curve_h[0], KIND_FLOAT)                                                                               \
  X(ls_curve_h[1], KIND_FLOAT)                                                                               \
  X(ls_curve_h[2], KIND_FLOAT)                                                                               \
  X(ls_curve_h[3], KIND_FLOAT)                                                                               \
  X(ls_curve_points, KIND_UINT)                                                                              \
  X(i_limit_a, KIND_FLOAT)                                                                                   \
  X(u_limit_v, KIND_FLOAT)                                                                                   \
  X(i_absurd_a, KIND_FLOAT)                                                                                  \
  X(u_absurd_v, KIND_FLOAT)                                                                                  \
  X(speed_limit_rad_s, KIND_FLOAT)

typedef struct {
  const char *name;
  size_t offset;
  int kind;
} py_field_t;

#define IMEST_PY_FIELD(f, kind) {#f, offsetof(imest_config_t, f), kind},
static const py_field_t k_fields[] = {IMEST_PY_CONFIG_FIELDS(IMEST_PY_FIELD)};
#define N_FIELDS ((int)(sizeof k_fields / sizeof k_fields[0]))

/* Every field is 4 bytes (float, int, unsigned, an enum): a field added to
 * imest_config_t and not to the table above stops this build. */
_Static_assert(sizeof(imest_config_t) == sizeof k_fields / sizeof k_fields[0] * sizeof(float),
               "imest_config_t has a field the Python table (IMEST_PY_CONFIG_FIELDS) does not list");

/* The result columns: imest-replay's CSV columns in its order (tools/replay/
 * replay.c), t_end_s counted from the record's first t; then more of
 * imest_result_t. `r` is the result, `t0_s` the record's first t [s]. */
#define IMEST_PY_COLUMNS(X)                                                                                  \
  X(t_end_s, KIND_FLOAT, t0_s + r->t_end_s)                                                                  \
  X(T_R_s, KIND_FLOAT, r->tr_s)                                                                              \
  X(R_S_ohm, KIND_FLOAT, r->rs_ohm)                                                                          \
  X(E_I, KIND_FLOAT, r->e_i)                                                                                 \
  X(valid, KIND_INT, r->valid)                                                                               \
  X(status, KIND_REASON, r->status)                                                                          \
  X(seq, KIND_UINT, r->seq)                                                                                  \
  X(K1, KIND_FLOAT, r->k1)                                                                                   \
  X(K2, KIND_FLOAT, r->k2)                                                                                   \
  X(pe_k1_rel, KIND_FLOAT, r->pe_k1_rel)                                                                     \
  X(pe_k2_rel, KIND_FLOAT, r->pe_k2_rel)                                                                     \
  X(H11, KIND_FLOAT, r->hessian[0][0])                                                                       \
  X(H12, KIND_FLOAT, r->hessian[0][1])                                                                       \
  X(H22, KIND_FLOAT, r->hessian[1][1])                                                                       \
  X(hessian_pd, KIND_INT, (r->flags & IMEST_FLAG_HESSIAN_PD) ? 1 : 0)                                        \
  X(n_roots, KIND_UINT, r->n_roots)                                                                          \
  X(n_admissible, KIND_UINT, r->n_admissible)                                                                \
  X(slip_ratio, KIND_FLOAT, r->slip_ratio)                                                                   \
  X(i_rms_a, KIND_FLOAT, r->i_rms_a)                                                                         \
  X(used_samples, KIND_UINT, r->used_samples)                                                                \
  X(flags, KIND_UINT, r->flags)                                                                              \
  X(tr_valid, KIND_INT, r->tr_valid)                                                                         \
  X(rs_valid, KIND_INT, r->rs_valid)                                                                         \
  X(tr_reason, KIND_REASON, r->tr_reason)                                                                    \
  X(rs_reason, KIND_REASON, r->rs_reason)                                                                    \
  X(span_s, KIND_FLOAT, r->span_s)                                                                           \
  X(windows, KIND_UINT, r->windows)                                                                          \
  X(tr_bound_rel, KIND_FLOAT, r->tr_bound_rel)                                                               \
  X(rs_bound_rel, KIND_FLOAT, r->rs_bound_rel)                                                               \
  X(samples, KIND_UINT, r->samples)                                                                          \
  X(overruns, KIND_UINT, r->overruns)                                                                        \
  X(E, KIND_FLOAT, r->e)                                                                                     \
  X(E_I_noise, KIND_FLOAT, r->e_i_noise)                                                                     \
  X(noise_i_a, KIND_FLOAT, r->noise_i_a)                                                                     \
  X(noise_u_v, KIND_FLOAT, r->noise_u_v)                                                                     \
  X(pe_k1, KIND_FLOAT, r->pe_k1)                                                                             \
  X(pe_k2, KIND_FLOAT, r->pe_k2)                                                                             \
  X(ls_noload_h, KIND_FLOAT, r->ls_noload_h)                                                                 \
  X(ls_window_h, KIND_FLOAT, r->ls_window_h)

typedef struct {
  const char *name;
  int kind;
} py_column_t;

#define IMEST_PY_COLUMN(c, kind, value) {#c, kind},
static const py_column_t k_columns[] = {IMEST_PY_COLUMNS(IMEST_PY_COLUMN)};
#define N_COLUMNS ((int)(sizeof k_columns / sizeof k_columns[0]))

/* The functions below are the library's Python interface (python/imest/_lib.py
 * declares their signatures); they have no header of their own. */
int imest_py_abi(void);
const char *imest_py_version(void);
int imest_py_config_fields(void);
const char *imest_py_config_name(int k);
int imest_py_config_kind(int k);
void imest_py_config_default(double *values);
int imest_py_config_check(const double *values, const char **field);
int imest_py_pwm_timing(const char *name);
int imest_py_columns(void);
const char *imest_py_column_name(int k);
int imest_py_column_kind(int k);
long imest_py_run(const double *values, int duty, long n, const double *v3, const double *vdc,
                  const double *i3, const double *theta, double fs_hz, double t0_s, double *out,
                  long max_rows, int *error);

int imest_py_abi(void)
{
  return IMEST_PY_ABI;
}

const char *imest_py_version(void)
{
  return IMEST_VERSION_STRING;
}

int imest_py_config_fields(void)
{
  return N_FIELDS;
}

const char *imest_py_config_name(int k)
{
  return k >= 0 && k < N_FIELDS ? k_fields[k].name : NULL;
}

int imest_py_config_kind(int k)
{
  return k >= 0 && k < N_FIELDS ? k_fields[k].kind : -1;
}

void imest_py_config_default(double *values)
{
  imest_config_t cfg;
  imest_config_default(&cfg);
  const char *raw = (const char *)&cfg;
  for (int k = 0; k < N_FIELDS; ++k) {
    const char *p = raw + k_fields[k].offset;
    switch (k_fields[k].kind) {
    case KIND_FLOAT: {
      float x;
      memcpy(&x, p, sizeof x);
      values[k] = (double)x;
      break;
    }
    case KIND_UINT: {
      unsigned int x;
      memcpy(&x, p, sizeof x);
      values[k] = (double)x;
      break;
    }
    case KIND_PWM_TIMING: {
      imest_pwm_timing_t x;
      memcpy(&x, p, sizeof x);
      values[k] = (double)x;
      break;
    }
    default: {
      int x;
      memcpy(&x, p, sizeof x);
      values[k] = (double)x;
      break;
    }
    }
  }
}

/* The flat values into a config: floats rounded to float32 as a cast does
 * (what imest-replay does with its options); an integer field must hold an
 * integer in its type's range, else IMEST_ERR_ARG naming it. */
static int config_from(const double *values, imest_config_t *cfg, const char **field)
{
  imest_config_default(cfg);
  char *raw = (char *)cfg;
  for (int k = 0; k < N_FIELDS; ++k) {
    char *p = raw + k_fields[k].offset;
    const double v = values[k];
    const int kind = k_fields[k].kind;
    if (kind == KIND_FLOAT) {
      const float x = (float)v;
      memcpy(p, &x, sizeof x);
      continue;
    }
    const double lo = kind == KIND_UINT ? 0.0 : (double)INT_MIN,
                 hi = kind == KIND_UINT ? (double)UINT_MAX : INT_MAX;
    if (!(v >= lo && v <= hi) || v != floor(v)) {
      if (field) *field = k_fields[k].name;
      return IMEST_ERR_ARG;
    }
    if (kind == KIND_UINT) {
      const unsigned int x = (unsigned int)v;
      memcpy(p, &x, sizeof x);
    } else if (kind == KIND_PWM_TIMING) {
      const imest_pwm_timing_t x = (imest_pwm_timing_t)(int)v;
      memcpy(p, &x, sizeof x);
    } else {
      const int x = (int)v;
      memcpy(p, &x, sizeof x);
    }
  }
  return IMEST_OK;
}

int imest_py_config_check(const double *values, const char **field)
{
  if (values == NULL) return IMEST_ERR_NULL;
  imest_config_t cfg;
  if (field) *field = NULL;
  const int rc = config_from(values, &cfg, field);
  return rc != IMEST_OK ? rc : imest_config_check(&cfg, field);
}

/* imest-replay's --pwm-timing words. */
int imest_py_pwm_timing(const char *name)
{
  if (name == NULL) return -1;
  if (strcmp(name, "next") == 0) return IMEST_PWM_NEXT_PERIOD;
  if (strcmp(name, "centred") == 0 || strcmp(name, "centered") == 0) return IMEST_PWM_CENTRED;
  if (strcmp(name, "last") == 0) return IMEST_PWM_LAST_PERIOD;
  return -1;
}

int imest_py_columns(void)
{
  return N_COLUMNS;
}

const char *imest_py_column_name(int k)
{
  return k >= 0 && k < N_COLUMNS ? k_columns[k].name : NULL;
}

int imest_py_column_kind(int k)
{
  return k >= 0 && k < N_COLUMNS ? k_columns[k].kind : -1;
}

typedef struct {
  double *out;
  long max_rows, rows;
  double t0_s;
} py_rows_t;

/* drive_window_fn: one result into the next row (counted beyond max_rows). */
static void put_row(void *ctx, const imest_result_t *r)
{
  py_rows_t *x = (py_rows_t *)ctx;
  const double t0_s = x->t0_s;
  if (x->rows < x->max_rows) {
    double *row = x->out + (size_t)x->rows * (size_t)N_COLUMNS;
    int k = 0;
#define IMEST_PY_PUT(c, kind, value) row[k++] = (double)(value);
    IMEST_PY_COLUMNS(IMEST_PY_PUT)
#undef IMEST_PY_PUT
  }
  x->rows++;
}

/* Runs n samples through the estimator as imest-replay does: the config from
 * `values` (fs_hz in it: the rate the ISR is told), every sample through the
 * float32 ISR call of the input (duty: imest_isr_duty with v3 the duties and
 * vdc the bus; else imest_isr_abc with v3 the phase voltages), the background
 * drained per window; at the end a partial window of at least half the length
 * (or a record shorter than one window) is estimated too, as replay does.
 * v3 and i3 are n x 3, row-major. fs_hz (double) is the record's rate for that
 * rule; t0_s is added to each window's t_end_s. Writes up to max_rows rows of
 * imest_py_columns() doubles to out and returns the number of windows (more
 * than max_rows: call again with room for them), or a negative imest_err_t
 * (the config: *error is then 0). *error: the first negative return of
 * imest_background() (the rows up to it are written), else 0. */
long imest_py_run(const double *values, int duty, long n, const double *v3, const double *vdc,
                  const double *i3, const double *theta, double fs_hz, double t0_s, double *out,
                  long max_rows, int *error)
{
  if (error) *error = 0;
  if (values == NULL || v3 == NULL || i3 == NULL || theta == NULL || (duty && vdc == NULL) ||
      (out == NULL && max_rows > 0) || n < 0)
    return IMEST_ERR_NULL;
  imest_config_t cfg;
  const char *field = NULL;
  int rc = config_from(values, &cfg, &field);
  if (rc != IMEST_OK) return rc;
  imest_t est;
  if ((rc = imest_init(&est, &cfg)) != IMEST_OK) return rc;
  py_rows_t rows = {out, max_rows, 0, t0_s};
  drive_t d;
  drive_init(&d, &est, put_row, &rows);
  for (long k = 0; k < n; ++k) {
    const size_t j = (size_t)k * 3u;
    const int got = duty ? drive_sample_duty(&d, v3 + j, vdc[k], i3 + j, theta[k])
                         : drive_sample(&d, v3 + j, i3 + j, theta[k]);
    if (got < 0) break;
  }
  const long win_n = lround((double)cfg.window_s * fs_hz), rest = win_n > 0 ? n % win_n : 0;
  if (rest > 0 && (2 * rest >= win_n || n < win_n)) (void)drive_flush(&d);
  if (error) *error = d.error;
  return rows.rows;
}
