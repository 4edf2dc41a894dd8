// Tests of the high-precision reference of Pintelon (2002) (reference/frf_id):
// noise-free exactness of Algorithms 1, 2.1 and 2.2 (SISO, FRF, MIMO), the
// bilinear back-transform, the cost of Eq. (35) and its gradient, the
// errors-in-variables data of Section 5, the DFT of Eq. (4), and the input
// checks.
//
// Tolerances. u = std::numeric_limits<Real>::epsilon() ≈ 1e-50 is the unit
// roundoff of the 50-digit format. On noise-free data every step of the
// algorithm is exact in exact arithmetic, so the identified G differs from the
// true one by rounding only: |ΔG|/max|G| ≲ c · κ · u, with κ the product of
// (i) (σ_1/σ_n)² — step 1c takes the singular vectors of K, whose eigenvalues
// are σ², so the subspace error is u·σ_1²/σ_n² — (ii) the condition of the
// least-squares problems of steps 2 and 3 and (iii) for continuous time the
// conditioning of the map to s (bilinear) or of the polynomial basis
// (orthogonal). Each test prints σ_1/σ_n and its worst error beside its bound.
#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/io.hpp"
#include "test_support.hpp"

#include <boost/math/constants/constants.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace frf_reference_test {  // named: the reference_test binary is one unit (reference/CMakeLists.txt)

using namespace fdsid::reference;

using test::mat;
using test::sci;

const Real u = std::numeric_limits<Real>::epsilon();
const Real pi = boost::math::constants::pi<Real>();

// Options of identify_frf: order n, r, and the continuous method (ignored for
// discrete data).
FrfOptions options_for(int order, int r, const char* method = "bilinear") {
  FrfOptions options;
  options.order = order;
  options.r = r;
  options.continuous_method = method;
  return options;
}

// Pintelon (2002) Eq. (36): 4th-order discrete-time system.
Model paper_system() {
  Model model;
  model.A = mat({{"0.8876", "0.4494", "0", "0"},
                 {"-0.4494", "0.7978", "0", "0"},
                 {"0", "0", "-0.6129", "0.064516"},
                 {"0", "0", "-6.4516", "-0.7419"}});
  model.B = mat({{"0.2247"}, {"0.8989"}, {"0.0323"}, {"0.1290"}});
  model.C = mat({{"0.4719", "0.1124", "9.6774", "1.6129"}});
  model.D = mat({{"0.9626"}});
  return model;
}

// A 2-input, 2-output, 3rd-order discrete system: poles 0.6 ± 0.3i, −0.5.
Model mimo_system() {
  Model model;
  model.A = mat({{"0.6", "0.3", "0"}, {"-0.3", "0.6", "0.2"}, {"0", "0", "-0.5"}});
  model.B = mat({{"1", "0.2"}, {"0.3", "-0.5"}, {"0.2", "0.7"}});
  model.C = mat({{"0.4", "0.1", "0.3"}, {"-0.2", "0.5", "0.6"}});
  model.D = mat({{"0.1", "0"}, {"0.05", "-0.2"}});
  return model;
}

// Continuous 4th-order system, two lightly damped resonances inside the band:
// ω = 1 rad/s (ζ = 0.05) and ω = 30 rad/s (ζ = 0.1).
Model continuous_system() {
  Model model;
  model.domain = "continuous";
  model.sample_time = 0;
  model.A = mat({{"0", "1", "0", "0"},
                 {"-1", "-0.1", "0", "0"},
                 {"0", "0", "0", "1"},
                 {"0", "0", "-900", "-6"}});
  model.B = mat({{"0"}, {"1"}, {"0"}, {"1"}});
  model.C = mat({{"1", "0.5", "200", "3"}});
  model.D = mat({{"0.1"}});
  return model;
}

// F irregular frequencies in (0, π): uniform spacing h = π/(F+1) jittered by
// 0.3 h sin(k²), which keeps them distinct and increasing.
std::vector<Real> irregular_grid(int F) {
  std::vector<Real> omega;
  const Real h = pi / (F + 1);
  for (int k = 0; k < F; ++k) omega.push_back(h * (k + 1) + Real("0.3") * h * sin(Real(k * k)));
  return omega;
}

// F log-spaced frequencies between 10^lo and 10^hi rad/s.
std::vector<Real> log_grid(int F, int lo, int hi) {
  std::vector<Real> omega;
  for (int k = 0; k < F; ++k)
    omega.push_back(pow(Real(10), Real(lo) + Real(hi - lo) * Real(k) / Real(F - 1)));
  return omega;
}

