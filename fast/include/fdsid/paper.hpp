#pragma once
/// The papers' examples and their reproductions: Akçay (2011) Section 4,
/// Tables 1 and 2. These drive `fdsid reproduce table1|table2`; the numbers
/// come out of the algorithms in spectrum_id.hpp, nothing is tabulated here.
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "fdsid/names.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid {

/// Akçay (2011) Section 4: the fourth-order system (from McKelvey et al. 1996),
/// its entries parsed from the paper's decimal strings.
StateSpace akcay_example_system();

/// Akçay (2011) Section 4 noise filter H(z) = (0.2 z^2 - 0.0904 z + 0.1839) /
/// (z^2 - 1.1111 z + 0.8520): s̃_k = ε H(z_k) v_k.
cplx akcay_noise_filter(cplx z);

/// The variance E|ε H(z_k) v_k|² = ε²|H(z_k)|² (E|v|² = 1) of Section 4's noise
/// at the M+1 samples z_k = e^{iπk/M}: the weights of the refined Table 2
/// (SpectrumData::variance).
Eigen::VectorXd akcay_noise_variance(int M, double epsilon);

struct Table1Row {
  int M = 0;
  Eigen::VectorXd vo_sigmas;     ///< singular values of Ĝ_9 F_8 (Eq. 13)
  Eigen::VectorXd akcay_sigmas;  ///< singular values of 𝒴 (Eq. 19), p = 9, r = 8
};

/// Table 1: noise-free data, p = 9, r = 8, M = 16, 32, ..., 512.
std::vector<Table1Row> reproduce_table1(const std::vector<int>& Ms = {16, 32, 64, 128, 256, 512});

/// How the complex noise v_k of Section 4 is drawn.
enum class NoiseVariance {
  /// E|v|^2 = 1: Re v and Im v independent N(0, 1/2) (the standard complex normal).
  UnitComplex,
  /// Re v and Im v each N(0, 1), so E|v|^2 = 2 ("unit variance" read per component).
  UnitPerComponent
};
/// "unit-complex", "unit-per-component" (reproduce table2 --noise-variance).
const NameTable<NoiseVariance>& noise_variance_names();
const char* to_string(NoiseVariance v);

struct Table2Options {
  int realizations = 100;
  std::uint64_t seed = 1;
  std::vector<int> Ms = {1000, 2000, 4000, 8000, 16000, 32000};
  int p = 50, r = 50, order = 4;
  double epsilon = 1e-3;
  /// The paper also ran vo1997 on the same data with ε = 1e-9 and saw it fail
  /// at step 6 in every case; 0 skips that run.
  double vo_epsilon = 1e-9;
  /// Conjugate is the reading that reproduces the paper's figures (README).
  Extension extension = Extension::Conjugate;
  NoiseVariance noise = NoiseVariance::UnitComplex;
  /// Also refine each Algorithm 1 estimate (refine_spectrum), weighted by the
  /// noise's variance ε²|H(z_k)|² (Section 4's noise filter, known here), and
  /// report its errors beside Algorithm 1's.
  bool refine = false;
  int threads = 0;  ///< 0: std::thread::hardware_concurrency()
  /// Called after each realisation (done, total over all M), from the worker
  /// threads, serialised; empty: no progress.
  std::function<void(int done, int total)> progress;
};

struct Table2Row {
  int M = 0;
  double l2 = 0, linf = 0;        ///< means over the successful realisations
  double l2_sd = 0, linf_sd = 0;  ///< sample standard deviations (NaN when no realisation returned a model)
  int failures = 0;               ///< realisations where Algorithm 1 failed
  std::string first_failure;      ///< the lowest-numbered failed realisation's message ("" when none)
  int vo_runs = 0, vo_failures = 0;
  int vo_split_failures = 0;  ///< of which at step 6, as the paper reports
  double vo_l2 = NAN;         ///< mean L2 error of the vo1997 runs that returned a model (NaN: none, or not run)
  std::vector<double> l2_all, linf_all;
  /// With options.refine: the refined estimates' errors over the realisations
  /// where Algorithm 1 and the refinement both returned a model (NaN without).
  double l2_refined = NAN, linf_refined = NAN, l2_refined_sd = NAN, linf_refined_sd = NAN;
  int refine_failures = 0;  ///< realisations where Algorithm 1 succeeded and the refinement failed
  std::vector<double> l2_refined_all, linf_refined_all;
};

