#pragma once
/// One adapter per implementation, so that a claim of the papers is written
/// once as a typed test (tests/scalar_typed_test.cpp) and run in double
/// (fast/) and in 50 digits (reference/): STYLE.md, "Tests templated over the
/// scalar". Each member is the side's own call, nothing more; the adapters
/// compute no expected values and assert nothing.
///
/// Decimal constants enter through number("0.5"): strtod (correctly rounded)
/// on the fast side, the reference's exact decimal parser on the other, never
/// a double literal. Both sides read the Section 4 system from the same
/// decimal strings, fixtures/systems/akcay2011.json.
#include <cmath>
#include <cstdio>
#include <complex>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <boost/math/constants/constants.hpp>
#include <Eigen/Dense>
#include <Eigen/LU>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/io.hpp"
#include "fdsid/model.hpp"
#include "fdsid/reference/io.hpp"
#include "fdsid/reference/spectrum_id.hpp"
#include "fdsid/spectrum_id.hpp"
#include "generators.hpp"
#include "linalg.hpp"

namespace fdsid::testing {

inline std::string source_path(const std::string& relative) { return std::string(FDSID_SOURCE_DIR) + "/" + relative; }

/// What a failed identification reported: whether it was the split of step 6
/// and its one-line message ("step 6: …" on both sides).
struct StepFailure {
  bool thrown = false;
  bool split = false;
  std::string what;
};

/// What an identification returned: the model, its order and the singular
/// values of step 3 (of 𝒴, or of Ĝ_pF_r for vo1997), largest first.
template <class Model, class Real>
struct Identification {
  Model model;
  int order = 0;
  std::vector<Real> sigma;
};

/// Akçay (2011) Table 1 at one M: singular values of Ĝ_9F_8 and of 𝒴
/// (p = 9, r = 8), max |Im Ĝ_9F_8| and max |S_k| of the data.
template <class Real>
struct Table1Sigmas {
  std::vector<Real> vo, akcay;
  Real vo_imaginary = 0;
  Real max_S = 0;
};

/// fast/: double precision, FFT-based 𝒴 (Eq. 19), Eigen's double decompositions
/// compiled once (tests/linalg.hpp).
struct FastSide {
  using Real = double;
  using Complex = std::complex<double>;
  using Model = StateSpace;
  using Data = SpectrumData;
  using Matrix = Eigen::MatrixXd;  // 𝒴 and Ĝ_pF_r are real here (built from real ŝ)

  static constexpr const char* name = "fast (double)";
  /// Unit roundoff u = 2^-53 (round to nearest): fl(x ∘ y) = (x ∘ y)(1 + δ), |δ| ≤ u.
  static Real unit_roundoff() { return std::numeric_limits<double>::epsilon() / 2; }
  static Real number(const char* decimal) { return std::strtod(decimal, nullptr); }
  static Real pi() { return M_PI; }
  static std::string show(Real x) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6e", x);
    return text;
  }
  /// How this side prints an eigenvalue modulus in a step-6 message: fmt(·, 4).
  static std::string printed_modulus(const char* decimal) { return fmt(number(decimal), 4); }

  static Model paper_system() { return read_model(source_path("fixtures/systems/akcay2011.json")); }
  static Data sample(const Model& model, int M) { return noise_free(model, M); }
  /// Scalar data S_k = f(e^{iπ(k−1)/M}), k = 1 … M+1 (not necessarily a spectrum).
  template <class F>
  static Data samples_of(int M, F f) {
    Data d;
    d.m = 1;
    d.M = M;
    d.S.resize(1, M + 1);
    for (int k = 0; k <= M; ++k) d.S(0, k) = f(std::polar(1.0, pi() * k / M));
    return d;
  }
  static Real max_abs_sample(const Data& d) { return d.S.cwiseAbs().maxCoeff(); }

  /// Step 1 as the reference reads it, S_{M+k} = conj(S_{M−k+2}) (identical to
  /// the Hermitian-part reading on Hermitian data).
  static constexpr Extension extension = Extension::Conjugate;