// Noise-free data Y = G U. frf: U = I_m (c = m); otherwise one column (c = 1)
// with input entries of varying modulus 1 + 0.5 sin(3k + i) and phase 0.7k² + i.
// variance = any positive function: (1 + (k mod 5))/10 · (1 + i).
FrfData make_data(const Model& model, const std::vector<Real>& omega, bool frf) {
  FrfData d;
  d.domain = model.domain;
  d.omega = omega;
  const Eigen::Index m = model.B.cols(), p = model.C.rows();
  for (std::size_t k = 0; k < omega.size(); ++k) {
    MatrixC U;
    if (frf) {
      U = MatrixC::Identity(m, m);
    } else {
      U.resize(m, 1);
      for (Eigen::Index i = 0; i < m; ++i) {
        const Real modulus = 1 + Real("0.5") * sin(Real(3 * static_cast<int>(k) + i));
        const Real phase = Real("0.7") * Real(static_cast<int>(k * k)) + Real(i);
        U(i, 0) = std::polar(modulus, phase);
      }
    }
    d.U.push_back(U);
    d.Y.push_back(frequency_response(model, omega[k]) * U);
    MatrixR var(p, U.cols());
    for (Eigen::Index i = 0; i < p; ++i)
      for (Eigen::Index j = 0; j < U.cols(); ++j)
        var(i, j) = Real(1 + static_cast<int>(k % 5)) / 10 * Real(1 + i);
    d.variance.push_back(var);
  }
  return d;
}

// Worst |G_hat − G_true| / max_ω |G_true| (max-entry norms) over the grid and
// the midpoints between grid points (geometric midpoints for log grids).
Real worst_response_error(const Model& truth, const Model& estimate,
                          const std::vector<Real>& omega, bool geometric, Real* at) {
  std::vector<Real> points = omega;
  std::sort(points.begin(), points.end());
  for (std::size_t k = 0; k + 1 < omega.size(); ++k)
    points.push_back(geometric ? sqrt(omega[k] * omega[k + 1]) : (omega[k] + omega[k + 1]) / 2);
  Real scale = 0, worst = 0;
  for (const Real& w : points)
    scale = std::max(scale, Real(frequency_response(truth, w).cwiseAbs().maxCoeff()));
  for (const Real& w : points) {
    const Real e = (frequency_response(estimate, w) - frequency_response(truth, w)).cwiseAbs().maxCoeff();
    if (e > worst) {
      worst = e;
      *at = w;
    }
  }
  return worst / scale;
}

// Worst relative distance from each true pole to the nearest estimated pole.
Real worst_pole_error(const Model& truth, const std::vector<Complex>& estimated) {
  Real worst = 0;
  EXPECT_EQ(estimated.size(), static_cast<std::size_t>(truth.A.rows()));
  for (const Complex& lambda : eigenvalues(truth.A)) {
    Real best = -1;
    for (const Complex& mu : estimated) {
      const Real d = abs(lambda - mu);
      if (best < 0 || d < best) best = d;
    }
    worst = std::max(worst, best / abs(lambda));
  }
  return worst;
}

// Identifies `truth` from `data`, checks G and the poles against `tol`, and
// that σ_1/σ_n stays below the `kappa_bound` the tolerance was derived from.
void check_exact(const std::string& name, const Model& truth, const FrfData& data,
                 const FrfOptions& options, bool geometric, const Real& kappa_bound,
                 const Real& tol) {
  const FrfResult result = identify_frf(data, options);
  const int n = options.order;
  const Real kappa = result.singular_values[0] / result.singular_values[n - 1];
  Real at = 0;
  const Real err_G = worst_response_error(truth, result.model, data.omega, geometric, &at);
  const Real err_poles = worst_pole_error(truth, result.poles);
  std::printf("%s: sigma_1/sigma_n = %s (bound %s), sigma_{n+1}/sigma_1 = %s, worst |dG|/|G| = %s"
              " at omega = %s, worst pole error %s (tol %s), V_sub = %s\n",
              name.c_str(), sci(kappa).c_str(), sci(kappa_bound).c_str(),
              sci(result.singular_values[n] / result.singular_values[0]).c_str(), sci(err_G).c_str(),
              sci(at).c_str(), sci(err_poles).c_str(), sci(tol).c_str(), sci(result.v_sub).c_str());
  EXPECT_LT(kappa, kappa_bound) << name << ": the tolerance derivation does not apply";
  EXPECT_LT(err_G, tol) << name;
  EXPECT_LT(err_poles, tol) << name;
  EXPECT_EQ(result.singular_values.size(),
            static_cast<std::size_t>(options.r * truth.C.rows()));
  EXPECT_EQ(result.model.domain, truth.domain);
}

// Discrete, noise-free. Bound: σ_1/σ_n ≤ 10 (checked), so (σ_1/σ_n)² ≤ 1e2;
// the LS problems of steps 2-3 and the (simple) eigenvalues add ≤ 1e4; c = 1e6
// covers the dimensions (r p ≤ 16, ≤ 2Fc = 80 terms per inner product):
// ≤ 1e12 u ≈ 1e-38. tol 1e-30 leaves a margin of 1e8 and still demands 30 digits.
TEST(FrfReference, DiscreteSisoIoNoiseFreeIsExact) {
  const Model truth = paper_system();
  const FrfData data = make_data(truth, irregular_grid(40), /*frf=*/false);
  const FrfOptions options = options_for(4, 8);
  check_exact("discrete io", truth, data, options, false, Real(10), Real("1e-30"));
}

TEST(FrfReference, DiscreteSisoFrfNoiseFreeIsExact) {
  const Model truth = paper_system();
  const FrfData data = make_data(truth, irregular_grid(40), /*frf=*/true);
  const FrfOptions options = options_for(4, 8);
  check_exact("discrete frf", truth, data, options, false, Real(10), Real("1e-30"));
}

