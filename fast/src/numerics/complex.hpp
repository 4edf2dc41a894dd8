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

}  // namespace fdsid::numerics
