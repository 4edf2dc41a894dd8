// Model core: transfer function, power spectrum, Lyapunov equation, spectral
// summands (Akçay 2011, Eqs. 2-3 and the summand split of Section 3).
#include <gtest/gtest.h>

#include "linalg.hpp"
#include "fdsid/error.hpp"
#include "fdsid/model.hpp"
#include "fdsid/paper.hpp"
#include "generators.hpp"
#include "tolerance.hpp"

namespace fdsid {
namespace {

using testing::kU;

StateSpace first_order(double a, double b, double c, double d) {
  StateSpace m;
  m.A = Eigen::MatrixXd::Constant(1, 1, a);
  m.B = Eigen::MatrixXd::Constant(1, 1, b);
  m.C = Eigen::MatrixXd::Constant(1, 1, c);
  m.D = Eigen::MatrixXd::Constant(1, 1, d);
  return m;
}

TEST(Model, TransferOfFirstOrderSystemIsClosedForm) {
  // G(z) = d + c b / (z - a), Eq. (2) for n = 1; a handful of flops, each with
  // relative error <= u, so 8u relative to |G| bounds the difference.
  const StateSpace m = first_order(0.5, 2.0, -0.75, 1.25);
  for (double w : {0.0, 0.3, 1.7, M_PI}) {
    const cplx z = std::polar(1.0, w);
    const cplx expected = 1.25 + (-0.75 * 2.0) / (z - 0.5);
    EXPECT_LE(std::abs(transfer(m, z)(0, 0) - expected), 8 * kU * std::abs(expected)) << "w = " << w;
  }
}

TEST(Model, PowerSpectrumOfFirstOrderSystemIsClosedForm) {
  // S(e^{iw}) = |G(e^{iw})|^2 (Eq. 3 with m = 1); relative error <= 16u.
  const StateSpace m = first_order(-0.3, 1.0, 0.4, 1.0);
  for (double w : {0.0, 1.0, 2.5}) {
    const cplx z = std::polar(1.0, w);
    const double expected = std::norm(1.0 + 0.4 / (z + 0.3));
    const cplx S = power_spectrum(m, z)(0, 0);
    EXPECT_LE(std::abs(S - expected), 16 * kU * expected);
  }
}

TEST(Model, LyapunovResidualIsAtRoundingLevel) {
  // P = A P A^T + Q: the residual of a backward-stable solver is bounded by
  // c u (||A||^2 + 1) ||P||; c = 64 covers the O(log) doubling steps.
  const StateSpace sys = akcay_example_system();
  const Eigen::MatrixXd Q = sys.B * sys.B.transpose();
  const Eigen::MatrixXd P = lyapunov(sys.A, Q);
  const double residual = (P - sys.A * P * sys.A.transpose() - Q).norm();
  const double bound = 64 * kU * (sys.A.squaredNorm() + 1) * P.norm();
  EXPECT_LE(residual, bound);
  EXPECT_LT((P - P.transpose()).norm(), kU * P.norm());
}

TEST(Model, LyapunovRefusesUnstableA) {
  const StateSpace m = first_order(1.5, 1, 1, 1);
  try {
    lyapunov(m.A, m.B * m.B.transpose());
    FAIL() << "no error for an unstable A";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    EXPECT_NE(std::string(e.what()).find("not stable"), std::string::npos);
  }
}

// The split S(z) = E + C(zI-A)^{-1}F + F^T(z^{-1}I - A^T)^{-1}C^T (Section 3)
// must reproduce G(z)G^T(1/z). Both sides are sums of O(n^2) products of
// quantities of size ||S||; with the Lyapunov solution accurate to
// c u κ(I - A⊗A) ||P|| and κ <= 1/(1 - ρ(A)^2) for the paper's system
// (ρ = 0.954), a relative tolerance of 64 n^2 u / (1 - ρ^2) bounds the gap.
void expect_summands_match(const StateSpace& sys) {
  const SpectralSummands s = spectral_summands(sys);
  const double rho = fdsid::testing::eigenvalues(sys.A).cwiseAbs().maxCoeff();
  const int n = sys.order();
  const double tol = 64.0 * n * n * kU / (1 - rho * rho);
  double worst = 0, scale = 0;
  for (int k = 0; k <= 64; ++k) {
    const cplx z = std::polar(1.0, M_PI * k / 64.0 + 0.01);
    const Eigen::MatrixXcd S = power_spectrum(sys, z);
    worst = std::max(worst, (summand_spectrum(s, z) - S).norm());
    scale = std::max(scale, S.norm());
  }
  EXPECT_LE(worst / scale, tol) << "worst relative difference " << worst / scale << ", tolerance " << tol;
}

TEST(Model, SpectralSummandsReproduceThePaperSpectrum) { expect_summands_match(akcay_example_system()); }

TEST(Model, SpectralSummandsReproduceAMimoSpectrum) {
  testing::SystemSpec spec;
  spec.channels = 2;
  spec.modes = {{0.7, 0.9, false}, {0.5, 0.0, true}};
  spec.mixing = {0.2, -0.5, 0.1, 0.4, 0.3, -0.2, 0.6, -0.1, 0.5};
  spec.b = {0.9, -0.2, 0.4, 0.8, -0.6, 0.3};
  spec.c = {0.5, -0.7, 0.2, 0.3, 0.6, -0.9};
  const StateSpace sys = testing::make_system(spec);
  ASSERT_TRUE(testing::meets_assumption_2_1(sys));
  expect_summands_match(sys);
}

TEST(Model, PolesAreSortedEigenvalues) {
  const Eigen::VectorXcd p = poles(akcay_example_system());
  ASSERT_EQ(p.size(), 4);
  for (int i = 1; i < 4; ++i) EXPECT_LE(std::abs(p(i - 1)), std::abs(p(i)));
  // The paper's A: the upper block has eigenvalues 0.8427 ± i sqrt(0.4494^2 - 0.0449^2).
  EXPECT_NEAR(p(3).real(), 0.8427, 1e-12);
}

TEST(Model, ValidateNamesTheWrongMatrix) {
  StateSpace m = first_order(0.5, 1, 1, 1);
  m.C = Eigen::MatrixXd::Ones(1, 2);
  try {
    validate(m, "cand.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("C must have 1 columns"), std::string::npos) << e.what();
  }
  m = first_order(0.5, 1, 1, 1);
  m.A(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(validate(m), Error);
}

}  // namespace
}  // namespace fdsid