// MIMO FRF data (c = m = 2), p = 2: same bound as above.
TEST(FrfReference, DiscreteMimoFrfNoiseFreeIsExact) {
  const Model truth = mimo_system();
  const FrfData data = make_data(truth, irregular_grid(30), /*frf=*/true);
  const FrfOptions options = options_for(3, 6);
  check_exact("discrete mimo frf", truth, data, options, false, Real(10), Real("1e-30"));
}

// Continuous, five decades (0.01 … 1000 rad/s), bilinear map with
// ω_scale = sqrt(0.01 · 1000) ≈ 3.16. The map w = (s̃ − 1)/(s̃ + 1) crowds the
// band ends onto w ≈ ±1 (arg w within 2/316 of 0 and π), which conditions the
// monomial rows worse than a spread grid: σ_1/σ_n ≤ 100 (checked), so
// (σ_1/σ_n)² ≤ 1e4; the back-transform Q = (I − A_w)⁻¹ adds ≤ 1e3 (the pole at
// 30 rad/s maps to |1 − w| ≈ 0.2, the one at 1 rad/s to |1 − w| ≈ 0.6); the
// resonances' peak/valley ratio in the relative-to-max measure adds ≤ 1e4; LS
// steps ≤ 1e4; c = 1e6: ≤ 1e21 u ≈ 1e-29 … use tol 1e-27 (measured ~1e-48).
TEST(FrfReference, ContinuousBilinearNoiseFreeIsExact) {
  const Model truth = continuous_system();
  const FrfData data = make_data(truth, log_grid(60, -2, 3), /*frf=*/false);
  const FrfOptions options = options_for(4, 8, "bilinear");
  check_exact("continuous bilinear", truth, data, options, true, Real(100), Real("1e-27"));
}

// Lightly damped modes at the angles `theta` (rad/sample, decimal strings),
// pole radius `rho`, real modal form, D = 1/10.
Model modes_at(const std::vector<const char*>& theta, const char* rho) {
  const Eigen::Index n = 2 * static_cast<Eigen::Index>(theta.size());
  Model model;
  model.A = MatrixR::Zero(n, n);
  model.B = MatrixR::Zero(n, 1);
  model.C = MatrixR::Zero(1, n);
  for (std::size_t i = 0; i < theta.size(); ++i) {
    const Real t(theta[i]), r(rho);
    const Eigen::Index j = 2 * static_cast<Eigen::Index>(i);
    model.A(j, j) = model.A(j + 1, j + 1) = r * cos(t);
    model.A(j, j + 1) = r * sin(t);
    model.A(j + 1, j) = -r * sin(t);
    model.B(j, 0) = Real(3) / 10;
    model.B(j + 1, 0) = Real(static_cast<int>(i) + 1) / 10;
    model.C(0, j) = Real(2) / 10;
    model.C(0, j + 1) = -Real(static_cast<int>(i) + 1) / 20;
  }
  model.D = MatrixR::Constant(1, 1, Real(1) / 10);
  return model;
}

// F lines spread irregularly over [lo, hi] rad/sample.
std::vector<Real> band(int F, const Real& lo, const Real& hi) {
  std::vector<Real> omega;
  for (int k = 0; k < F; ++k)
    omega.push_back(lo + (hi - lo) * (k + Real("0.3") * sin(Real(k * k)) / 2 + Real("0.2")) / F);
  return omega;
}

// Discrete, noise-free, narrow bands (issue 15, item 4), with the modes inside.
// (a) The F-16 record's band (2-15 Hz at 400 Hz: 6.5 % of [0, π], tan ratio
// 7.5), three modes, discrete_method "bilinear"; (b) [0.3, 0.5] rad/sample
// (tan ratio 1.7), two modes, discrete_method "orthogonal". Both bases keep
// the rows apart on these bands: σ_1/σ_n ≤ 10 (checked), so, as for the
// spread discrete grid above, (σ_1/σ_n)² ≤ 1e2, LS steps ≤ 1e4, c = 1e6, and
// the back-transforms (I − A_w)⁻¹ and (I − A')⁻¹ (poles near z = 1 map to
// s' ≈ 0 and w ≈ −1, far from the singular points) ≤ 1e3 each: ≤ 1e18 u ≈
// 1e-32; tol 1e-28 (measured ~1e-49).
TEST(FrfReference, DiscreteNarrowBandTustinBasesNoiseFreeAreExact) {
  const Real pi400 = pi / 200;  // 2π/400: 1 Hz at 400 Hz in rad/sample
  const Model wide = modes_at({"0.06", "0.12", "0.2"}, "0.99");
  FrfOptions bilinear = options_for(6, 14);
  bilinear.discrete_method = "bilinear";
  check_exact("discrete narrow-band bilinear", wide, make_data(wide, band(60, 2 * pi400, 15 * pi400), true), bilinear,
              false, Real(10), Real("1e-28"));
  const Model narrow = modes_at({"0.35", "0.45"}, "0.98");
  FrfOptions orthogonal = options_for(4, 10);
  orthogonal.discrete_method = "orthogonal";
  check_exact("discrete narrow-ratio orthogonal", narrow,
              make_data(narrow, band(60, Real("0.3"), Real("0.5")), true), orthogonal, false, Real(10),
              Real("1e-28"));
}

