// Golden tests of fast/ against the 50-digit reference: every file in
// fixtures/golden/ (written by fixtures/generate_golden.cpp, format in
// fixtures/README.md) is one case; fast/ runs the same inputs in double and
// is compared in similarity-invariant terms -- singular values of 𝒴 (Eq. 16)
// and Ĝ_p F_r (Eq. 13), poles, the true spectrum on the grid, the identified
// spectrum between the grid points, Ê and the Markov parameters Ĉ Â^{k-1} F̂.
//
// Boost.Math style: each comparison reports its worst error in units of its
// tolerance, where it occurred, and the tolerance with its derivation; the
// reference values are exact to ~1e-40 relative, so the whole error is fast/'s.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "linalg.hpp"
#include "fdsid/io.hpp"
#include "fdsid/model.hpp"
#include "fdsid/spectrum_id.hpp"
#include "tolerance.hpp"

namespace fdsid {
namespace {

using nlohmann::json;
using testing::eigenvalue_condition;
using testing::kU;
using testing::spectrum_tolerance;

const std::filesystem::path kGoldenDir = std::filesystem::path(FDSID_SOURCE_DIR) / "fixtures" / "golden";

std::vector<std::string> golden_cases() {
  std::vector<std::string> names;
  if (std::filesystem::is_directory(kGoldenDir))
    for (const auto& entry : std::filesystem::directory_iterator(kGoldenDir))
      // frf_*.json are Pintelon (2002) cases, checked by tests/frf_golden_test.cpp.
      if (entry.path().extension() == ".json" && entry.path().stem().string().rfind("frf_", 0) != 0)
        names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

double num(const json& v) { return std::stod(v.get<std::string>()); }

Eigen::VectorXd real_vector(const json& v) {
  Eigen::VectorXd x(v.size());
  for (size_t i = 0; i < v.size(); ++i) x(static_cast<Eigen::Index>(i)) = num(v[i]);
  return x;
}

Eigen::MatrixXd real_matrix(const json& v) {
  Eigen::MatrixXd X(v.size(), v[0].size());
  for (size_t i = 0; i < v.size(); ++i)
    for (size_t j = 0; j < v[i].size(); ++j) X(i, j) = num(v[i][j]);
  return X;
}

cplx complex_number(const json& pair) { return {num(pair[0]), num(pair[1])}; }

// One spectrum sample: a decimal (m = 1) or an m x m matrix of [re, im] pairs.
Eigen::MatrixXcd spectrum_sample(const json& v, int m) {
  Eigen::MatrixXcd S(m, m);
  if (m == 1) {
    S(0, 0) = num(v);
    return S;
  }
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) S(a, b) = complex_number(v[a][b]);
  return S;
}

std::string sci(double x, int digits = 3) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*e", digits - 1, x);
  return buffer;
}

// The worst error of one comparison in units of its tolerance, where it
// occurred, and how the tolerance was derived.
struct Worst {
  std::string what, derivation;
  double ratio = 0, error = 0, tolerance = 0;
  std::string where = "-";

