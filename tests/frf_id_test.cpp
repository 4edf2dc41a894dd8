// Pintelon (2002) Algorithms 1 and 2 in fast/ (fdsid/frf_id.hpp): exactness
// on noise-free data (the algorithms are consistent, and with Y = G₀U exactly
// step 1 has rank n_a, so the estimate equals G₀ up to rounding), automatic
// order and r (Section 5), the sample statistics of Section 4.1 and the
// errors-in-variables data of Section 5, and the failure paths.
// Tolerances: tests/frf_tolerance.hpp (rounding) or Monte Carlo intervals
// stated beside each check.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "linalg.hpp"
#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/simulate.hpp"
#include "frf_tolerance.hpp"
#include "statistics.hpp"
#include "tolerance.hpp"

namespace fdsid {
namespace {

using testing::check_noise_free;
using testing::complex_normal;
using testing::kU;
using testing::noise_free_frf;
using testing::noise_free_io;

// Pintelon (2002) Eq. (36), typed in here from the brief (independent of paper.cpp).
StateSpace eq36() {
  StateSpace s;
  s.A.resize(4, 4);
  s.A << 0.8876, 0.4494, 0, 0, -0.4494, 0.7978, 0, 0, 0, 0, -0.6129, 0.064516, 0, 0, -6.4516, -0.7419;
  s.B.resize(4, 1);
  s.B << 0.2247, 0.8989, 0.0323, 0.1290;
  s.C.resize(1, 4);
  s.C << 0.4719, 0.1124, 9.6774, 1.6129;
  s.D = Eigen::MatrixXd::Constant(1, 1, 0.9626);
  return s;
}

// F distinct frequencies drawn uniformly in [lo, hi], sorted.
Eigen::VectorXd random_grid(std::mt19937_64& rng, int F, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> w;
  while (static_cast<int>(w.size()) < F) {
    const double x = u(rng);
    if (std::find(w.begin(), w.end(), x) == w.end()) w.push_back(x);
  }
  std::sort(w.begin(), w.end());
  return Eigen::Map<Eigen::VectorXd>(w.data(), F);
}

// |U| log-uniform in [0.1, 10], phase uniform.
std::vector<Eigen::MatrixXcd> random_input(std::mt19937_64& rng, int F, int m) {
  std::uniform_real_distribution<double> lg(-1, 1), ph(-M_PI, M_PI);
  std::vector<Eigen::MatrixXcd> U;
  for (int k = 0; k < F; ++k) {
    Eigen::MatrixXcd u(m, 1);
    for (int a = 0; a < m; ++a) u(a, 0) = std::polar(std::pow(10.0, lg(rng)), ph(rng));
    U.push_back(u);
  }
  return U;
}

Eigen::VectorXd log_grid(double lo, double hi, int F) {
  Eigen::VectorXd w(F);
  for (int k = 0; k < F; ++k) w(k) = lo * std::pow(hi / lo, double(k) / (F - 1));
  return w;
}

// Fourth-order continuous system with resonances at 1 rad/s (ζ = 0.05) and
// 50 rad/s (ζ = 0.1), modal form, D = 0.1.
StateSpace two_resonances() {
  StateSpace s;
  s.domain = Domain::Continuous;
  s.A = Eigen::MatrixXd::Zero(4, 4);
  const double w[2] = {1.0, 50.0}, z[2] = {0.05, 0.1};
  for (int i = 0; i < 2; ++i) {
    const double re = -z[i] * w[i], im = w[i] * std::sqrt(1 - z[i] * z[i]);
    s.A.block(2 * i, 2 * i, 2, 2) << re, im, -im, re;
  }
  s.B.resize(4, 1);
  s.B << 1.0, 0.5, 30.0, -20.0;
  s.C.resize(1, 4);
  s.C << 0.7, -0.3, 1.2, 0.4;
  s.D = Eigen::MatrixXd::Constant(1, 1, 0.1);
  return s;
}

void expect_noise_free(const StateSpace& truth, const FrfResult& res, const FrfData& d,
                       ContinuousMethod method = ContinuousMethod::Bilinear, double omega_scale = 0) {
  ASSERT_EQ(res.order, truth.order());
  const testing::NoiseFreeCheck c = check_noise_free(truth, res, d, method, omega_scale);
  EXPECT_LE(c.g_ratio, 1.0) << c.describe();
  EXPECT_LE(c.pole_ratio, 1.0) << c.describe();
  std::cout << "  [measured] " << c.describe() << "\n";
}

// ---------------------------------------------------------------------------
// Noise-free exactness

TEST(FrfNoiseFree, DiscreteEq36PeriodicInputOutputOnRandomGrid) {
  std::mt19937_64 rng(36);
  const StateSpace sys = eq36();
  const int F = 120;
  const Eigen::VectorXd w = random_grid(rng, F, 0.0, M_PI);
  const FrfData d = noise_free_io(sys, w, random_input(rng, F, 1));
  for (int r : {6, 10, 16}) {
    SCOPED_TRACE("r = " + std::to_string(r));
    const FrfResult res = identify_frf_fixed(d, 4, r);
    EXPECT_EQ(res.r, r);
    expect_noise_free(sys, res, d);
  }
}

TEST(FrfNoiseFree, DiscreteEq36FrfFormOnRandomGrid) {
  std::mt19937_64 rng(37);
  const StateSpace sys = eq36();
  const Eigen::VectorXd w = random_grid(rng, 80, 0.0, M_PI);
  const FrfData d = noise_free_frf(sys, w);
  EXPECT_FALSE(d.has_noise_model);
  EXPECT_EQ(d.columns(), 1);
  const FrfResult res = identify_frf_fixed(d, 4, 8);
  expect_noise_free(sys, res, d);
}

TEST(FrfNoiseFree, ContinuousFiveDecadesBilinear) {
  const StateSpace sys = two_resonances();
  const FrfData d = noise_free_frf(sys, log_grid(0.01, 1000, 60));
  const FrfResult res = identify_frf_fixed(d, 4, 8, ContinuousMethod::Bilinear);
  EXPECT_EQ(res.model.domain, Domain::Continuous);
  expect_noise_free(sys, res, d, ContinuousMethod::Bilinear);
}

TEST(FrfNoiseFree, ContinuousFiveDecadesOrthogonal) {
  // Orthogonal bases on a five-decade band: the Forsythe recursion in s̃ has a
  // large σ1/σn, so error_estimate is large; the tolerance is derived from it
  // (frf_tolerance.hpp) and is asserted to stay below 1e-2 relative so that
  // the test still detects a wrong algorithm.
  const StateSpace sys = two_resonances();
  const FrfData d = noise_free_frf(sys, log_grid(0.01, 1000, 60));
  const FrfResult res = identify_frf_fixed(d, 4, 8, ContinuousMethod::Orthogonal);
  std::cout << "  [measured] orthogonal error_estimate " << res.error_estimate << "\n";
  expect_noise_free(sys, res, d, ContinuousMethod::Orthogonal);
  const double eps_A = testing::frf_qr_constant(60, 1, 8, 1, 1) * res.error_estimate;
  EXPECT_LT(eps_A, 1e-2) << "tolerance too loose to detect anything";
}

// Eq. (36)'s A with two inputs and two outputs (B, C, D extended by hand).
StateSpace eq36_two_by_two() {
  StateSpace sys = eq36();
  sys.B.resize(4, 2);
  sys.B << 0.2247, -0.3, 0.8989, 0.5, 0.0323, 0.7, 0.1290, -0.2;
  sys.C.resize(2, 4);
  sys.C << 0.4719, 0.1124, 9.6774, 1.6129, -0.8, 0.6, 0.5, 0.2;
  sys.D.resize(2, 2);
  sys.D << 0.9626, 0.1, -0.2, 0.5;
  return sys;
}

TEST(FrfNoiseFree, MimoTwoByTwoFrf) {
  std::mt19937_64 rng(22);
  const StateSpace sys = eq36_two_by_two();
  const FrfData d = noise_free_frf(sys, random_grid(rng, 60, 0.0, M_PI));
  EXPECT_EQ(d.columns(), 2);
  const FrfResult res = identify_frf_fixed(d, 4, 6);
  expect_noise_free(sys, res, d);
}

// A random stable w-domain model (entries of A uniform in ±0.35, of B, C, D
// in ±1), 3 outputs and 2 inputs, for the back-transformation tests.
StateSpace random_w_model(unsigned seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  StateSpace w;
  w.A = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) w.A(i, j) = 0.35 * u(rng);
  w.B = Eigen::MatrixXd::NullaryExpr(n, 2, [&] { return u(rng); });
  w.C = Eigen::MatrixXd::NullaryExpr(3, n, [&] { return u(rng); });
  w.D = Eigen::MatrixXd::NullaryExpr(3, 2, [&] { return u(rng); });
  return w;
}

// The 2-norm condition number.
double cond(const Eigen::MatrixXcd& X) {
  const Eigen::VectorXd s = fdsid::testing::singular_values(Eigen::MatrixXcd(X));
  return s(0) / s(s.size() - 1);
}

TEST(BilinearToContinuous, MatchesTheWDomainModelOnTheImaginaryAxis) {
  // G_c(jω) = G_w(w(jω)), w = (jω/ω_s − 1)/(jω/ω_s + 1). Tolerance: the
  // back-transformation solves with I − A_w (relative error ≤ γ_{4n} cond(I − A_w)
  // in A, B, C, D; Higham Thm 9.4 with a factor 4 for the products),
  // amplified into G by s(ξ) (frf_tolerance.hpp), plus the evaluation of both
  // transfers by LU, ≤ γ_{4n} cond(ξI − A) ‖terms‖ each:
  //   tol(ω) = 4n u [cond(I − A_w) s_c(jω) + cond(wI − A_w) s_w(w) + cond(jωI − A_c) s_c(jω)].
  const int n = 5;
  const StateSpace w = random_w_model(5, n);
  ASSERT_LT(fdsid::testing::eigenvalues(w.A).cwiseAbs().maxCoeff(), 1.0);
  const double ws = 7.5;
  const StateSpace c = bilinear_to_continuous(w, ws);
  EXPECT_EQ(c.domain, Domain::Continuous);
  const Eigen::MatrixXcd I = Eigen::MatrixXcd::Identity(n, n);
  const double c_iaw = cond(I - w.A.cast<cplx>());
  double worst = 0;
  for (double om : {1e-3, 0.1, 1.0, 7.5, 20.0, 300.0, 1e4}) {
    const cplx wz = testing::bilinear_point(om, ws), s(0, om);
    const double err = (transfer(c, s) - transfer(w, wz)).norm();
    const double tol = 4 * n * kU *
                       (c_iaw * testing::transfer_sensitivity(c, s) +
                        cond(wz * I - w.A.cast<cplx>()) * testing::transfer_sensitivity(w, wz) +
                        cond(s * I - c.A.cast<cplx>()) * testing::transfer_sensitivity(c, s));
    EXPECT_LE(err, tol) << "omega " << om;
    worst = std::max(worst, err / tol);
  }
  std::cout << "  [measured] worst error / tolerance " << worst << " (cond(I - A_w) = " << c_iaw << ")\n";
  // Round trip through the test's inverse transformation: the same poles.
  const StateSpace back = testing::continuous_to_bilinear(c, ws);
  EXPECT_LE((back.A - w.A).norm(), 4 * n * kU * c_iaw * c_iaw * w.A.norm());
  // A pole at w = 1 (s = ∞) is refused.
  StateSpace bad = w;
  bad.A = Eigen::MatrixXd::Identity(n, n);
  try {
    bilinear_to_continuous(bad, ws);
    ADD_FAILURE() << "no error for I - A_w = 0";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
  }
}

// ---------------------------------------------------------------------------
// Narrow-band discrete data (issue 15, item 4). On a small arc of the unit
// circle the powers of z are numerically dependent; Algorithm 2's bases on
// the Tustin frequencies tan(ω/2) identify the same noise-free data to the
// rounding tolerance of frf_tolerance.hpp.

// Lightly damped modes at the given angles (rad/sample), pole radius `rho`,
// real modal form, D = 0.1: a structure whose resonances lie in the band.
StateSpace modes_at(const std::vector<double>& theta, double rho) {
  const int n = 2 * static_cast<int>(theta.size());
  StateSpace s;
  s.A = Eigen::MatrixXd::Zero(n, n);
  s.B.resize(n, 1);
  s.C.resize(1, n);
  for (size_t i = 0; i < theta.size(); ++i) {
    const double re = rho * std::cos(theta[i]), im = rho * std::sin(theta[i]);
    s.A.block(2 * i, 2 * i, 2, 2) << re, im, -im, re;
    s.B.block(2 * i, 0, 2, 1) << 0.3, 0.1 * (i + 1);
    s.C.block(0, 2 * i, 1, 2) << 0.2, -0.05 * (i + 1);
  }
  s.D = Eigen::MatrixXd::Constant(1, 1, 0.1);
  return s;
}

// The noise-free check of a Tustin-basis estimate, printed.
void expect_tustin_noise_free(const StateSpace& truth, const FrfResult& res, const FrfData& d, DiscreteMethod m) {
  ASSERT_EQ(res.order, truth.order());
  EXPECT_EQ(res.model.domain, Domain::Discrete);
  const testing::NoiseFreeCheck c = check_noise_free(truth, res, d, ContinuousMethod::Bilinear, 0, -1, m);
  EXPECT_LE(c.g_ratio, 1.0) << c.describe();
  EXPECT_LE(c.pole_ratio, 1.0) << c.describe();
  std::cout << "  [measured] " << to_string(m) << ": " << c.describe() << "\n";
  // The tolerance still detects a wrong estimate (a pole moved by 1e-4).
  EXPECT_LT(c.eps_A, 1e-6) << "tolerance too loose to detect anything";
}

// The F-16 record's band: 2-15 Hz at 400 Hz, 6.5 % of [0, π], a ratio of 7.5
// on the Tustin axis, with three modes inside. r = 14 powers of z are
// dependent; the bilinear basis spreads the band over ~1.7 rad of the circle.
TEST(FrfNoiseFree, NarrowBandDiscreteBilinearBasis) {
  std::mt19937_64 rng(64);
  const StateSpace sys = modes_at({0.06, 0.12, 0.2}, 0.99);
  const Eigen::VectorXd w = random_grid(rng, 100, 2 * M_PI * 2 / 400, 2 * M_PI * 15 / 400);
  const FrfData d = noise_free_frf(sys, w);
  const FrfResult res = identify_frf_fixed(d, 6, 14, ContinuousMethod::Bilinear, 0, DiscreteMethod::Bilinear);
  // ω_s by default_discrete_scale: tan(ω_s/2) is the geometric mean of the band edges' tan(ω/2).
  EXPECT_NEAR(std::tan(res.omega_scale / 2), std::sqrt(std::tan(w.minCoeff() / 2) * std::tan(w.maxCoeff() / 2)),
              8 * kU * std::tan(res.omega_scale / 2));
  expect_tustin_noise_free(sys, res, d, DiscreteMethod::Bilinear);
  // Algorithm 1's monomial basis on the same data: refused as rank deficient
  // (naming the fix), or usable to far fewer digits.
  try {
    const FrfResult mono = identify_frf_fixed(d, 6, 14);
    std::cout << "  [measured] monomial error_estimate " << mono.error_estimate << " vs bilinear "
              << res.error_estimate << "\n";
    EXPECT_GT(mono.error_estimate, 1e3 * res.error_estimate);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical) << e.what();
    EXPECT_NE(std::string(e.what()).find("--method bilinear"), std::string::npos) << e.what();
    std::cout << "  [measured] monomial: " << e.what() << "\n";
  }
  // The automatic order and r (Section 5) with the bilinear basis.
  FrfOptions o;
  o.discrete = DiscreteMethod::Bilinear;
  const FrfResult automatic = identify_frf(noise_free_frf(sys, w, 1e-20), o);
  EXPECT_EQ(automatic.order, 6);
}

