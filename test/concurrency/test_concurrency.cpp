/* SPDX-License-Identifier: Apache-2.0 */
// The concurrency contract (include/imest/imest.h) under ThreadSanitizer.
//
// The ISR entry point (imest_isr_abc, or imest_isr_duty with an inverter
// model) runs on one thread at random instants: bursts, short busy-waits,
// yields and stalls between samples; imest_background() runs on another in a
// loop with random delays. The samples are recordings of the simulator: the
// motor at rest (no current: the verdict's no-current/standstill branch), then
// the paper's motor at rated load; windows of 40 ms, so that a case runs
// thousands of windows in seconds.
//
// A case fails on
// - any TSan report (run_tsan.sh sets halt_on_error=1): an access of the other
//   context's state that the hand-off does not order, i.e. the background
//   reading the ISR's live state instead of the published window, the ISR
//   reading state the background writes while a window is being filled, or
//   either side touching a buffer it does not own (a torn window). TSan sees
//   the hand-off's ordering in its acquire/release atomics
//   (src/common/imest_handoff.h);
// - the hand-off's bookkeeping (both modes): seq strictly increasing, each
//   window's samples and end time those of its seq, every window either
//   handed over and consumed once or dropped and counted in `overruns`, every
//   gap in seq counted, IMEST_FLAG_OVERRUN exactly on the windows after a gap;
// - paced mode (the ISR completes a window only after the background has
//   released the previous one, but runs ahead into the next one while the
//   background works): no window dropped, and every result byte for byte that
//   of a sequential replay of the same samples (the ISR call, then the
//   background drained whenever the call returned 1). With drops the later
//   results depend on which windows were dropped (the background centres on
//   its last valid estimate and combines windows), so the free-running mode
//   checks the bookkeeping only.
#include <gtest/gtest.h>

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

extern "C" {
#include "imest/imest.h"
#include "imsim/imsim.h"
}

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kFsHz = 4000.0;
constexpr float kWindowS = 0.04f; // 160 samples
constexpr double kRestS = 1.5;    // at rest, no current (0.83 s of it the first warm-up)
constexpr double kRunS = 4.5;     // then at rated load
constexpr uint64_t kSeeds[] = {1, 2, 3, 4, 5, 6, 7, 8};

struct Row {
  float a[3]; // phase voltages [V], or duties (duty input)
  float i[3]; // phase currents [A]
  float vdc;  // DC bus [V] (duty input)
  float th;   // mechanical angle, wrapped [rad]
};

struct Recording {
  bool duty = false;
  uint64_t seed = 0;
  imest_config_t cfg{};
  unsigned int window_n = 0;
  std::vector<Row> rows; // a whole number of windows
  unsigned long windows() const { return (unsigned long)(rows.size() / window_n); }
  std::string name() const
  {
    return std::string(duty ? "duty input" : "phase-voltage input") + ", seed " + std::to_string(seed);
  }
};

float wrap_angle(double th)
{
  th = std::fmod(th, 2.0 * M_PI);
  if (th < 0.0) th += 2.0 * M_PI;
  const float f = (float)th;
  return f >= (float)(2.0 * M_PI) ? 0.0f : f;
}

