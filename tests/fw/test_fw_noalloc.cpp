// Counts every global operator new and malloc call made while the fw estimators are
// constructed, fed a million samples (with gaps) and read out: the count must be zero.
// (Not built under ASan, which owns malloc.)
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>

#include "imu/bias_kf.hpp"
#include "imu/error_model.hpp"
#include "imu/model_fit.hpp"
#include "imu/online_adev.hpp"
#include "imu/residual_monitor.hpp"

namespace {
std::atomic<std::uint64_t> g_allocs{0};
bool g_counting = false;
}  // namespace

// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's allocator behind malloc, to forward to
extern "C" void* __libc_malloc(std::size_t size);
extern "C" void* malloc(std::size_t size) {        // NOLINT: interposes the C allocator
  if (g_counting) {
    ++g_allocs;
  }
  return __libc_malloc(size);
}
void* operator new(std::size_t size) {
  if (g_counting) {
    ++g_allocs;
  }
  void* p = __libc_malloc(size == 0 ? 1 : size);
  if (p == nullptr) {
    throw std::bad_alloc();
  }
  return p;
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/) noexcept { std::free(p); }

namespace {

TEST(FwNoAlloc, MillionUpdatesFilterAndFitAllocateNothing) {
  // The counter must work: one deliberate allocation is seen.
  g_counting = true;
  int* volatile probe = new int(1);
  g_counting = false;
  delete probe;
  ASSERT_EQ(g_allocs.load(), 1U);
  g_allocs = 0;

  g_counting = true;
  {
    imu::MultiAdev<6, 8, 22> adev;
    std::int32_t sample[6] = {};
    for (std::int32_t i = 0; i < 1000000; ++i) {
      for (std::int32_t c = 0; c < 6; ++c) {
        sample[c] = static_cast<std::int32_t>((std::int64_t{i} * 7919 + c * 104729) % 2001 - 1000);
      }
      adev.push(sample);
      if (i % 100000 == 99999) {
        adev.mark_missing(3);
      }
    }
    imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
    const std::size_t n = adev.channel(0).snapshot(pts, std::size(pts));
    EXPECT_GT(n, 50U);

    // The rest of what the co-processor runs: first-order model, float bias filter and monitors per
    // sample, and the fit of the model to the ADEV.
    imu::FirstOrderGm gm{};
    ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, gm), imu::ModelStatus::kOk);
    imu::ScalarBiasKf<float> kf;
    ASSERT_EQ(kf.configure(gm, 9.81), imu::KfStatus::kOk);
    imu::ResidualMonitors<4> mon;
    ASSERT_EQ(mon.configure(), imu::MonitorStatus::kOk);
    for (int i = 0; i < 1000000; ++i) {
      const auto s = kf.step(9.81F + 0.03F * static_cast<float>((i % 201) - 100) / 100.0F,
                             (i / 1000) % 2 == 0);
      if (s.updated) {
        mon.push(s.innovation, s.innovation_var);
      }
    }
    imu::FitOptions opt;
    opt.tau_max_s = 100.0;
    const imu::FitResult fr = imu::fit(pts, n, opt);
    g_counting = false;
    EXPECT_EQ(fr.status, imu::FitStatus::kOk);
  }
  g_counting = false;
  EXPECT_EQ(g_allocs.load(), 0U);
}

}  // namespace