// A band narrow in ratio too: [0.3, 0.5] rad/sample, tan ratio 1.7. Real
// Möbius maps only scale s', so the bilinear basis sees an arc of ~0.5 rad;
// the orthogonal bases (Algorithm 2.2 on s̃ = j tan(ω/2)/t_s) stay conditioned.
TEST(FrfNoiseFree, NarrowRatioBandDiscreteOrthogonalBasis) {
  std::mt19937_64 rng(65);
  const StateSpace sys = modes_at({0.35, 0.45}, 0.98);
  const Eigen::VectorXd w = random_grid(rng, 100, 0.3, 0.5);
  const FrfData d = noise_free_frf(sys, w);
  const FrfResult res = identify_frf_fixed(d, 4, 10, ContinuousMethod::Bilinear, 0, DiscreteMethod::Orthogonal);
  expect_tustin_noise_free(sys, res, d, DiscreteMethod::Orthogonal);
  for (DiscreteMethod m : {DiscreteMethod::Monomial, DiscreteMethod::Bilinear}) {
    try {
      const FrfResult other = identify_frf_fixed(d, 4, 10, ContinuousMethod::Bilinear, 0, m);
      std::cout << "  [measured] " << to_string(m) << " error_estimate " << other.error_estimate
                << " vs orthogonal " << res.error_estimate << "\n";
      EXPECT_GT(other.error_estimate, 1e3 * res.error_estimate) << to_string(m);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Numerical) << e.what();
      std::cout << "  [measured] " << to_string(m) << ": " << e.what() << "\n";
    }
  }
  // ω = π has no place on the tan(ω/2) axis: refused by name.
  Eigen::VectorXd wpi = w;
  wpi(w.size() - 1) = M_PI;
  try {
    identify_frf_fixed(noise_free_frf(sys, wpi), 4, 10, ContinuousMethod::Bilinear, 0, DiscreteMethod::Orthogonal);
    ADD_FAILURE() << "no error for omega = pi";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("omega = pi"), std::string::npos) << e.what();
  }
}