// The paper's motor (exp2: 30 Hz V/f, 115 V, rated load 2.064 N m) from its
// steady state, 12-bit sensors with noise, 4096-count encoder, no heating.
// Duty input: the PWM inverter (8 kHz, two periods per sample, 1 us dead
// time, device drops) with firmware timing, and the estimator told the
// inverter's model (20 % uncertain), so the verdict weighs the model's error.
Recording make_recording(bool duty, uint64_t seed)
{
  Recording rec;
  rec.duty = duty;
  rec.seed = seed;
  imsim_config_t sc;
  imsim_config_preset(&sc, "exp2");
  sc.start = IMSIM_START_STEADY;
  sc.thermal = false;
  sc.load_nm = 2.064;
  sc.fs_hz = kFsHz;
  sc.seed = seed;
  if (duty) {
    sc.supply = IMSIM_SUPPLY_PWM;
    sc.timing = IMSIM_TIMING_FIRMWARE;
    sc.carrier_hz = 8000.0;
    sc.dead_time_s = 1e-6;
    sc.v_switch_v = 1.0;
    sc.v_diode_v = 0.8;
  } else {
    sc.supply = IMSIM_SUPPLY_VF;
  }
  imsim_t sim;
  imsim_sample_t smp;
  if (imsim_init(&sim, &sc, &smp) != 0) {
    ADD_FAILURE() << imsim_error(&sim);
    return rec;
  }

  imest_config_t &cfg = rec.cfg;
  imest_config_default(&cfg);
  cfg.pole_pairs = (unsigned int)sc.pole_pairs;
  cfg.ls_h = (float)sc.ls_h;
  cfg.sigma = (float)sc.sigma;
  cfg.ls_uncertainty = 0.0f; /* the simulator's own constants: exact */
  cfg.sigma_uncertainty = 0.0f;
  cfg.fs_hz = (float)kFsHz;
  cfg.window_s = kWindowS;
  if (duty) {
    cfg.pwm_hz = (float)sc.carrier_hz;
    cfg.inverter.dead_time_s = (float)sc.dead_time_s;
    cfg.inverter.v_switch_v = (float)sc.v_switch_v;
    cfg.inverter.v_diode_v = (float)sc.v_diode_v;
    cfg.inverter.uncertainty = 0.2f;
  }
  const char *field = nullptr;
  EXPECT_EQ(imest_config_check(&cfg, &field), IMEST_OK) << (field ? field : "");
  rec.window_n = 2u * (unsigned int)(kWindowS * (float)kFsHz * 0.5f + 0.5f); // as imest_init

  const size_t n_rest = (size_t)std::lround(kRestS * kFsHz), n_run = (size_t)std::lround(kRunS * kFsHz);
  const size_t n = (n_rest + n_run) / rec.window_n * rec.window_n;
  rec.rows.reserve(n);
  // drive enabled, rotor at rest: zero voltage (duties 0.5 on the measured
  // bus), no current, the encoder still
  const float vdc0 = duty ? (float)smp.vdc_v : 0.0f;
  for (size_t k = 0; k < n_rest && rec.rows.size() < n; ++k) {
    Row r{};
    for (int p = 0; p < 3; ++p) r.a[p] = duty ? 0.5f : 0.0f;
    r.vdc = vdc0;
    r.th = 0.0f;
    rec.rows.push_back(r);
  }
  while (rec.rows.size() < n) {
    Row r{};
    for (int p = 0; p < 3; ++p) {
      r.a[p] = (float)(duty ? smp.duty[p] : smp.u_abc[p]);
      r.i[p] = (float)smp.i_abc[p];
    }
    r.vdc = duty ? (float)smp.vdc_v : 0.0f;
    r.th = wrap_angle(smp.theta);
    rec.rows.push_back(r);
    imsim_step(&sim, &smp);
  }
  return rec;
}

int feed(imest_t *est, const Recording &rec, size_t n)
{
  const Row &r = rec.rows[n];
  return rec.duty ? imest_isr_duty(est, r.a, r.vdc, r.i, r.th) : imest_isr_abc(est, r.a, r.i, r.th);
}

// Results are kept as the library wrote them, padding included (it clears the
// whole struct), so that two results compare byte for byte.
void keep(std::vector<imest_result_t> &v, const imest_result_t &r)
{
  v.emplace_back();
  std::memcpy(&v.back(), &r, sizeof r);
}

std::unique_ptr<imest_t> new_estimator(const Recording &rec)
{
  auto est = std::make_unique<imest_t>();
  EXPECT_EQ(imest_init(est.get(), &rec.cfg), IMEST_OK);
  return est;
}

// The sequential replay: the ISR call, then the background drained after
// every call that returned 1.
std::vector<imest_result_t> replay(const Recording &rec)
{
  auto est = new_estimator(rec);
  std::vector<imest_result_t> out;
  out.reserve(rec.windows());
  imest_result_t r;
  for (size_t n = 0; n < rec.rows.size(); ++n) {
    if (feed(est.get(), rec, n) == 1) {
      while (imest_background(est.get(), &r) == 1) keep(out, r);
    }
  }
  return out;
}

