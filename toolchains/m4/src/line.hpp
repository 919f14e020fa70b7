// Fixed-capacity text line for semihosting and host output: no heap, no stdio, no locale.
// Numbers are written exactly: unsigned/signed decimal integers and doubles as the 16 hex
// digits of their IEEE-754 bits (so host and target output compare bit for bit).
// Overflow truncates and sets truncated(); it never writes past the buffer. Cost: O(length).
#ifndef IMU_M4_LINE_HPP
#define IMU_M4_LINE_HPP

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace imu::m4 {

template <std::size_t kCapacity = 256>
class Line {
  static_assert(kCapacity >= 2, "room for one character and the terminator");

 public:
  Line& str(const char* s) {
    while (*s != '\0') {
      put(*s++);
    }
    return *this;
  }
  Line& u64(std::uint64_t v) {
    char digits[20];
    std::size_t n = 0;
    do {
      digits[n++] = static_cast<char>('0' + static_cast<int>(v % 10u));
      v /= 10u;
    } while (v != 0u);
    while (n > 0) {
      put(digits[--n]);
    }
    return *this;
  }
  /// All hex digits of an unsigned integer (8 for 32 bits, 16 for 64).
  template <typename U>
  Line& hex(U v) {
    static constexpr char kHex[] = "0123456789abcdef";
    for (int shift = static_cast<int>(8 * sizeof(U)) - 4; shift >= 0; shift -= 4) {
      put(kHex[(v >> static_cast<unsigned>(shift)) & 0xFu]);
    }
    return *this;
  }
  /// The IEEE-754 bits of a float in hex (8 digits, exact).
  Line& f32(float v) {
    std::uint32_t bits = 0;
    static_assert(sizeof bits == sizeof v, "IEEE-754 binary32");
    std::memcpy(&bits, &v, sizeof v);
    return hex(bits);
  }
  /// The IEEE-754 bits of `v` in hex (exact; the reader converts back with memcpy).
  Line& f64(double v) {
    std::uint64_t bits = 0;
    static_assert(sizeof bits == sizeof v, "IEEE-754 binary64");
    std::memcpy(&bits, &v, sizeof v);
    return hex(bits);
  }
  const char* c_str() const { return buf_; }
  bool truncated() const { return truncated_; }
  void clear() {
    n_ = 0;
    buf_[0] = '\0';
    truncated_ = false;
  }

 private:
  void put(char c) {
    if (n_ + 1 < kCapacity) {
      buf_[n_++] = c;
      buf_[n_] = '\0';
    } else {
      truncated_ = true;
    }
  }
  char buf_[kCapacity] = {};
  std::size_t n_ = 0;
  bool truncated_ = false;
};

}  // namespace imu::m4

#endif  // IMU_M4_LINE_HPP