// Orthogonal polynomial rows in s̃ = s/ω_scale ∈ j[0.0032, 316]. The basis is
// built by Gram–Schmidt in Arnoldi form (values at the nodes, stable), and
// σ_1/σ_n ≤ 1e5 (checked; the rows are orthonormal but the state-space
// coordinates of Ô_⊥ are graded), so (σ_1/σ_n)² ≤ 1e10; peak/valley ≤ 1e4,
// c = 1e6: ≤ 1e20 u ≈ 1e-30. The generalised shift uses H with entries up to
// |s̃| ≈ 316 and q_i(Â) of growth up to 316^{r−1}: allow another 1e4: tol 1e-26.
TEST(FrfReference, ContinuousOrthogonalNoiseFreeIsExact) {
  const Model truth = continuous_system();
  const FrfData data = make_data(truth, log_grid(60, -2, 3), /*frf=*/false);
  const FrfOptions options = options_for(4, 8, "orthogonal");
  check_exact("continuous orthogonal", truth, data, options, true, Real("1e5"), Real("1e-26"));
}

// FRF data, 2 outputs, both variants: same bounds as the SISO cases.
TEST(FrfReference, ContinuousSimoFrfNoiseFreeIsExact) {
  Model truth = continuous_system();
  truth.C = mat({{"1", "0.5", "200", "3"}, {"0", "2", "-50", "1"}});
  truth.D = mat({{"0.1"}, {"0"}});
  const FrfData data = make_data(truth, log_grid(60, -2, 3), /*frf=*/true);
  FrfOptions options = options_for(4, 8);
  check_exact("continuous bilinear simo frf", truth, data, options, true, Real(100),
              Real("1e-27"));
  options.continuous_method = "orthogonal";
  check_exact("continuous orthogonal simo frf", truth, data, options, true, Real("1e5"),
              Real("1e-26"));
}

// Continuous MIMO (2 inputs, 2 outputs, FRF data c = m = 2), both variants,
// 3rd-order system with poles −0.2 ± 2j and −10; 40 log-spaced points 0.01 …
// 100 rad/s. Same bound as the SISO bilinear case.
TEST(FrfReference, ContinuousMimoFrfNoiseFreeIsExact) {
  Model truth;
  truth.domain = "continuous";
  truth.sample_time = 0;
  truth.A = mat({{"-0.2", "2", "0"}, {"-2", "-0.2", "1"}, {"0", "0", "-10"}});
  truth.B = mat({{"1", "0"}, {"0.5", "-1"}, {"0", "3"}});
  truth.C = mat({{"1", "0", "0.5"}, {"0.3", "1", "-2"}});
  truth.D = mat({{"0", "0.1"}, {"0.2", "0"}});
  const FrfData data = make_data(truth, log_grid(40, -2, 2), /*frf=*/true);
  FrfOptions options = options_for(3, 6);
  check_exact("continuous bilinear mimo frf", truth, data, options, true, Real(100),
              Real("1e-27"));
  // Alg. 2.2 beyond its SISO origin (weights ‖U[k]‖²_F, ‖Y[k]‖²_F): same bound
  // as the SISO orthogonal case.
  options.continuous_method = "orthogonal";
  check_exact("continuous orthogonal mimo frf", truth, data, options, true, Real("1e5"),
              Real("1e-26"));
}

// The back-transform of Alg. 2.1 on its own: G_c(jω) = G_w(w(jω)) for a fixed
// w-domain model (evaluated as a "discrete" model at θ = arg w, since |w| = 1).
// Bound: one 3×3 solve with cond(I − A_w) ≲ 10 and the resolvents at ≲ 10:
// ≲ 1e3 u per entry: tol 1e-45.
TEST(FrfReference, BilinearBackTransformPreservesResponse) {
  Model w_model;
  w_model.A = mat({{"0.5", "0.4", "0"}, {"-0.4", "0.5", "0.1"}, {"0", "0", "-0.3"}});
  w_model.B = mat({{"1"}, {"0.2"}, {"-0.7"}});
  w_model.C = mat({{"0.3", "-1", "0.25"}});
  w_model.D = mat({{"0.4"}});
  const Real scale("2.5");
  const Model cont = bilinear_to_continuous(w_model, scale);
  Real worst = 0;
  for (const char* text : {"0.001", "0.3", "1", "2.5", "7", "100", "1e4"}) {
    const Real omega(text);
    const Complex st(Real(0), omega / scale);
    const Complex w = (st - Real(1)) / (st + Real(1));
    const MatrixC Gw = frequency_response(w_model, atan2(w.imag(), w.real()));
    const MatrixC Gc = frequency_response(cont, omega);
    worst = std::max(worst, Real((Gc - Gw).cwiseAbs().maxCoeff() / Gw.cwiseAbs().maxCoeff()));
  }
  std::printf("bilinear back-transform: worst relative error %s (tol 1e-45)\n", sci(worst).c_str());
  EXPECT_LT(worst, Real("1e-45"));
}

