// Golden tests of fast/'s Pintelon (2002) FRF identification against the
// 50-digit reference: every fixtures/golden/frf_*.json (written by
// fixtures/generate_frf_golden.cpp, format in fixtures/README.md) carries SISO
// data (ω, U, Y, σ² as "%.17g" doubles), the options, and what
// reference::identify_frf computed from exactly those numbers. fast/'s
// identify_frf_fixed runs on the same doubles with the same order, r, method
// and ω_scale and is compared in similarity-invariant terms: poles, Ĝ at the
// data frequencies and at the midpoints, the singular values of step 1c, V_SUB.
//
// Tolerances (tests/frf_tolerance.hpp, derived there, not tuned):
//   ε_A = 10 √(2Fc · r(m+p)) · u · max(κ, cond_3), u κ = error_estimate of fast/,
// the relative error of (Â, B̂, Ĉ, D̂) from the backward error of step 1b's QR
// of Zᵀ (2Fc × r(m+p)), Higham & Mary's probabilistic λ √(rows·cols) u with
// λ = 10, amplified by κ; cond_3 is the condition of step 3's (B, D) least
// squares, which κ omits (see below; as in
// properties/frf_vs_reference_property.cpp). The noisy cases use the same tolerances: the data
// are fixed numbers, both implementations compute the same mathematical
// function of them (the estimator), so their difference is again rounding
// amplified by the conditioning of that function at those data, which κ
// measures (the noise itself is not an error here). The reference's own error
// (u ≈ 1e-50) and the 40-digit rounding of its outputs are nil in double.
//
// Boost.Math style: each comparison prints its worst error in units of its
// tolerance and where.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "linalg.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "frf_tolerance.hpp"
#include "tolerance.hpp"

