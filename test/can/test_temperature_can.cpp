/* SPDX-License-Identifier: Apache-2.0 */
// IMEST_TEMP (imest_temperature.h): the temperatures' CAN frame at base + 6, packed, published and
// decoded; the six frames' reader keeps ignoring it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

extern "C" {
#include "imest/imest.h"
#include "imest/imest_can.h"
#include "imest/imest_temperature.h"
}

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

imest_temperature_t temps(float sc, float su, int sv, float rc, float ru, int rv)
{
  imest_temperature_t t;
  std::memset(&t, 0, sizeof t);
  t.stator_c = sc;
  t.stator_uncert_k = su;
  t.stator_valid = sv;
  t.rotor_c = rc;
  t.rotor_uncert_k = ru;
  t.rotor_valid = rv;
  return t;
}

imest_temperature_can_t round_trip(const imest_temperature_t &t, uint32_t base = IMEST_CAN_DEFAULT_BASE_ID,
                                   unsigned int counter = 7u)
{
  imest_can_frame_t f;
  imest_temperature_can_t d;
  std::memset(&d, 0x5A, sizeof d);
  EXPECT_EQ(imest_temperature_can_pack(&t, base, counter, &f), IMEST_OK);
  EXPECT_EQ(imest_temperature_can_decode(&f, base, &d), IMEST_CAN_DEC_OK);
  return d;
}

// what the DBC says: CRC-8 SAE J1850 over [6, bytes 0..6], written independently of the module
unsigned int crc_j1850(const unsigned char *d)
{
  unsigned int crc = 0xFFu;
  unsigned char buf[8] = {6u};
  std::memcpy(buf + 1, d, 7);
  for (unsigned char b : buf) {
    crc ^= b;
    for (int k = 0; k < 8; ++k) crc = (crc & 0x80u) ? ((crc << 1) ^ 0x1Du) & 0xFFu : (crc << 1) & 0xFFu;
  }
  return crc ^ 0xFFu;
}

// every member still 0, as memset left it
bool untouched(const imest_temperature_can_t &d)
{
  return d.stator_c == 0.0f && d.stator_uncert_k == 0.0f && d.stator_valid == 0 && d.rotor_c == 0.0f &&
         d.rotor_uncert_k == 0.0f && d.rotor_valid == 0 && d.counter == 0u && d.clamped == 0u;
}

struct Sent {
  std::vector<imest_can_frame_t> frames;
  int refuse = 0;
};

int send_fn(void *ctx, const imest_can_frame_t *f)
{
  auto *s = static_cast<Sent *>(ctx);
  if (s->refuse) return -1;
  s->frames.push_back(*f);
  return 0;
}

} // namespace

TEST(TemperatureCan, LayoutBytesAndCrc)
{
  // 85.25 degC = raw 8525 = 0x214D; -12.34 = -1234 = 0xFB2E; 3.0 K = 15; 4.4 K = 22
  const imest_temperature_t t = temps(85.25f, 3.0f, 1, -12.34f, 4.4f, 0);
  imest_can_frame_t f;
  ASSERT_EQ(imest_temperature_can_pack(&t, 0x6A0u, 0x1ABu, &f), IMEST_OK);
  EXPECT_EQ(f.id, 0x6A6u);
  EXPECT_EQ(f.dlc, 8u);
  const unsigned char want[7] = {0x4D, 0x21, 0x2E, 0xFB, 15u | 0x80u, 22u, 0xAB};
  for (int k = 0; k < 7; ++k) EXPECT_EQ(f.data[k], want[k]) << "octet " << k;
  EXPECT_EQ(f.data[7], crc_j1850(f.data));
  // the library's CRC, over the same octets
  unsigned char buf[8] = {6u};
  std::memcpy(buf + 1, f.data, 7);
  EXPECT_EQ(f.data[7], imest_can_crc8(buf, 8u));
  const imest_temperature_can_t d = round_trip(t, 0x6A0u, 0x1ABu);
  EXPECT_FLOAT_EQ(d.stator_c, 85.25f);
  EXPECT_FLOAT_EQ(d.stator_uncert_k, 3.0f);
  EXPECT_EQ(d.stator_valid, 1);
  EXPECT_FLOAT_EQ(d.rotor_c, -12.34f);
  EXPECT_FLOAT_EQ(d.rotor_uncert_k, 4.4f);
  EXPECT_EQ(d.rotor_valid, 0);
  EXPECT_EQ(d.counter, 0xABu);
  EXPECT_EQ(d.clamped, 0u);
}