TEST(BilinearToDiscrete, MatchesTheWDomainModelOnTheUnitCircle) {
  // G_z(e^{jω}) = G_w(w(ω)), w = (j tan(ω/2)/t_s − 1)/(j tan(ω/2)/t_s + 1).
  // Tolerance: as BilinearToContinuous's, with the two solves of the
  // back-transformation (frf_tolerance.hpp: relative ≤ 4n u cond(I − A')
  // (1 + cond(I − A_w)) in A_z, B_z, C_z, D_z):
  //   tol(ω) = 4n u [cond(I − A')(1 + cond(I − A_w)) s_z(z) + cond(wI − A_w) s_w(w) + cond(zI − A_z) s_z(z)].
  const int n = 5;
  const StateSpace w = random_w_model(6, n);
  ASSERT_LT(fdsid::testing::eigenvalues(w.A).cwiseAbs().maxCoeff(), 1.0);
  const double ws = 0.2;
  const StateSpace z = bilinear_to_discrete(w, ws);
  EXPECT_EQ(z.domain, Domain::Discrete);
  const Eigen::MatrixXcd I = Eigen::MatrixXcd::Identity(n, n);
  const double c_back = cond(I - testing::continuous_to_bilinear(z, 1.0).A.cast<cplx>()) *
                        (1 + cond(I - w.A.cast<cplx>()));
  double worst = 0;
  for (double om : {0.0, 1e-3, 0.05, 0.2, 0.7, 2.0, 3.0, M_PI}) {
    const cplx wz = testing::tustin_point(om, ws), zz = std::polar(1.0, om);
    const double err = (transfer(z, zz) - transfer(w, wz)).norm();
    const double tol = 4 * n * kU *
                       (c_back * testing::transfer_sensitivity(z, zz) +
                        cond(wz * I - w.A.cast<cplx>()) * testing::transfer_sensitivity(w, wz) +
                        cond(zz * I - z.A.cast<cplx>()) * testing::transfer_sensitivity(z, zz));
    EXPECT_LE(err, tol) << "omega " << om;
    worst = std::max(worst, err / tol);
  }
  std::cout << "  [measured] worst error / tolerance " << worst << "\n";
  // A w-domain pole at w = 1 (z = −1) is refused.
  StateSpace bad = w;
  bad.A = Eigen::MatrixXd::Identity(n, n);
  try {
    bilinear_to_discrete(bad, ws);
    ADD_FAILURE() << "no error for I - A_w = 0";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
  }
}

// ---------------------------------------------------------------------------
// An unstable estimate is said so (issue 14): the subspace estimate
// interpolates the data and does not enforce stability. Noise-free data of an
// unstable system (its frequency response is defined on the grid) give back
// the unstable pole exactly; a stable system gives no such warning.

bool has_unstable_warning(const FrfResult& res, const std::string& text) {
  for (const std::string& w : res.warnings)
    if (w.find("the identified model is unstable: pole " + text) == 0) return true;
  return false;
}

TEST(FrfWarnings, AnUnstableEstimateIsNamed) {
  StateSpace sys;  // G(z) = 0.5 + 1/(z - 1.25): a pole outside the unit circle
  sys.A = Eigen::MatrixXd::Constant(1, 1, 1.25);
  sys.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  sys.C = Eigen::MatrixXd::Constant(1, 1, 1.0);
  sys.D = Eigen::MatrixXd::Constant(1, 1, 0.5);
  Eigen::VectorXd w(40);
  for (int k = 0; k < 40; ++k) w(k) = M_PI * (k + 0.5) / 40;
  const FrfResult res = identify_frf_fixed(noise_free_frf(sys, w), 1, 4);
  EXPECT_TRUE(has_unstable_warning(res, "1.25+0j of modulus 1.25 >= 1")) << ::testing::PrintToString(res.warnings);

  StateSpace cont = two_resonances();  // the 50 rad/s pair moved to Re s = +5
  cont.A(2, 2) = cont.A(3, 3) = 5.0;
  const FrfResult rc = identify_frf_fixed(noise_free_frf(cont, log_grid(0.01, 1000, 60)), 4, 8);
  EXPECT_TRUE(has_unstable_warning(rc, "5")) << ::testing::PrintToString(rc.warnings);
  // Both members of the pair are named (a user review: the warning named one
  // of six unstable poles).
  EXPECT_NE(::testing::PrintToString(rc.warnings).find("j with real part >= 0 (2 unstable poles: 5"), std::string::npos)
      << ::testing::PrintToString(rc.warnings);
  EXPECT_NE(::testing::PrintToString(rc.warnings).find("); it fits"), std::string::npos)
      << ::testing::PrintToString(rc.warnings);

  const FrfResult stable = identify_frf_fixed(noise_free_frf(eq36(), w), 4, 8);
  for (const std::string& s : stable.warnings) EXPECT_EQ(s.find("unstable"), std::string::npos) << s;
}

// V_SUB (Eq. 35) of a model with a pole on the data's frequency axis: the
// residual there is infinite (G is; with U = 1 the product inf · 1 has a NaN
// imaginary part, and a NaN V_SUB would lose every comparison of the r
// search, so that it could be chosen), finite without that frequency.
TEST(FrfVSub, APoleOnTheFrequencyAxisGivesAnInfiniteVSub) {
  StateSpace sys;  // G(z) = 1/(z - 1): a pole at z = 1, omega = 0
  sys.A = Eigen::MatrixXd::Constant(1, 1, 1.0);
  sys.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  sys.C = Eigen::MatrixXd::Constant(1, 1, 1.0);
  sys.D = Eigen::MatrixXd::Zero(1, 1);
  const std::vector<Eigen::MatrixXcd> G(3, Eigen::MatrixXcd::Constant(1, 1, cplx(0.5, -0.25)));
  const FrfData on_pole = frf_data(Domain::Discrete, Eigen::Vector3d(0.0, 0.5, 1.0), G);
  EXPECT_EQ(v_sub(sys, on_pole), std::numeric_limits<double>::infinity());
  const FrfData off_pole = frf_data(Domain::Discrete, Eigen::Vector3d(0.25, 0.5, 1.0), G);
  EXPECT_TRUE(std::isfinite(v_sub(sys, off_pole)));
}

// ---------------------------------------------------------------------------
// Automatic order and r (Section 5)

TEST(FrfAutomatic, OrderFromNoiseFreeDataWithSmallDeclaredVariance) {
  std::mt19937_64 rng(11);
  const StateSpace sys = eq36();
  const FrfData d = noise_free_frf(sys, random_grid(rng, 200, 0.0, M_PI), 1e-12);
  ASSERT_TRUE(d.has_noise_model);
  const FrfResult res = identify_frf(d);
  EXPECT_EQ(res.order, 4);
  // Whitened noise-free data: components 5.. are rounding, far below the edge.
  std::cout << "  [measured] sigma_4^2 = " << res.singular_values(3) * res.singular_values(3)
            << ", sigma_5^2 = " << res.singular_values(4) * res.singular_values(4) << ", 2 x edge = "
            << 2 * res.noise_edge << "\n";
  EXPECT_GT(res.noise_edge, 1.0);
  const testing::NoiseFreeCheck c = check_noise_free(sys, res, d);
  EXPECT_LE(c.g_ratio, 1.0) << c.describe();
}

TEST(FrfAutomatic, OrderFromNoisyDataAtModerateSnr) {
  // 30 dB output SNR relative to |G| at each line (σ = 0.03 |G₀(ξ_k)|), known
  // variance. Order must be 4. The check can fail: the weakest mode must beat
  // 2 × the Marchenko–Pastur edge; the measured margin is printed.
  const StateSpace sys = eq36();
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    const Eigen::VectorXd w = random_grid(rng, 400, 0.0, M_PI);
    std::vector<Eigen::MatrixXcd> G;
    std::vector<Eigen::MatrixXd> V;
    for (int k = 0; k < w.size(); ++k) {
      const Eigen::MatrixXcd g0 = frequency_response(sys, w(k));
      const double v = std::pow(0.03 * std::abs(g0(0, 0)), 2);
      G.push_back(g0 + Eigen::MatrixXcd::Constant(1, 1, complex_normal(rng, v)));
      V.push_back(Eigen::MatrixXd::Constant(1, 1, v));
    }
    const FrfResult res = identify_frf(frf_data(Domain::Discrete, w, G, V));
    EXPECT_EQ(res.order, 4) << "seed " << seed;
    std::cout << "  [measured] seed " << seed << ": sigma_4^2 / (2 edge) = "
              << res.singular_values(3) * res.singular_values(3) / (2 * res.noise_edge)
              << ", sigma_5^2 / (2 edge) = " << res.singular_values(4) * res.singular_values(4) / (2 * res.noise_edge)
              << ", r = " << res.r << "\n";
    // r chosen by V_SUB (Eq. 35) in [⌈1.5 n⌉, 6 n] = [6, 24].
    EXPECT_GE(res.r, 6);
    EXPECT_LE(res.r, 24);
  }
}

