// Property: fast/ identify_frf_fixed (double, TSQR, Pintelon 2002 Algorithm 1)
// agrees with reference::identify_frf (50 digits, explicit Kronecker products,
// Eq. 9) on random stable minimal discrete SISO systems of order 1..4, on random
// non-uniform frequency grids of 20..60 lines, with noise-free and noisy FRF
// data. Both implementations receive the same double values (converted to the
// reference's Real through "%.17g" decimal strings, which round-trip exactly),
// so they compute the same estimator and their difference is the rounding of
// the double computation amplified by the problem's condition.
//
// Tolerance (derived, not tuned): fast's error_estimate ε = u·κ is the relative
// accuracy of Â (frf_id.hpp, κ = σ_1/σ_n · cond(Ô_r[1:r−1])). A relative
// perturbation ε of (A, B, C, D) moves G(ξ) = C R B + D, R = (ξI − A)⁻¹, by at
// most ε · S(ξ) to first order with the sensitivity
//   S(ξ) = ‖C R‖ ‖R B‖ (‖A‖ + ‖ξ I − A‖) + ‖C R B‖ + ‖D‖
// (δA enters as C R δA R B; δB and δC, whose relative error from the step-3 and
// step-2 least squares is of the same order ε, as δC R B + C R δB bounded by
// ‖C R‖‖R B‖‖ξI − A‖ each up to the identity C R B = (C R)(ξI − A)(R B);
// δD as ‖D‖). The check is |G_fast − G_ref| ≤ c · ε · S(ξ_k) at every data
// frequency with the stated constant c = 100 (the dimension factors of the
// norm bounds for n ≤ 4, r ≤ 10, and the rounding of the final eigen/LU
// evaluation of G, each O(n) u). The reference's own error (u ≈ 1e-50) is nil.
// The step-3 least-squares problem of (B, D) may be worse conditioned than κ;
// its condition is measured here (cond of the stacked real regressor) and, when
// it exceeds κ, ε is taken as u · max(κ, cond_3).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdio>
#include <random>
#include <sstream>

#include "linalg.hpp"
#include "fdsid/error.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/reference/frf_id.hpp"
#include "rc_generators.hpp"
#include "reference_bridge.hpp"

namespace fdsid::testing {
namespace {

reference::Real exact(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return reference::Real(buf);
}

reference::FrfData to_reference(const FrfData& d) {
  reference::FrfData r;
  r.domain = "discrete";
  for (int k = 0; k < d.frequencies(); ++k) {
    r.omega.push_back(exact(d.omega(k)));
    reference::MatrixC U(1, 1), Y(1, 1);
    U(0, 0) = reference::Complex(exact(d.U[k](0, 0).real()), exact(d.U[k](0, 0).imag()));
    Y(0, 0) = reference::Complex(exact(d.Y[k](0, 0).real()), exact(d.Y[k](0, 0).imag()));
    reference::MatrixR V(1, 1);
    V(0, 0) = exact(d.variance[k](0, 0));
    r.U.push_back(U);
    r.Y.push_back(Y);
    r.variance.push_back(V);
  }
  return r;
}


/// Condition number of step 3's real regressor for (B, D) given Â, Ĉ (Eq. 17
/// with W = 1/σ): rows Re/Im of [C R_k ⊗ 1, 1] / σ_k.
double step3_condition(const StateSpace& est, const FrfData& d) {
  const int n = est.order(), F = d.frequencies();
  Eigen::MatrixXd X(2 * F, n + 1);
  for (int k = 0; k < F; ++k) {
    const std::complex<double> z = std::polar(1.0, d.omega(k));
    const Eigen::MatrixXcd R = fdsid::testing::inverse(Eigen::MatrixXcd(z * Eigen::MatrixXcd::Identity(n, n) - est.A.cast<std::complex<double>>()));
    const Eigen::RowVectorXcd cr = est.C.cast<std::complex<double>>() * R;
    const double w = 1.0 / std::sqrt(d.variance[k](0, 0));
    for (int j = 0; j < n; ++j) {
      X(2 * k, j) = w * cr(j).real();
      X(2 * k + 1, j) = w * cr(j).imag();
    }
    X(2 * k, n) = w;
    X(2 * k + 1, n) = 0;
  }
  const Eigen::VectorXd s = fdsid::testing::singular_values(Eigen::MatrixXd(X));
  return s(0) / s(s.size() - 1);
}

RC_GTEST_PROP(FrfFastVsReference, SameEstimateAtEveryDataFrequency, ()) {
  const SystemSpec spec = *gen_system_spec(1, 4);  // SISO, order 1..4, stable, minimal, distinct eigenvalues
  const StateSpace sys = make_system(spec);
  const int n = sys.order();
  const int F = *rc::gen::inRange(20, 61);
  // Non-uniform grid: F distinct lines of ω = π j / 1000, j = 1..999, sorted.
  std::vector<int> lines = *rc::gen::unique<std::vector<int>>(F, rc::gen::inRange(1, 1000));
  std::sort(lines.begin(), lines.end());
  const int r = *rc::gen::inRange(n + 1, 2 * n + 3);  // 2 F c = 2F ≥ 40 ≥ r (m + p) = 2 r
  const bool noisy = *rc::gen::arbitrary<bool>();
  const std::uint64_t seed = *rc::gen::arbitrary<std::uint64_t>();
  RC_CLASSIFY(noisy, "noisy");
  RC_CLASSIFY(n >= 3, "order >= 3");

  // Data: G₀ at the grid plus (noisy) circular complex noise of variance σ_k² =
  // (1e-3)² · (1 + k mod 3) (non-constant weights), known to both implementations.
  Eigen::VectorXd omega(F);
  for (int k = 0; k < F; ++k) omega(k) = M_PI * lines[static_cast<size_t>(k)] / 1000.0;
  std::vector<Eigen::MatrixXcd> G = frequency_response(sys, omega);
  std::vector<Eigen::MatrixXd> var;
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int k = 0; k < F; ++k) {
    const double v = 1e-6 * (1 + k % 3);
    var.push_back(Eigen::MatrixXd::Constant(1, 1, v));
    if (noisy) G[k](0, 0) += std::sqrt(v / 2) * std::complex<double>(normal(gen), normal(gen));
  }
  const FrfData data = frf_data(Domain::Discrete, omega, G, var);