TEST(TemperatureCan, RoundTripOverTheRangesWithinTheResolution)
{
  for (int i = 0; i <= 1767; ++i) {
    const float c = -327.0f + 0.37f * (float)i; // -327 .. 326.8
    const float u = std::fabs(c) / 13.0f;       // 0 .. 25.2 K
    const imest_temperature_can_t d = round_trip(temps(c, u, 0, -c, u, 1));
    EXPECT_NEAR(d.stator_c, c, 0.005f + 1e-4f) << c;
    EXPECT_NEAR(d.rotor_c, -c, 0.005f + 1e-4f) << c;
    EXPECT_NEAR(d.stator_uncert_k, u, 0.1f + 1e-4f) << u;
    EXPECT_NEAR(d.rotor_uncert_k, u, 0.1f + 1e-4f) << u;
    EXPECT_EQ(d.stator_valid, 0);
    EXPECT_EQ(d.rotor_valid, 1);
  }
  // the raw steps themselves come back exactly (as float32 of raw / scale)
  for (int raw = -32767; raw <= 32767; raw += 97) {
    const float c = (float)raw / 100.0f;
    EXPECT_EQ(round_trip(temps(c, 1.0f, 1, c, 1.0f, 1)).stator_c, c) << raw;
  }
  for (int raw = 0; raw <= 125; ++raw) {
    const float u = (float)raw / 5.0f;
    const imest_temperature_can_t d = round_trip(temps(20.0f, u, 1, 20.0f, u, 1));
    EXPECT_EQ(d.stator_uncert_k, u) << raw;
    EXPECT_EQ(d.clamped, 0u) << raw;
  }
}

TEST(TemperatureCan, NotAvailableAndClamping)
{
  imest_temperature_can_t d = round_trip(temps(kNaN, kNaN, 0, kNaN, kNaN, 0));
  EXPECT_TRUE(std::isnan(d.stator_c));
  EXPECT_TRUE(std::isnan(d.stator_uncert_k));
  EXPECT_TRUE(std::isnan(d.rotor_c));
  EXPECT_TRUE(std::isnan(d.rotor_uncert_k));
  EXPECT_EQ(d.clamped, 0u);
  imest_can_frame_t f;
  const imest_temperature_t na = temps(kNaN, kNaN, 0, kNaN, kNaN, 0);
  ASSERT_EQ(imest_temperature_can_pack(&na, 0x6A0u, 0u, &f), IMEST_OK);
  EXPECT_EQ(f.data[0], 0x00);
  EXPECT_EQ(f.data[1], 0x80); // raw -32768
  EXPECT_EQ(f.data[4], 127);
  // beyond the range: the field's ends, flagged as bounds on decoding
  d = round_trip(temps(1000.0f, 30.0f, 1, -500.0f, kInf, 1));
  EXPECT_FLOAT_EQ(d.stator_c, 327.67f);
  EXPECT_FLOAT_EQ(d.rotor_c, -327.67f);
  EXPECT_FLOAT_EQ(d.stator_uncert_k, 25.2f);
  EXPECT_FLOAT_EQ(d.rotor_uncert_k, 25.2f);
  EXPECT_EQ(d.clamped, IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C | IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C |
                           IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT |
                           IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_UNCERT);
  d = round_trip(temps(kInf, 25.1f, 0, -kInf, 25.09f, 0));
  EXPECT_FLOAT_EQ(d.stator_c, 327.67f);
  EXPECT_FLOAT_EQ(d.rotor_c, -327.67f);
  EXPECT_FLOAT_EQ(d.stator_uncert_k, 25.2f); // 25.1 rounds to 25.2: the end
  EXPECT_FLOAT_EQ(d.rotor_uncert_k, 25.0f);  // 25.09 to 25.0: still a value
  EXPECT_EQ(d.clamped, IMEST_TEMPERATURE_CAN_CLAMP_STATOR_C | IMEST_TEMPERATURE_CAN_CLAMP_ROTOR_C |
                           IMEST_TEMPERATURE_CAN_CLAMP_STATOR_UNCERT);
  // just inside: not clamped; a negative uncertainty is sent as 0
  d = round_trip(temps(327.66f, -1.0f, 1, -327.66f, 0.0f, 1));
  EXPECT_FLOAT_EQ(d.stator_c, 327.66f);
  EXPECT_FLOAT_EQ(d.rotor_c, -327.66f);
  EXPECT_EQ(d.stator_uncert_k, 0.0f);
  EXPECT_EQ(d.clamped, 0u);
}

