// In-place ascending sort of finite doubles by their bit patterns.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace imu::analyze {

namespace radix_detail {

// The byte of x's order-preserving key at `shift`: the key is the IEEE-754 pattern with the
// sign bit set for positive values and every bit inverted for negative ones, so that unsigned
// key order is numeric order (-0.0 sorts just before +0.0; the two compare equal anyway).
inline std::size_t digit(double x, int shift) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  const std::uint64_t key = (bits >> 63U) != 0U ? ~bits : bits | (std::uint64_t{1} << 63U);
  return static_cast<std::size_t>((key >> static_cast<unsigned>(shift)) & 0xFFU);
}

// Most significant byte first (American flag sort): count each bucket, move every value into
// its bucket by cycles of swaps, then sort each bucket on the next byte.
inline void sort_from(double* a, std::size_t n, int shift) {
  constexpr std::size_t kSmall = 64;  // std::sort below this
  if (n < kSmall || shift < 0) {
    std::sort(a, a + n);
    return;
  }
  std::array<std::size_t, 256> count{};
  for (std::size_t i = 0; i < n; ++i) {
    ++count[digit(a[i], shift)];
  }
  if (std::find(count.begin(), count.end(), n) != count.end()) {
    sort_from(a, n, shift - 8);  // one bucket holds all: nothing to move at this byte
    return;
  }
  std::array<std::size_t, 256> next{};
  std::array<std::size_t, 256> end{};
  std::size_t at = 0;
  for (std::size_t b = 0; b < 256; ++b) {
    next[b] = at;
    at += count[b];
    end[b] = at;
  }
  for (std::size_t b = 0; b < 256; ++b) {
    while (next[b] < end[b]) {
      const std::size_t d = digit(a[next[b]], shift);
      if (d == b) {
        ++next[b];
      } else {
        std::swap(a[next[b]], a[next[d]++]);
      }
    }
  }
  std::size_t start = 0;
  for (std::size_t b = 0; b < 256; ++b) {
    if (count[b] > 1) {
      sort_from(a + start, count[b], shift - 8);
    }
    start += count[b];
  }
}

}  // namespace radix_detail

/// Sorts v (finite values only) ascending in place: O(n) per byte of the key where std::sort
/// makes about log2(n) passes, and no second buffer (a record can hold 2^22 values).
inline void sort_finite(std::vector<double>& v) {
  radix_detail::sort_from(v.data(), v.size(), 56);
}

}  // namespace imu::analyze