// V_sub (Eq. 35) of the true model on its own noise-free data is 0; a wrong D
// changes it by Σ_k |ΔD U|²/σ² exactly (FRF data: U = 1).
TEST(FrfReference, VSubOfTrueModelIsZero) {
  const Model truth = paper_system();
  const FrfData data = make_data(truth, irregular_grid(10), /*frf=*/true);
  EXPECT_LT(v_sub(truth, data), Real("1e-90"));
  Model wrong = truth;
  wrong.D(0, 0) += Real("0.5");
  Real expected = 0;
  for (const MatrixR& v : data.variance) expected += Real("0.25") / v(0, 0);
  EXPECT_LT(abs(v_sub(wrong, data) - expected) / expected, Real("1e-45"));
}

// ---------------------------------------------------------------------------
// cost_gradient: Eq. (35) and its gradient in (A, B, C, D)

// A deterministic stream of exact decimals q/1000, q ∈ {−1000, …, 1000}, from
// std::mt19937 (whose output sequence the standard fixes; the modulo is used
// instead of a distribution, whose algorithm is implementation-defined), so
// no value ever passes through a double.
class DecimalStream {
 public:
  explicit DecimalStream(std::uint32_t seed) : rng_(seed) {}
  Real operator()() { return Real(static_cast<int>(rng_() % 2001) - 1000) / Real(1000); }
  MatrixR matrix(Eigen::Index rows, Eigen::Index cols, const Real& scale) {
    MatrixR X(rows, cols);
    for (Eigen::Index i = 0; i < rows; ++i)
      for (Eigen::Index j = 0; j < cols; ++j) X(i, j) = scale * (*this)();
    return X;
  }

 private:
  std::mt19937 rng_;
};

// Data for `model` at `omega`: c columns of random inputs (entries in the unit
// square), Y = G U + a fixed random perturbation (each part in [−0.1, 0.1]),
// non-uniform variances (1 + (3k + 2i + j) mod 5)/4.
FrfData perturbed_data(const Model& model, const std::vector<Real>& omega, int c,
                       DecimalStream& draw) {
  FrfData d;
  d.domain = model.domain;
  d.omega = omega;
  const Eigen::Index m = model.B.cols(), p = model.C.rows();
  const Real tenth("0.1");
  for (std::size_t k = 0; k < omega.size(); ++k) {
    MatrixC U(m, c), noise(p, c);
    for (Eigen::Index i = 0; i < m; ++i)
      for (int j = 0; j < c; ++j) U(i, j) = Complex(draw(), draw());
    for (Eigen::Index i = 0; i < p; ++i)
      for (int j = 0; j < c; ++j) noise(i, j) = Complex(tenth * draw(), tenth * draw());
    d.U.push_back(U);
    d.Y.push_back(frequency_response(model, omega[k]) * U + noise);
    MatrixR var(p, c);
    for (Eigen::Index i = 0; i < p; ++i)
      for (int j = 0; j < c; ++j)
        var(i, j) = Real(1 + (3 * static_cast<int>(k) + 2 * static_cast<int>(i) + j) % 5) / 4;
    d.variance.push_back(var);
  }
  return d;
}

// The gradient of cost_gradient against central differences of v_sub (an
// independent evaluation of the cost, through frequency_response), entry by
// entry of A, B, C, D; and cost against v_sub. Returns the worst difference
// relative to the largest gradient entry.
//
// Tolerance. The central difference (V(θ + h e) − V(θ − h e))/(2h) differs from
// ∂V/∂θ_e by h²/6 · ∂³V/∂θ_e³ (truncation) plus the rounding error of the two
// V values divided by 2h. Each V carries ≈ c u κ V (u ≈ 1e-50; κ ≲ 10, the
// condition of the resolvent solves of these well-damped models; c ≲ 10 for
// sums of F p c ≤ 28 terms), so with h = 1e-20: truncation ≈ 1e-40 |V'''|,
// rounding ≈ u/h · V ≈ 1e-30 V (≲ 1e-28 V with the constants). V, V''' and the
// largest gradient entry are of comparable size for these O(1) models
// (V / max|∂V| is printed), so the discrepancy is ≈ 1e-30 relative to
// max|∂V|: tol 1e-25 leaves a margin of ≥ 1e3 and still rejects any slip in
// the formulas (a wrong transpose, conjugate or sign gives O(1)). cost vs
// v_sub: the same sums, with X B from (ξI − A)⁻¹ times B instead of a solve
// with right-hand side B: ≲ c u κ ≈ 1e-48 relative: tol 1e-45.
Real check_gradient(const std::string& name, const Model& model, const FrfData& data) {
  const CostGradient g = cost_gradient(model, data);
  const Real V = v_sub(model, data);
  const Real cost_error = abs(g.cost - V) / V;
  EXPECT_LT(cost_error, Real("1e-45")) << name;
  EXPECT_EQ(g.dA.rows(), model.A.rows());
  EXPECT_EQ(g.dA.cols(), model.A.cols());
  EXPECT_EQ(g.dB.rows(), model.B.rows());
  EXPECT_EQ(g.dB.cols(), model.B.cols());
  EXPECT_EQ(g.dC.rows(), model.C.rows());
  EXPECT_EQ(g.dC.cols(), model.C.cols());
  EXPECT_EQ(g.dD.rows(), model.D.rows());
  EXPECT_EQ(g.dD.cols(), model.D.cols());

  const Real h("1e-20");
  const Real scale = std::max({Real(g.dA.cwiseAbs().maxCoeff()), Real(g.dB.cwiseAbs().maxCoeff()),
                               Real(g.dC.cwiseAbs().maxCoeff()), Real(g.dD.cwiseAbs().maxCoeff())});
  Real worst = 0;
  std::string where = "none";
  const struct {
    const char* name;
    MatrixR Model::*theta;
    const MatrixR* grad;
  } parts[] = {{"A", &Model::A, &g.dA}, {"B", &Model::B, &g.dB}, {"C", &Model::C, &g.dC},
               {"D", &Model::D, &g.dD}};
  for (const auto& part : parts)
    for (Eigen::Index a = 0; a < (model.*part.theta).rows(); ++a)
      for (Eigen::Index b = 0; b < (model.*part.theta).cols(); ++b) {
        Model plus = model, minus = model;
        (plus.*part.theta)(a, b) += h;
        (minus.*part.theta)(a, b) -= h;
        const Real difference = (v_sub(plus, data) - v_sub(minus, data)) / (2 * h);
        const Real error = abs(difference - (*part.grad)(a, b)) / scale;
        if (error > worst) {
          worst = error;
          where = std::string(part.name) + "(" + std::to_string(a) + "," + std::to_string(b) + ")";
        }
      }
  std::printf("%s: V = %s, max|dV| = %s, |cost - v_sub|/V = %s (tol 1e-45), worst |central "
              "difference - gradient| / max|dV| = %s at d%s (tol 1e-25)\n",
              name.c_str(), sci(V).c_str(), sci(scale).c_str(), sci(cost_error).c_str(),
              sci(worst).c_str(), where.c_str());
  EXPECT_GT(scale, Real("1e-3")) << name << ": the gradient is too small for a relative check";
  EXPECT_LT(worst, Real("1e-25")) << name << " worst at d" << where;
  return worst;
}

