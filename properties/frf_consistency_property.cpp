// Property: consistency of Pintelon (2002) Algorithm 1 as F grows (Theorem 1
// with known variance, Theorem 2 with the sample variance of M = 4
// experiments): Ĝ − G₀ = O_p(F^{-1/2}), on random systems meeting Section
// 2.1's assumptions (rc_generators.hpp) and one more, stated and derived below:
// the noise is small against the system's weakest mode at the smallest F.
//
// Why that assumption (the cause of the failures that had this property
// disabled, one run in six): the rate is asymptotic. When the noise per sample
// σ is large against the smallest Hankel singular value σ_n, the weakest mode
// is not resolved at F = 50 (nor barely at 800), the error there is bounded by
// that mode's size instead of growing with the noise, and the ratio of the
// errors at F = 50 and 800 falls below 4. Found on
//   SystemSpec{channels=1, gain=0.4, modes=[{0.37, 1.16, 0} {0.38, 0.25, 0}], ...}
// (σ = 3.6e-2 against σ_n = 8.3e-3; 48 seeds, RMS relative error 2.1e-2,
// 1.3e-2, 9.3e-3, 3.8e-3, 2.1e-3 at F = 50, 200, 800, 3200, 12800: the ratio
// reaches 4 per factor 16 in F only from F = 800 on). That is the theorem
// holding, not failing; the property now states where it applies.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <random>

#include "linalg.hpp"
#include "fdsid/frf_id.hpp"
#include "frf_tolerance.hpp"
#include "rc_generators.hpp"
#include "statistics.hpp"
#include "tolerance.hpp"

