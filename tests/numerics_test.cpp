// The shared numerical layer of fast/ (fast/src/numerics/): FFT, streamed QR,
// rank test, Riccati and Stein solvers, optimisers, formats.
#include <gtest/gtest.h>

#include <cmath>

#include "fdsid/model.hpp"
#include "numerics/autoregression.hpp"
#include "numerics/constants.hpp"
#include "numerics/fft.hpp"
#include "numerics/fisher.hpp"
#include "fdsid/format.hpp"
#include "numerics/lyapunov.hpp"
#include "numerics/optimize.hpp"
#include "numerics/qr.hpp"
#include "numerics/rank.hpp"
#include "numerics/riccati.hpp"

namespace fdsid::numerics {
namespace {

TEST(NumericsFft, UnitaryRoundTripAndParseval) {
  const int P = 64;
  UnitaryFft fft(P);
  Eigen::VectorXd x(P);
  for (int t = 0; t < P; ++t) x(t) = std::sin(0.3 * t) + 0.1 * t;
  const Eigen::VectorXcd X = fft.forward(x);
  // Parseval of the unitary DFT: Σ x² = |X0|² + 2 Σ_{0<k<P/2} |Xk|² + |X_{P/2}|².
  double e = std::norm(X(0)) + std::norm(X(P / 2));
  for (int k = 1; k < P / 2; ++k) e += 2 * std::norm(X(k));
  // O(log P) rounding errors per coefficient: 100 u relative is ample.
  EXPECT_NEAR(e, x.squaredNorm(), 100 * kUnitRoundoff * x.squaredNorm());
  EXPECT_LE((fft.inverse(X) - x).norm(), 100 * kUnitRoundoff * x.norm());
  const std::vector<cplx> Xv = fft.forward(x.data());
  for (int k = 0; k <= P / 2; ++k) EXPECT_EQ(Xv[k], X(k));  // same transform, same scaling
}

TEST(NumericsQr, BitIdenticalWhateverTheThreadCount) {
  const int groups = 300, rpg = 4, cols = 7;
  const ChunkFill fill = [&](int g0, int g1, Eigen::Ref<Eigen::MatrixXd> rows) {
    for (int g = g0; g < g1; ++g)
      for (int i = 0; i < rpg; ++i)
        for (int j = 0; j < cols; ++j) rows((g - g0) * rpg + i, j) = std::cos(1.0 + g * 0.37 + i * 1.3 + j * j * 0.11);
  };
  StreamedQrOptions o;
  o.rows_per_chunk = 64;
  o.flops_per_block = 1000;  // force the maximum number of blocks
  o.threads = 1;
  const Eigen::MatrixXd R1 = streamed_qr_r(groups, rpg, cols, fill, o);
  for (int t : {2, 3, 8}) {
    o.threads = t;
    EXPECT_TRUE((streamed_qr_r(groups, rpg, cols, fill, o).array() == R1.array()).all()) << t << " threads";
  }
  // R agrees with one Householder QR of the whole matrix up to row signs.
  Eigen::MatrixXd A(groups * rpg, cols);
  fill(0, groups, A);
  const Eigen::MatrixXd R = Eigen::HouseholderQR<Eigen::MatrixXd>(A).matrixQR().topRows(cols).triangularView<Eigen::Upper>();
  for (int i = 0; i < cols; ++i) {
    const double s = (R(i, i) < 0) == (R1(i, i) < 0) ? 1.0 : -1.0;
    // Both backward stable: the difference is O(κ(A) u ‖A‖); 1e-10 ‖A‖ is ample here.
    EXPECT_LE((R.row(i) - s * R1.row(i)).norm(), 1e-10 * A.norm());
  }
}

TEST(NumericsRank, FloorIsSafetyTimesRoundoffTimesSizeFactor) {
  EXPECT_EQ(rank_floor(2.0, 10.0), 100 * kUnitRoundoff * 10.0 * 2.0);
  EXPECT_EQ(rank_floor(1.0, 10.0), 1e3 * kUnitRoundoff);  // spectrum_id step 8's historical floor
  Eigen::VectorXd d(3);
  d << 1.0, 0.5, 1e-20;
  EXPECT_FALSE(numerically_full_rank(d, 1.0));
  d(2) = 1e-3;
  EXPECT_TRUE(numerically_full_rank(d, 1.0));
  EXPECT_FALSE(numerically_full_rank(Eigen::VectorXd::Zero(2), 1.0));
}

TEST(NumericsRiccati, MinimumPhaseModelGivesItsOwnGramian) {
  // G(z) = 1 + 1/(z − 0.5) has its zero at −0.5: minimum phase, so the
  // stabilising solution of step 9 is the controllability Gramian P of G.
  StateSpace m;
  m.A = Eigen::MatrixXd::Constant(1, 1, 0.5);
  m.B = m.C = m.D = Eigen::MatrixXd::Constant(1, 1, 1.0);
  const SpectralSummands s = spectral_summands(m);
  const RiccatiSolution r = solve_spectral_riccati(s);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.method, "sda");
  EXPECT_NEAR(r.P(0, 0), 1.0 / (1 - 0.25), 1e-12);
  EXPECT_LE(riccati_residual(s, r.P), 1e-13);
}

TEST(NumericsStein, ScalarClosedForm) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Constant(1, 1, 0.9), Q = Eigen::MatrixXd::Constant(1, 1, 2.0);
  EXPECT_NEAR(stein_smith(A, Q)(0, 0), 2.0 / (1 - 0.81), 1e-12);
}