// ---- timing -----------------------------------------------------------------

void spin_us(double us)
{
  const auto end = Clock::now() +
                   std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::micro>(us));
  while (Clock::now() < end) {}
}

void sleep_us(long us)
{
  std::this_thread::sleep_for(std::chrono::microseconds(us));
}

// The ISR thread at real-time priority where the system permits it (it
// usually does not without privileges; then it stays as it is). Every wait of
// the test sleeps, so the background gets a core even if both share one.
bool try_isr_priority()
{
  sched_param p{};
  p.sched_priority = sched_get_priority_min(SCHED_FIFO);
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
}

// How the ISR paces one window's samples.
enum Tempo { kBurst, kFast, kSlow, kStall };

Tempo pick_tempo(std::mt19937_64 &rng)
{
  const unsigned v = (unsigned)(rng() % 10u);
  return v < 3u ? kBurst : v < 6u ? kFast : v < 9u ? kSlow : kStall;
}

void isr_pause(std::mt19937_64 &rng, Tempo t, unsigned int stall_at, unsigned int pos)
{
  switch (t) {
  case kBurst: break;
  case kFast: spin_us((double)(rng() % 3u)); break;
  case kSlow: spin_us(5.0 + (double)(rng() % 26u)); break; // about the background's time per window
  case kStall:
    if (pos == stall_at) sleep_us(1000 + (long)(rng() % 4000u));
    break;
  }
  if (rng() % 256u == 0u) std::this_thread::yield();
}

// ---- one run on two threads -------------------------------------------------

enum class Mode { kPaced, kFree };

struct Run {
  std::vector<imest_result_t> res; // in the order the background produced them
  unsigned long handed = 0;        // ISR calls that returned 1
  uint32_t overruns = 0;           // imest_overruns() at the end
  int bg_errors = 0;               // imest_background() < 0
  bool realtime = false;           // the ISR thread ran at SCHED_FIFO
  double seconds = 0.0;
};

Run run_threads(const Recording &rec, Mode mode, uint64_t seed)
{
  auto est_owner = new_estimator(rec);
  imest_t *est = est_owner.get();
  Run out;
  out.res.reserve(rec.windows());
  std::atomic<unsigned long> consumed{0};
  std::atomic<bool> isr_done{false};
  const auto t0 = Clock::now();

  std::thread bg([&] {
    std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 2u);
    imest_result_t r;
    for (;;) {
      const bool done = isr_done.load(std::memory_order_acquire);
      const int rc = imest_background(est, &r);
      if (rc == 1) {
        keep(out.res, r);
        consumed.fetch_add(1, std::memory_order_release);
        // now and then busy elsewhere for a while: several windows in free
        // mode (drops), a part of one when paced (the ISR waits)
        if (rng() % 4u == 0u) {
          const long us = mode == Mode::kFree ? 500 + (long)(rng() % 8000u) : (long)(rng() % 2000u);
          if (rng() % 2u)
            sleep_us(us);
          else
            spin_us((double)us);
        }
        continue;
      }
      if (rc != 0) {
        out.bg_errors++;
        break;
      }
      if (done) break; // the ISR had finished before this call found nothing
      switch (rng() % 4u) {
      case 0: std::this_thread::yield(); break;
      case 1: spin_us((double)(rng() % 50u)); break;
      case 2: sleep_us((long)(rng() % 200u)); break;
      default: break;
      }
    }
  });

  std::thread isr([&] {
    out.realtime = try_isr_priority();
    std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 1u);
    const unsigned int wn = rec.window_n;
    unsigned long handed = 0;
    Tempo tempo = kBurst;
    unsigned int stall_at = 0;
    bool patient = false;
    for (size_t n = 0; n < rec.rows.size(); ++n) {
      const unsigned int pos = (unsigned int)(n % wn);
      if (pos == 0u) {
        tempo = pick_tempo(rng);
        stall_at = (unsigned int)(rng() % wn);
        patient = rng() % 2u == 0u;
      }
      // The sample that completes this window only once the background has
      // released every window handed over before: always when paced; free
      // running, in half of the windows and for at most 20 ms (the others
      // complete whenever they do, and are dropped if the background is
      // still busy), so that both outcomes are frequent on any machine.
      if (pos == wn - 1u && (mode == Mode::kPaced || patient)) {
        const auto give_up = Clock::now() + std::chrono::milliseconds(20);
        while (consumed.load(std::memory_order_acquire) != handed &&
               (mode == Mode::kPaced || Clock::now() < give_up))
          sleep_us(20);
      }
      if (feed(est, rec, n) == 1) handed++;
      isr_pause(rng, tempo, stall_at, pos);
    }
    out.handed = handed;
    isr_done.store(true, std::memory_order_release);
  });

  isr.join();
  bg.join();
  out.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  out.overruns = imest_overruns(est);
  return out;
}