// The default r = 20 of the automatic order needs 20 powers of z that are
// independent on the data's band. On (0, 1.2] rad/sample (38 % of [0, π]) with
// a flat variance, C_Y of step 1c is the Toeplitz matrix Σ_k σ² cos((i − i')ω_k),
// whose eigenvalues fall like a prolate matrix's: smallest / largest 3e-17 at
// r = 18 and 2e-15 at r = 16 (numpy, a uniform grid of 468 lines on this band), so its
// Cholesky factorisation fails at r = 20 (the cubic-feedback circuit's oddms
// record failed so at its defaults). The default steps down to the largest r
// step 1 can use and says so in a note; an r the user gave is not changed.
TEST(FrfAutomatic, DefaultRStepsDownWhereTheBandMakesTwentyPowersDependent) {
  std::mt19937_64 rng(20);
  const StateSpace sys = modes_at({0.6}, 0.95);
  const Eigen::VectorXd w = random_grid(rng, 300, 0.004, 1.2);
  std::vector<Eigen::MatrixXcd> G;
  std::vector<Eigen::MatrixXd> V;
  for (int k = 0; k < w.size(); ++k) {
    G.push_back(frequency_response(sys, w(k)) + Eigen::MatrixXcd::Constant(1, 1, complex_normal(rng, 1e-8)));
    V.push_back(Eigen::MatrixXd::Constant(1, 1, 1e-8));
  }
  const FrfData d = frf_data(Domain::Discrete, w, G, V);
  try {
    FrfOptions given;
    given.r = 20;
    identify_frf(d, given);
    ADD_FAILURE() << "r = 20 given by the user was accepted or changed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical) << e.what();
  }
  const FrfResult res = identify_frf(d);
  EXPECT_EQ(res.order, 2);
  EXPECT_LT(res.order_r, 20);
  EXPECT_EQ(static_cast<int>(res.singular_values.size()), res.order_r);
  ASSERT_EQ(res.notes.size(), 1u);
  EXPECT_NE(res.notes[0].find("read at r = " + std::to_string(res.order_r) + ", not the default 20"),
            std::string::npos)
      << res.notes[0];
  std::cout << "  [measured] " << res.notes[0] << "\n";
  // Noise 1e-4 of |G| ≥ 0.1 in amplitude (SNR ≥ 60 dB over 300 lines): the
  // resonance lies within 1e-3 rad of 0.6 (a wrong order or a failed estimate misses it).
  double closest = M_PI;
  for (Eigen::Index i = 0; i < res.poles.size(); ++i)
    closest = std::min(closest, std::abs(std::arg(res.poles(i)) - 0.6));
  EXPECT_LT(closest, 1e-3);
  // A band where r = 20 is usable: no note.
  EXPECT_TRUE(identify_frf(noise_free_frf(sys, random_grid(rng, 300, 0.0, M_PI), 1e-12)).notes.empty());
}

// identify_frf_fixed over several noise models of the same measurements
// (issue 16: one QR of step 1b shared by the estimates of a Monte Carlo run)
// gives, bit for bit, what one call per noise model gives — in the monomial
// and in an orthogonal basis — and refuses data that differ in more than the
// variances.
TEST(FrfNoiseModels, SharedStepOneEqualsSeparateCallsBitForBit) {
  std::mt19937_64 rng(16);
  const StateSpace sys = eq36();
  const Eigen::VectorXd w = random_grid(rng, 200, 0.0, M_PI);
  std::vector<Eigen::MatrixXcd> G;
  std::vector<Eigen::MatrixXd> V1, V2;
  for (int k = 0; k < w.size(); ++k) {
    const Eigen::MatrixXcd g0 = frequency_response(sys, w(k));
    G.push_back(g0 + Eigen::MatrixXcd::Constant(1, 1, complex_normal(rng, 1e-4)));
    V1.push_back(Eigen::MatrixXd::Constant(1, 1, 1e-4));
    V2.push_back(Eigen::MatrixXd::Constant(1, 1, 1e-4 * (1 + 0.5 * std::sin(3 * w(k)))));
  }
  const std::vector<FrfData> models{frf_data(Domain::Discrete, w, G, V1), frf_data(Domain::Discrete, w, G, V2)};
  for (DiscreteMethod method : {DiscreteMethod::Monomial, DiscreteMethod::Orthogonal}) {
    SCOPED_TRACE(to_string(method));
    const std::vector<FrfResult> shared = identify_frf_fixed(models, 4, 10, ContinuousMethod::Bilinear, 0, method);
    ASSERT_EQ(shared.size(), 2u);
    for (int v = 0; v < 2; ++v) {
      const FrfResult one = identify_frf_fixed(models[v], 4, 10, ContinuousMethod::Bilinear, 0, method);
      EXPECT_TRUE((shared[v].model.A.array() == one.model.A.array()).all()) << v;
      EXPECT_TRUE((shared[v].model.B.array() == one.model.B.array()).all()) << v;
      EXPECT_TRUE((shared[v].model.C.array() == one.model.C.array()).all()) << v;
      EXPECT_TRUE((shared[v].model.D.array() == one.model.D.array()).all()) << v;
      EXPECT_TRUE((shared[v].singular_values.array() == one.singular_values.array()).all()) << v;
      EXPECT_EQ(shared[v].v_sub, one.v_sub) << v;
    }
    // The two noise models weight differently: the estimates differ.
    EXPECT_FALSE((shared[0].model.B.array() == shared[1].model.B.array()).all());
  }
  std::vector<FrfData> other = models;
  other[1].Y[7](0, 0) += 1e-3;
  try {
    identify_frf_fixed(other, 4, 10);
    ADD_FAILURE() << "data differing in Y were accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("more than the variances"), std::string::npos) << e.what();
  }
}

TEST(FrfAutomatic, RSelectionScansTheSectionFiveIntervalAndTakesTheMinimum) {
  std::mt19937_64 rng(8);
  const StateSpace sys = eq36();
  const Eigen::VectorXd w = random_grid(rng, 300, 0.0, M_PI);
  std::vector<Eigen::MatrixXcd> G;
  std::vector<Eigen::MatrixXd> V;
  for (int k = 0; k < w.size(); ++k) {
    G.push_back(frequency_response(sys, w(k)) + Eigen::MatrixXcd::Constant(1, 1, complex_normal(rng, 1e-4)));
    V.push_back(Eigen::MatrixXd::Constant(1, 1, 1e-4));
  }
  FrfOptions o;
  o.order = 4;
  const FrfResult res = identify_frf(frf_data(Domain::Discrete, w, G, V), o);
  const int lo = 6, hi = 24;  // ⌈1.5 · 4⌉, 6 · 4
  EXPECT_GE(res.r, lo);
  EXPECT_LE(res.r, hi);
  ASSERT_EQ(static_cast<int>(res.r_scan.size()), hi - lo + 1);
  double vmin = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < res.r_scan.size(); ++i) {
    EXPECT_EQ(res.r_scan[i].first, lo + static_cast<int>(i));
    vmin = std::min(vmin, res.r_scan[i].second);
  }
  EXPECT_EQ(res.v_sub, vmin);
  // V_SUB (Eq. 35) of the chosen model recomputed independently.
  double v = 0;
  for (int k = 0; k < w.size(); ++k) v += std::norm(G[k](0, 0) - frequency_response(res.model, w(k))(0, 0)) / 1e-4;
  EXPECT_NEAR(res.v_sub, v, 1e-10 * v);  // same sum, different order of F = 300 terms: ≤ F u v ≈ 3e-14 v
  // At the truth, V_SUB = Σ |N_k|²/σ² is a sum of F = 300 Exp(1) terms (mean F,
  // std √F); a consistent estimate fits 9 parameters and lies near or below
  // it: V_SUB < F + 5√F (5σ).
  std::cout << "  [measured] V_SUB = " << res.v_sub << " at r = " << res.r << " (bound " << 300 + 5 * std::sqrt(300.0)
            << ")\n";
  EXPECT_LT(res.v_sub, 300 + 5 * std::sqrt(300.0));
}

// An r whose estimate rounding decides (a user review: the F-16 FRF at order
// 10 chose r = 49, unusable, over a usable r = 44 with V_SUB 0.9 % higher) is
// not taken: the search takes the least V_SUB among the usable estimates.
// Six lightly damped modes (ζ = 0.01, 22 ... 57.6 rad/s, an F-16-like
// structure) on 267 lines of 2-15 Hz at SNR 40 dB: at the top of the r range
// (r = 6 n = 72) C_Y is so ill-conditioned that rounding-size moves make
// step 1c fail, and V_SUB is often least there.
TEST(FrfAutomatic, RSelectionPassesOverAnROfLeastVSubWhoseEstimateIsUnusable) {
  const std::vector<double> wn = {22.0, 25.0, 32.7, 41.6, 46.2, 57.6};
  const double zeta = 0.01;
  StateSpace sys;
  sys.domain = Domain::Continuous;
  sys.A = Eigen::MatrixXd::Zero(12, 12);
  sys.B.resize(12, 1);
  sys.C.resize(1, 12);
  for (size_t i = 0; i < wn.size(); ++i) {
    const double re = -zeta * wn[i], im = wn[i] * std::sqrt(1 - zeta * zeta);
    sys.A.block(2 * i, 2 * i, 2, 2) << re, im, -im, re;
    sys.B.block(2 * i, 0, 2, 1) << 1.0, 0.3 * static_cast<double>(i + 1);
    sys.C.block(0, 2 * i, 1, 2) << 1.0, -0.5;
  }
  sys.D = Eigen::MatrixXd::Constant(1, 1, 0.1);
  const int F = 267;
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(F, 2 * M_PI * 2.0, 2 * M_PI * 15.0);
  double power = 0;
  for (int k = 0; k < F; ++k) power += std::norm(frequency_response(sys, w(k))(0, 0)) / F;
  const double var = 1e-4 * power;
  FrfOptions o;
  o.order = 12;
  int passed_over = 0;
  for (unsigned seed = 0; seed < 6; ++seed) {
    std::mt19937_64 rng(seed);
    std::vector<Eigen::MatrixXcd> G;
    std::vector<Eigen::MatrixXd> V;
    for (int k = 0; k < F; ++k) {
      G.push_back(frequency_response(sys, w(k)) + Eigen::MatrixXcd::Constant(1, 1, complex_normal(rng, var)));
      V.push_back(Eigen::MatrixXd::Constant(1, 1, var));
    }
    const FrfData d = frf_data(Domain::Continuous, w, G, V);
    const FrfResult res = identify_frf(d, o);
    SCOPED_TRACE("seed " + std::to_string(seed) + ", r = " + std::to_string(res.r));
    EXPECT_TRUE(usable_precision(res.usability_estimate())) << res.usability_estimate();
    // Every r of smaller V_SUB gives an unusable estimate (or none).
    double least = res.v_sub;
    for (const auto& [r, v] : res.r_scan) {
      least = std::min(least, v);
      if (!(v < res.v_sub)) continue;
      try {
        const FrfResult other = identify_frf_fixed(d, 12, r, o.continuous, o.omega_scale, o.discrete, true);
        EXPECT_FALSE(usable_precision(other.usability_estimate())) << "r = " << r << ", V_SUB " << v;
      } catch (const Error&) {
      }
    }
    if (res.r_unusable_least_v_sub == 0) {
      EXPECT_EQ(res.v_sub, least);
      continue;
    }
    ++passed_over;
    const auto at = std::find_if(res.r_scan.begin(), res.r_scan.end(),
                                 [&](const auto& e) { return e.first == res.r_unusable_least_v_sub; });
    ASSERT_NE(at, res.r_scan.end());
    EXPECT_EQ(at->second, least);
    EXPECT_NE(::testing::PrintToString(res.notes).find("r = " + std::to_string(res.r) + " chosen, the least V_SUB"),
              std::string::npos)
        << ::testing::PrintToString(res.notes);
  }
  // The case the test is for occurs (3 of these 6 seeds when written; the
  // loop's checks hold whichever do).
  std::cout << "  [measured] least V_SUB's r unusable and passed over in " << passed_over << " of 6 seeds\n";
  EXPECT_GE(passed_over, 1);
}

