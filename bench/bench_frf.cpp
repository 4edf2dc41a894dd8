// Benchmarks of the Pintelon (2002) frequency-domain subspace identification
// (fdsid::identify_frf_fixed, Algorithm 1, discrete time, SISO) against a plain
// unstructured step 1: the full real data matrix Zᵀ (2F × r(m+p), Eqs. 9, 11,
// 18) formed explicitly and factored by one Eigen::HouseholderQR — what the
// chunked TSQR of fast/src/frf_id.cpp replaces. See bench/README.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "fdsid/frf_id.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/refine.hpp"

namespace {

using fdsid::cplx;

double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

// Periodic input/output data (c = 1) of the Eq. (36) plant on the uniform grid
// ω_k = π k / (F + 1), k = 1 … F, |U| = 1 with random phases, output noise
// CN(0, 1e-4) and that variance declared.
fdsid::FrfData make_data(int F) {
  const fdsid::StateSpace sys = fdsid::pintelon_plant();
  std::mt19937_64 rng(2002);
  std::uniform_real_distribution<double> ph(-M_PI, M_PI);
  std::normal_distribution<double> n(0.0, std::sqrt(0.5e-4));
  fdsid::FrfData d;
  d.omega.resize(F);
  for (int k = 0; k < F; ++k) {
    d.omega(k) = M_PI * (k + 1) / (F + 1);
    const cplx u = std::polar(1.0, ph(rng));
    const cplx nn(n(rng), n(rng));
    d.U.push_back(Eigen::MatrixXcd::Constant(1, 1, u));
    d.Y.push_back(fdsid::frequency_response(sys, d.omega(k)) * u + Eigen::MatrixXcd::Constant(1, 1, nn));
    d.variance.push_back(Eigen::MatrixXd::Constant(1, 1, 1e-4));
  }
  return d;
}

// One identification, n_a = 4. identify_frf_fixed splits the TSQR over
// threads when it has ≥ 2^24 flops per thread (F = 10^5), so wall time is reported.
void BM_IdentifyFrf(benchmark::State& state) {
  const int F = static_cast<int>(state.range(0)), r = static_cast<int>(state.range(1));
  const fdsid::FrfData d = make_data(F);
  for (auto _ : state) {
    fdsid::FrfResult res = fdsid::identify_frf_fixed(d, 4, r);
    benchmark::DoNotOptimize(res.model.A.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(F));
  state.counters["F"] = F;
  state.counters["r"] = r;
}

// identify_frf with the order given (n_a = 4) and r left to Section 5's
// search: every r in [1.5 n_a, 6 n_a] = [6, 24] screened by V_SUB (Eq. 35), the
// least one recomputed as identify_frf_fixed does — what a user waits for
// when no --r is given.
void BM_IdentifyFrfRSearch(benchmark::State& state) {
  const int F = static_cast<int>(state.range(0));
  const fdsid::FrfData d = make_data(F);
  fdsid::FrfOptions o;
  o.order = 4;
  for (auto _ : state) {
    fdsid::FrfResult res = fdsid::identify_frf(d, o);
    benchmark::DoNotOptimize(res.model.A.data());
    benchmark::ClobberMemory();
  }
  state.counters["F"] = F;
}

// Step 1 alone (TSQR of Zᵀ, C_Y, its Cholesky factor and the SVD of step 1c):
// fdsid::frf_singular_values, the part BM_PlainQR compares against.
void BM_Step1(benchmark::State& state) {
  const int F = static_cast<int>(state.range(0)), r = static_cast<int>(state.range(1));
  const fdsid::FrfData d = make_data(F);
  for (auto _ : state) {
    Eigen::VectorXd sv = fdsid::frf_singular_values(d, r);
    benchmark::DoNotOptimize(sv.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(F));
  state.counters["F"] = F;
  state.counters["r"] = r;
}

// The plain step 1b: Zᵀ (2F × 2r, rows Re and Im of [W_r(ξ_k) U(k); W_r(ξ_k) Y(k)]
// with W_r = [1, ξ, …, ξ^{r−1}]ᵀ) formed in memory, then one HouseholderQR
// (single-threaded, unblocked panel + blocked update as Eigen does it). Only
// step 1b, without steps 1c–3: a lower bound on what an unstructured
// implementation would cost.
void BM_PlainQR(benchmark::State& state) {
  const int F = static_cast<int>(state.range(0)), r = static_cast<int>(state.range(1));
  const fdsid::FrfData d = make_data(F);
  for (auto _ : state) {
    Eigen::MatrixXd Zt(2 * F, 2 * r);
    for (int k = 0; k < F; ++k) {
      const cplx xi = std::polar(1.0, d.omega(k));
      cplx w = 1.0;
      for (int i = 0; i < r; ++i) {
        const cplx u = w * d.U[k](0, 0), y = w * d.Y[k](0, 0);
        Zt(2 * k, i) = u.real();
        Zt(2 * k + 1, i) = u.imag();
        Zt(2 * k, r + i) = y.real();
        Zt(2 * k + 1, r + i) = y.imag();
        w *= xi;
      }
    }
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(Zt);
    benchmark::DoNotOptimize(qr.matrixQR().data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(F));
  state.counters["F"] = F;
  state.counters["r"] = r;
  state.counters["Zt_MiB"] = 2.0 * F * 2 * r * sizeof(double) / (1024.0 * 1024.0);
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int F : {999, 100000})
    for (int r : {8, 40}) b->Args({F, r});
}

// Throughput of `fdsid reproduce fig1`: Section 6.1's Monte Carlo (F = 999,
// M = 7, r = 8, n_a = 4; per run two identifications and β̂(α₀)) with
// state.range(0) threads. Counter runs_per_s; the paper's N_r = 10⁴ takes
// 10⁴ / runs_per_s seconds.
void BM_Figure1Runs(benchmark::State& state) {
  fdsid::FigureOptions o;
  o.runs = 200;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    const fdsid::FigureResult r = fdsid::reproduce_pintelon_figure(o);
    benchmark::DoNotOptimize(r.median_ratio);
  }
  state.counters["runs_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * o.runs, benchmark::Counter::kIsRate);
}
// One maximum-likelihood refinement (refine_ml, known variance) of the
// subspace estimate (n_a = 4, r = 8) on make_data(F): issue 15's target is
// ≤ 20 ms at F = 999. The subspace estimate is computed outside the loop.
void BM_RefineMl(benchmark::State& state) {
  const fdsid::FrfData d = make_data(static_cast<int>(state.range(0)));
  const fdsid::StateSpace start = fdsid::identify_frf_fixed(d, 4, 8).model;
  int iterations = 0;
  for (auto _ : state) {
    const fdsid::RefineResult r = fdsid::refine_ml(d, start);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.cost);
  }
  state.counters["F"] = static_cast<double>(state.range(0));
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_RefineMl)->Arg(999)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);

// One weighted refinement of Akçay's Algorithm 1 estimate (refine_spectrum) in
// Section 4's setting (order 4, ε = 1e-3, weights ε²|H(z_k)|²), M samples.
void BM_RefineSpectrum(benchmark::State& state) {
  const int M = static_cast<int>(state.range(0));
  const fdsid::StateSpace truth = fdsid::akcay_example_system();
  const Eigen::MatrixXcd clean = fdsid::sample_spectrum(truth, M);
  fdsid::SpectrumData d = fdsid::akcay_noisy_samples(clean, M, 1e-3, fdsid::NoiseVariance::UnitComplex, 1);
  fdsid::SpectrumOptions so;
  so.order = 4;
  so.p = so.r = 50;
  const fdsid::StateSpace start = fdsid::identify_spectrum(d, so).model;
  d.variance = fdsid::akcay_noise_variance(M, 1e-3);
  for (auto _ : state) {
    const fdsid::SpectrumRefineResult r = fdsid::refine_spectrum(d, start);
    benchmark::DoNotOptimize(r.cost);
  }
  state.counters["M"] = M;
}
BENCHMARK(BM_RefineSpectrum)->Arg(1000)->Arg(32000)->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);

BENCHMARK(BM_Figure1Runs)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

BENCHMARK(BM_IdentifyFrf)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);
BENCHMARK(BM_IdentifyFrfRSearch)->Arg(999)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);
BENCHMARK(BM_Step1)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);
// A middle size where step 1's QR splits into blocks of less than one chunk
// (numerics/qr.cpp: F = 5000, r = 40 gives seven blocks of 714 frequencies).
BENCHMARK(BM_Step1)->Args({5000, 40})->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);
BENCHMARK(BM_PlainQR)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", min_of);

}  // namespace

BENCHMARK_MAIN();