TEST(TemperatureCan, ValidBitsAreIndependent)
{
  for (int sv = 0; sv < 2; ++sv) {
    for (int rv = 0; rv < 2; ++rv) {
      const imest_temperature_can_t d = round_trip(temps(40.0f, 2.0f, sv ? 7 : 0, 50.0f, 3.0f, rv));
      EXPECT_EQ(d.stator_valid, sv);
      EXPECT_EQ(d.rotor_valid, rv);
      EXPECT_FLOAT_EQ(d.stator_c, 40.0f);
      EXPECT_FLOAT_EQ(d.rotor_uncert_k, 3.0f);
    }
  }
}

TEST(TemperatureCan, ForeignBadDlcBadCrcAndErrors)
{
  const imest_temperature_t t = temps(60.0f, 2.0f, 1, 70.0f, 3.0f, 1);
  imest_can_frame_t f;
  imest_temperature_can_t d;
  std::memset(&d, 0, sizeof d);
  ASSERT_EQ(imest_temperature_can_pack(&t, 0x6A0u, 3u, &f), IMEST_OK);
  // another node's, the six frames', the 29-bit twin: foreign, *out untouched
  for (uint32_t id : {0x6A5u, 0x6A7u, 0x6AEu, 0x6A0u, 0x6A6u | IMEST_CAN_ID_EXT, 0x6A6u | 0x40000000u}) {
    imest_can_frame_t g = f;
    g.id = id;
    EXPECT_EQ(imest_temperature_can_decode(&g, 0x6A0u, &d), IMEST_CAN_DEC_FOREIGN) << std::hex << id;
  }
  EXPECT_TRUE(untouched(d));
  imest_can_frame_t g = f;
  g.dlc = 7u;
  EXPECT_EQ(imest_temperature_can_decode(&g, 0x6A0u, &d), IMEST_CAN_DEC_BAD_DLC);
  // every single-bit error of the payload is caught by the CRC
  for (int bit = 0; bit < 64; ++bit) {
    g = f;
    g.data[bit / 8] = (unsigned char)(g.data[bit / 8] ^ (1u << (bit % 8)));
    EXPECT_EQ(imest_temperature_can_decode(&g, 0x6A0u, &d), IMEST_CAN_DEC_BAD_CRC) << bit;
  }
  // a six-frame payload (frame index 0 in the CRC) under base + 6 fails too
  imest_result_t r;
  std::memset(&r, 0, sizeof r);
  ASSERT_EQ(imest_can_pack(&r, 0u, 0x6A0u, 3u, 0u, &g), IMEST_OK);
  g.id = 0x6A6u;
  EXPECT_EQ(imest_temperature_can_decode(&g, 0x6A0u, &d), IMEST_CAN_DEC_BAD_CRC);
  EXPECT_TRUE(untouched(d));
  // NULL and identifiers without a base + 6
  EXPECT_EQ(imest_temperature_can_pack(nullptr, 0x6A0u, 0u, &f), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_can_pack(&t, 0x6A0u, 0u, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_can_decode(nullptr, 0x6A0u, &d), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_can_decode(&f, 0x6A0u, nullptr), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_can_pack(&t, 0x7F9u, 0u, &f), IMEST_OK);
  EXPECT_EQ(f.id, 0x7FFu);
  EXPECT_EQ(imest_temperature_can_pack(&t, 0x7FAu, 0u, &f), IMEST_ERR_ARG); // fine for the six frames
  EXPECT_EQ(imest_can_base_id_check(0x7FAu), IMEST_OK);
  EXPECT_EQ(imest_temperature_can_decode(&f, 0x7FAu, &d), IMEST_ERR_ARG);
  EXPECT_EQ(imest_temperature_can_pack(&t, 0x800u, 0u, &f), IMEST_ERR_ARG);
  EXPECT_EQ(imest_temperature_can_pack(&t, 0x1FFFFFFAu | IMEST_CAN_ID_EXT, 0u, &f), IMEST_ERR_ARG);
  EXPECT_EQ(imest_temperature_can_pack(&t, 0x6A0u | 0x40000000u, 0u, &f), IMEST_ERR_ARG);
}

TEST(TemperatureCan, ExtendedIdentifiers)
{
  const imest_temperature_t t = temps(-40.0f, 1.2f, 1, 155.0f, 5.0f, 0);
  for (uint32_t base :
       {0x18FF5000u | IMEST_CAN_ID_EXT, 0x100u | IMEST_CAN_ID_EXT, 0x1FFFFFF9u | IMEST_CAN_ID_EXT}) {
    imest_can_frame_t f;
    imest_temperature_can_t d;
    ASSERT_EQ(imest_temperature_can_pack(&t, base, 200u, &f), IMEST_OK);
    EXPECT_EQ(f.id, ((base & ~IMEST_CAN_ID_EXT) + 6u) | IMEST_CAN_ID_EXT);
    ASSERT_EQ(imest_temperature_can_decode(&f, base, &d), IMEST_CAN_DEC_OK);
    EXPECT_FLOAT_EQ(d.stator_c, -40.0f);
    EXPECT_FLOAT_EQ(d.rotor_c, 155.0f);
    EXPECT_EQ(d.counter, 200u);
    // the same number as an 11-bit base, or the 11-bit frame under the 29-bit base: foreign
    EXPECT_EQ(imest_temperature_can_decode(&f, base & ~IMEST_CAN_ID_EXT & 0x7FFu, &d), IMEST_CAN_DEC_FOREIGN);
    imest_can_frame_t g = f;
    g.id &= ~IMEST_CAN_ID_EXT;
    EXPECT_EQ(imest_temperature_can_decode(&g, base, &d), IMEST_CAN_DEC_FOREIGN);
  }
}

TEST(TemperatureCan, PublishedAfterTheWindowWithItsCounterAndIgnoredByTheReader)
{
  Sent sent;
  const imest_can_port_t port = {send_fn, &sent};
  imest_can_pub_t pub;
  ASSERT_EQ(imest_can_pub_init(&pub, &port, IMEST_CAN_DEFAULT_BASE_ID), IMEST_OK);
  imest_can_rx_t rx;
  ASSERT_EQ(imest_can_rx_init(&rx, IMEST_CAN_DEFAULT_BASE_ID), IMEST_OK);
  imest_result_t r;
  std::memset(&r, 0, sizeof r);
  r.tr_s = 0.12;
  r.rs_ohm = 3.2;
  unsigned int windows = 0u;
  for (unsigned int k = 0u; k < 300u; ++k) { // across the counter's wrap
    r.seq = k;
    sent.frames.clear();
    ASSERT_EQ(imest_can_publish(&pub, &r), 0);
    const imest_temperature_t t = temps(20.0f + 0.5f * (float)k, 2.0f, 1, 30.0f, 3.0f, 0);
    ASSERT_EQ(imest_temperature_can_publish(&pub, &t), 0);
    ASSERT_EQ(sent.frames.size(), 7u);
    imest_temperature_can_t d;
    ASSERT_EQ(imest_temperature_can_decode(&sent.frames[6], pub.base_id, &d), IMEST_CAN_DEC_OK);
    EXPECT_EQ(d.counter, k & 0xFFu);
    EXPECT_NEAR(d.stator_c, t.stator_c, 0.005f + 1e-4f);
    for (const imest_can_frame_t &f : sent.frames) {
      imest_can_window_t w;
      imest_can_rx_event_t ev;
      const int e = imest_can_rx_feed(&rx, &f, &w, &ev);
      if (&f == &sent.frames[6]) {
        EXPECT_EQ(e, (int)IMEST_CAN_EV_FOREIGN); // the six frames' reader ignores it
      } else if (e & (int)IMEST_CAN_EV_WINDOW) {
        EXPECT_EQ(w.counter, d.counter); // the same counter as its window
        EXPECT_EQ(w.have, 0x3Fu);
        windows++;
      }
      // and none of the six is IMEST_TEMP
      if (&f != &sent.frames[6])
        EXPECT_EQ(imest_temperature_can_decode(&f, pub.base_id, &d), IMEST_CAN_DEC_FOREIGN);
    }
  }
  EXPECT_EQ(windows, 300u);
  EXPECT_EQ(rx.st.lost, 0u);
  EXPECT_EQ(rx.st.corrupt, 0u);
  EXPECT_EQ(rx.st.foreign, 300u);
  // a refusal is counted in tx_failed, as the six frames' are
  sent.refuse = 1;
  const imest_temperature_t t = temps(20.0f, 2.0f, 1, 30.0f, 3.0f, 0);
  EXPECT_EQ(imest_temperature_can_publish(&pub, &t), 1);
  EXPECT_EQ(pub.tx_failed, 1u);
  EXPECT_EQ(imest_temperature_can_publish(nullptr, &t), IMEST_ERR_NULL);
  EXPECT_EQ(imest_temperature_can_publish(&pub, nullptr), IMEST_ERR_NULL);
  imest_can_pub_t edge;
  ASSERT_EQ(imest_can_pub_init(&edge, &port, 0x7FAu), IMEST_OK);
  EXPECT_EQ(imest_temperature_can_publish(&edge, &t), IMEST_ERR_ARG);
}

TEST(TemperatureCan, FromTheModulesOwnUpdate)
{
  imest_temperature_config_t tc;
  imest_temperature_config_default(&tc, 20.0f, 3.0f, 0.12f, 0.29f);
  imest_temperature_t t;
  ASSERT_EQ(imest_temperature_init(&t, &tc), IMEST_OK);
  imest_result_t r;
  std::memset(&r, 0, sizeof r);
  r.rs_ohm = 3.0 * 1.2; // +20 %: 0.2 x 254.5 = 50.9 K above 20 degC
  r.tr_s = 0.12 / 1.1;  // R_R +10 %: 24.5 K above
  r.rs_bound_rel = 0.001;
  r.tr_bound_rel = 0.001;
  r.rs_valid = r.tr_valid = 1;
  ASSERT_EQ(imest_temperature_update(&t, &r), 3);
  const imest_temperature_can_t d = round_trip(t);
  EXPECT_NEAR(d.stator_c, t.stator_c, 0.005f + 1e-4f);
  EXPECT_NEAR(d.stator_c, 70.9f, 0.01f);
  EXPECT_NEAR(d.rotor_c, t.rotor_c, 0.005f + 1e-4f);
  EXPECT_NEAR(d.stator_uncert_k, t.stator_uncert_k, 0.1f + 1e-4f);
  EXPECT_NEAR(d.rotor_uncert_k, t.rotor_uncert_k, 0.1f + 1e-4f);
  EXPECT_EQ(d.stator_valid, 1);
  EXPECT_EQ(d.rotor_valid, 1);
  // right after init: nothing computed yet, all not available
  ASSERT_EQ(imest_temperature_init(&t, &tc), IMEST_OK);
  const imest_temperature_can_t e = round_trip(t);
  EXPECT_TRUE(std::isnan(e.stator_c) && std::isnan(e.rotor_c) && std::isnan(e.stator_uncert_k));
  EXPECT_EQ(e.stator_valid + e.rotor_valid, 0);
}