// The r search screens every r from one QR of Zᵀ at the top of its range
// (columns interleaved, each r's R re-triangularised from a leading block),
// then recomputes the least as identify_frf_fixed does. Two checks:
//  - the chosen estimate is identify_frf_fixed's at the chosen r, bit for bit
//    (so --r reproduces what the search chose);
//  - every screened V_SUB agrees with identify_frf_fixed's at its r to
//    rounding. Tolerance: with e = w (Y − Ĝ U) the weighted residual (V =
//    ‖e‖²) and Ĝ moved by a relative ε, ‖δe‖ ≤ ε ‖w Ĝ U‖ ≈ ε √S, S = Σ
//    |Y|²/σ², so |δV| ≤ 2 ε √(S V) + ε² S. ε: the two estimates' rounding
//    errors added, each ≈ u × condition = error_estimate (the first-order
//    bound on Â's relative error, which bounds Ĝ's to first order); the
//    screened R is the R of two backward-stable QRs composed (twice the
//    columnwise backward error), so ε = (1 + 2) × error_estimate.
//  The tolerance is asserted to be far below what distinguishes one r from
//  another (V_SUB moves by ≥ 1e-5 relative between neighbouring r in these cases;
//  the tolerance must lie 10⁴ times below that), so a
//  wrong block, permutation or C_Y prefix cannot pass.
TEST(FrfAutomatic, RSearchScreensEveryRAsIdentifyFrfFixedDoesToRounding) {
  struct Case {
    std::string name;
    StateSpace sys;
    Eigen::VectorXd omega;
    ContinuousMethod method;
  };
  std::mt19937_64 rng(47);
  const std::vector<Case> cases = {
      {"discrete, powers of z", eq36(), random_grid(rng, 300, 0.0, M_PI), ContinuousMethod::Bilinear},
      {"discrete 2 x 2", eq36_two_by_two(), random_grid(rng, 200, 0.0, M_PI), ContinuousMethod::Bilinear},
      {"continuous, bilinear", two_resonances(), log_grid(0.1, 300, 200), ContinuousMethod::Bilinear},
      {"continuous, orthogonal", two_resonances(), log_grid(0.3, 100, 200), ContinuousMethod::Orthogonal},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    // Noisy FRF, variance 1e-4 × the mean power of the entries (SNR 40 dB).
    const FrfData clean = noise_free_frf(c.sys, c.omega);
    double power = 0;
    for (int k = 0; k < clean.frequencies(); ++k) power += clean.Y[k].squaredNorm() / clean.Y[k].size();
    const double var = 1e-4 * power / clean.frequencies();
    std::vector<Eigen::MatrixXcd> G;
    std::vector<Eigen::MatrixXd> V;
    for (int k = 0; k < clean.frequencies(); ++k) {
      Eigen::MatrixXcd g = clean.Y[k];
      for (Eigen::Index i = 0; i < g.size(); ++i) g(i) += complex_normal(rng, var);
      G.push_back(g);
      V.push_back(Eigen::MatrixXd::Constant(g.rows(), g.cols(), var));
    }
    const FrfData d = frf_data(c.sys.domain, c.omega, G, V);
    double S = 0;
    for (int k = 0; k < d.frequencies(); ++k) S += d.Y[k].squaredNorm() / var;
    FrfOptions o;
    o.order = 4;
    o.continuous = c.method;
    const FrfResult res = identify_frf(d, o);
    ASSERT_EQ(res.r_scan.size(), 19u);  // r = 6 … 24
    const FrfResult at = identify_frf_fixed(d, 4, res.r, o.continuous, 0, o.discrete, true);
    EXPECT_EQ(res.model.A, at.model.A);
    EXPECT_EQ(res.model.B, at.model.B);
    EXPECT_EQ(res.model.C, at.model.C);
    EXPECT_EQ(res.model.D, at.model.D);
    EXPECT_EQ(res.v_sub, at.v_sub);
    double worst = 0, loosest = 0, spread = std::numeric_limits<double>::infinity();
    double previous = 0;
    for (const auto& [r, v] : res.r_scan) {
      const FrfResult f = identify_frf_fixed(d, 4, r, o.continuous, 0, o.discrete, false);
      const double eps = 3 * f.error_estimate;
      const double tol = 2 * eps * std::sqrt(S * f.v_sub) + eps * eps * S;
      EXPECT_LE(std::abs(v - f.v_sub), tol) << "r = " << r << ": screened " << v << ", identify_frf_fixed " << f.v_sub;
      worst = std::max(worst, std::abs(v - f.v_sub) / tol);
      loosest = std::max(loosest, tol / f.v_sub);
      if (previous > 0) spread = std::min(spread, std::abs(f.v_sub / previous - 1));
      previous = f.v_sub;
    }
    std::cout << "  [measured] " << c.name << ": chosen r = " << res.r << ", worst |screened - fixed| / tolerance "
              << worst << ", loosest tolerance " << loosest << " x V_SUB, least change between neighbouring r "
              << spread << "\n";
    EXPECT_LT(loosest, 1e-4 * spread + 1e-300) << "tolerance too loose to tell one r from another";
  }
}

// ---------------------------------------------------------------------------
// Section 4.1: sample statistics, DFT of periods, periodic records

TEST(SampleStatistics, Eq25And32OnAHandExample) {
  // M = 3 periods, one line, SISO:
  //   U = 1, 1+j, 1−j  → Û = 1, deviations 0, j, −j, σ̂²_U = (0+1+1)/2 = 1
  //   Y = 1+j, 3+j, 2+4j → Ŷ = 2+2j, deviations −1−j, 1−j, 2j, σ̂²_Y = (2+2+4)/2 = 4
  //   σ̂_YU = Σ dY conj(dU) / 2 = (0 + (1−j)(−j) + (2j)(j)) / 2 = (−1−j−2)/2 = −1.5 − 0.5j
  // data.variance = σ̂²_Y / M = 4/3. All values are exact in binary except 4/3,
  // one rounded division: tolerance u · 4/3.
  const Eigen::VectorXd w = Eigen::VectorXd::Constant(1, 0.5);
  std::vector<std::vector<Eigen::VectorXcd>> U(3), Y(3);
  const cplx us[3] = {{1, 0}, {1, 1}, {1, -1}}, ys[3] = {{1, 1}, {3, 1}, {2, 4}};
  for (int l = 0; l < 3; ++l) {
    U[l].push_back(Eigen::VectorXcd::Constant(1, us[l]));
    Y[l].push_back(Eigen::VectorXcd::Constant(1, ys[l]));
  }
  const SampleStatistics st = sample_statistics(Domain::Discrete, w, U, Y);
  EXPECT_EQ(st.M, 3);
  EXPECT_EQ(st.data.U[0](0, 0), cplx(1, 0));
  EXPECT_EQ(st.data.Y[0](0, 0), cplx(2, 2));
  EXPECT_EQ(st.var_U[0](0), 1.0);
  EXPECT_NEAR(st.data.variance[0](0, 0), 4.0 / 3.0, kU * 4.0 / 3.0);
  EXPECT_EQ(st.cov_YU[0](0, 0), cplx(-1.5, -0.5));
  EXPECT_EQ(st.data.columns(), 1);
}