TEST(FrfReference, CostGradientMatchesCentralDifferences) {
  // Discrete, n = 3, m = 1, p = 2, c = 2 columns, F = 7. Entries of A in
  // [−0.3, 0.3]: every row sum of |A| ≤ 0.9, so ρ(A) ≤ ‖A‖_∞ < 1 (stable).
  DecimalStream draw(20240611u);
  Model discrete;
  discrete.A = draw.matrix(3, 3, Real("0.3"));
  discrete.B = draw.matrix(3, 1, Real(1));
  discrete.C = draw.matrix(2, 3, Real(1));
  discrete.D = draw.matrix(2, 1, Real(1));
  const FrfData d_data = perturbed_data(discrete, irregular_grid(7), 2, draw);
  check_gradient("cost gradient, discrete n=3 m=1 p=2", discrete, d_data);

  // Continuous, n = 2, m = 2, p = 1, c = 2, F = 7 log-spaced in 0.1 … 10 rad/s.
  // A = −I + entries in [−0.3, 0.3]: Gershgorin discs centred at ≤ −0.7 with
  // radius ≤ 0.3, so every eigenvalue has real part ≤ −0.4 (stable).
  Model continuous;
  continuous.domain = "continuous";
  continuous.sample_time = 0;
  continuous.A = draw.matrix(2, 2, Real("0.3")) - MatrixR::Identity(2, 2);
  continuous.B = draw.matrix(2, 2, Real(1));
  continuous.C = draw.matrix(1, 2, Real(1));
  continuous.D = draw.matrix(1, 2, Real(1));
  const FrfData c_data = perturbed_data(continuous, log_grid(7, -1, 1), 2, draw);
  check_gradient("cost gradient, continuous n=2 m=2 p=1", continuous, c_data);

  // The true model on its noise-free data is a minimum: V = 0 and ∇V = 0 up to
  // rounding (R_k ≲ 1e-49 per entry, gradient terms O(1) times that).
  FrfData clean = d_data;
  for (std::size_t k = 0; k < clean.omega.size(); ++k)
    clean.Y[k] = frequency_response(discrete, clean.omega[k]) * clean.U[k];
  const CostGradient at_truth = cost_gradient(discrete, clean);
  EXPECT_LT(at_truth.cost, Real("1e-90"));
  EXPECT_LT(at_truth.dA.cwiseAbs().maxCoeff(), Real("1e-45"));
  EXPECT_LT(at_truth.dB.cwiseAbs().maxCoeff(), Real("1e-45"));
  EXPECT_LT(at_truth.dC.cwiseAbs().maxCoeff(), Real("1e-45"));
  EXPECT_LT(at_truth.dD.cwiseAbs().maxCoeff(), Real("1e-45"));

  // Input checks: a model that disagrees with the data names the matrix.
  Model wrong = discrete;
  wrong.B = MatrixR::Ones(3, 2);  // the data have m = 1
  try {
    cost_gradient(wrong, d_data);
    ADD_FAILURE() << "B of the wrong shape accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("B is 3x2"), std::string::npos) << e.what();
  }
  wrong = discrete;
  wrong.C = MatrixR::Ones(1, 3);  // the data have p = 2
  EXPECT_THROW(cost_gradient(wrong, d_data), InputError);
  FrfData bad = d_data;
  bad.variance[4](1, 0) = 0;
  EXPECT_THROW(cost_gradient(discrete, bad), InputError);
}

