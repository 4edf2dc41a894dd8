// The oracle's comparison (fdsid/compare.hpp): similarity- and
// G -> G Q-invariant distances between two models, the spectral factor included
// (issue 13: a factor with a zero reflected outside the unit circle has the same
// spectrum, so only the factor's zeros and Markov parameters tell it apart).
#include <gtest/gtest.h>

#include <cmath>

#include "fdsid/compare.hpp"
#include "fdsid/error.hpp"
#include "fdsid/workflow.hpp"
#include "tolerance.hpp"

namespace fdsid {
namespace {

using testing::kU;

// Controllable canonical realisation of (b0 z^2 + b1 z + b2) / (z^2 + a1 z + a2).
StateSpace second_order(double b0, double b1, double b2, double a1, double a2) {
  StateSpace m;
  m.A.resize(2, 2);
  m.A << -a1, -a2, 1, 0;
  m.B.resize(2, 1);
  m.B << 1, 0;
  m.C.resize(1, 2);
  m.C << b1 - b0 * a1, b2 - b0 * a2;
  m.D = Eigen::MatrixXd::Constant(1, 1, b0);
  return m;
}

// Poles 0.6 ± 0.5 j: z^2 - 1.2 z + 0.61 (the system of
// Cli.CheckNamesAFactorWithAZeroOutsideTheUnitCircle).
const double kA1 = -1.2, kA2 = 0.61;

// The minimum-phase factor (z - 0.5)(z - 0.3) / den, and the same spectrum's
// factor with the zero 0.5 reflected to 2: (1 - 0.5 z)(z - 0.3) / den, since
// |1 - 0.5 e^{jw}| = |e^{jw} - 0.5| on the unit circle.
StateSpace minimum_phase() { return second_order(1, -0.8, 0.15, kA1, kA2); }
StateSpace reflected() { return second_order(-0.5, 1.15, -0.3, kA1, kA2); }

// Rounding bound of these comparisons: O(1) entries, products of at most
// K = 2n + 1 = 5 matrices of order 2, eigenvalues of 2 x 2 matrices with
// condition numbers below 10: each distance is a few hundred u at most;
// 1e3 u states it with margin and is still 1e12 times below what a reflected
// zero moves (1.5).
constexpr double kRounding = 1e3 * kU;

// The digits a model file carries: the most any entry needs to be read back
// exactly; rounding to them changes nothing, to one fewer changes something.
TEST(DigitsCarried, CountsTheLongestShortestDecimal) {
  StateSpace m;
  m.A = Eigen::MatrixXd::Constant(1, 1, 0.5);
  m.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  m.C = Eigen::MatrixXd::Constant(1, 1, 0.12345678);
  m.D = Eigen::MatrixXd::Constant(1, 1, -2.5e-3);
  EXPECT_EQ(digits_carried(m), 8);
  EXPECT_EQ(rounded_to_digits(m, 8).C(0, 0), m.C(0, 0));
  EXPECT_EQ(rounded_to_digits(m, 7).C(0, 0), 0.1234568);
  m.C(0, 0) = 1.0 / 3.0;
  EXPECT_EQ(digits_carried(m), 16);  // 0.3333333333333333
  m.C(0, 0) = 0.1 + 0.2;
  EXPECT_EQ(digits_carried(m), 17);  // 0.30000000000000004
}

TEST(CompareFactors, AReflectedZeroKeepsTheSpectrumButNotTheFactor) {
  const ModelComparison c = compare_models(reflected(), minimum_phase());
  EXPECT_LT(c.pole_distance, kRounding);
  EXPECT_LT(c.spectrum_error, kRounding);  // the same spectrum: S alone cannot tell
  EXPECT_LT(c.markov_error, kRounding);
  EXPECT_NEAR(c.zero_distance, 1.5, kRounding);  // 2 against 0.5
  EXPECT_NEAR(c.candidate_zero_modulus, 2.0, kRounding);
  EXPECT_TRUE(c.candidate_not_minimum_phase());
  EXPECT_NEAR(std::abs(c.reference_zero_near_mirror - cplx(0.5, 0)), 0.0, kRounding);
  EXPECT_NEAR(c.reference_zero_modulus, 0.5, kRounding);
  // H(0) = D D^T: 0.25 against 1.
  EXPECT_GT(c.factor_markov_error, 0.5);
}

TEST(CompareFactors, SimilarityAndSignOfTheFactorDoNotMatter) {
  StateSpace g = minimum_phase();
  Eigen::MatrixXd T(2, 2);
  T << 2, 1, -1, 3;
  const Eigen::MatrixXd Ti = T.inverse();
  g.A = (Ti * g.A * T).eval();
  g.B = (-Ti * g.B).eval();  // -G: the factor is unique up to G -> G Q, Q = -1 for m = 1
  g.C = (g.C * T).eval();
  g.D = -g.D;
  const ModelComparison c = compare_models(g, minimum_phase());
  EXPECT_LT(c.zero_distance, kRounding);
  EXPECT_LT(c.factor_markov_error, kRounding);
  EXPECT_FALSE(c.candidate_not_minimum_phase());
}

TEST(CompareFactors, AnOrthogonalMixOfAMimoFactorIsTheSameFactor) {
  StateSpace g;
  g.A.resize(3, 3);
  g.A << 0.5, 0.2, 0, -0.2, 0.5, 0.1, 0, 0, -0.4;
  g.B.resize(3, 2);
  g.B << 1, 0, 0.3, 1, -0.5, 0.2;
  g.C.resize(2, 3);
  g.C << 0.4, 0.1, 0.2, 0, 0.3, -0.6;
  g.D.resize(2, 2);
  g.D << 1, 0, 0.2, 0.8;
  const double t = 0.7;
  Eigen::MatrixXd Q(2, 2);
  Q << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
  StateSpace gq = g;
  gq.B = g.B * Q;
  gq.D = g.D * Q;
  const ModelComparison c = compare_models(gq, g);
  EXPECT_LT(c.spectrum_error, kRounding);
  EXPECT_LT(c.zero_distance, kRounding);
  EXPECT_LT(c.factor_markov_error, kRounding);
  // A factor that is not G Q: one entry of D moved by 0.01 is caught.
  gq.D(1, 1) = 0.81;
  EXPECT_GT(compare_models(gq, g).factor_markov_error, 1e-3);
}

TEST(OracleCheckSummary, NamesTheReflectedZero) {
  OracleCheck k;
  k.p = 5;
  k.r = 4;
  k.comparison = compare_models(reflected(), minimum_phase());
  // Stand-ins for the reference's perturbed reruns: the factor moved by 1e-10.
  set_oracle_tolerances(k, minimum_phase(), randomly_moved(minimum_phase(), 1e-10, 3), 0);
  EXPECT_TRUE(k.poles_agree());
  EXPECT_TRUE(k.spectrum_agrees());
  EXPECT_FALSE(k.factor_agrees());
  EXPECT_FALSE(k.agree());
  const std::string s = k.summary();
  EXPECT_NE(s.find("factor: zero 2 outside the unit circle; the minimum-phase factor has it at 0.5\n"),
            std::string::npos)
      << s;
  EXPECT_EQ(s.find("DISAGREES"), s.find('\n') + 1) << s;  // the verdict line follows the factor line
  // Measured tolerances (workflow.hpp): 10 x the largest move, so of the order
  // of 1e-9 here (moves of 1e-10 relative in A, B, C, D), every one positive.
  for (double t : {k.pole_tolerance, k.spectrum_tolerance, k.markov_tolerance, k.factor_tolerance, k.zero_tolerance}) {
    EXPECT_GT(t, 1e-12);
    EXPECT_LT(t, 1e-6);
  }
  EXPECT_THROW(set_oracle_tolerances(k, minimum_phase(), {}, 0), fdsid::Error);
}

}  // namespace
}  // namespace fdsid