TEST(PeriodSpectra, Eq4ScalingOnASine) {
  // x(t) = a cos(2π k0 t / P + φ): Eq. (4) gives X(k0) = a √P / 2 e^{jφ} and 0
  // elsewhere. FFT error in 2-norm ≤ 5 log2(P) u ‖x‖₂ (FFTW, Cooley–Tukey
  // bound with a constant 5), plus the sample generation (≤ 2u a per sample,
  // ≤ 2u a √P in 2-norm): tol = (5 log2 P · a √(P/2) + 2 a √P) u.
  const int P = 256, M = 3, k0 = 17;
  const double a = 2.5, phi = 0.7;
  Eigen::MatrixXd x(P * M, 1);
  for (int t = 0; t < P * M; ++t) x(t, 0) = a * std::cos(2 * M_PI * k0 * (t % P) / P + phi);
  const auto X = period_spectra(x, P, M, {k0, 3, P / 2});
  ASSERT_EQ(X.size(), 3u);
  const double tol = (5 * std::log2(P) * a * std::sqrt(P / 2.0) + 2 * a * std::sqrt(double(P))) * kU;
  const cplx expected = a * std::sqrt(double(P)) / 2 * std::polar(1.0, phi);
  for (int l = 0; l < M; ++l) {
    EXPECT_LE(std::abs(X[l][0](0) - expected), tol) << "period " << l;
    EXPECT_LE(std::abs(X[l][1](0)), tol);
    EXPECT_LE(std::abs(X[l][2](0)), tol);
  }
  // 1/√P, not 1/P or 1: the other scalings differ by √P = 16 from the expectation.
  EXPECT_GT(std::abs(expected), 100 * tol);
}

// Periodic multisine through a discrete model, steady state: simulate `skip`
// periods and drop them, keep M, add output noise of variance sigma2 per sample.
Eigen::MatrixXd periodic_record(const StateSpace& sys, int P, int M, int skip, const std::vector<int>& lines,
                                double sigma2, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> ph(-M_PI, M_PI);
  std::vector<double> phases;
  for (size_t i = 0; i < lines.size(); ++i) phases.push_back(ph(rng));
  std::normal_distribution<double> noise(0.0, std::sqrt(sigma2));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(sys.order());
  Eigen::MatrixXd rec(P * M, 2);
  for (int t = 0; t < P * (M + skip); ++t) {
    double u = 0;
    for (size_t i = 0; i < lines.size(); ++i) u += std::cos(2 * M_PI * lines[i] * (t % P) / P + phases[i]);
    const double y = (sys.C * x)(0) + sys.D(0, 0) * u;
    x = sys.A * x + sys.B.col(0) * u;
    if (t >= P * skip) {
      rec(t - P * skip, 0) = u;
      rec(t - P * skip, 1) = y + noise(rng);
    }
  }
  return rec;
}

TEST(RecordStatistics, SteadyStatePeriodicRecordMatchesFrequencyResponse) {
  // Eq. (36) plant, ρ(A) = 0.954; skipping 4 periods of P = 256 leaves a
  // transient ≤ κ(V) ρ^1024 ‖x₀‖ ≈ 1e-20: steady state to rounding.
  // Output noise σ² = 1e-18 per sample (DFT of Eq. 4 keeps the variance), so
  // Ŷ − G₀Û ~ CN(0, σ²/M); |Ĝ − G₀| ≤ 6 σ/√(M) / |Û| fails with probability
  // e^{-36} per line. Rounding of the simulation: |δy| ≤ n u κ(V) ‖B‖ Σ|u| / (1 − ρ)
  // per sample, in the DFT ≤ √P times that, divided by |Û|.
  const StateSpace sys = eq36();
  const int P = 256, M = 4;
  std::vector<int> lines;
  for (int k = 3; k <= 120; k += 7) lines.push_back(k);
  const double sigma2 = 1e-18;
  std::mt19937_64 rng(4);
  const Eigen::MatrixXd rec = periodic_record(sys, P, M, 4, lines, sigma2, rng);
  RecordMeta meta;
  meta.period = P;
  meta.periods = M;
  meta.excited_lines = lines;
  const SampleStatistics st = record_statistics(rec, 1, meta, Domain::Discrete);
  ASSERT_EQ(st.data.frequencies(), static_cast<int>(lines.size()));
  const double rho = 0.954, kv = testing::eigenvalue_condition_number_of_basis(sys.A);
  const double round = 4 * kU * kv * sys.B.norm() * lines.size() / (1 - rho) * std::sqrt(double(P));
  double worst = 0, var_ratio = 0;
  for (int k = 0; k < st.data.frequencies(); ++k) {
    EXPECT_DOUBLE_EQ(st.data.omega(k), 2 * M_PI * lines[k] / P);
    const cplx U = st.data.U[k](0, 0);
    // Each line carries a unit cosine: |Û| = √P / 2.
    EXPECT_NEAR(std::abs(U), std::sqrt(double(P)) / 2, 1e-12);
    const cplx G = st.data.Y[k](0, 0) / U;
    const double tol = (6 * std::sqrt(sigma2 / M) + round) / std::abs(U);
    const double err = std::abs(G - frequency_response(sys, st.data.omega(k))(0, 0));
    EXPECT_LE(err, tol) << "line " << lines[k];
    worst = std::max(worst, err / tol);
    var_ratio += st.data.variance[k](0, 0) * M / sigma2;
  }
  // Mean over F lines of σ̂²_Y/σ²: each (M−1) σ̂²/σ² ~ Gamma(M−1, 1) (complex
  // normal), so the mean has std 1/√(F(M−1)); 5σ interval.
  const int F = st.data.frequencies();
  var_ratio /= F;
  EXPECT_NEAR(var_ratio, 1.0, 5 / std::sqrt(double(F) * (M - 1)));
  std::cout << "  [measured] worst |G^ - G0| / tol = " << worst << ", mean sigma^2_Y / sigma^2 = " << var_ratio << "\n";
}

// require_input_power on both of its floors: the noise floor (input noise of
// std 0.05: a line without input has |U|^2 / (s^2_U / M) ~ F(2, 14)) and the
// rounding floor (a noise-free input: unexcited lines at ~1e-32 of the energy).
// The odd multisine has |U_k|^2 ~ P/(2*64) = 2 per line against a noise
// variance 0.0025/M: the right lines are never quiet. Shifted by one, each
// listed line is quiet with probability 0.99; more than half of 63 fail to be
// quiet with probability < 1e-60.
TEST(RecordStatistics, ListedLinesWithoutInputPowerAreRefused) {
  for (double input_noise : {0.05, 0.0}) {
    RecordOptions o;
    o.period = 256;
    o.periods = 8;
    for (int k = 1; k < 128; k += 2) o.lines.push_back(k);
    o.output_noise_std = 0.05;
    o.input_noise_std = input_noise;
    o.seed = 5;
    RecordMeta meta;
    const Eigen::MatrixXd rec = simulate_periodic_record(eq36(), o, meta);
    EXPECT_NO_THROW(require_input_power(rec, 1, meta)) << "input noise " << input_noise;
    RecordMeta shifted = meta;
    shifted.excited_lines.clear();
    for (int k : meta.excited_lines) shifted.excited_lines.push_back(k + 1);  // even lines 2 ... 128
    try {
      require_input_power(rec, 1, shifted);
      ADD_FAILURE() << "shifted lines accepted, input noise " << input_noise;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("listed lines carry no input power"), std::string::npos) << e.what();
    }
  }
}

TEST(RecordStatistics, ContinuousDomainLinesAreInRadiansPerSecond) {
  std::mt19937_64 rng(9);
  const StateSpace sys = eq36();
  const int P = 64;
  const Eigen::MatrixXd rec = periodic_record(sys, P, 3, 8, {1, 5, 32}, 1e-6, rng);
  RecordMeta meta;
  meta.period = P;
  meta.periods = 3;
  meta.sample_time = 0.01;
  meta.excited_lines = {1, 5, 32};
  const SampleStatistics st = record_statistics(rec, 1, meta, Domain::Continuous);
  EXPECT_DOUBLE_EQ(st.data.omega(1), 2 * M_PI * 5 / (P * 0.01));
  EXPECT_EQ(st.data.sample_time, 0.01);
  EXPECT_EQ(st.data.domain, Domain::Continuous);
}

// ---------------------------------------------------------------------------
// Section 5: errors-in-variables

// One line of M periods with noisy input and output: N_U ~ CN(0, σ²_U),
// N_Y = β G₀ N_U + N' with N' ~ CN(0, σ'²) (correlated input/output noise).
struct EivLine {
  cplx U0, G0;
  double var_U, var_Yind, beta;
};

SampleStatistics eiv_experiment(const std::vector<EivLine>& lines, int M, std::mt19937_64& rng) {
  std::vector<std::vector<Eigen::VectorXcd>> U(M), Y(M);
  Eigen::VectorXd w(lines.size());
  for (size_t k = 0; k < lines.size(); ++k) {
    w(k) = 0.1 + 0.2 * k;
    for (int l = 0; l < M; ++l) {
      const cplx nu = complex_normal(rng, lines[k].var_U);
      const cplx ny = lines[k].beta * lines[k].G0 * nu + complex_normal(rng, lines[k].var_Yind);
      U[l].push_back(Eigen::VectorXcd::Constant(1, lines[k].U0 + nu));
      Y[l].push_back(Eigen::VectorXcd::Constant(1, lines[k].G0 * lines[k].U0 + ny));
    }
  }
  return sample_statistics(Domain::Discrete, w, U, Y);
}