// ---- checks -----------------------------------------------------------------

// The hand-off's bookkeeping, whatever was dropped.
void check_bookkeeping(const Recording &rec, const Run &run, Mode mode)
{
  SCOPED_TRACE(rec.name() + (mode == Mode::kPaced ? ", paced" : ", free running"));
  const auto &res = run.res;
  const unsigned long windows = rec.windows();
  EXPECT_EQ(run.bg_errors, 0);
  // every window handed over is consumed exactly once; every other one was
  // dropped and counted
  EXPECT_EQ((unsigned long)res.size(), run.handed);
  EXPECT_EQ((unsigned long)run.overruns, windows - (unsigned long)res.size());
  if (mode == Mode::kPaced) EXPECT_EQ(run.overruns, 0u);
  std::vector<std::string> bad;
  auto expect = [&](bool ok, size_t k, const std::string &what) {
    if (!ok)
      bad.push_back("result " + std::to_string(k) + " (seq " + std::to_string(res[k].seq) + "): " + what);
  };
  for (size_t k = 0; k < res.size(); ++k) {
    const imest_result_t &r = res[k];
    if (k > 0) expect(r.seq > res[k - 1].seq, k, "seq not above the previous result's");
    expect((unsigned long)r.seq < windows, k, "seq beyond the windows completed");
    // the window's own length and end time: a torn window would mix the
    // numbers of two
    expect(r.samples == rec.window_n, k, "samples " + std::to_string(r.samples));
    expect(r.used_samples <= r.samples, k, "used_samples " + std::to_string(r.used_samples));
    const double t_end = ((double)r.seq * rec.window_n + r.samples - 1.0) / kFsHz;
    expect(std::fabs(r.t_end_s - t_end) <= 1e-9 * t_end + 1e-12, k, "t_end_s not that of its seq");
    // `overruns` is read while the window is judged: it counts every window
    // dropped before this one (seq - k of them: each earlier seq was either
    // consumed, k of them, or dropped) and may count windows the ISR dropped
    // meanwhile, but none after the next window handed over (the ISR cannot
    // hand over another one while the background holds this one). So
    // seq - k <= overruns <= seq' - (k + 1) for the next result's seq'; where
    // the background keeps up the two are equal, and the gap in seq before a
    // result is the increase of overruns.
    const uint32_t dropped_before = r.seq - (uint32_t)k;
    const uint32_t dropped_by_next = k + 1 < res.size() ? res[k + 1].seq - (uint32_t)(k + 1) : run.overruns;
    expect(r.overruns >= dropped_before, k,
           "overruns " + std::to_string(r.overruns) + " below the " + std::to_string(dropped_before) +
               " windows dropped before it");
    expect(r.overruns <= dropped_by_next, k,
           "overruns " + std::to_string(r.overruns) + " above the " + std::to_string(dropped_by_next) +
               " windows dropped before the next one handed over");
    if (k > 0) expect(r.overruns >= res[k - 1].overruns, k, "overruns decreased");
    // IMEST_FLAG_OVERRUN: the window right before this one was dropped
    const bool gap = r.seq != (k > 0 ? res[k - 1].seq + 1u : 0u);
    expect(((r.flags & IMEST_FLAG_OVERRUN) != 0u) == gap, k,
           gap ? "IMEST_FLAG_OVERRUN missing after a gap in seq" : "IMEST_FLAG_OVERRUN without a gap in seq");
  }
  for (size_t j = 0; j < bad.size() && j < 10; ++j) ADD_FAILURE() << bad[j];
  EXPECT_TRUE(bad.empty()) << bad.size() << " bookkeeping errors in " << res.size() << " results";
}