  /// ŝ_0 … ŝ_{N−1} of Eq. (20), m × m each.
  static std::vector<Matrix> fourier_coefficients(const Data& d) {
    const Eigen::MatrixXd shat = fdsid::fourier_coefficients(d, extension);
    std::vector<Matrix> s;
    for (Eigen::Index k = 0; k < shat.cols(); ++k) s.push_back(shat.col(k).reshaped(d.m, d.m));
    return s;
  }
  /// 𝒴 (pm × rm): fast/ builds it by Eq. (19) from the FFT's ŝ.
  static Matrix akcay_Y(const Data& d, int p, int r) {
    return akcay_matrix(fdsid::fourier_coefficients(d, extension), d.m, p, r);
  }
  static Real max_abs(const Matrix& X) { return X.cwiseAbs().maxCoeff(); }
  static std::vector<Real> singular_values(const Eigen::MatrixXd& X) {
    const Eigen::VectorXd s = fdsid::testing::singular_values(X);
    return std::vector<Real>(s.data(), s.data() + s.size());
  }

  /// Singular values of Ĝ_9F_8 and 𝒴 (p = 9, r = 8) as `fdsid reproduce
  /// table1` computes them (fdsid/paper.hpp), and max |Im Ĝ_9F_8|: 0, since
  /// van_overschee_matrix is assembled from the real ŝ.
  using Table1 = Table1Sigmas<Real>;
  static Table1 table1(int M) {
    const Table1Row row = reproduce_table1({M}).front();
    Table1 t;
    t.vo.assign(row.vo_sigmas.data(), row.vo_sigmas.data() + row.vo_sigmas.size());
    t.akcay.assign(row.akcay_sigmas.data(), row.akcay_sigmas.data() + row.akcay_sigmas.size());
    t.max_S = max_abs_sample(sample(paper_system(), M));
    return t;
  }

  /// Algorithm 1 (or vo1997) with order, p, r given: the model and the
  /// singular values of step 3 (of 𝒴, or of Ĝ_pF_r for vo1997).
  using Identified = Identification<Model, Real>;
  static Identified identify(const Data& d, int order, int p, int r, bool van_overschee) {
    SpectrumOptions o;
    o.method = van_overschee ? Method::VanOverschee1997 : Method::Akcay2011;
    o.order = order;
    o.p = p;
    o.r = r;
    o.extension = extension;
    const SpectrumResult result = identify_spectrum(d, o);
    const Eigen::VectorXd& s = result.singular_values;
    return {result.model, result.order, std::vector<Real>(s.data(), s.data() + s.size())};
  }
  /// {‖S_estimate(e^{iω}) − S_truth(e^{iω})‖_F, ‖S_truth(e^{iω})‖_F}.
  static std::pair<Real, Real> spectrum_error(const Model& truth, const Model& estimate, const Real& omega) {
    const Complex z = std::polar(1.0, omega);
    const Eigen::MatrixXcd S = power_spectrum(truth, z);
    return {(power_spectrum(estimate, z) - S).norm(), S.norm()};
  }
  /// Largest distance from a pole of `truth` to the nearest pole of `estimate`.
  static Real pole_error(const Model& truth, const Model& estimate) { return testing::pole_error(truth, estimate); }
  /// ρ(A) and ρ(A − B D⁻¹ C): the largest pole and zero moduli.
  static Real pole_radius(const Model& model) { return fdsid::testing::eigenvalues(model.A).cwiseAbs().maxCoeff(); }
  static Real zero_radius(const Model& model) {
    const Eigen::MatrixXd Z = model.A - model.B * fdsid::testing::inverse(model.D) * model.C;
    return fdsid::testing::eigenvalues(Z).cwiseAbs().maxCoeff();
  }

  static StepFailure identify_failure(const Data& d, int order, int p, int r) {
    SpectrumOptions o;
    o.order = order;
    o.p = p;
    o.r = r;
    o.extension = extension;
    try {
      identify_spectrum(d, o);
    } catch (const Error& e) {
      return {true, e.kind() == ErrorKind::Split && e.where() == "step 6", e.what()};
    }
    return {};
  }
};

/// reference/: 50-digit cpp_bin_float, 𝒴 by the explicit Kronecker products
/// of Eq. (16), DFTs as direct sums.
struct ReferenceSide {
  using Real = reference::Real;
  using Complex = reference::Complex;
  using Model = reference::Model;
  using Data = reference::Spectrum;
  using Matrix = reference::MatrixC;  // Eq. (16) in complex arithmetic: Im 𝒴 is rounding

