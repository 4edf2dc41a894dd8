#pragma once
// Complex arithmetic helpers of fast/ (internal header).
#include <complex>

namespace fdsid::numerics {

/// 1/w as conj(w)/|w|² without libgcc's overflow-guarded complex division
/// (__divdc3, a sixth of the gap diagnosis's time before). Accurate to a few
/// u when |w|² neither overflows nor underflows: callers use it where |w| is
/// bounded away from 0 and infinity (a point of the unit circle or the
/// imaginary axis minus a pole at least e^-30 off it, |w|² ≥ 1e-26).
inline std::complex<double> reciprocal(std::complex<double> w) {
  const double d = w.real() * w.real() + w.imag() * w.imag();
  return {w.real() / d, -w.imag() / d};
}

/// a·b by the textbook formula, without the C99 Annex G recovery of an
/// infinite product that GCC inlines around every std::complex product (a
/// NaN test and a branch to __muldc3): 30 % of identify-frf at r = 8 was
/// Resolvent::left's 24 products per frequency. Differs from a·b only when
/// an operand is infinite or NaN, where the callers' finiteness checks fail
/// either way.
inline std::complex<double> multiply(std::complex<double> a, std::complex<double> b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

}  // namespace fdsid::numerics
