/* SPDX-License-Identifier: Apache-2.0 */
// CAN telemetry: codec, publisher, reader, candump, callback and SocketCAN ports.
#include <gtest/gtest.h>

#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

extern "C" {
#include "example_stm32.h"
#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest_can_callback.h"
#include "imest_can_id.h"
#include "imest_candump.h"
#include "imest_socketcan.h"
}

namespace {

imest_result_t golden_result()
{
  imest_result_t r;
  std::memset(&r, 0, sizeof r);
  r.seq = 0x12345678u;
  r.valid = 1;
  r.status = IMEST_REASON_NONE;
  r.tr_valid = 1;
  r.rs_valid = 1;
  r.tr_reason = IMEST_REASON_NONE;
  r.rs_reason = IMEST_REASON_NONE;
  r.span_s = 1.0;
  r.windows = 1;
  r.tr_bound_rel = 0.01;
  r.rs_bound_rel = 0.05;
  r.flags = IMEST_FLAG_HESSIAN_PD;
  r.tr_s = 0.125;
  r.rs_ohm = 1.5;
  r.e_i = 0.02;
  r.pe_k1_rel = 0.01;
  r.pe_k2_rel = 0.005;
  r.n_roots = 3;
  r.n_admissible = 1;
  return r;
}

std::string hex(const imest_can_frame &f)
{
  char b[32];
  std::string s;
  for (unsigned i = 0; i < f.dlc; i++) {
    std::snprintf(b, sizeof b, "%02X", f.data[i]);
    s += b;
  }
  return s;
}

constexpr unsigned kAll = (1u << IMEST_CAN_NFRAMES) - 1u;

imest_can_window_t roundtrip(const imest_result_t &r, uint32_t base = IMEST_CAN_DEFAULT_BASE_ID)
{
  imest_can_window_t w;
  imest_can_window_clear(&w);
  for (unsigned i = 0; i < IMEST_CAN_NFRAMES; i++) {
    imest_can_frame f;
    EXPECT_EQ(imest_can_pack(&r, i, base, 7u, 0u, &f), IMEST_OK);
    EXPECT_EQ(imest_can_decode_frame(&f, base, &w, nullptr), IMEST_CAN_DEC_OK);
  }
  EXPECT_EQ(w.have, kAll);
  return w;
}

imest_can_pub_t make_pub(const imest_can_port *port, uint32_t base = IMEST_CAN_DEFAULT_BASE_ID)
{
  imest_can_pub_t pub;
  EXPECT_EQ(imest_can_pub_init(&pub, port, base), IMEST_OK);
  return pub;
}

// A port that records frames and can be told to fail.
struct FakePort {
  std::vector<imest_can_frame> frames;
  unsigned calls = 0;
  unsigned fail_index_mask = 0; // fail frames whose offset bit is set
  bool fail_all = false;
  static int send(void *ctx, const imest_can_frame *f)
  {
    FakePort *p = static_cast<FakePort *>(ctx);
    p->calls++;
    unsigned off = (f->id - IMEST_CAN_DEFAULT_BASE_ID) & 0x7FFu;
    if (p->fail_all || ((p->fail_index_mask >> off) & 1u)) return -1;
    p->frames.push_back(*f);
    return 0;
  }
  imest_can_port port() { return imest_can_port{&FakePort::send, this}; }
};

} // namespace

// ---------------------------------------------------------------- codec