namespace fdsid {
namespace {

using nlohmann::json;
using testing::kU;

const std::filesystem::path kGoldenDir = std::filesystem::path(FDSID_SOURCE_DIR) / "fixtures" / "golden";

std::vector<std::string> frf_golden_cases() {
  std::vector<std::string> names;
  if (std::filesystem::is_directory(kGoldenDir))
    for (const auto& entry : std::filesystem::directory_iterator(kGoldenDir)) {
      const std::string stem = entry.path().stem().string();
      if (entry.path().extension() == ".json" && stem.rfind("frf_", 0) == 0) names.push_back(stem);
    }
  std::sort(names.begin(), names.end());
  return names;
}

double num(const json& v) { return std::stod(v.get<std::string>()); }
cplx complex_number(const json& pair) { return {num(pair[0]), num(pair[1])}; }

std::string sci(double x, int digits = 3) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*e", digits - 1, x);
  return buffer;
}

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

class FrfGoldenFixture : public ::testing::TestWithParam<std::string> {};

TEST_P(FrfGoldenFixture, FastMatchesReference) {
  std::ifstream file(kGoldenDir / (GetParam() + ".json"));
  ASSERT_TRUE(file) << (kGoldenDir / (GetParam() + ".json")).string();
  const json golden = json::parse(file);
  ASSERT_EQ(golden.at("format").get<std::string>(), "fdsid-golden-frf-1");
  const json& in = golden.at("inputs");
  const json& dat = golden.at("data");
  const json& out = golden.at("outputs");
  const int n = in.at("order"), r = in.at("r");
  ASSERT_EQ(in.at("m").get<int>(), 1);
  ASSERT_EQ(in.at("p").get<int>(), 1);
  ASSERT_EQ(in.at("c").get<int>(), 1);
  const std::string method_name = in.at("method");
  ASSERT_TRUE(method_name == "discrete" || method_name == "bilinear" || method_name == "orthogonal") << method_name;
  const bool cont = method_name != "discrete";
  const ContinuousMethod method = method_name == "orthogonal" ? ContinuousMethod::Orthogonal : ContinuousMethod::Bilinear;
  const double ws = cont ? num(in.at("omega_scale")) : 1.0;

  // The file's data, exactly the doubles the reference was fed.
  FrfData d;
  d.domain = cont ? Domain::Continuous : Domain::Discrete;
  const int F = static_cast<int>(dat.at("omega").size());
  ASSERT_EQ(F, in.at("F").get<int>());
  d.omega.resize(F);
  for (int k = 0; k < F; ++k) {
    d.omega(k) = num(dat.at("omega")[k]);
    d.U.push_back(Eigen::MatrixXcd::Constant(1, 1, complex_number(dat.at("U")[k])));
    d.Y.push_back(Eigen::MatrixXcd::Constant(1, 1, complex_number(dat.at("Y")[k])));
    d.variance.push_back(Eigen::MatrixXd::Constant(1, 1, num(dat.at("variance")[k])));
  }
  const FrfResult res = identify_frf_fixed(d, n, r, method, cont ? ws : 0.0);
  ASSERT_EQ(res.order, n);
  const StateSpace& est = res.model;
  const int m = 1, p = 1, c = 1;

  // ε_A of tests/frf_tolerance.hpp and the model in the domain where
  // Algorithm 1 ran (where ε_A applies): w-domain (bilinear), s̃ = s/ω_s (orthogonal).
  const StateSpace inner = !cont ? est
                           : method == ContinuousMethod::Bilinear ? testing::continuous_to_bilinear(est, ws)
                                                                  : testing::scaled(est, ws);
  auto xi_of = [&](double w) -> cplx {
    if (!cont) return std::polar(1.0, w);
    return method == ContinuousMethod::Bilinear ? testing::bilinear_point(w, ws) : cplx(0.0, w / ws);
  };
  // Step 3 (Eq. 17, W = 1/σ) solves a real least-squares problem for (B̂, D̂)
  // given (Â, Ĉ), regressor rows Re/Im of [Ĉ R_k U_k, U_k]/σ_k, R_k = (ξ_k I − Â)⁻¹
  // in the inner domain. κ of error_estimate does not contain its condition
  // cond_3, which can be the larger one (the orthogonal-basis case: ξ = s̃ up
  // to 316j, where G ≈ D̂); as in properties/frf_vs_reference_property.cpp the
  // relative error of B̂, D̂ is then u · cond_3 amplified like the rest, so
  // ε_A uses u · max(κ, cond_3) (= error_estimate when κ ≥ cond_3).
  double cond3 = 0;
  {
    const int nn = inner.order();
    Eigen::MatrixXd X(2 * F, nn + 1);
    for (int k = 0; k < F; ++k) {
      Eigen::MatrixXcd M = -inner.A.cast<cplx>();
      M.diagonal().array() += xi_of(d.omega(k));
      const Eigen::RowVectorXcd cr =
          fdsid::testing::solve(Eigen::MatrixXcd(M.transpose()), Eigen::MatrixXcd(inner.C.transpose().cast<cplx>())).transpose();
      const cplx Uk = d.U[k](0, 0);
      const double wk = 1.0 / std::sqrt(d.variance[k](0, 0));
      for (int j = 0; j <= nn; ++j) {
        const cplx v = wk * (j < nn ? cr(j) * Uk : Uk);
        X(2 * k, j) = v.real();
        X(2 * k + 1, j) = v.imag();
      }
    }
    const Eigen::VectorXd sv = fdsid::testing::singular_values(Eigen::MatrixXd(X));
    cond3 = sv(0) / sv(sv.size() - 1);
  }
  const double qr_const = testing::frf_qr_constant(F, c, r, m, p);
  const double eps_A = qr_const * kU * std::max(res.condition, cond3);
  const std::string eps_text = "eps_A = 10 sqrt(2Fc r(m+p)) = " + sci(qr_const) + " x u max(kappa = " +
                               sci(res.condition) + ", cond_3 = " + sci(cond3) + ") = " + sci(eps_A);
  std::vector<Worst> checks;

  // 1. Poles. First-order Bauer–Fike per eigenvalue of the inner Â:
  // |δμ_i| ≤ ε_A ‖Â‖₂ κ_i, κ_i = ‖x_i‖‖y_i‖/|y_iᴴx_i|, mapped to the model's
  // domain by |dλ/dμ| (bilinear 2ω_s/|1 − μ|², orthogonal ω_s), plus for the
  // bilinear variant the back-transformation's rounding 4n u cond(I − Â_w)
  // ‖Â_c‖ κ(Â_c) (as in frf_tolerance.hpp), plus u|λ| for the 40-digit value
  // read into double.
  {
    Worst w;
    w.what = "poles";
    w.derivation = eps_text + "; tol_i = eps_A ||A_inner|| kappa_i |dlambda/dmu| + back-transform 4n u cond(I-A_w) "
                              "||A_c|| kappa(A_c) + u|lambda|; nearest fast pole to each reference pole";
    const fdsid::testing::EigenDecomposition es = fdsid::testing::eigen_decomposition(inner.A);
    const Eigen::MatrixXcd& V = es.vectors;
    const Eigen::MatrixXcd& W = es.inverse_vectors;
    const double nA = testing::spectral_norm(inner.A.cast<cplx>());
    double back = 0;
    if (cont && method == ContinuousMethod::Bilinear) {
      const Eigen::VectorXd sv =
          fdsid::testing::singular_values(Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n) - inner.A));
      back = 4.0 * n * kU * sv(0) / sv(n - 1) * testing::spectral_norm(est.A.cast<cplx>()) *
             testing::eigenvalue_condition(est.A);
    }
    Eigen::VectorXcd lam(n);
    Eigen::VectorXd tol_i(n);
    for (int i = 0; i < n; ++i) {
      const cplx mu = es.values(i);
      const double kappa = V.col(i).norm() * W.row(i).norm();
      double deriv = 1;
      lam(i) = mu;
      if (cont && method == ContinuousMethod::Bilinear) {
        lam(i) = ws * (1.0 + mu) / (1.0 - mu);
        deriv = 2 * ws / std::norm(1.0 - mu);
      } else if (cont) {
        lam(i) = ws * mu;
        deriv = ws;
      }
      tol_i(i) = eps_A * nA * kappa * deriv + back;
    }
    const json& ref_poles = out.at("poles");
    ASSERT_EQ(static_cast<int>(ref_poles.size()), n);
    for (int i = 0; i < n; ++i) {
      const cplx expected = complex_number(ref_poles[i]);
      Eigen::Index j = 0;
      const double err = (lam.array() - expected).abs().minCoeff(&j);
      w.add(err, tol_i(j) + kU * std::abs(expected),
            "pole " + std::to_string(i + 1) + " (" + sci(expected.real(), 6) + (expected.imag() < 0 ? " - " : " + ") +
                sci(std::abs(expected.imag()), 6) + "i)");
    }
    checks.push_back(w);
  }

  // 2. Ĝ at the data frequencies and at the midpoints: first-order expansion
  // of G = D + C R B with every matrix perturbed by ε_A relatively,
  // ‖δG(ξ)‖ ≤ ε_A s(ξ) (frf_tolerance.hpp, transfer_sensitivity of the inner model).
  std::vector<double> g_tol_data(F);
  {
    Worst w;
    w.what = "G at the data frequencies and the midpoints";
    w.derivation = eps_text + "; tol = eps_A s(xi), s = ||CR|| ||A|| ||RB|| + ||C|| ||RB|| + ||CR|| ||B|| + ||D|| "
                              "of the inner model";
    const json& G_data = out.at("G_data");
    ASSERT_EQ(static_cast<int>(G_data.size()), F);
    for (int k = 0; k < F; ++k) {
      const double tol = eps_A * testing::transfer_sensitivity(inner, xi_of(d.omega(k)));
      g_tol_data[k] = tol;
      w.add(std::abs(frequency_response(est, d.omega(k))(0, 0) - complex_number(G_data[k])), tol,
            "data omega_" + std::to_string(k + 1) + " = " + sci(d.omega(k), 6));
    }
    const json& mids = out.at("omega_mid");
    const json& G_mid = out.at("G_mid");
    ASSERT_EQ(mids.size(), G_mid.size());
    for (size_t k = 0; k < mids.size(); ++k) {
      const double om = num(mids[k]);
      const double tol = eps_A * testing::transfer_sensitivity(inner, xi_of(om));
      w.add(std::abs(frequency_response(est, om)(0, 0) - complex_number(G_mid[k])), tol,
            "midpoint " + std::to_string(k + 1) + " omega = " + sci(om, 6));
    }
    checks.push_back(w);
  }

  // 3. Singular values of step 1c, M = C_Y^{-1/2} R22ᵀ. Weyl: |σ̂_i − σ_i| ≤
  // ‖δM‖₂. Step 1b's QR has backward error ≤ 10 √(rows·cols) u ‖Z‖ (rows = 2Fc,
  // cols = r(m+p), the constant of frf_qr_constant); the projection onto the
  // complement of 𝐔^re (R22) and the whitening by L⁻¹ amplify it relative to
  // ‖M‖ = σ_1 by at most the conditioning κ ≥ cond(R11) that error_estimate
  // already carries, so ‖δM‖₂ ≤ ε_A σ_1 (absolute, the same for every i; for
  // i > n of noise-free cases σ_i is the data's double rounding, ≲ 1e-14 σ_1,
  // and this absolute bound is all that can be asserted).
  {
    Worst w;
    w.what = "singular values of step 1c";
    const Eigen::VectorXd expected = [&] {
      const json& s = out.at("singular_values");
      Eigen::VectorXd v(s.size());
      for (size_t i = 0; i < s.size(); ++i) v(static_cast<Eigen::Index>(i)) = num(s[i]);
      return v;
    }();
    ASSERT_EQ(res.singular_values.size(), expected.size());
    const double tol = eps_A * expected(0);
    w.derivation = "Weyl |dsigma_i| <= ||dM||_2 <= eps_A sigma_1 = " + sci(eps_A) + " x " + sci(expected(0)) + " = " +
                   sci(tol) + "; " + eps_text;
    for (Eigen::Index i = 0; i < expected.size(); ++i)
      w.add(std::abs(res.singular_values(i) - expected(i)), tol, "sigma_" + std::to_string(i + 1));
    checks.push_back(w);
  }

  // 4. V_SUB = Σ |e_k|²/σ²_k, e_k = Y_k − Ĝ_k U_k. With |δĜ_k| ≤ g_k = ε_A s(ξ_k)
  // (check 2) and the double rounding of e_k, ≤ 2u(|Y_k| + |Ĝ_k||U_k|), so
  // |δe_k| ≤ h_k = g_k|U_k| + 2u(|Y_k| + |Ĝ_k||U_k|):
  //   |δV| ≤ 2 Σ |e_k| h_k/σ²_k + Σ h_k²/σ²_k ≤ 2 √V √H + H, H = Σ h_k²/σ²_k
  // (Cauchy–Schwarz), plus the summation's own rounding F u V.
  {
    Worst w;
    w.what = "V_SUB (Eq. 35)";
    const double V_ref = num(out.at("v_sub"));
    double H = 0;
    for (int k = 0; k < F; ++k) {
      const double U = std::abs(d.U[k](0, 0)), Gk = std::abs(complex_number(out.at("G_data")[k]));
      const double h = g_tol_data[k] * U + 2 * kU * (std::abs(d.Y[k](0, 0)) + Gk * U);
      H += h * h / d.variance[k](0, 0);
    }
    const double tol = 2 * std::sqrt(V_ref * H) + H + F * kU * V_ref;
    w.derivation = "|dV| <= 2 sqrt(V H) + H + F u V, H = sum (eps_A s(xi_k)|U_k| + 2u(|Y_k| + |G_k||U_k|))^2 / "
                   "sigma2_k = " + sci(H) + ", V = " + sci(V_ref);
    w.add(std::abs(res.v_sub - V_ref), tol, "V = " + sci(V_ref, 6) + " (relative tol " + sci(tol / V_ref) + ")");
    checks.push_back(w);
  }

  const auto worst = std::max_element(checks.begin(), checks.end(),
                                      [](const Worst& a, const Worst& b) { return a.ratio < b.ratio; });
  const std::string line = GetParam() + ": worst of all in " + worst->summary();
  RecordProperty("worst_error_in_tolerances", sci(worst->ratio));
  RecordProperty("worst_error_where", worst->what + " at " + worst->where);
  std::printf("[golden] %s\n", line.c_str());
  for (const Worst& w : checks)
    std::printf("[golden]   %s\n[golden]     tolerance: %s\n", w.summary().c_str(), w.derivation.c_str());
  SCOPED_TRACE(line);
  for (const Worst& w : checks) EXPECT_LE(w.ratio, 1.0) << w.summary() << "\n  tolerance: " << w.derivation;
}

std::string case_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

INSTANTIATE_TEST_SUITE_P(Reference, FrfGoldenFixture, ::testing::ValuesIn(frf_golden_cases()), case_name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FrfGoldenFixture);  // AllFrfCasesPresent says what is missing

TEST(FrfGoldenFixtures, AllFrfCasesPresent) {
  // The cases of fixtures/generate_frf_golden.cpp; rerun it if one is missing.
  const std::vector<std::string> expected = {
      "frf_continuous4_F50_r8_bilinear", "frf_continuous4_F50_r8_bilinear_noisy", "frf_continuous4_F50_r8_orthogonal",
      "frf_pintelon2002_F40_r8_discrete", "frf_pintelon2002_F40_r8_discrete_noisy"};
  const std::vector<std::string> present = frf_golden_cases();
  for (const std::string& name : expected)
    EXPECT_TRUE(std::find(present.begin(), present.end(), name) != present.end())
        << name << ".json missing from " << kGoldenDir.string() << " (run generate_frf_golden <repo>/fixtures)";
}

}  // namespace
}  // namespace fdsid
