// Benchmarks of the power-spectrum identification (Akçay 2011 Algorithm 1,
// fdsid::identify_spectrum) against one FFTW transform of the same length,
// and of the Table 2 Monte Carlo reproduction. See bench/README.md for the
// targets these figures are checked against.
#include <benchmark/benchmark.h>
#include <fftw3.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "fdsid/paper.hpp"
#include "fdsid/spectrum_id.hpp"

namespace {

constexpr double kEpsilon = 1e-3;
constexpr std::uint64_t kSeed = 12345;

// With --benchmark_repetitions=R, also report the fastest repetition: the
// least disturbed figure on a shared machine.
double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

// Peak resident set size of the process so far (getrusage ru_maxrss, KiB on Linux).
double peak_rss_mib() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

fdsid::SpectrumData noisy_data(int M) {
  const fdsid::StateSpace sys = fdsid::akcay_example_system();
  const Eigen::MatrixXcd clean = fdsid::sample_spectrum(sys, M);
  return fdsid::akcay_noisy_samples(clean, M, kEpsilon, fdsid::NoiseVariance::UnitComplex, kSeed);
}

// Algorithm 1 on M+1 noisy samples of the Section 4 system, p = r = 50, n = 4,
// single-threaded. The data are generated before the timed loop.
void BM_Identify(benchmark::State& state) {
  const int M = static_cast<int>(state.range(0));
  const fdsid::SpectrumData data = noisy_data(M);
  fdsid::SpectrumOptions opt;
  opt.method = fdsid::Method::Akcay2011;
  opt.order = 4;
  opt.p = 50;
  opt.r = 50;
  const double rss_before = peak_rss_mib();
  double min_spectrum = 0.0;
  for (auto _ : state) {
    fdsid::SpectrumResult res = fdsid::identify_spectrum(data, opt);
    benchmark::DoNotOptimize(res.model.A.data());
    min_spectrum = res.min_spectrum;
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(M + 1));  // spectrum samples
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(M + 1) * static_cast<int64_t>(sizeof(fdsid::cplx)));
  state.counters["N"] = 2.0 * M;
  state.counters["min_spectrum"] = min_spectrum;
  // Process-wide peak RSS (monotone): after this run, and before its timed loop
  // (data already generated), so the difference bounds what identify_spectrum
  // added to the peak.
  state.counters["peak_rss_MiB"] = peak_rss_mib();
  state.counters["peak_rss_before_MiB"] = rss_before;
}
BENCHMARK(BM_Identify)->Arg(1000)->Arg(32000)->Arg(1000000)->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);

// The yardstick: one FFTW complex-to-real transform of length N = 2M (M+1
// complex inputs, N real outputs), FFTW_ESTIMATE, planned outside the loop.
// c2r destroys its input, so the input is restored each iteration by a memcpy
// from a saved copy, done between PauseTiming/ResumeTiming so that only
// fftw_execute is timed.
void BM_FftwC2R(benchmark::State& state) {
  const int M = static_cast<int>(state.range(0));
  const int N = 2 * M;
  const fdsid::SpectrumData data = noisy_data(M);
  struct FftwFree {
    void operator()(void* p) const { fftw_free(p); }
  };
  std::unique_ptr<fftw_complex, FftwFree> in(fftw_alloc_complex(static_cast<size_t>(M) + 1));
  std::unique_ptr<fftw_complex, FftwFree> saved(fftw_alloc_complex(static_cast<size_t>(M) + 1));
  std::unique_ptr<double, FftwFree> out(fftw_alloc_real(static_cast<size_t>(N)));
  for (int k = 0; k <= M; ++k) {
    saved.get()[k][0] = data.S(0, k).real();
    saved.get()[k][1] = data.S(0, k).imag();
  }
  const size_t in_bytes = sizeof(fftw_complex) * (static_cast<size_t>(M) + 1);
  // FFTW_ESTIMATE does not overwrite the arrays while planning; fill afterwards anyway.
  const auto plan_start = std::chrono::steady_clock::now();
  fftw_plan plan = fftw_plan_dft_c2r_1d(N, in.get(), out.get(), FFTW_ESTIMATE);
  const double plan_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - plan_start).count();
  for (auto _ : state) {
    state.PauseTiming();
    std::memcpy(in.get(), saved.get(), in_bytes);
    state.ResumeTiming();
    fftw_execute(plan);
    benchmark::DoNotOptimize(out.get());
    benchmark::ClobberMemory();
  }
  fftw_destroy_plan(plan);
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(N));  // output points
  state.counters["N"] = static_cast<double>(N);
  // Not timed above: one FFTW_ESTIMATE planning of this size (identify_spectrum plans on every call).
  state.counters["plan_ms"] = plan_ms;
}
BENCHMARK(BM_FftwC2R)->Arg(1000)->Arg(32000)->Arg(1000000)->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min_of);

// Table 2 of Akçay (2011): 100 realisations at each M = 1000 ... 32000 (and the
// vo1997 runs at ε = 1e-9), on all cores (threads = 0).
void BM_Table2(benchmark::State& state) {
  fdsid::Table2Options o;
  o.realizations = 100;
  o.threads = 0;
  int failures = 0;
  for (auto _ : state) {
    const std::vector<fdsid::Table2Row> rows = fdsid::reproduce_table2(o);
    failures = 0;
    for (const auto& r : rows) failures += r.failures;
    benchmark::DoNotOptimize(rows.data());
  }
  state.counters["threads"] = static_cast<double>(std::thread::hardware_concurrency());
  state.counters["failures"] = failures;
}
BENCHMARK(BM_Table2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