// Section 5 by hand, M = 4, F = 1: U^[l] = j + d_l, Y^[l] = 2 + e_l with
// d = (1, −1, 0, 0), e = (j, −j, 0, 0). Then Û = j, Ŷ = 2, Ĝ = −2j, |Ĝ|² = 4,
// σ̂²_U = (1 + 1)/3 = 2/3, σ̂²_Y = (1 + 1)/3 = 2/3,
// σ̂²_YU = (j·1 + (−j)(−1))/3 = 2j/3 (Eq. 32: e_l conj d_l).
// Corrected Eq. (31): σ̂²_YU/(Ŷ conj Û) = (2j/3)/(−2j) = −1/3, so
// σ̂²_G = 4 (1/6 + 2/3 + 2/3) = 6 and the data variance is 6/M = 3/2.
// As printed (Ŷ Û = 2j): (2j/3)/(2j) = 1/3, σ̂²_G = 4 (1/6 + 2/3 − 2/3) = 2/3.
// Direct check: δG_l = G(δY/Ŷ − δU/Û) = (−2j)(±j/2 ∓ (−j)) = ±3, whose sample
// variance is (9 + 9)/3 = 6 — the conjugate is right.
// Bound: a handful of operations on exact small numbers: tol 1e-48.
TEST(FrfReference, ErrorsInVariablesUsesConjugate) {
  const Complex j(Real(0), Real(1));
  std::vector<std::vector<MatrixC>> U_l, Y_l;
  const Complex d[4] = {Complex(1), Complex(-1), Complex(0), Complex(0)};
  const Complex e[4] = {j, -j, Complex(0), Complex(0)};
  for (int l = 0; l < 4; ++l) {
    U_l.push_back({MatrixC::Constant(1, 1, j + d[l])});
    Y_l.push_back({MatrixC::Constant(1, 1, Complex(2) + e[l])});
  }
  const SampleStatistics st = sample_statistics("discrete", {Real("0.5")}, U_l, Y_l);
  const Real tol("1e-48");
  EXPECT_EQ(st.M, 4);
  EXPECT_LT(abs(st.data.U[0](0, 0) - j), tol);
  EXPECT_LT(abs(st.data.Y[0](0, 0) - Complex(2)), tol);
  EXPECT_LT(abs(st.data.variance[0](0, 0) - Real(2) / 12), tol);  // σ̂²_Y / M = (2/3)/4
  EXPECT_LT(abs(st.var_U[0](0, 0) - Real(2) / 3), tol);
  EXPECT_LT(abs(st.cov_YU[0](0, 0) - Real(2) / 3 * j), tol);
  const FrfData g = errors_in_variables(st);
  ASSERT_EQ(g.U.size(), 1u);
  EXPECT_LT(abs(g.U[0](0, 0) - Complex(1)), tol);
  EXPECT_LT(abs(g.Y[0](0, 0) - Complex(Real(0), Real(-2))), tol);
  const Real var = g.variance[0](0, 0);
  std::printf("errors-in-variables: sigma_G^2 / M = %s (expected 1.5; printed Eq. 31 gives %s)\n",
              var.str(20).c_str(), (Real(2) / 3 / 4).str(20).c_str());
  EXPECT_LT(abs(var - Real("1.5")), tol);
}

// Eq. (4): N = 16, 3 periods. Channel 0: 2.5 sin(2π·3t/16) gives Z(3) =
// 2.5·√16/2 · e^{−jπ/2} = −5j in every period and Z(5) = 0; channel 1:
// 1.5 cos(2π·2t/16) gives Z(2) = 1.5·4/2 = 3. Bound: 16-term sums of O(1)
// terms with correctly rounded sin/cos: ≲ 100 u: tol 1e-47.
TEST(FrfReference, PeriodSpectraOfSine) {
  const int N = 16, periods = 3;
  std::vector<std::vector<Real>> channels(2);
  for (int t = 0; t < N * periods; ++t) {
    channels[0].push_back(Real("2.5") * sin(2 * pi * 3 * t / N));
    channels[1].push_back(Real("1.5") * cos(2 * pi * 2 * t / N));
  }
  const auto Z = period_spectra(channels, N, periods, {2, 3, 5});
  ASSERT_EQ(Z.size(), 3u);
  const Real tol("1e-47");
  Real worst = 0;
  for (int l = 0; l < periods; ++l) {
    ASSERT_EQ(Z[l].size(), 3u);
    ASSERT_EQ(Z[l][1].rows(), 2);
    worst = std::max(worst, abs(Z[l][1](0, 0) - Complex(Real(0), Real(-5))));
    worst = std::max(worst, abs(Z[l][0](0, 0)));
    worst = std::max(worst, abs(Z[l][2](0, 0)));
    worst = std::max(worst, abs(Z[l][0](1, 0) - Complex(3)));
    worst = std::max(worst, abs(Z[l][1](1, 0)));
  }
  std::printf("period_spectra: worst error %s (tol 1e-47)\n", sci(worst).c_str());
  EXPECT_LT(worst, tol);
  EXPECT_THROW(period_spectra(channels, N, periods, {9}), InputError);
  EXPECT_THROW(period_spectra(channels, N, 2, {1}), InputError);
}