struct Field {
  const char *name;
  size_t off, size;
};
constexpr Field field(const char *name, size_t off, size_t size)
{
  return Field{name, off, size};
}
#define IMEST_FIELD(f) field(#f, offsetof(imest_result_t, f), sizeof(imest_result_t::f))
constexpr Field kFields[] = {
    IMEST_FIELD(seq),         IMEST_FIELD(samples),      IMEST_FIELD(used_samples),
    IMEST_FIELD(overruns),    IMEST_FIELD(valid),        IMEST_FIELD(status),
    IMEST_FIELD(tr_valid),    IMEST_FIELD(tr_reason),    IMEST_FIELD(rs_valid),
    IMEST_FIELD(rs_reason),   IMEST_FIELD(flags),        IMEST_FIELD(t_end_s),
    IMEST_FIELD(span_s),      IMEST_FIELD(windows),      IMEST_FIELD(tr_s),
    IMEST_FIELD(rs_ohm),      IMEST_FIELD(tr_bound_rel), IMEST_FIELD(rs_bound_rel),
    IMEST_FIELD(k1),          IMEST_FIELD(k2),           IMEST_FIELD(e),
    IMEST_FIELD(e_i),         IMEST_FIELD(e_i_noise),    IMEST_FIELD(noise_i_a),
    IMEST_FIELD(noise_u_v),   IMEST_FIELD(hessian),      IMEST_FIELD(pe_k1),
    IMEST_FIELD(pe_k2),       IMEST_FIELD(pe_k1_rel),    IMEST_FIELD(pe_k2_rel),
    IMEST_FIELD(slip_ratio),  IMEST_FIELD(i_rms_a),      IMEST_FIELD(ls_noload_h),
    IMEST_FIELD(ls_window_h), IMEST_FIELD(n_roots),      IMEST_FIELD(n_admissible),
    IMEST_FIELD(roots_k2),
};
#undef IMEST_FIELD
// kFields in declaration order with nothing between two but padding
constexpr bool lists_every_field()
{
  size_t end = 0;
  for (const Field &f : kFields) {
    if (f.off < end || f.off - end >= alignof(double)) return false;
    end = f.off + f.size;
  }
  return sizeof(imest_result_t) - end < alignof(double);
}
static_assert(lists_every_field(), "kFields does not list every field of imest_result_t");

// The fields in which a differs from b (the comparison itself is of every
// byte: this only names them).
std::string differing_fields(const imest_result_t &a, const imest_result_t &b)
{
  std::string o;
  const auto *pa = reinterpret_cast<const unsigned char *>(&a),
             *pb = reinterpret_cast<const unsigned char *>(&b);
  for (const Field &f : kFields) {
    if (std::memcmp(pa + f.off, pb + f.off, f.size) == 0) continue;
    char buf[160];
    if (f.size == sizeof(double)) { // every 8-byte field is a double
      double x, y;
      std::memcpy(&x, pa + f.off, sizeof x);
      std::memcpy(&y, pb + f.off, sizeof y);
      std::snprintf(buf, sizeof buf, " %s (%.17g vs %.17g)", f.name, x, y);
    } else {
      std::snprintf(buf, sizeof buf, " %s", f.name);
    }
    o += buf;
  }
  return o.empty() ? " (in padding, or in a field kFields does not list)" : o;
}