TEST(CanCodec, Crc8SaeJ1850CheckValue)
{
  const unsigned char s[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(imest_can_crc8(s, 9u), 0x4Bu);
  EXPECT_EQ(imest_can_crc8(s, 0u), 0x00u);
}

// The exact bytes on the bus (computed independently with Python struct /
// int.to_bytes): pins the layout, byte order and CRC on every host. Frames
// 0..3 are byte for byte those of layout 1 (before VERDICT and BOUNDS).
TEST(CanCodec, GoldenFrames)
{
  const imest_result_t r = golden_result();
  const char *expect[IMEST_CAN_NFRAMES] = {"0000003EC8005AD3", "0000C03FFA005A86", "F401000360045A1A",
                                           "7856341202015AC4", "000003E803015A8D", "F401C40900005A55"};
  for (unsigned i = 0; i < IMEST_CAN_NFRAMES; i++) {
    imest_can_frame f;
    ASSERT_EQ(imest_can_pack(&r, i, IMEST_CAN_DEFAULT_BASE_ID, 0x5Au, 0x0102u, &f), IMEST_OK);
    EXPECT_EQ(f.id, IMEST_CAN_DEFAULT_BASE_ID + i);
    EXPECT_EQ(f.dlc, 8u);
    EXPECT_EQ(hex(f), expect[i]) << "frame " << i;
  }
}

TEST(CanCodec, ErrorsFollowTheApiContract)
{
  const imest_result_t r = golden_result();
  imest_can_frame f;
  imest_can_window_t w;
  imest_can_window_clear(&w);
  EXPECT_EQ(imest_can_pack(&r, IMEST_CAN_NFRAMES, 0x6A0u, 0u, 0u, &f), IMEST_ERR_ARG);
  EXPECT_EQ(imest_can_pack(&r, 0u, 0x7FCu, 0u, 0u, &f), IMEST_ERR_ARG) << "0x7FC+5 is not an 11-bit id";
  EXPECT_EQ(imest_can_pack(nullptr, 0u, 0x6A0u, 0u, 0u, &f), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_pack(&r, 0u, 0x6A0u, 0u, 0u, nullptr), IMEST_ERR_NULL);
  ASSERT_EQ(imest_can_pack(&r, 0u, 0x6A0u, 0u, 0u, &f), IMEST_OK);
  EXPECT_EQ(imest_can_decode_frame(nullptr, 0x6A0u, &w, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_decode_frame(&f, 0x6A0u, nullptr, nullptr), IMEST_ERR_NULL);
  imest_can_rx_t rx;
  EXPECT_EQ(imest_can_rx_init(nullptr, 0x6A0u), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_rx_init(&rx, 0x800u), IMEST_ERR_ARG);
  ASSERT_EQ(imest_can_rx_init(&rx, 0x6A0u), IMEST_OK);
  EXPECT_EQ(imest_can_rx_feed(nullptr, &f, &w, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_rx_feed(&rx, nullptr, &w, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_rx_flush(nullptr, &w, nullptr), IMEST_ERR_NULL);
}

TEST(CanCodec, BaseIdentifierRange)
{
  EXPECT_EQ(imest_can_base_id_check(0u), IMEST_OK);
  EXPECT_EQ(imest_can_base_id_check(0x7FFu - (IMEST_CAN_NFRAMES - 1u)), IMEST_OK);
  EXPECT_EQ(imest_can_base_id_check(0x7FFu - (IMEST_CAN_NFRAMES - 2u)), IMEST_ERR_ARG);
  EXPECT_EQ(imest_can_base_id_check(0x800u), IMEST_ERR_ARG) << "needs IMEST_CAN_ID_EXT";
  EXPECT_EQ(imest_can_base_id_check(0x800u | IMEST_CAN_ID_EXT), IMEST_OK);
  EXPECT_EQ(imest_can_base_id_check((0x1FFFFFFFu - (IMEST_CAN_NFRAMES - 1u)) | IMEST_CAN_ID_EXT), IMEST_OK);
  EXPECT_EQ(imest_can_base_id_check((0x1FFFFFFFu - (IMEST_CAN_NFRAMES - 2u)) | IMEST_CAN_ID_EXT),
            IMEST_ERR_ARG);
  EXPECT_EQ(imest_can_base_id_check(0x20000000u | IMEST_CAN_ID_EXT), IMEST_ERR_ARG);
}

// The table itself: every signal inside its frame's 48 data bits, no overlap,
// each clamped field guarded by exactly one transmitted saturation bit.
TEST(CanCodec, SignalTableIsConsistent)
{
  unsigned n = 0;
  const imest_can_signal_t *t = imest_can_signal_table(&n);
  ASSERT_GT(n, 0u);
  uint64_t used[IMEST_CAN_NFRAMES] = {};
  for (unsigned k = 0; k < n; k++) {
    ASSERT_LT(t[k].frame, IMEST_CAN_NFRAMES) << k;
    ASSERT_GE(t[k].len, 1u) << k;
    ASSERT_LE(t[k].start + t[k].len, IMEST_CAN_COUNTER_START) << "signal " << k << " runs into the counter";
    const uint64_t bits = (t[k].len == 64 ? ~0ull : ((1ull << t[k].len) - 1u)) << t[k].start;
    EXPECT_EQ(used[t[k].frame] & bits, 0u) << "signal " << k << " overlaps another";
    used[t[k].frame] |= bits;
    if (k > 0) {
      EXPECT_TRUE(t[k].frame > t[k - 1].frame ||
                  (t[k].frame == t[k - 1].frame && t[k].start > t[k - 1].start))
          << "table not ordered by frame and start bit at " << k;
    }
    switch (t[k].kind) {
    case IMEST_CAN_F32: EXPECT_EQ(t[k].len, 32u) << k; break;
    case IMEST_CAN_SCALED: EXPECT_GT(t[k].scale, 1u) << k; break;
    case IMEST_CAN_COUNT: EXPECT_LE(t[k].len, 16u) << k << ": unsigned int has 16 bits on C2000"; break;
    case IMEST_CAN_ENUM:
      EXPECT_GE(1u << t[k].len, IMEST_REASON_TRANSIENT + 2u) << k << ": every reason must fit";
      break;
    case IMEST_CAN_BOOL:
    case IMEST_CAN_FLAG:
    case IMEST_CAN_SAT: EXPECT_EQ(t[k].len, 1u) << k; break;
    default: break;
    }
    if (t[k].kind == IMEST_CAN_F32 || t[k].kind == IMEST_CAN_SCALED) {
      unsigned carried = 0;
      for (unsigned j = 0; j < n; j++) carried += t[j].kind == IMEST_CAN_SAT && t[j].mask == t[k].mask;
      EXPECT_EQ(carried, 1u) << "signal " << k << ": saturation bit 0x" << std::hex << t[k].mask;
    }
  }
  for (unsigned i = 0; i < IMEST_CAN_NFRAMES; i++) EXPECT_NE(used[i], 0u) << "frame " << i << " is empty";
}

TEST(CanCodec, RoundTripAllFields)
{
  const imest_result_t r = golden_result();
  imest_can_window_t w = roundtrip(r);
  EXPECT_EQ(w.result.seq, r.seq);
  EXPECT_EQ(w.result.tr_s, 0.125);
  EXPECT_EQ(w.result.rs_ohm, 1.5);
  EXPECT_NEAR(w.result.e_i, 0.02, 0.5e-4);
  EXPECT_NEAR(w.result.pe_k1_rel, 0.01, 1e-5);
  EXPECT_NEAR(w.result.pe_k2_rel, 0.005, 1e-5);
  EXPECT_EQ(w.result.valid, 1);
  EXPECT_EQ(w.result.status, IMEST_REASON_NONE);
  EXPECT_EQ(w.result.tr_valid, 1);
  EXPECT_EQ(w.result.rs_valid, 1);
  EXPECT_EQ(w.result.tr_reason, IMEST_REASON_NONE);
  EXPECT_EQ(w.result.rs_reason, IMEST_REASON_NONE);
  EXPECT_DOUBLE_EQ(w.result.tr_bound_rel, 0.01);
  EXPECT_DOUBLE_EQ(w.result.rs_bound_rel, 0.05);
  EXPECT_DOUBLE_EQ(w.result.span_s, 1.0);
  EXPECT_EQ(w.result.windows, 1u);
  EXPECT_EQ(w.result.flags, (unsigned)IMEST_FLAG_HESSIAN_PD);
  EXPECT_EQ(w.sat, 0u);
  EXPECT_EQ(w.result.n_roots, 3u);
  EXPECT_EQ(w.result.n_admissible, 1u);
  EXPECT_EQ(w.counter, 7u);
}

TEST(CanCodec, ClearedWindowSaysNotReceived)
{
  imest_can_window_t w;
  imest_can_window_clear(&w);
  EXPECT_EQ(w.have, 0u);
  EXPECT_TRUE(std::isnan(w.result.tr_s));
  EXPECT_TRUE(std::isnan(w.result.span_s));
  EXPECT_TRUE(std::isnan(w.result.rs_bound_rel));
  EXPECT_EQ(w.result.status, -1);
  EXPECT_EQ(w.result.tr_reason, -1);
  EXPECT_EQ(w.result.tr_valid, 0);
  imest_can_window_clear(nullptr); // no effect, no crash
}

// T_R from 1 ms to 10 s and R_S from 1 mohm to 100 ohm (and well beyond):
// float32 on the bus, so the decoded value is exactly (float)x.
TEST(CanCodec, Float32RangeAndResolution)
{
  for (int e = -60; e <= 30; e++) {
    for (double m : {1.0, 1.2345678901, 3.3333333333, 9.87654321}) {
      imest_result_t r = golden_result();
      r.tr_s = m * std::pow(10.0, e / 10.0);
      r.rs_ohm = 1.0 / r.tr_s;
      imest_can_window_t w = roundtrip(r);
      EXPECT_EQ(w.result.tr_s, static_cast<double>(static_cast<float>(r.tr_s)));
      EXPECT_EQ(w.result.rs_ohm, static_cast<double>(static_cast<float>(r.rs_ohm)));
      EXPECT_LE(std::fabs(w.result.tr_s - r.tr_s), 6e-8 * r.tr_s);
      EXPECT_EQ(w.sat, 0u);
    }
  }
}

TEST(CanCodec, NonFiniteAndOutOfRangeFloats)
{
  imest_result_t r = golden_result();
  r.tr_s = NAN;
  r.rs_ohm = INFINITY;
  imest_can_window_t w = roundtrip(r);
  EXPECT_TRUE(std::isnan(w.result.tr_s));
  EXPECT_TRUE(std::isinf(w.result.rs_ohm) && w.result.rs_ohm > 0);
  EXPECT_EQ(w.sat, 0u) << "NaN / inf are carried, not saturated";

  r.tr_s = 1e300; // finite but beyond float32: clamped with a flag
  r.rs_ohm = -1e39;
  w = roundtrip(r);
  EXPECT_EQ(w.result.tr_s, static_cast<double>(FLT_MAX));
  EXPECT_EQ(w.result.rs_ohm, -static_cast<double>(FLT_MAX));
  EXPECT_EQ(w.sat, IMEST_CAN_SAT_TR | IMEST_CAN_SAT_RS);

  r.tr_s = -std::numeric_limits<double>::infinity();
  r.rs_ohm = static_cast<double>(FLT_MAX); // the largest in-range value is not saturated
  w = roundtrip(r);
  EXPECT_TRUE(std::isinf(w.result.tr_s) && w.result.tr_s < 0);
  EXPECT_EQ(w.result.rs_ohm, static_cast<double>(FLT_MAX));
  EXPECT_EQ(w.sat, 0u);
}

TEST(CanCodec, ScaledFieldsResolutionSaturationAndNaN)
{
  imest_result_t r = golden_result();
  // resolution and rounding
  r.e_i = 1.23456;
  r.pe_k1_rel = 0.123456;
  r.pe_k2_rel = 0.00001; // half a step: rounds up to one step
  r.tr_bound_rel = 0.0123456;
  r.span_s = 0.2504;
  imest_can_window_t w = roundtrip(r);
  EXPECT_NEAR(w.result.e_i, 1.2346, 1e-12);
  EXPECT_NEAR(w.result.pe_k1_rel, 0.12346, 1e-12);
  EXPECT_NEAR(w.result.pe_k2_rel, 0.00002, 1e-12);
  EXPECT_NEAR(w.result.tr_bound_rel, 0.01234, 1e-12);
  EXPECT_NEAR(w.result.span_s, 0.250, 1e-12);
  EXPECT_EQ(w.sat, 0u);
  // the largest representable values, not saturated
  r.e_i = 6.5534;
  r.pe_k1_rel = 1.31068;
  r.pe_k2_rel = 0.0;
  r.rs_bound_rel = 1.31068;
  r.span_s = 65.534;
  w = roundtrip(r);
  EXPECT_NEAR(w.result.e_i, 6.5534, 1e-12);
  EXPECT_NEAR(w.result.pe_k1_rel, 1.31068, 1e-12);
  EXPECT_EQ(w.result.pe_k2_rel, 0.0);
  EXPECT_NEAR(w.result.rs_bound_rel, 1.31068, 1e-12);
  EXPECT_NEAR(w.result.span_s, 65.534, 1e-12);
  EXPECT_EQ(w.sat, 0u);
  // beyond: clamped to the maximum, with the flag
  r.e_i = 100.0;
  r.pe_k1_rel = INFINITY;
  r.pe_k2_rel = 1.3107;
  r.tr_bound_rel = 2.0;
  r.rs_bound_rel = 0.01;
  r.span_s = 120.0;
  w = roundtrip(r);
  EXPECT_NEAR(w.result.e_i, 6.5534, 1e-12);
  EXPECT_NEAR(w.result.pe_k1_rel, 1.31068, 1e-12);
  EXPECT_NEAR(w.result.pe_k2_rel, 1.31068, 1e-12);
  EXPECT_NEAR(w.result.tr_bound_rel, 1.31068, 1e-12);
  EXPECT_NEAR(w.result.span_s, 65.534, 1e-12);
  EXPECT_EQ(w.sat, IMEST_CAN_SAT_EI | IMEST_CAN_SAT_PEK1 | IMEST_CAN_SAT_PEK2 | IMEST_CAN_SAT_TRB |
                       IMEST_CAN_SAT_SPAN);
  // negative: clamped to 0 with the flag
  r = golden_result();
  r.e_i = -0.5;
  r.rs_bound_rel = -1.0;
  w = roundtrip(r);
  EXPECT_EQ(w.result.e_i, 0.0);
  EXPECT_EQ(w.result.rs_bound_rel, 0.0);
  EXPECT_EQ(w.sat, IMEST_CAN_SAT_EI | IMEST_CAN_SAT_RSB);
  // NaN: "not available" (raw all ones), no flag
  r.e_i = NAN;
  r.pe_k1_rel = NAN;
  r.pe_k2_rel = NAN;
  r.tr_bound_rel = NAN;
  r.rs_bound_rel = NAN;
  r.span_s = NAN;
  w = roundtrip(r);
  EXPECT_TRUE(std::isnan(w.result.e_i));
  EXPECT_TRUE(std::isnan(w.result.pe_k1_rel));
  EXPECT_TRUE(std::isnan(w.result.pe_k2_rel));
  EXPECT_TRUE(std::isnan(w.result.tr_bound_rel));
  EXPECT_TRUE(std::isnan(w.result.rs_bound_rel));
  EXPECT_TRUE(std::isnan(w.result.span_s));
  EXPECT_EQ(w.sat, 0u);
}

TEST(CanCodec, VerdictsReasonsFlagsAndCounts)
{
  imest_result_t r = golden_result();
  r.valid = 0;
  r.status = IMEST_REASON_RS_OUT_OF_RANGE;
  r.tr_valid = 1;
  r.rs_valid = 0;
  r.rs_reason = IMEST_REASON_RS_OUT_OF_RANGE;
  r.flags = IMEST_FLAG_WARMUP | IMEST_FLAG_INPUT_FAULT | IMEST_FLAG_ADC_SAT | IMEST_FLAG_ENCODER_FAULT |
            IMEST_FLAG_OVERRUN;
  r.n_roots = 20;
  r.n_admissible = 40; // saturates at 31
  r.windows = 60;
  imest_can_window_t w = roundtrip(r);
  EXPECT_EQ(w.result.valid, 0);
  EXPECT_EQ(w.result.status, IMEST_REASON_RS_OUT_OF_RANGE);
  EXPECT_EQ(w.result.tr_valid, 1);
  EXPECT_EQ(w.result.rs_valid, 0);
  EXPECT_EQ(w.result.tr_reason, IMEST_REASON_NONE);
  EXPECT_EQ(w.result.rs_reason, IMEST_REASON_RS_OUT_OF_RANGE);
  EXPECT_EQ(w.result.flags, r.flags);
  EXPECT_EQ(w.result.n_roots, 20u);
  EXPECT_EQ(w.result.n_admissible, 31u);
  EXPECT_EQ(w.result.windows, 60u);
  r.windows = 1000; // saturates at 255
  EXPECT_EQ(roundtrip(r).result.windows, 255u);
  // every reason travels as its stable number
  for (int reason = IMEST_REASON_WARMUP; reason <= IMEST_REASON_TRANSIENT; reason++) {
    r.status = r.tr_reason = r.rs_reason = reason;
    w = roundtrip(r);
    EXPECT_EQ(w.result.status, reason);
    EXPECT_EQ(w.result.tr_reason, reason);
    EXPECT_EQ(w.result.rs_reason, reason);
  }
  r.status = 300; // not a reason: out of range (255)
  r.tr_reason = -3;
  EXPECT_EQ(roundtrip(r).result.status, 255);
  EXPECT_EQ(roundtrip(r).result.tr_reason, 255);
  r.valid = 5; // any nonzero is "valid"
  r.rs_valid = -1;
  EXPECT_EQ(roundtrip(r).result.valid, 1);
  EXPECT_EQ(roundtrip(r).result.rs_valid, 1);
}

TEST(CanCodec, ExtendedIdentifiers)
{
  const uint32_t base = 0x18FF5000u | IMEST_CAN_ID_EXT;
  imest_result_t r = golden_result();
  imest_can_frame f;
  ASSERT_EQ(imest_can_pack(&r, 3u, base, 0u, 0u, &f), IMEST_OK);
  EXPECT_EQ(f.id, 0x18FF5003u | IMEST_CAN_ID_EXT);
  imest_can_window_t w = roundtrip(r, base);
  EXPECT_EQ(w.result.seq, r.seq);
  // the same number as a standard id, or the other kind, is not ours
  imest_can_window_t w2;
  imest_can_window_clear(&w2);
  f.id = 0x6A0u | IMEST_CAN_ID_EXT;
  EXPECT_EQ(imest_can_decode_frame(&f, 0x6A0u, &w2, nullptr), IMEST_CAN_DEC_FOREIGN);
  f.id = 0x6A0u + IMEST_CAN_NFRAMES;
  EXPECT_EQ(imest_can_decode_frame(&f, 0x6A0u, &w2, nullptr), IMEST_CAN_DEC_FOREIGN);
  f.id = 0x69Fu;
  EXPECT_EQ(imest_can_decode_frame(&f, 0x6A0u, &w2, nullptr), IMEST_CAN_DEC_FOREIGN);
}

TEST(CanCodec, EverySingleBitErrorIsDetected)
{
  const imest_result_t r = golden_result();
  for (unsigned i = 0; i < IMEST_CAN_NFRAMES; i++) {
    imest_can_frame f;
    ASSERT_EQ(imest_can_pack(&r, i, 0x6A0u, 1u, 0u, &f), IMEST_OK);
    for (unsigned bit = 0; bit < 64; bit++) {
      imest_can_frame g = f;
      g.data[bit / 8] = static_cast<unsigned char>(g.data[bit / 8] ^ (1u << (bit % 8)));
      imest_can_window_t w;
      imest_can_window_clear(&w);
      EXPECT_EQ(imest_can_decode_frame(&g, 0x6A0u, &w, nullptr), IMEST_CAN_DEC_BAD_CRC)
          << "frame " << i << " bit " << bit;
      EXPECT_EQ(w.have, 0u);
    }
    // a frame sent under another frame's identifier fails its CRC (data id)
    imest_can_frame g = f;
    g.id = 0x6A0u + ((i + 1u) % IMEST_CAN_NFRAMES);
    imest_can_window_t w;
    imest_can_window_clear(&w);
    EXPECT_EQ(imest_can_decode_frame(&g, 0x6A0u, &w, nullptr), IMEST_CAN_DEC_BAD_CRC);
    g = f;
    g.dlc = 7u;
    EXPECT_EQ(imest_can_decode_frame(&g, 0x6A0u, &w, nullptr), IMEST_CAN_DEC_BAD_DLC);
  }
}

// ---------------------------------------------------------------- publisher

TEST(CanPublish, InitValidatesArguments)
{
  imest_can_pub_t pub;
  FakePort p;
  imest_can_port port = p.port();
  EXPECT_EQ(imest_can_pub_init(nullptr, &port, 0x6A0u), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_pub_init(&pub, nullptr, 0x6A0u), IMEST_ERR_NULL);
  imest_can_port bad = {nullptr, nullptr};
  EXPECT_EQ(imest_can_pub_init(&pub, &bad, 0x6A0u), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_pub_init(&pub, &port, 0x7FAu), IMEST_OK);
  EXPECT_EQ(imest_can_pub_init(&pub, &port, 0x7FBu), IMEST_ERR_ARG); // 0x7FB+5 > 0x7FF
  EXPECT_EQ(imest_can_pub_init(&pub, &port, 0x800u), IMEST_ERR_ARG);
  EXPECT_EQ(imest_can_pub_init(&pub, &port, 0x1FFFFFFAu | IMEST_CAN_ID_EXT), IMEST_OK);
  EXPECT_EQ(imest_can_pub_init(&pub, &port, 0x1FFFFFFBu | IMEST_CAN_ID_EXT), IMEST_ERR_ARG);
  EXPECT_EQ(imest_can_pub_init(&pub, &port, 0x20000000u | IMEST_CAN_ID_EXT), IMEST_ERR_ARG);
  imest_result_t r = golden_result();
  imest_can_pub_t zero;
  std::memset(&zero, 0, sizeof zero);
  EXPECT_EQ(imest_can_publish(&zero, &r), IMEST_ERR_NULL) << "not initialised";
  EXPECT_EQ(p.calls, 0u);
}

TEST(CanPublish, SixFramesPerWindowAndRollingCounter)
{
  FakePort p;
  imest_can_port port = p.port();
  imest_can_pub_t pub = make_pub(&port);
  imest_result_t r = golden_result();
  pub.counter = 254u; // exercise the wrap of the 8-bit counter
  for (unsigned k = 0; k < 3; k++) {
    r.seq = k;
    EXPECT_EQ(imest_can_publish(&pub, &r), 0);
  }
  ASSERT_EQ(p.frames.size(), 3u * IMEST_CAN_NFRAMES);
  const unsigned expect_ctr[3] = {254u, 255u, 0u};
  for (unsigned k = 0; k < p.frames.size(); k++) {
    EXPECT_EQ(p.frames[k].id, IMEST_CAN_DEFAULT_BASE_ID + k % IMEST_CAN_NFRAMES);
    EXPECT_EQ(p.frames[k].data[6], expect_ctr[k / IMEST_CAN_NFRAMES]);
  }
  EXPECT_EQ(pub.counter, 257u);
  EXPECT_EQ(pub.tx_failed, 0u);
  EXPECT_EQ(imest_can_publish(nullptr, &r), IMEST_ERR_NULL);
  EXPECT_EQ(imest_can_publish(&pub, nullptr), IMEST_ERR_NULL);
}

TEST(CanPublish, FailedSendsAreCountedReportedAndNotRetried)
{
  FakePort p;
  imest_can_port port = p.port();
  imest_can_pub_t pub = make_pub(&port);
  imest_result_t r = golden_result();
  const unsigned N = IMEST_CAN_NFRAMES;
  p.fail_index_mask = 1u << IMEST_CAN_FRAME_RS; // queue refuses the second frame
  EXPECT_EQ(imest_can_publish(&pub, &r), 1);
  EXPECT_EQ(p.calls, N) << "one call per frame, no retry";
  EXPECT_EQ(pub.tx_failed, 1u);
  p.fail_all = true; // bus-off
  EXPECT_EQ(imest_can_publish(&pub, &r), static_cast<int>(N));
  EXPECT_EQ(p.calls, 2u * N);
  EXPECT_EQ(pub.tx_failed, 1u + N);
  p.fail_all = false;
  p.fail_index_mask = 0u;
  EXPECT_EQ(imest_can_publish(&pub, &r), 0);
  EXPECT_EQ(pub.counter, 3u);
  // the status frame carries the count
  ASSERT_EQ(p.frames.size(), 2u * N - 1u);
  imest_can_window_t w;
  imest_can_window_clear(&w);
  ASSERT_EQ(imest_can_decode_frame(&p.frames[N - 1u + IMEST_CAN_FRAME_STAT], IMEST_CAN_DEFAULT_BASE_ID, &w,
                                   nullptr),
            IMEST_CAN_DEC_OK);
  EXPECT_EQ(w.tx_failed, 1u + N);
  // the first window's status frame already counted its own failed frame
  imest_can_window_clear(&w);
  ASSERT_EQ(
      imest_can_decode_frame(&p.frames[IMEST_CAN_FRAME_STAT - 1u], IMEST_CAN_DEFAULT_BASE_ID, &w, nullptr),
      IMEST_CAN_DEC_OK);
  EXPECT_EQ(w.tx_failed, 1u);
  // saturation of the 16-bit field
  pub.tx_failed = 70000u;
  EXPECT_EQ(imest_can_publish(&pub, &r), 0);
  imest_can_window_clear(&w);
  ASSERT_EQ(imest_can_decode_frame(&p.frames[p.frames.size() - N + IMEST_CAN_FRAME_STAT],
                                   IMEST_CAN_DEFAULT_BASE_ID, &w, nullptr),
            IMEST_CAN_DEC_OK);
  EXPECT_EQ(w.tx_failed, 65535u);
}

// ---------------------------------------------------------------- reader

namespace {
std::vector<imest_can_frame> stream(unsigned n, unsigned seq0 = 0, unsigned ctr0 = 0)
{
  std::vector<imest_can_frame> v;
  imest_result_t r = golden_result();
  for (unsigned k = 0; k < n; k++) {
    r.seq = seq0 + k;
    r.tr_s = 0.1 + 0.01 * k;
    for (unsigned i = 0; i < IMEST_CAN_NFRAMES; i++) {
      imest_can_frame f;
      imest_can_pack(&r, i, 0x6A0u, (ctr0 + k) & 0xFFu, 0u, &f);
      v.push_back(f);
    }
  }
  return v;
}

struct Fed {
  std::vector<imest_can_window_t> windows;
  std::vector<imest_can_rx_event_t> events;
  imest_can_rx_t rx;
};

Fed feed(const std::vector<imest_can_frame> &v)
{
  Fed o;
  imest_can_rx_init(&o.rx, 0x6A0u);
  for (const auto &f : v) {
    imest_can_window_t w;
    imest_can_rx_event_t e;
    const int ev = imest_can_rx_feed(&o.rx, &f, &w, &e);
    EXPECT_GE(ev, 0);
    if (ev & IMEST_CAN_EV_WINDOW) o.windows.push_back(w);
    if (ev & ~IMEST_CAN_EV_WINDOW) o.events.push_back(e);
  }
  imest_can_window_t w;
  imest_can_rx_event_t e;
  const int ev = imest_can_rx_flush(&o.rx, &w, &e);
  if (ev > 0) {
    o.windows.push_back(w);
    o.events.push_back(e);
  }
  return o;
}

constexpr unsigned N = IMEST_CAN_NFRAMES;
} // namespace

TEST(CanReader, CleanStreamAcrossCounterWrap)
{
  Fed o = feed(stream(10, 100, 250));
  ASSERT_EQ(o.windows.size(), 10u);
  EXPECT_TRUE(o.events.empty());
  for (unsigned k = 0; k < 10; k++) {
    EXPECT_EQ(o.windows[k].have, kAll);
    EXPECT_EQ(o.windows[k].result.seq, 100u + k);
    EXPECT_EQ(o.windows[k].result.tr_s, static_cast<double>(static_cast<float>(0.1 + 0.01 * k)));
  }
  EXPECT_EQ(o.rx.st.frames, 10u * N);
  EXPECT_EQ(o.rx.st.lost + o.rx.st.repeated + o.rx.st.corrupt + o.rx.st.incomplete + o.rx.st.late, 0u);
}

TEST(CanReader, LostFrameGivesLossEventAndIncompleteWindow)
{
  auto v = stream(6);
  v.erase(v.begin() + 3 * N + IMEST_CAN_FRAME_RS); // window 3 loses IMEST_RS
  Fed o = feed(v);
  ASSERT_EQ(o.windows.size(), 6u);
  EXPECT_EQ(o.windows[3].have, kAll & ~(1u << IMEST_CAN_FRAME_RS));
  EXPECT_TRUE(std::isnan(o.windows[3].result.rs_ohm));
  EXPECT_EQ(o.windows[3].result.seq, 3u);
  EXPECT_EQ(o.rx.st.lost, 1u);
  EXPECT_EQ(o.rx.st.incomplete, 1u);
  EXPECT_EQ(o.rx.st.seq_gaps, 0u);
  ASSERT_EQ(o.events.size(), 1u);
  EXPECT_EQ(o.events[0].events & (IMEST_CAN_EV_LOST | IMEST_CAN_EV_INCOMPLETE),
            IMEST_CAN_EV_LOST | IMEST_CAN_EV_INCOMPLETE);
  EXPECT_EQ(o.events[0].lost, 1u);
  EXPECT_EQ(o.events[0].prev_counter, 2u);
}

TEST(CanReader, LostWholeWindowIsBusLossNotEstimatorGap)
{
  auto v = stream(6);
  v.erase(v.begin() + 2 * N, v.begin() + 3 * N); // window 2 entirely
  Fed o = feed(v);
  EXPECT_EQ(o.windows.size(), 5u);
  EXPECT_EQ(o.rx.st.lost, N);
  EXPECT_EQ(o.rx.st.incomplete, 0u);
  EXPECT_EQ(o.rx.st.seq_gaps, 0u);
}

TEST(CanReader, EstimatorOverrunShowsAsSequenceGap)
{
  auto v = stream(3, 0, 0);
  auto w = stream(3, 10, 3); // counter continues, seq jumps 2 -> 10
  v.insert(v.end(), w.begin(), w.end());
  Fed o = feed(v);
  EXPECT_EQ(o.windows.size(), 6u);
  EXPECT_EQ(o.rx.st.lost, 0u);
  EXPECT_EQ(o.rx.st.seq_gaps, 7u);
}

TEST(CanReader, RepeatedAndCorruptedCopiesAreDropped)
{
  auto v = stream(4);
  imest_can_frame bad = v[5];
  bad.data[2] ^= 0x10u;
  imest_can_frame shortf = v[8];
  shortf.dlc = 5u;
  imest_can_frame foreign = v[0];
  foreign.id = 0x123u;
  v.insert(v.begin() + 5, bad);  // corrupted copy before the good one
  v.insert(v.begin() + 3, v[2]); // repeat
  v.insert(v.begin() + 11, shortf);
  v.insert(v.begin() + 1, foreign);
  Fed o = feed(v);
  ASSERT_EQ(o.windows.size(), 4u);
  for (auto &w : o.windows) EXPECT_EQ(w.have, kAll);
  EXPECT_EQ(o.rx.st.repeated, 1u);
  EXPECT_EQ(o.rx.st.corrupt, 2u);
  EXPECT_EQ(o.rx.st.foreign, 1u);
  EXPECT_EQ(o.rx.st.lost, 0u);
}

// A frame that arrives corrupted is counted once, as corrupted, not also as lost.
TEST(CanReader, CorruptedFrameIsNotAlsoCountedLost)
{
  auto v = stream(5);
  v[2 * N + 1].data[0] ^= 0x01u; // window 2, IMEST_RS: bad CRC
  v[3 * N + N - 1].dlc = 3u;     // window 3, last frame: bad length
  v[4 * N].data[7] ^= 0xFFu;     // window 4, first frame: bad CRC
  Fed o = feed(v);
  ASSERT_EQ(o.windows.size(), 5u);
  EXPECT_EQ(o.rx.st.corrupt, 3u);
  EXPECT_EQ(o.rx.st.lost, 0u);
  EXPECT_EQ(o.rx.st.incomplete, 3u);
}

// The sender restarts: sequence number and counter start again. No loss.
TEST(CanReader, SenderRestartIsNotCountedAsLoss)
{
  auto v = stream(10, 50, 77);
  auto w = stream(5, 0, 0);
  v.insert(v.end(), w.begin(), w.end());
  Fed o = feed(v);
  EXPECT_EQ(o.windows.size(), 15u);
  EXPECT_EQ(o.rx.st.restarts, 1u);
  EXPECT_EQ(o.rx.st.lost, 0u);
  EXPECT_EQ(o.rx.st.seq_gaps, 0u);
  EXPECT_EQ(o.rx.st.incomplete, 0u);
  // ... and frames lost right after the restart still count
  v = stream(10, 50, 77);
  w = stream(5, 0, 0);
  w.erase(w.begin() + N + 2);
  v.insert(v.end(), w.begin(), w.end());
  o = feed(v);
  EXPECT_EQ(o.rx.st.restarts, 1u);
  EXPECT_EQ(o.rx.st.lost, 1u);
}

TEST(CanReader, FlushReturnsTheLastWindowWithoutCountingTheUnrecordedTail)
{
  auto v = stream(3, 0, 0);
  v.erase(v.end() - 2, v.end()); // capture ended two frames early
  Fed o = feed(v);
  ASSERT_EQ(o.windows.size(), 3u);
  EXPECT_EQ(o.windows.back().have, kAll >> 2) << "flush returns the last, incomplete window";
  EXPECT_EQ(o.rx.st.lost, 0u);
  EXPECT_EQ(o.rx.st.incomplete, 1u);
  imest_can_window_t x;
  EXPECT_EQ(imest_can_rx_flush(&o.rx, &x, nullptr), 0);
}

TEST(CanReader, JoiningMidWindowIsNotLoss)
{
  auto v = stream(3, 0, 0);
  v.erase(v.begin(), v.begin() + 4); // the monitor started during window 0
  Fed o = feed(v);
  ASSERT_EQ(o.windows.size(), 3u);
  EXPECT_EQ(o.rx.st.lost, 0u);
  EXPECT_EQ(o.rx.st.incomplete, 1u);
}

// A controller sending by identifier priority from several mailboxes can put
// the next window's first frame before this window's last one.
TEST(CanReader, LateFrameIsNotLost)
{
  auto v = stream(4, 0, 0);
  std::swap(v[2 * N - 1], v[2 * N]); // window 1's last frame after window 2's first
  Fed o = feed(v);
  ASSERT_EQ(o.windows.size(), 4u);
  EXPECT_EQ(o.rx.st.late, 1u);
  EXPECT_EQ(o.rx.st.lost, 0u);
  EXPECT_EQ(o.rx.st.incomplete, 1u);
  EXPECT_EQ(o.windows[2].have, kAll) << "the window after it is not disturbed";
}

// Random drops and corruptions (and a sender restart) over many streams: the
// totals are exact, every corrupted frame is counted once as corrupted and
// never also as lost. The first and last windows stay intact (what is missing
// before the first or after the last frame received is not loss by design).
TEST(CanReader, RandomLossAndCorruptionAreCountedExactly)
{
  std::mt19937 rng(12345u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int run = 0; run < 300; run++) {
    const unsigned windows = 30;
    const unsigned restart_at = (run % 3 == 0) ? 15u : 0u; // the node reboots before window 15
    std::vector<imest_can_frame> sent;
    for (unsigned k = 0; k < windows; k++) {
      const bool after = restart_at != 0 && k >= restart_at;
      auto w = stream(1, after ? k - restart_at : 100u + k, after ? k - restart_at : 40u + k);
      sent.insert(sent.end(), w.begin(), w.end());
    }
    std::vector<imest_can_frame> rx_frames;
    unsigned dropped = 0, corrupted = 0;
    for (size_t i = 0; i < sent.size(); i++) {
      const unsigned k = static_cast<unsigned>(i / N);
      const bool keep = k == 0 || k == windows - 1 ||
                        (k == restart_at && i % N == IMEST_CAN_FRAME_STAT); // the restart is seen
      const double x = u(rng);
      if (!keep && x < 0.12) {
        dropped++;
      } else if (!keep && x < 0.18) {
        imest_can_frame f = sent[i];
        if (x < 0.15) {
          f.data[static_cast<unsigned>(x * 1e4) % 8u] ^= 0x24u;
        } else {
          f.dlc = 6u;
        }
        rx_frames.push_back(f);
        corrupted++;
      } else {
        rx_frames.push_back(sent[i]);
      }
    }
    Fed o = feed(rx_frames);
    ASSERT_EQ(o.rx.st.corrupt, corrupted) << "run " << run;
    ASSERT_EQ(o.rx.st.lost, dropped) << "run " << run;
    ASSERT_EQ(o.rx.st.restarts, restart_at ? 1u : 0u) << "run " << run;
    ASSERT_EQ(o.rx.st.repeated + o.rx.st.late + o.rx.st.seq_gaps, 0u) << "run " << run;
    ASSERT_EQ(o.rx.st.frames, rx_frames.size());
  }
}

// ---------------------------------------------------------------- identifiers (tools)

TEST(CanIdParse, OneParserForEveryTool)
{
  uint32_t id = 0;
  char err[256];
  EXPECT_EQ(imest_can_id_parse("0x6A0", 0, "--ext", &id, err, sizeof err), IMEST_OK);
  EXPECT_EQ(id, 0x6A0u);
  EXPECT_EQ(imest_can_id_parse("1696", 0, "--ext", &id, err, sizeof err), IMEST_OK);
  EXPECT_EQ(id, 0x6A0u);
  EXPECT_EQ(imest_can_id_parse("0x18FF5000", 0, "--ext", &id, err, sizeof err), IMEST_OK);
  EXPECT_EQ(id, 0x18FF5000u | IMEST_CAN_ID_EXT) << "above 0x7FF: extended, automatically";
  EXPECT_EQ(imest_can_id_parse("0x98FF5000", 0, "--ext", &id, err, sizeof err), IMEST_OK);
  EXPECT_EQ(id, 0x18FF5000u | IMEST_CAN_ID_EXT) << "CAN_EFF_FLAG | id, as older scripts wrote it";
  EXPECT_EQ(imest_can_id_parse("0x100", 1, "--ext", &id, err, sizeof err), IMEST_OK);
  EXPECT_EQ(id, 0x100u | IMEST_CAN_ID_EXT) << "forced extended";
  EXPECT_EQ(imest_can_id_parse("0x7FA", 0, "--ext", &id, err, sizeof err), IMEST_OK);
  EXPECT_EQ(imest_can_id_parse("0x1FFFFFFA", 0, "--ext", &id, err, sizeof err), IMEST_OK);
  struct Bad {
    const char *text;
    const char *why;
  } bad[] = {{"0x7FB", "beyond the 11-bit range (largest base 0x7FA); use a lower base, or --can-ext"},
             {"0x1FFFFFFB", "beyond the 29-bit range (largest base 0x1FFFFFFA)"},
             {"0x20000000", "beyond the 29-bit range (largest identifier 0x1FFFFFFF)"},
             {"0xFFFFFFFFFF", "beyond the 29-bit range"},
             {"-1", "negative"},
             {"zz", "not an identifier"},
             {"", "not an identifier"},
             {"0x", "not an identifier"},
             {"6A0", "not an identifier"},
             {"0x6A0 junk", "not an identifier"}};
  for (const auto &b : bad) {
    id = 12345u;
    EXPECT_EQ(imest_can_id_parse(b.text, 0, "--can-ext", &id, err, sizeof err), IMEST_ERR_ARG) << b.text;
    EXPECT_NE(std::string(err).find(b.why), std::string::npos) << b.text << " -> " << err;
    EXPECT_EQ(id, 12345u) << "untouched on error";
  }
  EXPECT_EQ(imest_can_id_parse(nullptr, 0, "--ext", &id, err, sizeof err), IMEST_ERR_NULL);
  char buf[24];
  EXPECT_STREQ(imest_can_id_format(0x6A0u, buf, sizeof buf), "0x6A0");
  EXPECT_STREQ(imest_can_id_format(0x6A0u | IMEST_CAN_ID_EXT, buf, sizeof buf), "0x000006A0");
}

// ---------------------------------------------------------------- candump

TEST(Candump, FormatLines)
{
  imest_can_frame f = {0x6A0u, 8u, {0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x01, 0x7F, 0x80}};
  char buf[IMEST_CANDUMP_LINE_MAX];
  ASSERT_GT(imest_candump_format(buf, sizeof buf, 1700000000.25, nullptr, &f), 0);
  EXPECT_STREQ(buf, "(1700000000.250000) vcan0 6A0#DEADBEEF00017F80");
  f.id = 0x18FF5003u | IMEST_CAN_ID_EXT;
  f.dlc = 2u;
  ASSERT_GT(imest_candump_format(buf, sizeof buf, 1.9999999, "can1", &f), 0);
  EXPECT_STREQ(buf, "(0000000002.000000) can1 18FF5003#DEAD");
  f.id = 0x7u;
  f.dlc = 0u;
  ASSERT_GT(imest_candump_format(buf, sizeof buf, -5.0, "vcan0", &f), 0);
  EXPECT_STREQ(buf, "(0000000000.000000) vcan0 007#");
  EXPECT_EQ(imest_candump_format(buf, 10u, 0.0, nullptr, &f), -1) << "buffer too small";
  f.dlc = 9u;
  EXPECT_EQ(imest_candump_format(buf, sizeof buf, 0.0, nullptr, &f), -1);
  f.dlc = 1u;
  f.id = 0x800u;
  EXPECT_EQ(imest_candump_format(buf, sizeof buf, 0.0, nullptr, &f), -1);
  f.id = 0x1u;
  EXPECT_EQ(imest_candump_format(buf, sizeof buf, 0.0, "bad name", &f), -1);
}

TEST(Candump, ParseGoodLines)
{
  imest_can_frame f;
  double t = 0;
  char ifn[IMEST_CANDUMP_IFNAMSIZ];
  const char *err = nullptr;
  ASSERT_EQ(imest_candump_parse("(1700000000.123456) vcan0 123#DEADbeef\n", &t, ifn, &f, &err),
            IMEST_CANDUMP_OK);
  EXPECT_DOUBLE_EQ(t, 1700000000.123456);
  EXPECT_STREQ(ifn, "vcan0");
  EXPECT_EQ(f.id, 0x123u);
  EXPECT_EQ(f.dlc, 4u);
  EXPECT_EQ(f.data[0], 0xDEu);
  EXPECT_EQ(f.data[3], 0xEFu);
  ASSERT_EQ(imest_candump_parse("  (0.5)\tcan0  18FF5003#0102030405060708\r\n", &t, ifn, &f, &err),
            IMEST_CANDUMP_OK);
  EXPECT_EQ(f.id, 0x18FF5003u | IMEST_CAN_ID_EXT);
  EXPECT_EQ(f.dlc, 8u);
  EXPECT_EQ(f.data[7], 8u);
  ASSERT_EQ(imest_candump_parse("(1.0) vcan0 7FF#", &t, nullptr, &f, &err), IMEST_CANDUMP_OK);
  EXPECT_EQ(f.dlc, 0u);
  EXPECT_EQ(imest_candump_parse("\n", &t, nullptr, &f, &err), IMEST_CANDUMP_EMPTY);
  EXPECT_EQ(imest_candump_parse("", &t, nullptr, &f, &err), IMEST_CANDUMP_EMPTY);
}

TEST(Candump, ParseMalformedAndTruncatedLines)
{
  struct Case {
    const char *line;
    const char *why;
  } cases[] = {
      {"vcan0 123#00", "expected '('"},
      {"(1700000000.000000", "')'"},
      {"(1700000000.000000)", "blank"},
      {"(1700000000.000000) vcan0", "truncated"},
      {"(1700000000.000000) vcan0 ", "missing frame"},
      {"(1700000000.000000) vcan0 12", "'#'"},
      {"(1700000000.000000) vcan0 123", "'#'"},
      {"(abc) vcan0 123#00", "timestamp"},
      {"(17.) vcan0 123#00", "timestamp"},
      {"(17) vcan0 123#00", "timestamp"},
      {"(1.5) vcan0 12#00", "3 (standard) or 8 (extended)"},
      {"(1.5) vcan0 1234#00", "3 (standard) or 8 (extended)"},
      {"(1.5) vcan0 800#00", "above 0x7FF"},
      {"(1.5) vcan0 20000080#0000000000000000", "error frame"},
      {"(1.5) vcan0 123#0", "odd number"},
      {"(1.5) vcan0 123#DEADBEE", "odd number"},
      {"(1.5) vcan0 123#001122334455667788", "more than 8"},
      {"(1.5) vcan0 123##1001122", "CAN FD"},
      {"(1.5) vcan0 123#R", "remote"},
      {"(1.5) vcan0 123#00 junk", "unexpected"},
      {"(1.5) vcan0 123#00G1", "unexpected"},
      {"(1.5) averyveryverylongifname 123#00", "15 characters"},
  };
  for (const auto &c : cases) {
    imest_can_frame f;
    const char *err = nullptr;
    EXPECT_EQ(imest_candump_parse(c.line, nullptr, nullptr, &f, &err), IMEST_CANDUMP_ERROR) << c.line;
    ASSERT_NE(err, nullptr) << c.line;
    EXPECT_NE(std::string(err).find(c.why), std::string::npos) << c.line << " -> " << err;
  }
}

TEST(Candump, PortWritesParseableLines)
{
  FILE *fp = std::tmpfile();
  ASSERT_NE(fp, nullptr);
  imest_candump_port cd;
  EXPECT_EQ(imest_candump_port_open(&cd, fp, "bad name"), -1);
  EXPECT_EQ(imest_candump_port_open(&cd, nullptr, nullptr), -1);
  ASSERT_EQ(imest_candump_port_open(&cd, fp, nullptr), 0);
  EXPECT_STREQ(cd.iface, "vcan0");
  imest_can_pub_t pub = make_pub(&cd.port);
  imest_result_t r = golden_result();
  imest_candump_port_set_time(&cd, 1700000012.5);
  ASSERT_EQ(imest_can_publish(&pub, &r), 0);
  EXPECT_EQ(cd.lines, N);
  std::rewind(fp);
  char line[128];
  imest_can_window_t w;
  imest_can_window_clear(&w);
  unsigned n = 0;
  while (std::fgets(line, sizeof line, fp)) {
    imest_can_frame f;
    double t;
    char ifn[IMEST_CANDUMP_IFNAMSIZ];
    const char *err = nullptr;
    ASSERT_EQ(imest_candump_parse(line, &t, ifn, &f, &err), IMEST_CANDUMP_OK) << line;
    EXPECT_DOUBLE_EQ(t, 1700000012.5);
    EXPECT_STREQ(ifn, "vcan0");
    EXPECT_EQ(imest_can_decode_frame(&f, 0x6A0u, &w, nullptr), IMEST_CAN_DEC_OK);
    n++;
  }
  EXPECT_EQ(n, N);
  EXPECT_EQ(w.have, kAll);
  EXPECT_EQ(w.result.tr_s, 0.125);
  std::fclose(fp);
}

TEST(Candump, WriteErrorIsAFailedSend)
{
  FILE *fp = std::fopen("/dev/full", "w");
  if (fp == nullptr) GTEST_SKIP() << "/dev/full not available";
  std::setvbuf(fp, nullptr, _IONBF, 0);
  imest_candump_port cd;
  ASSERT_EQ(imest_candump_port_open(&cd, fp, "vcan0"), 0);
  imest_can_pub_t pub = make_pub(&cd.port);
  imest_result_t r = golden_result();
  EXPECT_EQ(imest_can_publish(&pub, &r), static_cast<int>(N));
  EXPECT_EQ(pub.tx_failed, N);
  EXPECT_EQ(cd.failed, N);
  std::fclose(fp);
}

// ---------------------------------------------------------------- callback port

namespace {
struct HalLog {
  std::vector<imest_can_frame> f;
  std::vector<int> ext;
  int refuse = 0;
};
int hal_tx(void *hal, uint32_t id, int extended, const unsigned char *data, unsigned dlc)
{
  HalLog *h = static_cast<HalLog *>(hal);
  if (h->refuse) return 1;
  imest_can_frame f;
  f.id = id;
  f.dlc = dlc;
  std::memcpy(f.data, data, dlc);
  h->f.push_back(f);
  h->ext.push_back(extended);
  return 0;
}
} // namespace

TEST(CanCallbackPort, ForwardsFramesAndCountsRefusals)
{
  HalLog hal;
  imest_can_callback cb;
  EXPECT_EQ(imest_can_callback_init(nullptr, hal_tx, &hal), -1);
  EXPECT_EQ(imest_can_callback_init(&cb, nullptr, &hal), -1);
  ASSERT_EQ(imest_can_callback_init(&cb, hal_tx, &hal), 0);
  imest_can_pub_t pub = make_pub(&cb.port, 0x1ABCDE0u | IMEST_CAN_ID_EXT);
  imest_result_t r = golden_result();
  ASSERT_EQ(imest_can_publish(&pub, &r), 0);
  ASSERT_EQ(hal.f.size(), N);
  for (unsigned i = 0; i < N; i++) {
    EXPECT_EQ(hal.f[i].id, 0x1ABCDE0u + i) << "HAL gets the bare 29-bit id";
    EXPECT_EQ(hal.ext[i], 1);
    imest_can_frame expect;
    imest_can_pack(&r, i, 0x1ABCDE0u | IMEST_CAN_ID_EXT, 0u, 0u, &expect);
    EXPECT_EQ(0, std::memcmp(expect.data, hal.f[i].data, 8));
  }
  hal.refuse = 1;
  EXPECT_EQ(imest_can_publish(&pub, &r), static_cast<int>(N));
  EXPECT_EQ(cb.sent, N);
  EXPECT_EQ(cb.failed, N);
  EXPECT_EQ(pub.tx_failed, N);
}

// The STM32-HAL-style example (software queue of 8 in front of 3 mailboxes) on the fake HAL.
TEST(CanCallbackPort, Stm32ExampleQueuesDrainsAndRefusesWhenBusOff)
{
  static CAN_HandleTypeDef hcan;
  static example_can_tx_t tx;
  std::memset(&hcan, 0, sizeof hcan);
  example_can_tx_init(&tx, &hcan);
  imest_can_callback cb;
  ASSERT_EQ(imest_can_callback_init(&cb, example_stm32_can_tx, &tx), 0);
  imest_can_pub_t pub = make_pub(&cb.port);
  imest_result_t r = golden_result();
  // 6 frames, 3 mailboxes: all accepted, 3 wait in the queue
  ASSERT_EQ(imest_can_publish(&pub, &r), 0);
  EXPECT_EQ(HAL_CAN_GetTxMailboxesFreeLevel(&hcan), 0u);
  fake_can_complete(&hcan); // the interrupt moves the queued three into mailboxes
  fake_can_complete(&hcan);
  ASSERT_EQ(hcan.n_log, N);
  for (unsigned i = 0; i < N; i++) EXPECT_EQ(hcan.log[i].id, 0x6A0u + i);
  // bus-off: 8 frames fit the queue, then refusals are counted, not retried
  hcan.bus_off = 1;
  EXPECT_EQ(imest_can_publish(&pub, &r), 0);                        // window 1: queued
  EXPECT_EQ(imest_can_publish(&pub, &r), static_cast<int>(N - 2u)); // window 2: 2 queued
  EXPECT_EQ(imest_can_publish(&pub, &r), static_cast<int>(N));      // window 3: none
  EXPECT_EQ(pub.tx_failed, 2u * N - 2u);
  // recovery: the queue drains, the next window partly goes out
  hcan.bus_off = 0;
  EXPECT_EQ(imest_can_publish(&pub, &r), 3) << "3 old frames move to the mailboxes: room for 3 new";
  for (int k = 0; k < 10; k++) fake_can_complete(&hcan);
  EXPECT_EQ(hcan.n_log, N + N + 2u + 3u);
  // the reader sees the loss: 4 frames of window 2, all of window 3; window 4's
  // last 3 are after the end of this capture (not counted)
  imest_can_rx_t rx;
  imest_can_rx_init(&rx, 0x6A0u);
  for (unsigned i = 0; i < hcan.n_log; i++) {
    imest_can_frame f;
    f.id = hcan.log[i].id;
    f.dlc = hcan.log[i].dlc;
    for (unsigned b = 0; b < 8; b++) f.data[b] = hcan.log[i].data[b];
    imest_can_window_t w;
    imest_can_rx_feed(&rx, &f, &w, nullptr);
  }
  imest_can_window_t w;
  EXPECT_GT(imest_can_rx_flush(&rx, &w, nullptr), 0);
  EXPECT_EQ(rx.st.corrupt, 0u);
  EXPECT_EQ(rx.st.windows, 4u);
  EXPECT_EQ(rx.st.lost, (N - 2u) + N);
}

// ---------------------------------------------------------------- SocketCAN

TEST(SocketCan, ErrorsAreClear)
{
  imest_socketcan sc;
  int rc = imest_socketcan_open(&sc, "vcan0");
  if (rc == -EAFNOSUPPORT || rc == -EPROTONOSUPPORT) {
    // this machine: no CAN in the kernel
    EXPECT_NE(std::string(sc.err).find("no SocketCAN support"), std::string::npos) << sc.err;
    EXPECT_NE(std::string(sc.err).find("can-raw"), std::string::npos) << sc.err;
    EXPECT_NE(std::string(sc.err).find("vcan0"), std::string::npos) << sc.err;
    EXPECT_EQ(sc.fd, -1);
  } else {
    if (rc == 0) imest_socketcan_close(&sc);
    rc = imest_socketcan_open(&sc, "imestnosuch0");
    EXPECT_EQ(rc, -ENODEV);
    EXPECT_NE(std::string(sc.err).find("no such network interface 'imestnosuch0'"), std::string::npos)
        << sc.err;
  }
  rc = imest_socketcan_open(&sc, "a-name-far-too-long-for-ifnamsiz");
  EXPECT_EQ(rc, -EINVAL);
  EXPECT_NE(std::string(sc.err).find("invalid CAN interface name"), std::string::npos);
  rc = imest_socketcan_open(&sc, "");
  EXPECT_EQ(rc, -EINVAL);
  // a port that failed to open refuses frames (counted by the publisher)
  imest_can_pub_t pub = make_pub(&sc.port);
  imest_result_t r = golden_result();
  EXPECT_EQ(imest_can_publish(&pub, &r), static_cast<int>(N));
  EXPECT_EQ(pub.tx_failed, N);
  imest_can_frame f;
  EXPECT_EQ(imest_socketcan_recv(&sc, &f, 0, nullptr), -EINVAL);
  imest_socketcan_close(&sc);
  imest_socketcan_close(&sc);
}

// ---------------------------------------------------------------- wiring

// The application publishes each result imest_background() returns; what
// arrives decodes to that result, verdicts and all. The estimator itself
// sends nothing.
TEST(CanPublish, ApplicationPublishesEveryBackgroundResult)
{
  static imest_t s;
  imest_config_t cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = 2;
  cfg.ls_h = 0.2908f;
  cfg.sigma = 0.096f;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.window_s = 0.25f;
  ASSERT_EQ(imest_init(&s, &cfg), IMEST_OK);
  FakePort p;
  imest_can_port port = p.port();
  imest_can_pub_t pub = make_pub(&port);
  imest_can_rx_t rx;
  imest_can_rx_init(&rx, IMEST_CAN_DEFAULT_BASE_ID);
  std::vector<imest_result_t> results;
  size_t fed = 0;
  std::vector<imest_can_window_t> windows;
  for (int n = 0; n < 4000; n++) {
    const float t = static_cast<float>(n) / 4000.0f;
    const float w = 2.0f * 3.14159265f * 20.0f;
    if (imest_isr_ab(&s, 100.0f * std::cos(w * t), 100.0f * std::sin(w * t), 5.0f * std::cos(w * t - 0.5f),
                     5.0f * std::sin(w * t - 0.5f), std::fmod(0.9f * w * t / 2.0f, 6.2831853f))) {
      imest_result_t r;
      while (imest_background(&s, &r) == 1) {
        EXPECT_EQ(p.frames.size(), N * results.size()) << "imest_background() must not send";
        EXPECT_EQ(imest_can_publish(&pub, &r), 0);
        results.push_back(r);
      }
      for (; fed < p.frames.size(); fed++) {
        imest_can_window_t win;
        if (imest_can_rx_feed(&rx, &p.frames[fed], &win, nullptr) & IMEST_CAN_EV_WINDOW)
          windows.push_back(win);
      }
    }
  }
  ASSERT_GE(results.size(), 3u);
  ASSERT_EQ(p.frames.size(), N * results.size());
  ASSERT_EQ(windows.size(), results.size());
  auto same = [](double bus, double x) {
    return std::isnan(x) ? std::isnan(bus) : bus == static_cast<double>(static_cast<float>(x));
  };
  for (size_t k = 0; k < results.size(); k++) {
    const imest_result_t &a = windows[k].result, &b = results[k];
    EXPECT_EQ(windows[k].have, kAll);
    EXPECT_EQ(a.seq, b.seq);
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.valid, b.valid ? 1 : 0);
    EXPECT_EQ(a.tr_valid, b.tr_valid ? 1 : 0);
    EXPECT_EQ(a.rs_valid, b.rs_valid ? 1 : 0);
    EXPECT_EQ(a.tr_reason, b.tr_reason);
    EXPECT_EQ(a.rs_reason, b.rs_reason);
    EXPECT_EQ(a.windows, b.windows);
    EXPECT_NEAR(a.span_s, b.span_s, 0.5e-3);
    EXPECT_EQ(std::isnan(a.tr_bound_rel), std::isnan(b.tr_bound_rel));
    EXPECT_TRUE(same(a.tr_s, b.tr_s)) << a.tr_s << " " << b.tr_s;
    EXPECT_TRUE(same(a.rs_ohm, b.rs_ohm)) << a.rs_ohm << " " << b.rs_ohm;
  }
  EXPECT_EQ(pub.counter, results.size());
  EXPECT_EQ(rx.st.lost + rx.st.corrupt + rx.st.repeated, 0u);
}
