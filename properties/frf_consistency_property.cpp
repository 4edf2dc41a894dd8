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

// RMS over seeds and test frequencies of |Ĝ − G₀| / |G₀|, uniform grids
// ω_k = π (k − ½)/F (Assumption 8), output noise CN(0, σ²) (noise_variance);
// M = 0: known variance; M ≥ 2: M experiments and the sample statistics
// (Ŷ, σ̂²/M).
double rms_error(const StateSpace& sys, int F, int M, int r, int seeds, std::uint64_t seed0) {
  const std::vector<double> test_w = {0.15, 0.6, 1.2, 2.0, 2.9};
  const double var = noise_variance(sys);
  double acc = 0;
  int count = 0;
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
    for (double om : test_w) {
      const cplx g0 = frequency_response(sys, om)(0, 0);
      acc += std::norm((frequency_response(res.model, om)(0, 0) - g0) / g0);
      ++count;
    }
  }
  return std::sqrt(acc / count);
}

RC_GTEST_PROP(FrfConsistency, GErrorShrinksLikeOneOverSqrtF, ()) {
  // Theorems 1 and 2: the RMS error at F = 800 is 1/4 of that at F = 50.
  // Margin, two factors:
  //  - statistics: the RMS over S seeds of a complex Gaussian error has
  //    log-std ≤ 1/(2√S) (χ² with ≥ 2S degrees of freedom; fully correlated
  //    test frequencies are the worst case); the ratio of two independent RMS
  //    ≤ 1/√(2S). z = 4.5 (one-sided p = 3.4e-6, Bonferroni over the ≤ 200
  //    checks of 100 cases: family error ≤ 7e-4): exp(−4.5/√(2S)) = 0.399 for S = 12;
  //  - the second-order terms, ≤ 10 % of the first at F = 50 (noise_variance)
  //    and less at 800: the ratio may be biased by (1 − 0.1)/(1 + 0.1) = 0.818.
  // floor = 4 · 0.818 · 0.399 = 1.31. No upper bound: at F = 50 second-order
  // terms may as well make the ratio larger.
  // With the sample variance (M = 4) the errors are Gaussian mixtures (random
  // weights 1/σ̂²); Theorem 3 bounds the inflation by (M−2)/(M−3) at both F,
  // so the same margin is used.
  const SystemSpec spec = *gen_system_spec(1, 4);
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), r = 2 * n + 2, S = 12;
  const std::uint64_t seed = *rc::gen::inRange<std::uint64_t>(0, 1000000);
  const double floor = 4 * (0.9 / 1.1) * std::exp(-4.5 / std::sqrt(2.0 * S));
  RC_LOG() << spec << "\nseed " << seed << ", sigma " << std::sqrt(noise_variance(sys))
           << ", smallest Hankel singular value " << smallest_hankel_singular_value(sys) << "\n";
  for (int M : {0, 4}) {
    const double e50 = rms_error(sys, kSmallestF, M, r, S, seed), e800 = rms_error(sys, kLargestF, M, r, S, seed);
    RC_LOG() << (M == 0 ? "known variance" : "sample variance, M = 4") << ": RMS error F=50 " << e50
             << ", F=800 " << e800 << ", ratio " << e50 / e800 << " (>= " << floor << ")\n";
    RC_CLASSIFY(e50 / e800 < 3, M == 0 ? "known: ratio < 3" : "sample: ratio < 3");
    RC_CLASSIFY(e50 / e800 > 6, M == 0 ? "known: ratio > 6" : "sample: ratio > 6");
    RC_ASSERT(e50 / e800 >= floor);
  }
}

}  // namespace
}  // namespace fdsid::testing
