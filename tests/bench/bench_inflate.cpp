// Inflater throughput on the shared data: every miCOMPRESSED element of the two ADIS16405 MAT
// files is inflated whole, one benchmark per file: `zlib` through inflate_zlib (header, RFC 1951
// blocks, Adler-32 check: what the reader does), `raw` through inflate_raw (the Huffman/LZ77
// decoder alone, without the 2-byte header and the Adler-32 trailer).
// Printed: counters out_MBps and in_MBps (10^6 bytes per second of inflated output and of
// compressed input); Google Benchmark's own bytes_per_second column is output in 1024-based units.
// Run: build/tests/bench/bench_inflate [--benchmark_repetitions=5]
// Without ../shared (IMU_SHARED_DIR) every benchmark is skipped with a message.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/mat/zlib.hpp"

namespace {

constexpr std::uint32_t kMiCompressed = 15U;
constexpr std::size_t kMatHeader = 128U;

struct Element {
  std::size_t offset;  // of the zlib stream in the file
  std::size_t bytes;   // compressed size
};

struct MatBytes {
  std::vector<std::uint8_t> data;
  std::vector<Element> compressed;
  std::string error;  // empty when usable
};

std::uint32_t load_le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8U) |
         (static_cast<std::uint32_t>(p[2]) << 16U) | (static_cast<std::uint32_t>(p[3]) << 24U);
}

// Reads the file and lists its top-level miCOMPRESSED elements (little-endian level 5 files, as
// scipy writes them; anything else is reported, not benchmarked).
MatBytes load(const std::string& path) {
  MatBytes m;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    m.error = "shared data absent: " + path;
    return m;
  }
  std::uint8_t buf[1U << 16U];
  std::size_t got = 0;
  while ((got = std::fread(buf, 1, sizeof buf, f)) > 0U) {
    m.data.insert(m.data.end(), buf, buf + got);
  }
  static_cast<void>(std::fclose(f));
  if (m.data.size() < kMatHeader || m.data[126] != 'I' || m.data[127] != 'M') {
    m.error = path + ": not a little-endian level 5 MAT-file";
    return m;
  }
  std::size_t off = kMatHeader;
  while (m.data.size() - off >= 8U) {
    const std::uint32_t type = load_le32(&m.data[off]);
    const std::size_t bytes = load_le32(&m.data[off + 4U]);
    const std::size_t payload = off + 8U;
    if (bytes > m.data.size() - payload) {
      m.error = path + ": truncated element at offset " + std::to_string(off);
      return m;
    }
    std::size_t padded = bytes;
    if (type == kMiCompressed) {
      m.compressed.push_back(Element{payload, bytes});
    } else {
      padded += (8U - bytes % 8U) % 8U;
    }
    off = payload + padded > m.data.size() ? m.data.size() : payload + padded;
  }
  if (m.compressed.empty()) {
    m.error = path + ": no miCOMPRESSED element";
  }
  return m;
}

// One element, whole: zlib stream, or its deflate data alone when raw.
imu::mat::InflateResult inflate(const MatBytes& m, const Element& e, bool raw,
                                std::vector<std::uint8_t>& out) {
  const std::uint8_t* z = &m.data[e.offset];
  const std::size_t cap = imu::mat::max_inflated_size(e.bytes);
  if (raw) {
    if (e.bytes < 6U) {
      return imu::mat::InflateResult{imu::mat::InflateStatus::truncated_input, 0};
    }
    return imu::mat::inflate_raw(z + 2, e.bytes - 6U, cap, imu::mat::InflateMode::whole, out);
  }
  return imu::mat::inflate_zlib(z, e.bytes, cap, imu::mat::InflateMode::whole, out);
}

void BM_InflateFile(benchmark::State& state, const char* file, bool raw) {
  const MatBytes m = load(std::string(IMU_SHARED_DIR) + "/data/" + file);
  if (!m.error.empty()) {
    state.SkipWithError(m.error.c_str());
    for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    }
    return;
  }
  std::vector<std::uint8_t> out;
  std::size_t in_bytes = 0;
  std::size_t out_bytes = 0;
  for (const Element& e : m.compressed) {  // one untimed pass: sizes, and every element is valid
    const auto r = inflate(m, e, raw, out);
    if (r.status != imu::mat::InflateStatus::ok) {
      const std::string msg = std::string(file) + ": " + imu::mat::describe(r.status);
      state.SkipWithError(msg.c_str());
      for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
      }
      return;
    }
    in_bytes += e.bytes;
    out_bytes += out.size();
  }
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    for (const Element& e : m.compressed) {
      const auto r = inflate(m, e, raw, out);
      benchmark::DoNotOptimize(r);
      benchmark::DoNotOptimize(out.data());
    }
  }
  const auto iters = static_cast<double>(state.iterations());
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(out_bytes));
  state.counters["out_MBps"] = benchmark::Counter(iters * static_cast<double>(out_bytes) * 1e-6,
                                                  benchmark::Counter::kIsRate);
  state.counters["in_MBps"] = benchmark::Counter(iters * static_cast<double>(in_bytes) * 1e-6,
                                                 benchmark::Counter::kIsRate);
  state.counters["elements"] = static_cast<double>(m.compressed.size());
  state.counters["ratio"] = static_cast<double>(out_bytes) / static_cast<double>(in_bytes);
}
BENCHMARK_CAPTURE(BM_InflateFile, imu1_zlib, "adis16405_imu1.mat", false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_InflateFile, imu2_zlib, "adis16405_imu2.mat", false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_InflateFile, imu1_raw, "adis16405_imu1.mat", true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_InflateFile, imu2_raw, "adis16405_imu2.mat", true)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