// The recording reaches what the test is about: windows judged through the
// no-current/standstill branch (it reads the tracked current offsets) and
// windows whose error bounds were computed (with the duty input they read the
// inverter model at the bus voltage).
void check_coverage(const Recording &rec, const std::vector<imest_result_t> &ref)
{
  SCOPED_TRACE(rec.name());
  int low_current = 0, bounds = 0, valid = 0;
  for (const auto &r : ref) {
    low_current += (r.tr_reason == IMEST_REASON_NO_CURRENT || r.tr_reason == IMEST_REASON_STANDSTILL) ? 1 : 0;
    bounds += std::isfinite(r.tr_bound_rel) ? 1 : 0;
    valid += r.tr_valid ? 1 : 0;
  }
  EXPECT_GE(low_current, 5) << "windows through the no-current/standstill branch";
  EXPECT_GE(bounds, 20) << "windows with computed error bounds";
  EXPECT_GE(valid, 5) << "windows with a valid T_R";
  std::printf(
      "  %s: %lu windows, replay: %zu results, %d no current/standstill, %d with bounds, %d T_R valid\n",
      rec.name().c_str(), rec.windows(), ref.size(), low_current, bounds, valid);
}

const char *priority(bool realtime)
{
  return realtime ? "the ISR thread at SCHED_FIFO" : "the ISR thread at normal priority (SCHED_FIFO refused)";
}

void paced_case(bool duty)
{
  unsigned long windows = 0;
  double seconds = 0.0;
  bool realtime = true;
  for (const uint64_t seed : kSeeds) {
    const Recording rec = make_recording(duty, seed);
    ASSERT_FALSE(rec.rows.empty());
    const std::vector<imest_result_t> ref = replay(rec);
    check_coverage(rec, ref);
    const Run run = run_threads(rec, Mode::kPaced, seed);
    check_bookkeeping(rec, run, Mode::kPaced);
    windows += rec.windows();
    seconds += run.seconds;
    realtime = realtime && run.realtime;
    SCOPED_TRACE(rec.name() + ", paced");
    ASSERT_EQ(run.res.size(), ref.size());
    int differ = 0;
    for (size_t k = 0; k < ref.size(); ++k) {
      if (std::memcmp(&run.res[k], &ref[k], sizeof ref[k]) == 0) continue;
      if (++differ <= 8)
        ADD_FAILURE() << "window seq " << ref[k].seq << " (" << imest_reason_name(ref[k].status)
                      << " in the replay) differs from the sequential replay in:"
                      << differing_fields(run.res[k], ref[k]);
    }
    EXPECT_EQ(differ, 0) << "of " << ref.size()
                         << " results differ from the sequential replay: a result depends on when the "
                            "background ran (it read state the ISR had changed since the window was "
                            "published, or the ISR read state the background wrote mid-window)";
  }
  std::printf("  paced, %s: %lu windows on two threads in %.2f s, none dropped, %s\n",
              duty ? "duty input" : "phase-voltage input", windows, seconds, priority(realtime));
}

void free_case(bool duty)
{
  unsigned long windows = 0, handed = 0, dropped = 0;
  double seconds = 0.0;
  bool realtime = true;
  for (const uint64_t seed : kSeeds) {
    const Recording rec = make_recording(duty, seed);
    ASSERT_FALSE(rec.rows.empty());
    const Run run = run_threads(rec, Mode::kFree, seed);
    check_bookkeeping(rec, run, Mode::kFree);
    windows += rec.windows();
    handed += (unsigned long)run.res.size();
    dropped += run.overruns;
    seconds += run.seconds;
    realtime = realtime && run.realtime;
    std::printf("  free, %s: %lu windows, %zu handed over, %u dropped, %.2f s\n", rec.name().c_str(),
                rec.windows(), run.res.size(), run.overruns, run.seconds);
  }
  // the run did what it is for: windows dropped, and windows handed over
  EXPECT_GT(dropped, windows / 20u) << "too few overruns to test them";
  EXPECT_GT(handed, windows / 5u) << "too few windows handed over";
  std::printf("  free, %s: %lu windows on two threads in %.2f s: %lu handed over, %lu dropped, %s\n",
              duty ? "duty input" : "phase-voltage input", windows, seconds, handed, dropped,
              priority(realtime));
}

} // namespace

TEST(Concurrency, PhaseInputPaced)
{
  paced_case(false);
}

TEST(Concurrency, PhaseInputFree)
{
  free_case(false);
}

TEST(Concurrency, DutyInputPaced)
{
  paced_case(true);
}

TEST(Concurrency, DutyInputFree)
{
  free_case(true);
}