// The exact autocovariances of x(t) = 1.5 x(t−1) − 0.8 x(t−2) + e(t) (poles
// of modulus √0.8, at ±0.58 rad): ρ(1) = φ₁/(1 − φ₂), ρ(k) = φ₁ρ(k−1) + φ₂ρ(k−2)
// (Yule–Walker). From them the Levinson–Durbin recursion gives the whitening
// filter (1, −1.5, 0.8) and reflection coefficients 0 beyond order 2, so
// Schwarz's criterion picks order 2 (each further order costs ln N and gains
// nothing). Tolerance: the recursion's error is u times the condition of the
// 3 × 3 Toeplitz matrix of ρ (96 here) times a small constant (10):
// ≈ 2e-13, checked at 1e-12. White noise's (1, 0, …) gives the filter (1).
TEST(NumericsAutoregression, LevinsonDurbinRecoversAnArTwo) {
  const double phi1 = 1.5, phi2 = -0.8;
  Eigen::VectorXd r(11);
  r(0) = 1;
  r(1) = phi1 / (1 - phi2);
  for (int k = 2; k < 11; ++k) r(k) = phi1 * r(k - 1) + phi2 * r(k - 2);
  const Eigen::VectorXd a = whitening_filter(3.7 * r, 10, 1e5);  // any positive factor
  ASSERT_EQ(a.size(), 3);
  EXPECT_NEAR(a(0), 1, 1e-12);
  EXPECT_NEAR(a(1), -phi1, 1e-12);
  EXPECT_NEAR(a(2), -phi2, 1e-12);
  Eigen::VectorXd white = Eigen::VectorXd::Zero(11);
  white(0) = 2;
  EXPECT_EQ(whitening_filter(white, 10, 1e5).size(), 1);
}

TEST(NumericsOptimize, MinimisersFindAQuadraticsMinimum) {
  const auto r = minimize_1d([](double x) { return (x - 0.3) * (x - 0.3) + 1; }, -1, 2, 11);
  EXPECT_NEAR(r.first, 0.3, 1e-6);
  const Eigen::Vector2d x = nelder_mead(
      [](const Eigen::Vector2d& v) { return std::pow(v(0) - 1, 2) + 3 * std::pow(v(1) + 2, 2); }, Eigen::Vector2d(0, 0),
      Eigen::Vector2d(0.5, 0.5));
  EXPECT_NEAR(x(0), 1, 1e-4);
  EXPECT_NEAR(x(1), -2, 1e-4);
}

TEST(NumericsFormat, FormatsOfTheDiagnostics) {
  EXPECT_EQ(fmt(1e-8, 4), "1e-08");
  EXPECT_EQ(fmt(0.123456789, 6), "0.123457");
  EXPECT_EQ(sci(1234.56, 3), "1.235e+03");
  // Review finding 8 of stop 47: a relative error in (0.1, 1) was "usable to about 0 significant digits".
  EXPECT_NE(precision_warning(0.117, "A", "c").find("usable to about its order of magnitude"), std::string::npos);
  EXPECT_NE(precision_warning(0.02, "A", "c").find("usable to about 1 significant digit ("), std::string::npos);
  EXPECT_EQ(precision_warning(2.0, "A", "c").rfind("UNUSABLE", 0), 0u);
}

// One term's p is its own survival function S(t) (χ²₂'s tail at −2 ln S is
// S): S(t) = e^{−t} for known variances and (1 + t/(M−1))^{−(M−1)} for the
// sample variances of M periods (the F(2, 2M − 2) law); t chosen so that
// S = 0.3, to rounding (a few u through log1p/exp and Boost's χ² tail).
TEST(NumericsFisher, OneTermsPIsItsSurvivalFunction) {
  const double S = 0.3;
  Eigen::VectorXd known(1), sample(1);
  known << -std::log(S);
  const int M = 8;
  sample << (M - 1) * (std::pow(S, -1.0 / (M - 1)) - 1);
  EXPECT_NEAR(fisher_p(known, 0), S, 1e-14);
  EXPECT_NEAR(fisher_p(sample, M), S, 1e-14);
  EXPECT_NEAR(fisher_statistic(sample, M), -2 * std::log(S), 1e-14);
  // Two equal terms: X = −4 ln S against χ²₄, whose tail is e^{−x/2}(1 + x/2).
  Eigen::VectorXd two(2);
  two << sample(0), sample(0);
  const double x = -4 * std::log(S);
  EXPECT_NEAR(fisher_p(two, M), std::exp(-x / 2) * (1 + x / 2), 1e-14);
  // q fitted parameters: χ²(2K − q); with 2K − q = 2 the tail is e^{−x/2}.
  EXPECT_NEAR(fisher_p(two, M, 2), std::exp(-x / 2), 1e-14);
  EXPECT_NEAR(fisher_p_below(two, M, 2), 1 - std::exp(-x / 2), 1e-14);
  EXPECT_EQ(fisher_p(Eigen::VectorXd(0), M), 1.0);
}

}  // namespace
}  // namespace fdsid::numerics