  void add(double err, double tol, const std::string& at) {
    if (!(err / tol <= ratio)) {  // NaN errors are recorded too
      ratio = err / tol;
      error = err;
      tolerance = tol;
      where = at;
    }
  }
  std::string summary() const {
    return what + ": worst " + sci(ratio) + " tol (error " + sci(error) + " at " + where + ", tolerance " +
           sci(tolerance) + ")";
  }
};

void expect_within(const Worst& w) {
  EXPECT_LE(w.ratio, 1.0) << w.summary() << "\n  tolerance: " << w.derivation;
}

Eigen::VectorXd singular_values(const Eigen::MatrixXd& X) { return fdsid::testing::singular_values(Eigen::MatrixXd(X)); }

class GoldenFixture : public ::testing::TestWithParam<std::string> {};

TEST_P(GoldenFixture, FastMatchesReference) {
  std::ifstream file(kGoldenDir / (GetParam() + ".json"));
  ASSERT_TRUE(file) << (kGoldenDir / (GetParam() + ".json")).string();
  const json golden = json::parse(file);
  const json& in = golden.at("inputs");
  const json& out = golden.at("outputs");
  const int M = in.at("M"), p = in.at("p"), r = in.at("r"), n = in.at("order");
  const std::string method_name = in.at("method");
  ASSERT_TRUE(method_name == "akcay2011" || method_name == "vo1997") << method_name;
  const Method method = method_name == "vo1997" ? Method::VanOverschee1997 : Method::Akcay2011;

  // The fast pipeline in double on the same inputs.
  const StateSpace truth = read_model(std::string(FDSID_SOURCE_DIR) + "/" + in.at("system").get<std::string>());
  SpectrumData data;
  data.m = truth.outputs();
  data.M = M;
  data.S = sample_spectrum(truth, M);
  const int m = data.m, N = 2 * M;
  ASSERT_EQ(m, in.at("m").get<int>());
  ASSERT_EQ(N, in.at("N").get<int>());
  const Eigen::MatrixXd shat = fourier_coefficients(data, Extension::HermitianPart);
  const Eigen::MatrixXd Y = akcay_matrix(shat, m, p, r);
  const Eigen::MatrixXd GF = van_overschee_matrix(shat, m, p, r);
  SpectrumOptions options;
  options.method = method;
  options.order = n;
  options.p = p;
  options.r = r;
  const SpectrumResult result = identify_spectrum(data, options);
  ASSERT_EQ(result.order, n);

  // Golden values.
  const Eigen::VectorXd sigma_Y = real_vector(out.at("singular_values_Y"));
  const Eigen::VectorXd sigma_GF = real_vector(out.at("singular_values_GF"));
  const Eigen::VectorXd& sigma_H = method == Method::Akcay2011 ? sigma_Y : sigma_GF;  // step 3's matrix
  std::vector<Eigen::MatrixXcd> S_true, S_identified;
  for (const json& v : out.at("true_spectrum").at("S")) S_true.push_back(spectrum_sample(v, m));
  for (const json& v : out.at("identified_spectrum").at("S")) S_identified.push_back(spectrum_sample(v, m));
  ASSERT_EQ(static_cast<int>(S_true.size()), M + 1);
  ASSERT_EQ(static_cast<int>(S_identified.size()), M);
  double S_max = 0;  // max_z ||S(z)||_F over the grid and the midpoints, as in tolerance.hpp
  for (const auto& S : S_true) S_max = std::max(S_max, S.norm());
  for (const auto& S : S_identified) S_max = std::max(S_max, S.norm());

  // The one tolerance of Algorithm 1 (tests/tolerance.hpp): relative spectrum
  // error <= 4 (p + r) m log2(N) u κ, κ = σ1/σ_{2n} of the matrix whose range
  // step 3 takes (𝒴, or Ĝ_p F_r for vo1997). Wedin's sin Θ bound divides by the
  // gap σ_{2n} - σ_{2n+1}, which is σ_{2n} when the matrix has rank 2n (𝒴 on
  // noise-free data: σ_{2n+1} is 50-digit rounding) and is used as written for
  // Ĝ_p F_r, whose rank may exceed 2n at small M (Table 1).
  const double sigma_next = 2 * n < sigma_H.size() ? sigma_H(2 * n) : 0.0;
  const double kappa = sigma_H(0) / (sigma_H(2 * n - 1) - sigma_next);
  const double tol_alg = spectrum_tolerance(p, r, m, N, kappa);

  std::vector<Worst> checks;

  // 1. Singular values of 𝒴 and of Ĝ_p F_r. Weyl: |σ̂_i - σ_i| <= ||δX||_2, and
  // tolerance.hpp bounds ||δ𝒴||_2 (likewise ||δ(Ĝ_p F_r)||_2, one of its two
  // Hankel terms) by weyl = (p + r) m log2(N) u ||S||_inf. We compare relative
  // to σ1, as the paper's Table 1 is read: tol = tol_alg · σ1 = 4 κ σ1 (p + r)
  // m log2(N) u, which is >= weyl whenever ||S||_inf <= 4 κ σ1 (true for every
  // fixture: κ >= 4.5 and ||S||_inf <= 4 σ1); the max with weyl keeps the bound
  // valid where it is not. For i > 2n the reference σ_i is zero to 50
  // digits and the double one is rounding, so this absolute floor is all that
  // is asserted there.
  const double weyl = (p + r) * m * std::log2(double(N)) * kU * S_max;
  for (int which = 0; which < 2; ++which) {
    const Eigen::VectorXd& expected = which == 0 ? sigma_Y : sigma_GF;
    const Eigen::VectorXd actual = singular_values(which == 0 ? Y : GF);
    const double tol = std::max(tol_alg * expected(0), weyl);
    Worst w;
    w.what = which == 0 ? "singular values of Y (Eq. 16)" : "singular values of G_p F_r (Eq. 13)";
    w.derivation = "Weyl |dsigma_i| <= ||dX||_2 <= (p+r) m log2(N) u ||S||_inf = " + sci(weyl) + "; tol = max(" +
                   sci(tol_alg) + " (spectrum_tolerance, kappa = " + sci(kappa) + ") x sigma1 = " + sci(expected(0)) +
                   ", Weyl) = " + sci(tol) + ", absolute, also the floor for i > 2n";
    ASSERT_EQ(actual.size(), expected.size()) << w.what;
    for (Eigen::Index i = 0; i < expected.size(); ++i)
      w.add(std::abs(actual(i) - expected(i)), tol, "sigma_" + std::to_string(i + 1));
    checks.push_back(w);
  }
  {
    // 1b. The singular values identify_spectrum's own step 3 reports (the
    // eigen-decomposition of 𝒴 where it is symmetric, every SISO fixture with
    // p = r; Jacobi otherwise), held to Weyl's bound alone, not to the
    // algorithm's κ-scaled tolerance: the matrix carries ‖δX‖₂ ≤ weyl from the
    // Fourier coefficients (above), and a backward-stable decomposition adds
    // ‖E‖₂ ≤ c·(p m)·u·σ1 (spectrum_id.cpp, step 3), c = 1 taken: the
    // bound is the sum.
    const double tol = weyl + p * m * kU * sigma_H(0);
    Worst w;
    w.what = "identify_spectrum's step 3 singular values";
    w.derivation = "Weyl: |dsigma_i| <= weyl + (p m) u sigma1 = " + sci(weyl) + " + " + sci(p * m * kU * sigma_H(0)) +
                   " = " + sci(tol) + ", absolute";
    ASSERT_EQ(result.singular_values.size(), sigma_H.size()) << w.what;
    for (Eigen::Index i = 0; i < sigma_H.size(); ++i)
      w.add(std::abs(result.singular_values(i) - sigma_H(i)), tol, "sigma_" + std::to_string(i + 1));
    checks.push_back(w);
  }

  // 2. Poles. First order, |δλ_i| <= κ_i ||δÃ||_2 (Wilkinson), κ_i the
  // eigenvalue condition number of Ã = (J_d U_2n)^† J_u U_2n (step 5: the
  // matrix whose eigenvalues are computed; the block-diagonal Â of step 7 is
  // normal and would hide it). Ã is a smooth function of U_2n whose relative
  // perturbation is bounded like the spectrum's, ||δÃ|| <= tol_alg ||Ã||; so
  // tol = tol_alg · κ(Ã) · ||Ã||_2, κ(Ã) = max_i κ_i (tolerance.hpp).
  {
    const Eigen::MatrixXd& H = method == Method::Akcay2011 ? Y : GF;
    const Eigen::MatrixXd U2n = fdsid::testing::left_singular_vectors(H, 2 * n);
    const Eigen::MatrixXd A_tilde = shift_matrix(U2n, m);
    const double kappa_eig = eigenvalue_condition(A_tilde);
    const double A_norm = singular_values(A_tilde)(0);
    const double tol = tol_alg * kappa_eig * A_norm;
    Worst w;
    w.what = "poles";
    w.derivation = "|dlambda| <= kappa_i ||dA~||; tol = " + sci(tol_alg) + " (spectrum_tolerance) x kappa(A~) = " +
                   sci(kappa_eig) + " x ||A~||_2 = " + sci(A_norm) + " = " + sci(tol);
    std::vector<cplx> expected;
    for (const json& z : out.at("poles")) expected.push_back(complex_number(z));
    const Eigen::VectorXcd actual = poles(result.model);
    ASSERT_EQ(static_cast<size_t>(actual.size()), expected.size());
    // Match by the permutation with the smallest largest distance (n! <= 720
    // for the orders of the fixtures): conjugate pairs have equal moduli, so
    // the sorted orders of the two sides may differ in the last bit.
    std::vector<int> perm(expected.size()), best;
    std::iota(perm.begin(), perm.end(), 0);
    double best_max = INFINITY;
    do {
      double worst = 0;
      for (size_t i = 0; i < expected.size(); ++i) worst = std::max(worst, std::abs(actual(perm[i]) - expected[i]));
      if (worst < best_max) {
        best_max = worst;
        best = perm;
      }
    } while (std::next_permutation(perm.begin(), perm.end()));
    for (size_t i = 0; i < expected.size(); ++i) {
      std::ostringstream at;
      at << "pole " << i + 1 << " (" << sci(expected[i].real(), 6) << (expected[i].imag() < 0 ? " - " : " + ")
         << sci(std::abs(expected[i].imag()), 6) << "i)";
      w.add(std::abs(actual(best[i]) - expected[i]), tol, at.str());
    }
    checks.push_back(w);
  }

  // 3. True spectrum on the grid (fdsid::sample_spectrum, the input of every
  // other comparison). Not an output of Algorithm 1, so its tolerance is that
  // of G(z) = D + C (zI - A)^{-1} B in double, first order per point: the
  // entries carry relative error u (decimal → double), LU of zI - A is
  // backward stable (||ΔA|| <= 2n u ||zI - A||), so with R = (zI - A)^{-1},
  //   ||δG|| <= (2n + 3) u (||C|| ||R|| (1 + ||A||) ||R B|| + ||C|| ||R B|| + ||D||),
  //   ||δS|| = ||δG G^H + G δG^H|| <= 2 ||G|| ||δG|| + m u ||S||,
  // spectral norms (Frobenius ≤ √m spectral: one more factor √m on ||δS||_F).
  {
    Worst w;
    w.what = "true spectrum on the grid";
    w.derivation = "first-order error of G(z) = D + C (zI-A)^{-1} B with rounded entries and LU: sqrt(m) (2 ||G|| "
                   "||dG|| + m u ||S||), ||dG|| <= (2n+3) u (||C|| ||R|| (1+||A||) ||RB|| + ||C|| ||RB|| + ||D||), "
                   "relative to max||S||_F";
    const int order = truth.order();
    const double norm_A = singular_values(truth.A)(0), norm_C = singular_values(truth.C)(0),
                 norm_D = singular_values(truth.D)(0);
    for (int k = 0; k <= M; ++k) {
      const cplx z = std::polar(1.0, M_PI * k / M);
      const Eigen::MatrixXcd zI_A = z * Eigen::MatrixXcd::Identity(order, order) - truth.A.cast<cplx>();
      const Eigen::MatrixXcd R = fdsid::testing::inverse(zI_A);
      const Eigen::MatrixXcd RB = R * truth.B.cast<cplx>();
      const double norm_R = fdsid::testing::singular_values(Eigen::MatrixXcd(R))(0);
      const double norm_RB = fdsid::testing::singular_values(Eigen::MatrixXcd(RB))(0);
      const Eigen::MatrixXcd G = transfer(truth, z);
      const double norm_G = fdsid::testing::singular_values(Eigen::MatrixXcd(G))(0);
      const double dG = (2 * order + 3) * kU * (norm_C * norm_R * (1 + norm_A) * norm_RB + norm_C * norm_RB + norm_D);
      const double tol = std::sqrt(double(m)) * (2 * norm_G * dG + m * kU * S_true[k].norm()) / S_max;
      const Eigen::MatrixXcd S = Eigen::Map<const Eigen::MatrixXcd>(data.S.col(k).data(), m, m);
      w.add((S - S_true[k]).norm() / S_max, tol, "omega = pi*" + std::to_string(k) + "/" + std::to_string(M));
    }
    checks.push_back(w);
  }

  // 4. Identified spectrum between the grid points: the quantity tolerance.hpp
  // bounds, max_z ||Ŝ_fast(z) - Ŝ_ref(z)||_F / max_z ||S(z)||_F <= tol_alg. (For
  // vo1997 Ŝ_ref is biased, not S; the same perturbation argument holds around it.)
  {
    Worst w;
    w.what = "identified spectrum between the grid points";
    w.derivation = "spectrum_tolerance(p=" + std::to_string(p) + ", r=" + std::to_string(r) + ", m=" +
                   std::to_string(m) + ", N=" + std::to_string(N) + ", sigma1/(sigma_2n - sigma_2n+1) = " +
                   sci(kappa) + ") = " + sci(tol_alg) + ", relative to max||S||_F = " + sci(S_max);
    for (int k = 1; k <= M; ++k) {
      const cplx z = std::polar(1.0, M_PI * (k - 0.5) / M);
      const double err = (power_spectrum(result.model, z) - S_identified[k - 1]).norm() / S_max;
      w.add(err, tol_alg, "omega = pi*(" + std::to_string(k) + " - 1/2)/" + std::to_string(M));
    }
    checks.push_back(w);
  }

  // 5. Ê and the Markov parameters Ĉ Â^{k-1} F̂ (similarity invariant): they
  // are the Fourier coefficients of Ŝ (Ŝ(z) = Ê + Σ_k Ĉ Â^{k-1} F̂ z^{-k} + its
  // transpose at 1/z), and a Fourier coefficient is bounded by the sup of its
  // function: |δ entry| <= max_z ||δŜ(z)||_2 <= tol_alg · max_z ||S(z)||_F.
  {
    Worst w;
    w.what = "E and Markov parameters C A^(k-1) F";
    w.derivation = "Fourier coefficients of S^: |d| <= max_z ||dS^(z)|| <= tol_alg = " + sci(tol_alg) +
                   " x max||S||_F = " + sci(S_max);
    const double tol = tol_alg * S_max;
    const SpectralSummands& s = result.summands;
    const Eigen::MatrixXd E = real_matrix(out.at("E"));
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b)
        w.add(std::abs(s.E(a, b) - E(a, b)), tol, "E(" + std::to_string(a + 1) + "," + std::to_string(b + 1) + ")");
    Eigen::MatrixXd power = Eigen::MatrixXd::Identity(n, n);
    const json& markov = out.at("markov");
    for (size_t k = 0; k < markov.size(); ++k) {
      const Eigen::MatrixXd expected = real_matrix(markov[k]);
      const Eigen::MatrixXd actual = s.C * power * s.F;
      for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b)
          w.add(std::abs(actual(a, b) - expected(a, b)), tol,
                "C A^" + std::to_string(k) + " F (" + std::to_string(a + 1) + "," + std::to_string(b + 1) + ")");
      power = power * s.A;
    }
    checks.push_back(w);
  }

  // Summary: one line per case (stdout and the test's XML properties).
  const auto worst = std::max_element(checks.begin(), checks.end(),
                                      [](const Worst& a, const Worst& b) { return a.ratio < b.ratio; });
  const std::string line = GetParam() + ": worst of all in " + worst->summary();
  RecordProperty("worst_error_in_tolerances", sci(worst->ratio));
  RecordProperty("worst_error_where", worst->what + " at " + worst->where);
  std::printf("[golden] %s\n", line.c_str());
  for (const Worst& w : checks)
    std::printf("[golden]   %s\n[golden]     tolerance: %s\n", w.summary().c_str(), w.derivation.c_str());
  SCOPED_TRACE(line);
  for (const Worst& w : checks) expect_within(w);
}

// Names the parameterised cases after their files (letters, digits and '_').
std::string case_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

INSTANTIATE_TEST_SUITE_P(Reference, GoldenFixture, ::testing::ValuesIn(golden_cases()), case_name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(GoldenFixture);  // AllCasesPresent says what is missing

TEST(GoldenFixtures, AllCasesPresent) {
  // The six cases of fixtures/generate_golden.cpp; rerun it if one is missing.
  const std::vector<std::string> expected = {
      "akcay2011_M16_p16_r16_akcay2011", "akcay2011_M16_p9_r8_akcay2011",  "akcay2011_M16_p9_r8_vo1997",
      "akcay2011_M64_p20_r20_akcay2011", "akcay2011_M64_p9_r8_akcay2011", "mimo2x2_example_M32_p12_r12_akcay2011"};
  const std::vector<std::string> present = golden_cases();
  for (const std::string& name : expected)
    EXPECT_TRUE(std::find(present.begin(), present.end(), name) != present.end())
        << name << ".json missing from " << kGoldenDir.string() << " (run generate_golden <repo>/fixtures)";
}

}  // namespace
}  // namespace fdsid