TEST(ErrorsInVariables, ConjugateInEq31MatchesMonteCarloVarianceAndPrintedFormDoesNot) {
  // Non-real inputs (U₀ = 2j, 2e^{j0.6}, 2e^{j2.2}), σ_U = 0.05|U₀| (26 dB),
  // β = 0.7: to first order var(Ĝ) = |G₀|² (σ²_U/|U₀|² (1 − β)² + σ'²/|Y₀|²) / M,
  // while Eq. (31) as printed (Ŷ Û in the denominator) changes the sign of the
  // cross term where U₀² is imaginary. Monte Carlo with R runs: the sample
  // variance of Ĝ has relative std ≈ 1/√R (|δG|² ~ exponential); the mean of the
  // returned σ̂²_G/M has a smaller one (average of R ratio estimates). 5σ of
  // the first: the corrected form must lie within 5/√R relative (plus second-
  // order terms ~ σ²_U/(M|U₀|²) = 3e-4), the printed one outside it.
  const int M = 8, R = 4000;
  std::vector<EivLine> lines = {{cplx(0, 2), std::polar(1.5, 0.4), 0.01, 0.001, 0.7},
                                {std::polar(2.0, 0.6), std::polar(0.8, -1.0), 0.01, 0.0005, 0.7},
                                {std::polar(2.0, 2.2), std::polar(2.0, 2.5), 0.01, 0.002, 0.7}};
  const size_t F = lines.size();
  std::mt19937_64 rng(31);
  std::vector<cplx> sum(F, 0.0);
  std::vector<double> sum2(F, 0), var_fixed(F, 0), var_printed(F, 0);
  for (int run = 0; run < R; ++run) {
    const SampleStatistics st = eiv_experiment(lines, M, rng);
    int dropped = -1;
    const FrfData d = errors_in_variables(st, nullptr, 10.0, &dropped);
    ASSERT_EQ(dropped, 0);
    ASSERT_EQ(d.frequencies(), static_cast<int>(F));
    for (size_t k = 0; k < F; ++k) {
      const cplx G = d.Y[k](0, 0);
      sum[k] += G;
      sum2[k] += std::norm(G);
      var_fixed[k] += d.variance[k](0, 0);
      // Eq. (31) exactly as printed: σ̂_YU / (Ŷ Û).
      const cplx Y = st.data.Y[k](0, 0), U = st.data.U[k](0, 0);
      const double vY = st.data.variance[k](0, 0) * M, vU = st.var_U[k](0);
      var_printed[k] += std::norm(G) * (vY / std::norm(Y) + vU / std::norm(U) - 2 * (st.cov_YU[k](0, 0) / (Y * U)).real()) / M;
    }
  }
  const double ci = 5 / std::sqrt(double(R)) + 3e-4;
  for (size_t k = 0; k < F; ++k) {
    const double mc = (sum2[k] - std::norm(sum[k]) / R) / (R - 1);
    const double fixed = var_fixed[k] / R, printed = var_printed[k] / R;
    std::cout << "  [measured] line " << k << ": MC var(G^) " << mc << ", corrected Eq. 31 " << fixed << " (ratio "
              << fixed / mc << "), printed Eq. 31 " << printed << " (ratio " << printed / mc << "), CI +-" << ci
              << "\n";
    EXPECT_NEAR(fixed / mc, 1.0, ci) << "line " << k;
    EXPECT_GT(std::abs(printed / mc - 1.0), ci) << "line " << k;
  }
}

TEST(ErrorsInVariables, FirstPassWeightIsLessBiasedThanTheGhatWeight) {
  // Eq. (36) plant, U₀ = e^{jφ_k}, input and output noise CN(0, 0.01 |·|²)
  // per period (20 dB, uncorrelated), M = 6, r = 8. Bias measure per seed:
  // b = mean over five test frequencies of Re((Ĝ(ω) − G₀(ω)) / G₀(ω)), for the
  // Ĝ-based weight (b_G) and the first pass (b_1, weight at G₁ = the Ĝ-weighted
  // estimate). Over S seeds: means and standard errors, and the paired
  // difference b_G − b_1 (same data, so most noise cancels).
  // Asserted (5 standard errors each):
  //  (a) at F = 100 and F = 1600 the first pass is less biased: mean(b_G − b_1) < −5 SE;
  //  (b) the Ĝ-weight bias does not vanish as F grows: |mean b_G| > 5 SE at F = 1600.
  // Measured and printed, not asserted (see the report): the first pass keeps a
  // bias ≈ −σ²_U / (M |U₀|²) = −1/600 (its weight still has |Û|² in it).
  const StateSpace sys = eq36();
  const int M = 6, S = 16;
  const std::vector<double> test_w = {0.2, 0.5, 1.0, 2.0, 2.8};
  for (int F : {100, 1600}) {
    double mg = 0, m1 = 0, md = 0, sg = 0, s1 = 0, sd = 0;
    for (int s = 0; s < S; ++s) {
      std::mt19937_64 rng(1000 + s);
      std::vector<std::vector<Eigen::VectorXcd>> U(M), Y(M);
      Eigen::VectorXd w(F);
      for (int k = 0; k < F; ++k) {
        w(k) = M_PI * (k + 0.5) / F;
        const cplx U0 = std::polar(1.0, 2 * M_PI * std::uniform_real_distribution<double>(0, 1)(rng));
        const cplx Y0 = frequency_response(sys, w(k))(0, 0) * U0;
        for (int l = 0; l < M; ++l) {
          U[l].push_back(Eigen::VectorXcd::Constant(1, U0 + complex_normal(rng, 0.01)));
          Y[l].push_back(Eigen::VectorXcd::Constant(1, Y0 + complex_normal(rng, 0.01 * std::norm(Y0))));
        }
      }
      const SampleStatistics st = sample_statistics(Domain::Discrete, w, U, Y);
      const FrfResult g = identify_frf_fixed(errors_in_variables(st, nullptr, 10.0), 4, 8);
      const FrfResult f = identify_frf_fixed(errors_in_variables(st, &g.model, 10.0), 4, 8);
      double bg = 0, b1 = 0;
      for (double om : test_w) {
        const cplx G0 = frequency_response(sys, om)(0, 0);
        bg += ((frequency_response(g.model, om)(0, 0) - G0) / G0).real() / test_w.size();
        b1 += ((frequency_response(f.model, om)(0, 0) - G0) / G0).real() / test_w.size();
      }
      mg += bg / S;
      m1 += b1 / S;
      md += (bg - b1) / S;
      sg += bg * bg / S;
      s1 += b1 * b1 / S;
      sd += (bg - b1) * (bg - b1) / S;
    }
    auto se = [&](double mean_sq, double mean) { return std::sqrt(std::max(0.0, mean_sq - mean * mean) / (S - 1)); };
    std::cout << "  [measured] F = " << F << ": bias G^-weight " << mg << " +- " << se(sg, mg) << ", first pass " << m1
              << " +- " << se(s1, m1) << ", paired difference " << md << " +- " << se(sd, md)
              << " (prediction for the first pass: -1/600 = " << -1.0 / 600 << ")\n";
    EXPECT_LT(md, -5 * se(sd, md)) << "F = " << F;
    if (F == 1600) {
      EXPECT_GT(std::abs(mg), 5 * se(sg, mg));
    }
  }
}

// ---------------------------------------------------------------------------
// Failure paths

template <class F>
void expect_error(ErrorKind kind, F&& f, const char* what) {
  try {
    f();
    ADD_FAILURE() << what << ": no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), kind) << what << ": " << e.what();
  }
}

TEST(FrfErrors, BadInputsThrowTheRightKind) {
  std::mt19937_64 rng(2);
  const StateSpace sys = eq36();
  const Eigen::VectorXd w = random_grid(rng, 40, 0.05, 3.0);
  const FrfData good = noise_free_frf(sys, w);
  ASSERT_NO_THROW(identify_frf_fixed(good, 4, 8));

  expect_error(ErrorKind::Dimension, [&] { identify_frf_fixed(good, 4, 4); }, "r = order");
  expect_error(ErrorKind::Dimension, [&] { identify_frf_fixed(good, 4, 3); }, "r < order");
  {
    FrfData d = good;
    d.omega(7) = d.omega(3);
    expect_error(ErrorKind::Grid, [&] { identify_frf_fixed(d, 4, 8); }, "repeated frequency");
  }
  for (double v : {0.0, -1.0, std::nan("")}) {
    FrfData d = good;
    d.variance[5](0, 0) = v;
    expect_error(ErrorKind::Input, [&] { identify_frf_fixed(d, 4, 8); }, "bad variance");
  }
  for (double bad : {-0.1, M_PI + 1e-12, 4.0}) {
    FrfData d = good;
    d.omega(0) = bad;
    expect_error(ErrorKind::Grid, [&] { identify_frf_fixed(d, 4, 8); }, "omega outside [0, pi]");
  }
  {
    FrfData d = good;
    d.omega(0) = 0.0;  // allowed in discrete time
    d.Y[0] = frequency_response(sys, 0.0);
    EXPECT_NO_THROW(identify_frf_fixed(d, 4, 8));
    d.domain = Domain::Continuous;
    expect_error(ErrorKind::Grid, [&] { identify_frf_fixed(d, 4, 8); }, "continuous omega = 0");
    d.omega(0) = -1.0;
    expect_error(ErrorKind::Grid, [&] { identify_frf_fixed(d, 4, 8); }, "continuous omega < 0");
  }
  {
    // Matrices of another shape at one frequency: refused where they enter
    // (one contiguous stack per field), and a variance stack of another shape
    // than Y by validate.
    std::vector<Eigen::MatrixXcd> G(40, Eigen::MatrixXcd::Ones(1, 1));
    G[17] = Eigen::MatrixXcd::Ones(2, 1);
    expect_error(ErrorKind::Input, [&] { frf_data(Domain::Discrete, w, G); }, "G of another shape");
    try {
      frf_data(Domain::Discrete, w, G);
    } catch (const Error& e) {
      EXPECT_EQ(e.where(), "frequency 18");
    }
    FrfData d = good;
    d.variance.resize(40, 2, 1);
    for (int k = 0; k < 40; ++k) d.variance[k].setOnes();
    expect_error(ErrorKind::Input, [&] { identify_frf_fixed(d, 4, 8); }, "variance of another shape than Y");
  }
  {
    FrfData d = noise_free_frf(sys, random_grid(rng, 7, 0.1, 3.0));  // 2Fc = 14 < r(m+p) = 16
    expect_error(ErrorKind::Dimension, [&] { identify_frf_fixed(d, 4, 8); }, "too few frequencies for r");
  }
  {
    FrfData d = noise_free_io(sys, w, std::vector<Eigen::MatrixXcd>(40, Eigen::MatrixXcd::Zero(1, 1)));
    expect_error(ErrorKind::Numerical, [&] { identify_frf_fixed(d, 4, 8); }, "U = 0 at all lines");
  }
  {
    // A single excited line cannot excite r = 8 basis functions: 𝐔^re has rank 2.
    std::vector<Eigen::MatrixXcd> U(40, Eigen::MatrixXcd::Zero(1, 1));
    U[10](0, 0) = 1.0;
    FrfData d = noise_free_io(sys, w, U);
    expect_error(ErrorKind::Numerical, [&] { identify_frf_fixed(d, 4, 8); }, "one excited line");
  }
}

