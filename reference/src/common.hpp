// Helpers shared by the reference translation units (not installed, not part
// of the interface in reference/include): the Kronecker product of the
// papers' notation sections, the N-th roots of unity on which both papers'
// DFTs are written, and message formatting. Nothing here instantiates an
// Eigen decomposition (see spectrum_id.cpp for why that matters).
#pragma once

#include "fdsid/reference/spectrum_id.hpp"

#include <boost/math/constants/constants.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace fdsid::reference::detail {

/// X ⊗ Y, the Kronecker product as defined in Akçay (2011) Section 1.1 and
/// Pintelon (2002) Section 1: block (i, j) of the result is X(i, j)·Y.
template <class Matrix>
Matrix kron(const Matrix& X, const Matrix& Y) {
  Matrix K(X.rows() * Y.rows(), X.cols() * Y.cols());
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index j = 0; j < X.cols(); ++j)
      K.block(i * Y.rows(), j * Y.cols(), Y.rows(), Y.cols()) = X(i, j) * Y;
  return K;
}

/// e^{i2πq/N} for any integer q. The exponent is reduced mod N first, so a
/// power z_j^k = e^{i2π(j−1)k/N} comes from one correctly reduced angle
/// (2π·q)/N with π in 50 digits, never from repeated multiplication.
inline Complex unit_root(long long q, int N) {
  long long reduced = q % N;
  if (reduced < 0) reduced += N;
  const Real angle = 2 * boost::math::constants::pi<Real>() * Real(reduced) / Real(N);
  return Complex(cos(angle), sin(angle));
}

/// The N-th roots of unity, tabulated once: roots(q) = unit_root(q, N) for any
/// integer q, without a cos/sin per matrix entry.
class UnitRoots {
 public:
  explicit UnitRoots(int N) : N_(N), roots_(N) {
    for (int q = 0; q < N; ++q) roots_[q] = unit_root(q, N);
  }
  const Complex& operator()(long long q) const {
    long long reduced = q % N_;
    if (reduced < 0) reduced += N_;
    return roots_[static_cast<std::size_t>(reduced)];
  }

 private:
  int N_;
  std::vector<Complex> roots_;
};

/// x in scientific notation with `digits` digits after the point (messages).
inline std::string fmt(const Real& x, int digits = 6) {
  return x.str(digits, std::ios_base::scientific);
}

inline bool finite(const Real& x) { return (boost::multiprecision::isfinite)(x); }
inline bool finite(const Complex& z) { return finite(z.real()) && finite(z.imag()); }

}  // namespace fdsid::reference::detail
