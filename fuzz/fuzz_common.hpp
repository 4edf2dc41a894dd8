#pragma once
// Shared helpers of the libFuzzer targets (see fuzz/README.md).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include <Eigen/Dense>

#include "fdsid/model.hpp"

namespace fdsid_fuzz {

/// Reads bytes from the fuzz input; past its end it yields a fixed filler so
/// that short inputs still make full-size requests deterministic.
class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : p_(data), n_(size) {}
  size_t left() const { return n_ - i_; }
  uint8_t byte(uint8_t filler = 1) { return i_ < n_ ? p_[i_++] : filler; }
  /// An integer in [lo, hi].
  int range(int lo, int hi) { return lo + static_cast<int>(byte() % static_cast<unsigned>(hi - lo + 1)); }
  double raw_double() {
    unsigned char b[8] = {0};
    for (unsigned char& c : b) c = byte(0);
    double d;
    std::memcpy(&d, b, sizeof d);
    return d;
  }
  /// A double chosen by a tag byte: raw 8 bytes (any bit pattern: NaN, Inf,
  /// denormals, ...), a special value, or a small value so that well-posed
  /// data also occur. Past the end of the input: 1.0.
  double value() {
    if (left() == 0) return 1.0;
    const uint8_t tag = byte();
    switch (tag & 3u) {
      case 0: return raw_double();
      case 1: {
        static const double special[] = {0.0,
                                         -0.0,
                                         1.0,
                                         -1.0,
                                         std::numeric_limits<double>::quiet_NaN(),
                                         std::numeric_limits<double>::infinity(),
                                         -std::numeric_limits<double>::infinity(),
                                         std::numeric_limits<double>::denorm_min(),
                                         -std::numeric_limits<double>::denorm_min(),
                                         std::numeric_limits<double>::min(),
                                         std::numeric_limits<double>::max(),
                                         -std::numeric_limits<double>::max(),
                                         1e300,
                                         -1e300,
                                         1e-300,
                                         -1e-300,
                                         std::numeric_limits<double>::epsilon(),
                                         1.0 + std::numeric_limits<double>::epsilon(),
                                         3.141592653589793,
                                         1e-12,
                                         1e12};
        return special[(tag >> 2) % (sizeof special / sizeof special[0])];
      }
      case 2: return static_cast<double>(static_cast<int8_t>(byte())) / 16.0;
      default: return 1.0 + static_cast<double>(tag >> 2) / 8.0;  // positive, moderate
    }
  }

 private:
  const uint8_t* p_;
  size_t n_;
  size_t i_ = 0;
};

[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fdsid fuzz invariant violated: %s\n", what);
  std::fflush(stderr);
  __builtin_trap();
}

inline bool finite(const Eigen::MatrixXd& m) { return m.size() == 0 || m.allFinite(); }
inline bool finite(const Eigen::MatrixXcd& m) {
  return m.size() == 0 || (m.real().allFinite() && m.imag().allFinite());
}

/// A returned model must have consistent shapes and finite entries.
inline void check_model(const fdsid::StateSpace& s, const char* who) {
  const auto n = s.A.rows();
  if (s.A.cols() != n || s.B.rows() != n || s.C.cols() != n || s.D.rows() != s.C.rows() ||
      s.D.cols() != s.B.cols()) {
    std::fprintf(stderr, "%s: inconsistent model shapes\n", who);
    fail("model shapes");
  }
  if (!finite(s.A) || !finite(s.B) || !finite(s.C) || !finite(s.D)) {
    std::fprintf(stderr, "%s: non-finite model returned without an Error\n", who);
    fail("non-finite model");
  }
  if (!std::isfinite(s.sample_time)) {
    std::fprintf(stderr, "%s: non-finite sample_time\n", who);
    fail("non-finite sample_time");
  }
}

}  // namespace fdsid_fuzz