  static constexpr const char* name = "reference (50 digits)";
  /// Unit roundoff u = ε/2 of the cpp_bin_float<50> format (round to nearest).
  static Real unit_roundoff() { return std::numeric_limits<Real>::epsilon() / 2; }
  static Real number(const char* decimal) { return reference::parse_decimal(decimal); }
  static Real pi() { return boost::math::constants::pi<Real>(); }
  static std::string show(const Real& x) { return x.str(6, std::ios_base::scientific); }
  /// How the reference prints an eigenvalue modulus in a step-6 message (10 digits after the point).
  static std::string printed_modulus(const char* decimal) {
    return number(decimal).str(10, std::ios_base::scientific);
  }

  static Model paper_system() { return reference::read_model(source_path("fixtures/systems/akcay2011.json")); }
  static Data sample(const Model& model, int M) { return reference::sample_spectrum(model, M); }
  template <class F>
  static Data samples_of(int M, F f) {
    Data d;
    d.m = 1;
    d.M = M;
    for (int k = 0; k <= M; ++k) {
      const Real omega = pi() * Real(k) / Real(M);
      reference::MatrixC S(1, 1);
      S(0, 0) = f(Complex(cos(omega), sin(omega)));
      d.S.push_back(S);
    }
    return d;
  }
  static Real max_abs_sample(const Data& d) {
    Real worst = 0;
    for (const Matrix& S : d.S) worst = std::max(worst, max_abs(S));
    return worst;
  }

  static std::vector<Matrix> fourier_coefficients(const Data& d) { return reference::fourier_coefficients(d); }
  static Matrix akcay_Y(const Data& d, int p, int r) { return reference::akcay_Y(d, p, r); }
  static Real max_abs(const Matrix& X) {
    Real worst = 0;
    for (Eigen::Index i = 0; i < X.size(); ++i) worst = std::max(worst, abs(X.data()[i]));
    return worst;
  }
  static std::vector<Real> singular_values(const reference::MatrixR& X) { return reference::singular_values(X); }

  using Table1 = Table1Sigmas<Real>;
  static Table1 table1(int M) {
    const Data d = sample(paper_system(), M);
    const Matrix GF = reference::vo_GF(d, 9, 8);
    Table1 t;
    t.vo = singular_values(reference::MatrixR(GF.real()));
    t.akcay = singular_values(reference::MatrixR(akcay_Y(d, 9, 8).real()));
    Real imaginary = 0;
    for (Eigen::Index i = 0; i < GF.size(); ++i) imaginary = std::max(imaginary, abs(GF.data()[i].imag()));
    t.vo_imaginary = imaginary;
    t.max_S = max_abs_sample(d);
    return t;
  }

  using Identified = Identification<Model, Real>;
  static Identified identify(const Data& d, int order, int p, int r, bool van_overschee) {
    const reference::Result result = reference::identify_spectrum(d, order, p, r, van_overschee);
    return {result.model, result.order, van_overschee ? result.singular_values_vo : result.singular_values_Y};
  }
  static std::pair<Real, Real> spectrum_error(const Model& truth, const Model& estimate, const Real& omega) {
    const Complex z(cos(omega), sin(omega));
    const reference::MatrixC S = reference::spectrum_of(truth, z);
    return {(reference::spectrum_of(estimate, z) - S).norm(), S.norm()};
  }
  static Real pole_error(const Model& truth, const Model& estimate) {
    const std::vector<Complex> a = reference::eigenvalues(truth.A), b = reference::eigenvalues(estimate.A);
    Real worst = 0;
    for (const Complex& lambda : a) {
      Real nearest = -1;
      for (const Complex& mu : b)
        if (nearest < 0 || abs(mu - lambda) < nearest) nearest = abs(mu - lambda);
      worst = std::max(worst, nearest);
    }
    return worst;
  }
  static Real radius(const reference::MatrixR& X) {
    Real worst = 0;
    for (const Complex& lambda : reference::eigenvalues(X)) worst = std::max(worst, abs(lambda));
    return worst;
  }
  static Real pole_radius(const Model& model) { return radius(model.A); }
  static Real zero_radius(const Model& model) {
    return radius(reference::MatrixR(model.A - model.B * model.D.partialPivLu().solve(model.C)));
  }

  static StepFailure identify_failure(const Data& d, int order, int p, int r) {
    try {
      reference::identify_spectrum(d, order, p, r);
    } catch (const reference::StepError& e) {
      return {true, e.step() == 6, e.what()};
    } catch (const reference::Error& e) {
      return {true, false, e.what()};
    }
    return {};
  }
};

}  // namespace fdsid::testing
