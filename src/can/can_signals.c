/* SPDX-License-Identifier: Apache-2.0 */
/* The CAN telemetry layout: one line per signal. Packing, decoding and the
 * saturation bits all read this table (can_codec.c); tools/imest.dbc names
 * the same signals for CAN tools, and test/can/test_dbc.py proves the two
 * equal. Adding a signal = one line here (a field of imest_result_t) plus its
 * line in the DBC.
 *
 * Ranges (why these widths): port/README.md. Reserved bits are sent as 0:
 * QUAL 31, 47; VERDICT 19..23; BOUNDS 34..47. */
#include <stddef.h>

#include "imest/imest_can.h"

/* The field's offset in imest_result_t, checked at compile time against the
 * C type the kind reads (no match in _Generic = a compile error). */
#define R_              ((imest_result_t *)0)
#define AT_(f)          (unsigned short)offsetof(imest_result_t, f)
#define FIELD_F32(f)    _Generic(R_->f, double : AT_(f))
#define FIELD_SCALED(f) _Generic(R_->f, double : AT_(f))
#define FIELD_COUNT(f)  _Generic(R_->f, unsigned int : AT_(f))
#define FIELD_U32(f)    _Generic(R_->f, uint32_t : AT_(f))
#define FIELD_ENUM(f)   _Generic(R_->f, int : AT_(f))
#define FIELD_BOOL(f)   _Generic(R_->f, int : AT_(f))
#define FIELD_FLAG(f)   _Generic(R_->f, unsigned int : AT_(f))
#define FIELD_SAT(f)    0u /* not a result field: the codec's saturation bits */
#define FIELD_TXFAIL(f) 0u /* not a result field: the publisher's count */

/* The table reads like the DBC: one signal per line, columns aligned. */
// clang-format off
#define SIG(frame, start, len, kind, scale, field, mask) \
  {scale, FIELD_##kind(field), mask, IMEST_CAN_FRAME_##frame, start, len, IMEST_CAN_##kind}

static const imest_can_signal_t k_signals[] = {
    /*  frame   start len kind    scale   field         mask                      DBC name */
    SIG(TR,       0, 32, F32,    1u,     tr_s,         IMEST_CAN_SAT_TR),        /* TR_s */
    SIG(TR,      32, 16, SCALED, 10000u, e_i,          IMEST_CAN_SAT_EI),        /* EI */
    SIG(RS,       0, 32, F32,    1u,     rs_ohm,       IMEST_CAN_SAT_RS),        /* RS_ohm */
    SIG(RS,      32, 16, SCALED, 50000u, pe_k2_rel,    IMEST_CAN_SAT_PEK2),      /* PE_K2_rel */
    SIG(QUAL,     0, 16, SCALED, 50000u, pe_k1_rel,    IMEST_CAN_SAT_PEK1),      /* PE_K1_rel */
    SIG(QUAL,    16,  8, ENUM,   1u,     status,       0u),                      /* Status */
    SIG(QUAL,    24,  1, BOOL,   1u,     valid,        0u),                      /* Valid */
    SIG(QUAL,    25,  1, FLAG,   1u,     flags,        IMEST_FLAG_HESSIAN_PD),   /* HessianPD */
    SIG(QUAL,    26,  1, SAT,    1u,     none,         IMEST_CAN_SAT_TR),        /* Sat_TR */
    SIG(QUAL,    27,  1, SAT,    1u,     none,         IMEST_CAN_SAT_RS),        /* Sat_RS */
    SIG(QUAL,    28,  1, SAT,    1u,     none,         IMEST_CAN_SAT_EI),        /* Sat_EI */
    SIG(QUAL,    29,  1, SAT,    1u,     none,         IMEST_CAN_SAT_PEK1),      /* Sat_PE_K1 */
    SIG(QUAL,    30,  1, SAT,    1u,     none,         IMEST_CAN_SAT_PEK2),      /* Sat_PE_K2 */
    SIG(QUAL,    32,  1, FLAG,   1u,     flags,        IMEST_FLAG_WARMUP),       /* Flag_Warmup */
    SIG(QUAL,    33,  1, FLAG,   1u,     flags,        IMEST_FLAG_INPUT_FAULT),  /* Flag_InputFault */
    SIG(QUAL,    34,  1, FLAG,   1u,     flags,        IMEST_FLAG_ADC_SAT),      /* Flag_AdcSat */
    SIG(QUAL,    35,  1, FLAG,   1u,     flags,        IMEST_FLAG_ENCODER_FAULT), /* Flag_EncoderFault */
    SIG(QUAL,    36,  1, FLAG,   1u,     flags,        IMEST_FLAG_OVERRUN),      /* Flag_Overrun */
    SIG(QUAL,    37,  5, COUNT,  1u,     n_roots,      0u),                      /* NRoots */
    SIG(QUAL,    42,  5, COUNT,  1u,     n_admissible, 0u),                      /* NAdmissible */
    SIG(STAT,     0, 32, U32,    1u,     seq,          0u),                      /* Seq */
    SIG(STAT,    32, 16, TXFAIL, 1u,     none,         0u),                      /* TxFailed */
    SIG(VERDICT,  0,  8, ENUM,   1u,     tr_reason,    0u),                      /* TR_reason */
    SIG(VERDICT,  8,  8, ENUM,   1u,     rs_reason,    0u),                      /* RS_reason */
    SIG(VERDICT, 16,  1, BOOL,   1u,     tr_valid,     0u),                      /* TR_valid */
    SIG(VERDICT, 17,  1, BOOL,   1u,     rs_valid,     0u),                      /* RS_valid */
    SIG(VERDICT, 18,  1, SAT,    1u,     none,         IMEST_CAN_SAT_SPAN),      /* Sat_Span */
    SIG(VERDICT, 24, 16, SCALED, 1000u,  span_s,       IMEST_CAN_SAT_SPAN),      /* Span_s */
    SIG(VERDICT, 40,  8, COUNT,  1u,     windows,      0u),                      /* Windows */
    SIG(BOUNDS,   0, 16, SCALED, 50000u, tr_bound_rel, IMEST_CAN_SAT_TRB),       /* TR_bound_rel */
    SIG(BOUNDS,  16, 16, SCALED, 50000u, rs_bound_rel, IMEST_CAN_SAT_RSB),       /* RS_bound_rel */
    SIG(BOUNDS,  32,  1, SAT,    1u,     none,         IMEST_CAN_SAT_TRB),       /* Sat_TR_bound */
    SIG(BOUNDS,  33,  1, SAT,    1u,     none,         IMEST_CAN_SAT_RSB),       /* Sat_RS_bound */
};
// clang-format on

const imest_can_signal_t *imest_can_signal_table(unsigned int *count)
{
  if (count != NULL) *count = (unsigned int)(sizeof k_signals / sizeof k_signals[0]);
  return k_signals;
}
