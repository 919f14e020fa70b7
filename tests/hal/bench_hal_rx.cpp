// Throughput of the receive path on one core, printed as frames/s and samples/s:
//  1. decode only: pre-encoded frames pushed through Receiver<8> (no system calls);
//  2. socket reader: a producer thread sends through the loopback socket pair while this
//     thread runs the real reader (poll + recvmmsg batches + Receiver); the rate is taken over
//     the reader thread's CPU time (CLOCK_THREAD_CPUTIME_ID), i.e. what one core sustains, and
//     the wall-clock rate is printed next to it.
// Target: 20 x a 6-channel 1 kHz IMU = 20,000 samples/s (FD: 20,000 frames/s; classic CAN:
// 6 frames per sample, 120,000 frames/s). Exit status 1 if a socket figure is below it.
// Usage: bench_hal_rx [samples]   (default 200000)
#include <time.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include "imu/hal/linux/can_socket.hpp"
#include "imu/hal/rx_pump.hpp"

namespace {

using imu::hal::EncodedFrames;
using imu::hal::IoStatus;
using imu::hal::Layout;

constexpr double kTargetSamplesPerS = 20.0 * 1000.0;

double seconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

imu::hal::SampleRecord sample(std::uint32_t seq) {
  imu::hal::SampleRecord s{};
  s.seq = seq;
  s.t_sensor_ns = 1'000'000ULL * seq;
  for (int c = 0; c < 6; ++c) {
    s.counts[c] = static_cast<std::int32_t>(seq * 7U) - 1000 * c;
  }
  return s;
}

const char* name(Layout l) { return l == Layout::kFd ? "CAN FD " : "classic"; }

void bench_decode(Layout layout, std::uint32_t n) {
  std::vector<imu::hal::CanFrame> frames;
  EncodedFrames out{};
  for (std::uint32_t s = 0; s < n; ++s) {
    imu::hal::encode(sample(s), layout, out);
    frames.insert(frames.end(), out.frame, out.frame + out.count);
  }
  imu::hal::Receiver<8> rx;
  imu::hal::RxEvent e{};
  std::uint64_t checksum = 0;
  const double t0 = seconds(CLOCK_THREAD_CPUTIME_ID);
  for (const auto& f : frames) {
    (void)rx.push(f, imu::hal::wire_size(f), 0);
    while (rx.pop(e)) {
      checksum += static_cast<std::uint64_t>(e.rec.sample.counts[0]);
    }
  }
  const double dt = seconds(CLOCK_THREAD_CPUTIME_ID) - t0;
  std::printf("decode only   %s: %10.0f frames/s %10.0f samples/s (%llu samples, checksum %llu)\n",
              name(layout), static_cast<double>(frames.size()) / dt,
              static_cast<double>(rx.stats().samples) / dt,
              static_cast<unsigned long long>(rx.stats().samples),
              static_cast<unsigned long long>(checksum));
}

bool bench_socket(Layout layout, std::uint32_t n) {
  imu::hal::CanSocket tx;
  imu::hal::CanSocket rx_sock;
  if (imu::hal::CanSocket::open_pair(tx, rx_sock) != IoStatus::kOk) {
    std::printf("socketpair failed: %s\n", tx.error());
    return false;
  }
  std::thread producer([&tx, layout, n] {
    EncodedFrames out{};
    for (std::uint32_t s = 0; s < n; ++s) {
      imu::hal::encode(sample(s), layout, out);
      for (std::size_t k = 0; k < out.count; ++k) {
        if (tx.send(out.frame[k], -1) != IoStatus::kOk) {
          return;
        }
      }
    }
  });
  imu::hal::Receiver<8> rx;
  static imu::hal::RxPump<8> pump;
  std::uint64_t delivered = 0;
  const double c0 = seconds(CLOCK_THREAD_CPUTIME_ID);
  const double w0 = seconds(CLOCK_MONOTONIC);
  while (delivered < n) {
    const IoStatus s = pump.run_once(rx_sock, rx, 1000, [&delivered](const imu::hal::RxEvent& e) {
      if (e.type == imu::hal::RxEvent::Type::kSample) {
        ++delivered;
      } else if (e.type == imu::hal::RxEvent::Type::kMissing) {
        delivered += e.missing_count;
      }
    });
    if (s != IoStatus::kOk) {
      break;
    }
  }
  const double cpu = seconds(CLOCK_THREAD_CPUTIME_ID) - c0;
  const double wall = seconds(CLOCK_MONOTONIC) - w0;
  producer.join();
  const auto& ls = rx_sock.stats();
  const double frames = static_cast<double>(ls.rx_frames);
  const double samples = static_cast<double>(rx.stats().samples);
  const double per_core = samples / cpu;
  std::printf(
      "socket reader %s: %10.0f frames/s %10.0f samples/s per reader core (wall: %.0f samples/s),"
      " %.1f frames/batch, missing %llu, = %.0fx a 6-channel 1 kHz IMU\n",
      name(layout), frames / cpu, per_core, samples / wall,
      frames / static_cast<double>(ls.rx_batches),
      static_cast<unsigned long long>(rx.stats().missing), per_core / 1000.0);
  return per_core >= kTargetSamplesPerS && rx.stats().missing == 0 && samples >= n;
}

}  // namespace

int main(int argc, char** argv) {
  const std::uint32_t n =
      argc > 1 ? static_cast<std::uint32_t>(std::strtoul(argv[1], nullptr, 10)) : 200000U;
  bench_decode(Layout::kFd, n);
  bench_decode(Layout::kClassic, n);
  const bool fd_ok = bench_socket(Layout::kFd, n);
  const bool cc_ok = bench_socket(Layout::kClassic, n);
  std::printf("target %.0f samples/s per core: CAN FD %s, classic %s\n", kTargetSamplesPerS,
              fd_ok ? "met" : "NOT MET", cc_ok ? "met" : "NOT MET");
  return fd_ok && cc_ok ? 0 : 1;
}