TEST(FrfErrors, BadRecordsThrowInputErrors) {
  std::mt19937_64 rng(3);
  const StateSpace sys = eq36();
  const int P = 32;
  const Eigen::MatrixXd rec = periodic_record(sys, P, 3, 10, {2, 5}, 1e-6, rng);
  RecordMeta meta;
  meta.period = P;
  meta.periods = 3;
  meta.excited_lines = {2, 5};
  ASSERT_NO_THROW(record_statistics(rec, 1, meta, Domain::Discrete));
  expect_error(ErrorKind::Input, [&] { record_statistics(rec.topRows(3 * P - 5), 1, meta, Domain::Discrete); },
               "not whole periods");
  {
    RecordMeta m = meta;
    m.excited_lines.clear();
    expect_error(ErrorKind::Input, [&] { record_statistics(rec, 1, m, Domain::Discrete); }, "no excited lines");
  }
  {
    RecordMeta m = meta;
    m.excited_lines = {2, P / 2 + 1};
    expect_error(ErrorKind::Input, [&] { record_statistics(rec, 1, m, Domain::Discrete); }, "line > P/2");
    m.excited_lines = {2, 2};
    expect_error(ErrorKind::Input, [&] { record_statistics(rec, 1, m, Domain::Discrete); }, "repeated line");
    m.excited_lines = {0, 2};
    expect_error(ErrorKind::Input, [&] { record_statistics(rec, 1, m, Domain::Discrete); }, "line 0");
  }
  {
    RecordMeta m = meta;
    m.periods = 1;
    m.period = 3 * P;
    expect_error(ErrorKind::Input, [&] { record_statistics(rec, 1, m, Domain::Discrete); }, "M = 1");
    std::vector<std::vector<Eigen::VectorXcd>> one(1, std::vector<Eigen::VectorXcd>(1, Eigen::VectorXcd::Ones(1)));
    expect_error(ErrorKind::Input, [&] { sample_statistics(Domain::Discrete, Eigen::VectorXd::Ones(1), one, one); },
                 "sample_statistics M = 1");
  }
  {
    // An exactly repeated period has zero sample variance: no noise model.
    Eigen::MatrixXd same(3 * P, 2);
    for (int l = 0; l < 3; ++l) same.middleRows(l * P, P) = rec.topRows(P);
    expect_error(ErrorKind::Input, [&] { record_statistics(same, 1, meta, Domain::Discrete); }, "zero variance");
  }
}

}  // namespace
}  // namespace fdsid

// Resource limits (issue: refuse before allocating, with the figure): a request
// far beyond any machine's memory is an Error of kind Resource naming MiB.
TEST(ResourceLimits, RequireMemoryRefusesWithTheFigures) {
  try {
    fdsid::require_memory(1e30, "test", "a 1e30-byte request");
    FAIL() << "no error";
  } catch (const fdsid::Error& e) {
    EXPECT_EQ(e.kind(), fdsid::ErrorKind::Resource);
    EXPECT_NE(std::string(e.what()).find("MiB"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(fdsid::require_memory(1024.0, "test", "a kilobyte"));
  EXPECT_GT(fdsid::available_memory_bytes(), 0.0);
}

namespace fdsid {

// Theorems 1 and 2 on the paper's own plant (Eq. 36), known variance and sample
// variance with M = 4: the relative error of Ĝ at five fixed frequencies (RMS
// over them, per seed) shrinks like F^{-1/2} from F = 100 to F = 1600 (ratio
// 4). Uniform grids ω_k = π(k − ½)/F, noise CN(0, σ²) on Ŷ with
// σ = 0.03 · RMS|G₀ − D|. Margins as in properties/frf_consistency_property.cpp:
//  - known variance: the log of an RMS over S = 12 seeds has std ≤ 1/(2√S),
//    a ratio of two ≤ 1/√(2S); z = 4.5 (one-sided 3.4e-6):
//    ratio ≥ 4 exp(−4.5/√(2S)) = 1.60;
//  - sample variance: the errors' spread has no χ² law (step 3's weights
//    1/σ̂² have moments of order < M − 1 = 3 only), so 24 seeds per F and the
//    exact Mann–Whitney test (tests/statistics.hpp) of "the error at F = 100
//    divided by 4 √((M−3)/(M−2)) = 2.83 (Eq. (28)'s inflation) is
//    stochastically larger than the error at F = 1600", rejected below 3.4e-6.
TEST(FrfConsistency, PintelonPlantErrorShrinksLikeOneOverSqrtF) {
  const StateSpace sys = pintelon_plant();
  const int r = 8, M = 4;
  const std::vector<double> test_w = {0.15, 0.6, 1.2, 2.0, 2.9};
  double g2 = 0;
  for (int k = 0; k < 64; ++k) g2 += (frequency_response(sys, M_PI * (k + 0.5) / 64) - sys.D).squaredNorm() / 64;
  const double var = 9e-4 * g2;
  auto errors = [&](int F, int M, int S) {
    std::vector<double> per_seed;
    for (int s = 0; s < S; ++s) {
      std::mt19937_64 rng(1000 + 7919 * s + F + 31 * M);
      Eigen::VectorXd w(F);
      for (int k = 0; k < F; ++k) w(k) = M_PI * (k + 0.5) / F;
      const std::vector<Eigen::MatrixXcd> G0 = frequency_response(sys, w);
      FrfData d;
      if (M == 0) {
        std::vector<Eigen::MatrixXcd> G;
        std::vector<Eigen::MatrixXd> V;
        for (int k = 0; k < F; ++k) {
          G.push_back(G0[k] + Eigen::MatrixXcd::Constant(1, 1, testing::complex_normal(rng, var)));
          V.push_back(Eigen::MatrixXd::Constant(1, 1, var));
        }
        d = frf_data(Domain::Discrete, w, G, V);
      } else {
        std::vector<std::vector<Eigen::VectorXcd>> U(M), Y(M);
        for (int k = 0; k < F; ++k)
          for (int l = 0; l < M; ++l) {
            U[l].push_back(Eigen::VectorXcd::Ones(1));
            Y[l].push_back(Eigen::VectorXcd::Constant(1, G0[k](0, 0) + testing::complex_normal(rng, M * var)));
          }
        d = sample_statistics(Domain::Discrete, w, U, Y).data;
      }
      const FrfResult res = identify_frf_fixed(d, 4, r);
      double acc = 0;
      for (double om : test_w) {
        const cplx g0 = frequency_response(sys, om)(0, 0);
        acc += std::norm((frequency_response(res.model, om)(0, 0) - g0) / g0);
      }
      per_seed.push_back(std::sqrt(acc / test_w.size()));
    }
    return per_seed;
  };
  auto rms = [](const std::vector<double>& e) {
    double acc = 0;
    for (double x : e) acc += x * x;
    return std::sqrt(acc / e.size());
  };
  const int S = 12;
  const double floor = 4 * std::exp(-4.5 / std::sqrt(2.0 * S));
  const double e100 = rms(errors(100, 0, S)), e1600 = rms(errors(1600, 0, S));
  std::printf("consistency (known variance): RMS error F=100 %.3g, F=1600 %.3g, ratio %.3g (>= %.3g)\n", e100,
              e1600, e100 / e1600, floor);
  EXPECT_GE(e100 / e1600, floor);

  const double c = 4 * std::sqrt((M - 3.0) / (M - 2.0)), alpha = 3.4e-6;
  std::vector<double> scaled100 = errors(100, M, 24);
  const std::vector<double> s1600 = errors(1600, M, 24);
  for (double& e : scaled100) e /= c;
  const double p = testing::mann_whitney_p_value(scaled100, s1600);
  std::printf("consistency (sample variance, M = 4): RMS error F=100 %.3g, F=1600 %.3g; F=100 / %.3g below "
              "F=1600 with p %.3g (>= %.3g)\n",
              rms(scaled100) * c, rms(s1600), c, p, alpha);
  EXPECT_GE(p, alpha);
}

}  // namespace fdsid
