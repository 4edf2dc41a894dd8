#include "numerics/fft.hpp"

#include <fftw3.h>

#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <tuple>

#include "fdsid/error.hpp"

namespace fdsid::numerics {

namespace {

// FFTW's planner is not thread-safe (fftw_execute_* is): every plan of fast/
// is made and destroyed under this one lock, so that Monte Carlo runs may
// identify in threads.
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

enum class Kind { R2C, C2R };

// Plans per (kind, n, howmany), made once on FFTW-aligned scratch arrays and
// kept for the life of the process; the cache destroys them at exit (so
// LeakSanitizer, e.g. in the fuzz targets, sees no leak).
struct PlanCache : std::map<std::tuple<Kind, int, int>, fftw_plan> {
  ~PlanCache() {
    for (auto& kv : *this) fftw_destroy_plan(kv.second);
  }
};

fftw_plan cached_plan(Kind kind, int n, int howmany) {
  static PlanCache cache;
  std::lock_guard<std::mutex> lock(planner_mutex());
  const auto key = std::make_tuple(kind, n, howmany);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const std::size_t bins = static_cast<std::size_t>(n / 2 + 1) * howmany;
  fftw_complex* c = fftw_alloc_complex(bins);
  double* r = fftw_alloc_real(static_cast<std::size_t>(n) * howmany);
  fftw_plan plan = nullptr;
  if (c && r) {
    if (kind == Kind::C2R)
      plan = fftw_plan_many_dft_c2r(1, &n, howmany, c, nullptr, howmany, 1, r, nullptr, howmany, 1, FFTW_ESTIMATE);
    else
      plan = fftw_plan_many_dft_r2c(1, &n, howmany, r, nullptr, howmany, 1, c, nullptr, howmany, 1, FFTW_ESTIMATE);
  }
  fftw_free(c);
  fftw_free(r);
  if (plan) cache.emplace(key, plan);
  return plan;
}

fftw_complex* as_fftw(cplx* p) { return reinterpret_cast<fftw_complex*>(p); }

}  // namespace

void FftwFree::operator()(void* p) const { fftw_free(p); }

RealBuffer alloc_real(std::size_t n) { return RealBuffer(fftw_alloc_real(n)); }
ComplexBuffer alloc_complex(std::size_t n) {
  return ComplexBuffer(reinterpret_cast<cplx*>(fftw_alloc_complex(n)));
}

RealFft::RealFft(int n, const char* where)
    : n_(n), time_(alloc_real(static_cast<std::size_t>(n))), freq_(alloc_complex(static_cast<std::size_t>(n / 2 + 1))) {
  if (!time_ || !freq_) throw Error(ErrorKind::Resource, where, "FFTW could not allocate its buffers");
  r2c_ = cached_plan(Kind::R2C, n, 1);
  c2r_ = cached_plan(Kind::C2R, n, 1);
  if (!r2c_ || !c2r_)
    throw Error(ErrorKind::Resource, where, "FFTW could not plan a transform of length " + std::to_string(n));
}

void RealFft::forward() { fftw_execute_dft_r2c(r2c_, time_.get(), as_fftw(freq_.get())); }
void RealFft::backward() { fftw_execute_dft_c2r(c2r_, as_fftw(freq_.get()), time_.get()); }

UnitaryFft::UnitaryFft(int P, const char* where) : fft_(P, where), scale_(1.0 / std::sqrt(static_cast<double>(P))) {}

Eigen::VectorXcd UnitaryFft::forward(const Eigen::VectorXd& x) {
  const int P = fft_.size();
  for (int t = 0; t < P; ++t) fft_.time()[t] = x(t);
  fft_.forward();
  Eigen::VectorXcd X(P / 2 + 1);
  for (int k = 0; k <= P / 2; ++k) X(k) = scale_ * fft_.freq()[k];
  return X;
}

Eigen::VectorXd UnitaryFft::inverse(const Eigen::VectorXcd& X) {
  const int P = fft_.size();
  cplx* c = fft_.freq();
  for (int k = 0; k <= P / 2; ++k) c[k] = cplx(scale_ * X(k).real(), scale_ * X(k).imag());
  c[0].imag(0);
  if (P % 2 == 0) c[P / 2].imag(0);
  fft_.backward();
  return Eigen::Map<const Eigen::VectorXd>(fft_.time(), P);
}

std::vector<cplx> UnitaryFft::forward(const double* x) {
  const int P = fft_.size();
  std::copy(x, x + P, fft_.time());
  fft_.forward();
  std::vector<cplx> X(static_cast<std::size_t>(P / 2 + 1));
  for (std::size_t k = 0; k < X.size(); ++k) X[k] = scale_ * fft_.freq()[k];
  return X;
}

std::vector<double> UnitaryFft::inverse(const std::vector<cplx>& X) {
  const int P = fft_.size();
  std::copy(X.begin(), X.end(), fft_.freq());
  fft_.backward();
  std::vector<double> x(fft_.time(), fft_.time() + P);
  for (double& v : x) v *= scale_;
  return x;
}

void c2r_many(int n, int howmany, cplx* in, double* out, const char* where) {
  const fftw_plan plan = cached_plan(Kind::C2R, n, howmany);
  if (!plan) throw Error(ErrorKind::Numerical, where, "FFTW could not plan a transform of length " + std::to_string(n));
  fftw_execute_dft_c2r(plan, as_fftw(in), out);
}

}  // namespace fdsid::numerics