namespace fdsid::testing {
namespace {

constexpr int kSmallestF = 50, kLargestF = 800;

// Smallest Hankel singular value √λ_min(W_c W_o) of a stable model.
double smallest_hankel_singular_value(const StateSpace& sys) {
  const Eigen::MatrixXd Wc = lyapunov(sys.A, sys.B * sys.B.transpose());
  const Eigen::MatrixXd Wo = lyapunov(sys.A.transpose(), sys.C.transpose() * sys.C);
  return std::sqrt(fdsid::testing::eigenvalues(Wc * Wo).real().minCoeff());
}

// The noise variance σ² of the property:
//  - 3 % of the RMS of the dynamic part G₀ − D over the band (the part the
//    subspace step sees), as long as
//  - σ/√F ≤ σ_n/10 at F = 50 (the assumption above): the noise the weakest
//    direction sees is a tenth of its singular value, so first-order
//    perturbation theory (errors linear in the noise, hence ∝ F^{-1/2}) holds
//    with second-order terms ≤ 10 % of the first (bias of the ratio below).
double noise_variance(const StateSpace& sys) {
  double g2 = 0;
  for (int k = 0; k < 64; ++k) g2 += (frequency_response(sys, M_PI * (k + 0.5) / 64) - sys.D).squaredNorm() / 64;
  const double sigma = std::min(0.03 * std::sqrt(g2), 0.1 * smallest_hankel_singular_value(sys) * std::sqrt(kSmallestF));
  return sigma * sigma;
}

// Per seed, the RMS over test frequencies of |Ĝ − G₀| / |G₀|; uniform grids
// ω_k = π (k − ½)/F (Assumption 8), output noise CN(0, σ²) (noise_variance);
// M = 0: known variance; M ≥ 2: M experiments and the sample statistics
// (Ŷ, σ̂²/M).
std::vector<double> errors_per_seed(const StateSpace& sys, int F, int M, int r, int seeds, std::uint64_t seed0) {
  const std::vector<double> test_w = {0.15, 0.6, 1.2, 2.0, 2.9};
  const double var = noise_variance(sys);
  std::vector<double> errors;
  for (int s = 0; s < seeds; ++s) {
    std::mt19937_64 rng(seed0 + 7919 * s + F);
    Eigen::VectorXd w(F);
    for (int k = 0; k < F; ++k) w(k) = M_PI * (k + 0.5) / F;
    FrfData d;
    if (M == 0) {
      std::vector<Eigen::MatrixXcd> G;
      std::vector<Eigen::MatrixXd> V;
      for (int k = 0; k < F; ++k) {
        G.push_back(frequency_response(sys, w(k)) + Eigen::MatrixXcd::Constant(1, 1, complex_normal(rng, var)));
        V.push_back(Eigen::MatrixXd::Constant(1, 1, var));
      }
      d = frf_data(Domain::Discrete, w, G, V);
    } else {
      std::vector<std::vector<Eigen::VectorXcd>> U(M), Y(M);
      for (int k = 0; k < F; ++k) {
        const cplx G0 = frequency_response(sys, w(k))(0, 0);
        for (int l = 0; l < M; ++l) {
          U[l].push_back(Eigen::VectorXcd::Ones(1));
          // per-experiment variance M σ² so that Ŷ has σ² as with M = 0
          Y[l].push_back(Eigen::VectorXcd::Constant(1, G0 + complex_normal(rng, M * var)));
        }
      }
      d = sample_statistics(Domain::Discrete, w, U, Y).data;
    }
    const FrfResult res = identify_frf_fixed(d, sys.order(), r);
    double acc = 0;
    for (double om : test_w) {
      const cplx g0 = frequency_response(sys, om)(0, 0);
      acc += std::norm((frequency_response(res.model, om)(0, 0) - g0) / g0);
    }
    errors.push_back(std::sqrt(acc / test_w.size()));
  }
  return errors;
}

double rms(const std::vector<double>& e) {
  double acc = 0;
  for (double x : e) acc += x * x;
  return std::sqrt(acc / e.size());
}

RC_GTEST_PROP(FrfConsistency, GErrorShrinksLikeOneOverSqrtF, ()) {
  // Theorems 1 and 2: the error at F = 800 is 1/4 of that at F = 50.
  // The second-order terms are ≤ 10 % of the first at F = 50 (noise_variance)
  // and less at 800: the ratio may be biased by (1 − 0.1)/(1 + 0.1) = 0.818.
  // No upper bound: at F = 50 second-order terms may as well make it larger.
  // Each check is one-sided at p = 3.4e-6 (z = 4.5), Bonferroni over the 200
  // checks of 100 cases: family error ≤ 7e-4.
  //
  // Known variance (M = 0): the RMS over S = 12 seeds of a complex Gaussian
  // error has log-std ≤ 1/(2√S) (χ² with ≥ 2S degrees of freedom; fully
  // correlated test frequencies are the worst case); the ratio of two
  // independent RMS ≤ 1/√(2S): floor = 4 · 0.818 · exp(−4.5/√(2S)) = 1.31.
  //
  // Sample variance (M = 4): the error is a Gaussian mixture, with step 3's
  // random weights 1/σ̂²_k (inverse χ² with 2(M − 1) = 6 degrees of freedom:
  // moments of order < 3 only). Its mean square exists (Eq. (28): at most
  // (M−2)/(M−3) = 2 × the known-variance one), but the spread of a mean of
  // squared errors needs E{σ⁸/σ̂⁸}, infinite for M ≤ 5, so the RMS has no
  // χ² margin: one frequency with σ̂² = 0.005 σ² made one seed's error at
  // F = 800 15 × the others' and the RMS ratio 1.30 (seed=2317880433).
  // Instead, S = 24 seeds per F and the exact Mann–Whitney test, which needs no
  // law: the hypothesis is that the error at F = 50 divided by
  // c = 4 · 0.818 · √((M−3)/(M−2)) = 2.31 (the inflation of Eq. (28) may be
  // reached at 800 and not at 50) is stochastically larger than the error at
  // F = 800; it is rejected when P(U ≥ u) < 3.4e-6. Power: with the measured
  // spread of one seed's log-error (std 0.37), an estimator that does not
  // converge has P(e50/c < e800) ≈ 0.95, U ≈ 545 of 576, p < 1e-7.
  const SystemSpec spec = *gen_system_spec(1, 4);
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), r = 2 * n + 2, S = 12, M = 4, S_sample = 24;
  const std::uint64_t seed = *rc::gen::inRange<std::uint64_t>(0, 1000000);
  const double alpha = 3.4e-6, bias = 0.9 / 1.1;
  RC_LOG() << spec << "\nseed " << seed << ", sigma " << std::sqrt(noise_variance(sys))
           << ", smallest Hankel singular value " << smallest_hankel_singular_value(sys) << "\n";

  const double floor = 4 * bias * std::exp(-4.5 / std::sqrt(2.0 * S));
  const double e50 = rms(errors_per_seed(sys, kSmallestF, 0, r, S, seed));
  const double e800 = rms(errors_per_seed(sys, kLargestF, 0, r, S, seed));
  RC_LOG() << "known variance: RMS error F=50 " << e50 << ", F=800 " << e800 << ", ratio " << e50 / e800
           << " (>= " << floor << ")\n";
  RC_CLASSIFY(e50 / e800 < 3, "known: ratio < 3");
  RC_CLASSIFY(e50 / e800 > 6, "known: ratio > 6");
  RC_ASSERT(e50 / e800 >= floor);

  const double c = 4 * bias * std::sqrt((M - 3.0) / (M - 2.0));
  std::vector<double> scaled50 = errors_per_seed(sys, kSmallestF, M, r, S_sample, seed);
  const std::vector<double> s800 = errors_per_seed(sys, kLargestF, M, r, S_sample, seed);
  RC_CLASSIFY(rms(scaled50) / rms(s800) < 3, "sample: RMS ratio < 3");
  for (double& e : scaled50) e /= c;
  const double p = mann_whitney_p_value(scaled50, s800);
  RC_LOG() << "sample variance, M = 4: error F=50 / " << c << " below error F=800 with p " << p << " (>= "
           << alpha << ")\n";
  RC_ASSERT(p >= alpha);
}

}  // namespace
}  // namespace fdsid::testing
