// Expected-like result type of the MAT-file reader and writer (host only).
//
// Contract: a Result<T> holds either a value or a MatError. The error message is one line that
// names the file, the variable (when there is one) and the problem, ready to print as is, e.g.
//   "adis.mat: variable 'acc_q' not found; variables: acc_x, acc_y"
// No exceptions cross this API. value() and error() have the precondition ok() / !ok() (checked
// with assert in debug builds).
#ifndef IMU_MAT_RESULT_HPP
#define IMU_MAT_RESULT_HPP

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace imu::mat {

/// One-line, printable description of why an operation failed.
struct MatError {
  std::string message;
};

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor): like expected
  Result(MatError error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  [[nodiscard]] bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  [[nodiscard]] const T& value() const& {
    assert(ok());
    return std::get<0>(v_);
  }
  [[nodiscard]] T& value() & {
    assert(ok());
    return std::get<0>(v_);
  }
  [[nodiscard]] T&& value() && {
    assert(ok());
    return std::get<0>(std::move(v_));
  }
  [[nodiscard]] const MatError& error() const {
    assert(!ok());
    return std::get<1>(v_);
  }

 private:
  std::variant<T, MatError> v_;
};

/// Result of an operation that produces nothing but can fail.
template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(MatError error) : error_(std::move(error)), failed_(true) {}  // NOLINT(google-explicit-constructor)

  [[nodiscard]] bool ok() const { return !failed_; }
  explicit operator bool() const { return ok(); }
  [[nodiscard]] const MatError& error() const {
    assert(!ok());
    return error_;
  }

 private:
  MatError error_{};
  bool failed_ = false;
};

using Status = Result<void>;

}  // namespace imu::mat

#endif  // IMU_MAT_RESULT_HPP