/// Table 2: Monte Carlo over noise realisations, p = r = 50, ε = 1e-3, order 4.
/// The noise is drawn on the M+1 given samples only (Eq. 7) and extended with
/// them by step 1 according to options.extension. Realisation i of size M uses
/// its own generator seeded from (seed, i, M), so results do not depend on the
/// number of threads. Errors are the measured L2 and L∞ norms of Section 4 on
/// the M+1 grid points, Ŝ from the identified spectral factor.
std::vector<Table2Row> reproduce_table2(const Table2Options& options);

/// The Section 4 measurement: noise-free samples plus ε H(z_k) v_k, k = 1..M+1.
SpectrumData akcay_noisy_samples(const Eigen::MatrixXcd& clean, int M, double epsilon, NoiseVariance noise,
                                 std::uint64_t seed);

/// Measured L2 and L∞ errors of Section 4 (max singular value for m > 1).
void spectrum_errors(const StateSpace& model, const Eigen::MatrixXcd& truth, int M, double& l2, double& linf);

// ---------------------------------------------------------------------------
// Pintelon (2002) Section 6.1

/// Pintelon (2002) Eq. (36): the fourth-order plant of McKelvey et al. (1996),
/// from the printed decimal strings (A(3,4) = 0.064516 as printed there; the
/// garbled B and C entries read as in Akçay 2011: B(4) = 0.1290, C(4) = 1.6129).
StateSpace pintelon_plant();
/// Eq. (37): the second-order noise model (A_n, B_n, C_n, D_n = 0.2).
StateSpace pintelon_noise_model();
/// σ_Y(k)² = |H_0(z_k)|² with H_0 the monic form of Eq. (37): H_0 = H / D_n.
double pintelon_noise_variance(double omega);

struct FigureOptions {
  int runs = 10000;         ///< N_r (the paper's 10⁴)
  std::uint64_t seed = 1;
  int order = 4;            ///< n_a: 4 for Fig. 1 (no model errors), 1 for Fig. 2
  int M = 7;                ///< experiments (periods)
  int F = 999;              ///< frequencies f_k/f_s = k/2000
  int r = 8;
  /// |U(k)|; the paper does not give it. 1 by default; √N/2 with N = 2000
  /// (a unit sine under the DFT scaling of Eq. 4) is the other natural choice.
  double input_level = 1.0;
  int threads = 0;          ///< 0: std::thread::hardware_concurrency()
  /// Called after each block of runs (runs done, runs), from the worker
  /// threads, serialised; empty: no progress.
  std::function<void(int done, int total)> progress;
};

struct FigureResult {
  Eigen::VectorXd frequency;      ///< f_k / f_s = k / 2000
  Eigen::VectorXd ratio;          ///< std(G(θ̂_S)) / std(G(θ̂)) per frequency (Fig. 1b / 2b, solid line)
  Eigen::VectorXd theory;         ///< Eq. (28): √(1 + var(G(α₀, β̂)) / ((M − 3) var(G(θ̂)))) (Fig. 1b dashed)
  double bound = 0;               ///< Eq. (30): √((M − 2)/(M − 3))
  double median_ratio = 0;
  Eigen::VectorXd std_subspace, std_sample, std_known_alpha;
  Eigen::VectorXcd truth, mean_subspace, mean_sample;
  int runs = 0;                   ///< successful runs (all three estimates returned)
  int failures = 0;
  std::string first_failure;      ///< "run i: <error>" of the lowest-numbered failed run ("" when none)
};

/// Section 6.1's Monte Carlo: per run, M experiments Y^[l] = G₀ U + N^[l]
/// with circular complex normal N^[l] of variance |H₀(z_k)|², then (i) the
/// sample-subspace estimate θ̂_S (Ŷ, σ̂²/M), (ii) the subspace estimate θ̂
/// (Ŷ, σ²/M) and (iii) β̂(α₀) (true A, C; B, D by Eq. 17 with σ²/M).
/// U(k) = input_level · e^{jφ_k}, φ_k uniform from the seed and the same in
/// every run and experiment (a periodic input). Run i draws from its own
/// generator seeded by (seed, i); sums are accumulated per block of runs and
/// merged in block order, so the result does not depend on the thread count.
FigureResult reproduce_pintelon_figure(const FigureOptions& options);

}  // namespace fdsid
