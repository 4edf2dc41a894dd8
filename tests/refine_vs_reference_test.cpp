// The 50-digit reference confirms that fast/'s maximum-likelihood refinement
// (fdsid/refine.hpp) stops at a stationary point of the cost (issue 15, item 5):
// reference::cost_gradient evaluates ∂V/∂(A, B, C, D) exactly at the refined
// model, and its size is held to what the solver's stopping rule allows.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fdsid/frf_id.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/reference/frf_id.hpp"
#include "fdsid/refine.hpp"
#include "reference_bridge.hpp"

namespace fdsid {
namespace {

using testing::to_reference;

// ‖J‖_F of the whitened residuals r = (Y − G U)/σ in the entries of A, B, C,
// D (real and imaginary parts), in double: with P = C X, Q = X B U, X = (ξI − A)⁻¹,
// ∂(GU)/∂A_ab = P(:, a) Q(b, :), ∂/∂B_ql = P(:, q) U(l, :), ∂/∂C_oq = e_o Q(q, :),
// ∂/∂D_ol = e_o U(l, :).
double jacobian_norm(const StateSpace& m, const FrfData& d) {
  double s = 0;
  const int n = m.order();
  for (int k = 0; k < d.frequencies(); ++k) {
    const cplx xi = m.domain == Domain::Discrete ? std::polar(1.0, d.omega(k)) : cplx(0, d.omega(k));
    const Eigen::MatrixXcd X = (xi * Eigen::MatrixXcd::Identity(n, n) - m.A.cast<cplx>()).inverse();
    const Eigen::MatrixXcd P = m.C * X, Q = X * m.B * d.U[k];
    for (int o = 0; o < d.outputs(); ++o)
      for (int j = 0; j < d.columns(); ++j) {
        const double p2 = P.row(o).squaredNorm(), q2 = Q.col(j).squaredNorm(), u2 = d.U[k].col(j).squaredNorm();
        s += (p2 * q2 + p2 * u2 + q2 + u2) / d.variance[k](o, j);
      }
  }
  return std::sqrt(s);
}

double gradient_norm(const reference::CostGradient& g) {
  double s = 0;
  for (const reference::MatrixR* X : {&g.dA, &g.dB, &g.dC, &g.dD})
    for (Eigen::Index i = 0; i < X->size(); ++i) s += std::pow(static_cast<double>((*X)(i)), 2);
  return std::sqrt(s);
}

// Bound. For V = ‖r‖², g = 2 Jᵀ r = 2 Jᵀ P_J r, so ‖g‖ ≤ 2 ‖J‖_F ‖P_J r‖,
// and ‖P_J r‖² is the decrease a Gauss–Newton step still promises. Ceres stops
// when a step lowers V by less than function_tolerance = 1e-14 of V; near the
// optimum Levenberg–Marquardt's step realises at least a tenth of the promised
// decrease (its damping is then small), so ‖P_J r‖² ≤ 10 · 1e-14 · V and
// ‖g‖ ≤ 2 ‖J‖_F √(1e-13 V). The range of J is the tangent space of the order-n
// transfer functions in any coordinates, so the bound holds for the gradient in
// A, B, C, D although the solver works in modal coordinates. Rounding the
// refined model to double moves g by ≤ 2‖J‖² u ‖θ‖, far below this.
// Tightness: the same bound fails at the subspace estimate (checked below),
// and a cost weighted by 1/σ instead of 1/σ² would be stationary elsewhere.
TEST(RefineVsReference, RefinedModelIsStationaryIn50Digits) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01(0, 1);
  const StateSpace plant = pintelon_plant();
  const int F = 120;
  Eigen::VectorXd omega(F);
  std::vector<Eigen::MatrixXcd> G(F);
  std::vector<Eigen::MatrixXd> var(F);
  for (int k = 0; k < F; ++k) {
    omega(k) = M_PI * (k + 1) / (F + 1);
    const double v = 1e-3 * pintelon_noise_variance(omega(k));
    G[k] = frequency_response(plant, omega(k));
    G[k](0, 0) += std::sqrt(v / 2) * cplx(n01(rng), n01(rng));
    var[k] = Eigen::MatrixXd::Constant(1, 1, v);
  }
  const FrfData d = frf_data(Domain::Discrete, omega, G, var);
  const StateSpace sub = identify_frf_fixed(d, 4, 8).model;
  const RefineResult r = refine_ml(d, sub);
  ASSERT_EQ(r.termination, "convergence");
  const reference::FrfData rd = to_reference(d);
  const reference::CostGradient g = reference::cost_gradient(to_reference(r.model), rd);
  const double bound = 2 * jacobian_norm(r.model, d) * std::sqrt(1e-13 * static_cast<double>(g.cost));
  EXPECT_LT(gradient_norm(g), bound) << "V = " << static_cast<double>(g.cost);
  // The cost fast/ reports is the reference's to the rounding of a sum of F terms.
  EXPECT_NEAR(r.cost, static_cast<double>(g.cost), 1e-12 * r.cost);
  // Tightness: the subspace estimate is not stationary by this measure.
  const reference::CostGradient g0 = reference::cost_gradient(to_reference(sub), rd);
  EXPECT_GT(gradient_norm(g0), 2 * jacobian_norm(sub, d) * std::sqrt(1e-13 * static_cast<double>(g0.cost)));
}

// Errors-in-variables (RefineOptions::input_variance): the refined model is a
// stationary point of the EIV cost by reference::eiv_cost_gradient. The bound
// is the one above with the Jacobian of the EIV residuals r = e/√v(θ):
// ∂r = −∂G U/√v − e ∂v/(2 v^{3/2}), ∂v = 2 Re(∂G (conj(G) σ²_U − conj(σ_YU))),
// so |∂r| ≤ |∂G| (|U|/√v + |e| |conj(G) σ²_U − conj(σ_YU)|/v^{3/2}), and
// Σ_θ |∂G/∂θ|² over the entries of A, B, C, D is ‖CX‖²‖XB‖² + ‖CX‖² + ‖XB‖² + 1.
// Tightness: the output-error optimum of the same data (input noise ignored)
// is not stationary by this measure, nor is the subspace estimate.
double eiv_jacobian_norm(const StateSpace& m, const FrfData& d, const RefineOptions& o) {
  double s = 0;
  const int n = m.order();
  for (int k = 0; k < d.frequencies(); ++k) {
    const cplx xi = m.domain == Domain::Discrete ? std::polar(1.0, d.omega(k)) : cplx(0, d.omega(k));
    const Eigen::MatrixXcd X = (xi * Eigen::MatrixXcd::Identity(n, n) - m.A.cast<cplx>()).inverse();
    const Eigen::MatrixXcd P = m.C * X, Q = X * m.B;
    const cplx G = m.D(0, 0) + (P * m.B)(0, 0), U = d.U[k](0, 0);
    const cplx e = d.Y[k](0, 0) - G * U;
    const double v = d.variance[k](0, 0) + std::norm(G) * o.input_variance(k) -
                     2 * (o.input_output_covariance(k) * std::conj(G)).real();
    const double dG2 = P.squaredNorm() * Q.squaredNorm() + P.squaredNorm() + Q.squaredNorm() + 1;
    const double factor = std::abs(U) / std::sqrt(v) +
                          std::abs(e) * std::abs(std::conj(G) * o.input_variance(k) - std::conj(o.input_output_covariance(k))) /
                              (v * std::sqrt(v));
    s += dG2 * factor * factor;
  }
  return std::sqrt(s);
}

TEST(RefineVsReference, ErrorsInVariablesRefinedModelIsStationaryIn50Digits) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n01(0, 1);
  const StateSpace plant = pintelon_plant();
  const int F = 120, M = 6;
  Eigen::VectorXd omega(F);
  for (int k = 0; k < F; ++k) omega(k) = M_PI * (k + 1) / (F + 1);
  std::vector<std::vector<Eigen::VectorXcd>> U_l(M), Y_l(M);
  for (int l = 0; l < M; ++l)
    for (int k = 0; k < F; ++k) {
      const double sy = std::sqrt(1e-3 * pintelon_noise_variance(omega(k)) * M / 2), su = std::sqrt(0.02 * M / 2);
      U_l[l].push_back(Eigen::VectorXcd::Constant(1, 1.0 + su * cplx(n01(rng), n01(rng))));
      Y_l[l].push_back(Eigen::VectorXcd::Constant(1, frequency_response(plant, omega(k))(0, 0) + sy * cplx(n01(rng), n01(rng))));
    }
  const SampleStatistics st = sample_statistics(Domain::Discrete, omega, U_l, Y_l);
  RefineOptions oe;
  oe.noise = RefineNoise::Sample;
  oe.periods = M;
  RefineOptions eiv = oe;
  eiv_input_noise(st, eiv);
  const StateSpace sub = identify_frf_fixed(st.data, 4, 8).model;
  const RefineResult r = refine_ml(st.data, sub, eiv);
  ASSERT_EQ(r.termination, "convergence");
  const reference::FrfData rd = to_reference(st.data);
  std::vector<reference::Real> var_u;
  std::vector<reference::Complex> cov_yu;
  for (int k = 0; k < F; ++k) {
    var_u.push_back(reference::Real(eiv.input_variance(k)));  // the doubles fast/ used, exactly
    cov_yu.push_back(reference::Complex(reference::Real(eiv.input_output_covariance(k).real()),
                                        reference::Real(eiv.input_output_covariance(k).imag())));
  }
  auto stationary = [&](const StateSpace& m, double* ratio) {
    const reference::CostGradient g = reference::eiv_cost_gradient(to_reference(m), rd, var_u, cov_yu);
    const double bound = 2 * eiv_jacobian_norm(m, st.data, eiv) * std::sqrt(1e-13 * static_cast<double>(g.cost));
    *ratio = gradient_norm(g) / bound;
    return g;
  };
  double at_ml = 0, at_oe = 0, at_sub = 0;
  const reference::CostGradient g = stationary(r.model, &at_ml);
  EXPECT_LT(at_ml, 1.0);
  EXPECT_NEAR(r.cost, static_cast<double>(g.cost), 1e-12 * r.cost);
  stationary(refine_ml(st.data, sub, oe).model, &at_oe);
  stationary(sub, &at_sub);
  std::printf("gradient / bound: EIV optimum %.2e, output-error optimum %.2e, subspace %.2e\n", at_ml, at_oe, at_sub);
  EXPECT_GT(at_oe, 1.0);
  EXPECT_GT(at_sub, 1.0);
}

}  // namespace
}  // namespace fdsid
