#pragma once
// The one FFT facility of fast/ (internal header): FFTW3 plans made under one
// planner lock, cached per (kind, length, count) for the life of the process,
// and executed with FFTW's new-array interface on FFTW-aligned buffers, which is
// thread-safe (FFTW 3 manual §5.4 "Thread safety": only the planner is not).
#include <Eigen/Dense>
#include <complex>
#include <cstddef>
#include <memory>
#include <vector>

struct fftw_plan_s;  // FFTW's opaque plan (fftw_plan is fftw_plan_s*)

namespace fdsid::numerics {

using cplx = std::complex<double>;

/// Frees memory from fftw_malloc (FFTW's 16/32-byte SIMD alignment).
struct FftwFree {
  void operator()(void* p) const;
};
using RealBuffer = std::unique_ptr<double[], FftwFree>;
using ComplexBuffer = std::unique_ptr<cplx[], FftwFree>;  // cplx is layout-compatible with fftw_complex
/// FFTW-aligned arrays of n elements (null when out of memory).
RealBuffer alloc_real(std::size_t n);
ComplexBuffer alloc_complex(std::size_t n);

/// Unnormalised real DFTs of length n on buffers owned by the object:
/// forward() X(k) = Σ_t x(t) e^{−j2πkt/n}, k = 0 … n/2 (time() → freq());
/// backward() x(t) = Σ_{k=0}^{n−1} X(k) e^{+j2πkt/n} with X(n−k) = conj X(k)
/// (freq() → time(); FFTW's c2r overwrites freq(), and ignores the imaginary
/// parts of X(0) and, n even, X(n/2)).
/// Method: FFTW_ESTIMATE plans from the process-wide cache (planning is
/// deterministic for a given length and alignment, so results do not depend on
/// the order in which threads plan). Fails: Error(Resource) when FFTW cannot
/// allocate or plan.
class RealFft {
 public:
  /// `where` names the caller in the Error thrown when FFTW fails.
  explicit RealFft(int n, const char* where = "fft");
  int size() const { return n_; }
  double* time() { return time_.get(); }
  cplx* freq() { return freq_.get(); }
  void forward();
  void backward();

 private:
  int n_;
  RealBuffer time_;
  ComplexBuffer freq_;
  fftw_plan_s* r2c_ = nullptr;  // owned by the plan cache
  fftw_plan_s* c2r_ = nullptr;
};

/// The unitary DFT of one period (Pintelon & Schoukens Eq. 4):
/// X(k) = P^{-1/2} Σ_t x(t) e^{−j2πkt/P}, k = 0 … P/2, and its inverse for a
/// real signal. Two calling conventions, each keeping the rounding of the code
/// it replaced (bit-identical results): the Eigen overloads scale before the
/// inverse transform and zero Im X(0), Im X(P/2); the pointer/std::vector
/// overloads scale after it.
class UnitaryFft {
 public:
  explicit UnitaryFft(int P, const char* where = "fft");
  int size() const { return fft_.size(); }
  Eigen::VectorXcd forward(const Eigen::VectorXd& x);
  Eigen::VectorXd inverse(const Eigen::VectorXcd& X);
  std::vector<cplx> forward(const double* x);
  std::vector<double> inverse(const std::vector<cplx>& X);

 private:
  RealFft fft_;
  double scale_;
};

/// `howmany` interleaved unnormalised c2r transforms of length n:
/// out[t·howmany + j] = Σ_k in[k·howmany + j] e^{+j2πkt/n}, k over 0 … n−1 with
/// the Hermitian extension of in's n/2+1 rows. `in` and `out` must come from
/// alloc_complex/alloc_real ((n/2+1)·howmany and n·howmany elements); `in` is
/// overwritten. Fails: Error(Numerical, where) when FFTW cannot plan.
void c2r_many(int n, int howmany, cplx* in, double* out, const char* where);

}  // namespace fdsid::numerics