// Sample statistics feed Algorithm 1: M = 3 noise-free repetitions (all equal
// output would give zero variance, so a deterministic ±δ pattern is added to Y
// with δ = 1e-3) — checks the plumbing and that V_sub is small.
TEST(FrfReference, SampleStatisticsPipeline) {
  const Model truth = paper_system();
  const std::vector<Real> omega = irregular_grid(30);
  const FrfData base = make_data(truth, omega, /*frf=*/false);
  std::vector<std::vector<MatrixC>> U_l(3), Y_l(3);
  const Real delta("1e-3");
  for (int l = 0; l < 3; ++l)
    for (std::size_t k = 0; k < omega.size(); ++k) {
      U_l[l].push_back(base.U[k]);
      const Real shift = delta * Real(l - 1);  // −δ, 0, +δ: mean unchanged
      Y_l[l].push_back(base.Y[k] + MatrixC::Constant(1, 1, Complex(shift, shift)));
    }
  const SampleStatistics st = sample_statistics("discrete", omega, U_l, Y_l);
  // σ̂²_Y = (2δ² + 2δ²)/2 = 2δ², divided by M = 3.
  EXPECT_LT(abs(st.data.variance[0](0, 0) - 2 * delta * delta / 3), Real("1e-50"));
  const FrfOptions options = options_for(4, 8);
  const FrfResult result = identify_frf(st.data, options);
  std::printf("sample pipeline: V_sub = %s\n", sci(result.v_sub).c_str());
  EXPECT_LT(result.v_sub, Real("1e-50"));
  Real at = 0;
  EXPECT_LT(worst_response_error(truth, result.model, omega, false, &at), Real("1e-30"));
}

// read_frf_csv: exact decimal parsing, optional G_var column, bad header.
TEST(FrfReference, ReadFrfCsv) {
  const std::string path = ::testing::TempDir() + "frf_reference_test.csv";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("omega,G_re,G_im,G_var\n0.1,0.8876,-1.5e-1,0.01\n0.2,1,2,0.04\n", f);
    std::fclose(f);
  }
  const FrfData data = read_frf_csv(path, "continuous");
  ASSERT_EQ(data.omega.size(), 2u);
  EXPECT_EQ(data.domain, "continuous");
  EXPECT_EQ(data.omega[0], Real("0.1"));
  EXPECT_EQ(data.Y[0](0, 0), Complex(Real("0.8876"), Real("-0.15")));
  EXPECT_EQ(data.variance[1](0, 0), Real("0.04"));
  EXPECT_EQ(data.U[1](0, 0), Complex(1));
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("omega,G_re\n0.1,1\n", f);
    std::fclose(f);
  }
  EXPECT_THROW(read_frf_csv(path), InputError);
  std::remove(path.c_str());
}

// Input checks: each throws InputError naming the problem.
TEST(FrfReference, InputErrors) {
  const Model truth = paper_system();
  const FrfData data = make_data(truth, irregular_grid(40), /*frf=*/false);
  FrfOptions options;
  options.order = 4;
  options.r = 4;  // r ≤ order
  EXPECT_THROW(identify_frf(data, options), InputError);
  options.r = 8;
  options.order = 0;
  EXPECT_THROW(identify_frf(data, options), InputError);
  options.order = 4;

  FrfData repeated = data;
  repeated.omega[7] = repeated.omega[3];
  try {
    identify_frf(repeated, options);
    ADD_FAILURE() << "repeated frequency accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("repeated"), std::string::npos) << e.what();
  }

  FrfData zero_var = data;
  zero_var.variance[5](0, 0) = 0;
  try {
    identify_frf(zero_var, options);
    ADD_FAILURE() << "zero variance accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frequency index 5"), std::string::npos) << e.what();
  }
  FrfData nan_var = data;
  nan_var.variance[2](0, 0) = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_THROW(identify_frf(nan_var, options), InputError);

  FrfData out_of_range = data;
  out_of_range.omega[0] = Real(4);
  EXPECT_THROW(identify_frf(out_of_range, options), InputError);

  // 2 F c = 14 < r (m + p) = 16.
  const FrfData few = make_data(truth, irregular_grid(7), /*frf=*/false);
  EXPECT_THROW(identify_frf(few, options), InputError);

  FrfData bad_shape = data;
  bad_shape.Y[3] = MatrixC::Zero(2, 1);
  EXPECT_THROW(identify_frf(bad_shape, options), InputError);

  std::vector<std::vector<MatrixC>> one(1, std::vector<MatrixC>(1, MatrixC::Ones(1, 1)));
  EXPECT_THROW(sample_statistics("discrete", {Real("0.5")}, one, one), InputError);

  options.continuous_method = "nonsense";
  FrfData cont = make_data(continuous_system(), log_grid(20, -1, 2), false);
  EXPECT_THROW(identify_frf(cont, options), InputError);
}

}  // namespace