  std::ostringstream context;
  context << spec << "\nF = " << F << ", r = " << r << ", noisy = " << noisy << ", seed = " << seed << "\nlines (pi/1000):";
  for (int j : lines) context << " " << j;
  RC_LOG() << context.str() << "\n";

  FrfResult fast;
  try {
    fast = identify_frf_fixed(data, n, r);
  } catch (const Error& e) {
    RC_FAIL(std::string("fast failed: ") + e.what());
  }
  reference::FrfOptions ro;
  ro.order = n;
  ro.r = r;
  reference::FrfResult ref;
  try {
    ref = reference::identify_frf(to_reference(data), ro);
  } catch (const reference::Error& e) {
    RC_FAIL(std::string("reference failed: ") + e.what());
  }
  const StateSpace ref_model = to_double(ref.model);

  constexpr double u = 0x1p-53;
  const double kappa3 = step3_condition(fast.model, data);
  const double eps = std::max(fast.error_estimate, u * kappa3);
  constexpr double c = 100.0;
  RC_LOG() << "kappa = " << fast.condition << ", step-3 condition = " << kappa3 << ", eps = " << eps << "\n";

  const Eigen::MatrixXcd A = fast.model.A.cast<std::complex<double>>();
  const double normA = fast.model.A.norm(), normD = fast.model.D.norm();
  double worst_ratio = 0;
  for (int k = 0; k < F; ++k) {
    const std::complex<double> z = std::polar(1.0, omega(k));
    const Eigen::MatrixXcd zA = z * Eigen::MatrixXcd::Identity(n, n) - A;
    const Eigen::MatrixXcd R = fdsid::testing::inverse(zA);
    const double cr = (fast.model.C.cast<std::complex<double>>() * R).norm();
    const double rb = (R * fast.model.B.cast<std::complex<double>>()).norm();
    const Eigen::MatrixXcd Gf = frequency_response(fast.model, omega(k));
    const Eigen::MatrixXcd Gr = frequency_response(ref_model, omega(k));
    const double S = cr * rb * (normA + zA.norm()) + (Gf - fast.model.D.cast<std::complex<double>>()).norm() + normD;
    const double tol = c * eps * S;
    const double diff = (Gf - Gr).norm();
    worst_ratio = std::max(worst_ratio, diff / tol);
    if (!(diff <= tol)) {
      RC_LOG() << "frequency " << k << " (omega = " << omega(k) << "): |G_fast - G_ref| = " << diff << " > tol "
               << tol << " = " << c << " * " << eps << " * S " << S << "\n";
      RC_FAIL("fast and reference FRF estimates differ beyond c * eps * S");
    }
  }
  // Measured margin, reported by decade of max |G_fast − G_ref| / tol.
  RC_TAG(worst_ratio > 0.1 ? "ratio > 1e-1" : worst_ratio > 1e-2 ? "ratio in (1e-2, 1e-1]"
         : worst_ratio > 1e-3 ? "ratio in (1e-3, 1e-2]" : "ratio <= 1e-3");
}

}  // namespace
}  // namespace fdsid::testing
