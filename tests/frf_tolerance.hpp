#pragma once
/// Tolerances and noise-free data for Pintelon (2002) Algorithms 1 and 2
/// (fdsid/frf_id.hpp), shared by tests/frf_id_test.cpp and
/// properties/frf_properties.cpp.
///
/// Derivation of the noise-free tolerance. FrfResult::error_estimate = u κ,
/// κ = (σ1/σn of step 1c) · cond(Ô_r[1:r−1]) is the first-order amplification
/// of a relative backward error of size u into Â. The backward error of the
/// Householder QR of Zᵀ (2Fc rows × r(m+p) columns) is γ̃_{rows·cols} in
/// Higham's worst case (Thm 19.4); its probabilistic form (Higham & Mary 2019)
/// is λ √(rows · cols) u with a modest λ, here λ = 10 (which also covers the
/// SVD of step 1c and the least-squares solves of steps 2 and 3, each
/// backward stable with a constant ≤ the QR's). Hence
///     relative error of Â (and Ĉ, B̂, D̂) ≤ ε_A = 10 √(2Fc · r(m+p)) · error_estimate.
/// Poles: Bauer–Fike to first order per eigenvalue, |δλ_i| ≤ ε_A ‖Â‖₂ κ_i(Â).
/// G: first-order expansion of G = D + C R B, R = (ξI − A)⁻¹, with every one of
/// A, B, C, D perturbed by ε_A relatively:
///     ‖δG(ξ)‖ ≤ ε_A (‖Ĉ R‖ ‖Â‖ ‖R B̂‖ + ‖Ĉ‖ ‖R B̂‖ + ‖Ĉ R‖ ‖B̂‖ + ‖D̂‖)  =: ε_A s(ξ).
/// Added to the pole tolerance: the truth's own rounding and that of the
/// bilinear back-transformation, 4n u cond(I − Â_w) ‖Â_c‖ κ(Â_c).
/// Continuous time maps these through ξ(s): bilinear w = (s̃ − 1)/(s̃ + 1),
/// dλ_c/dλ_w = 2 ω_s / (1 − λ_w)²; orthogonal bases ξ = s̃ = s/ω_s, λ_c = ω_s λ̃.
/// Discrete time, DiscreteMethod::Bilinear: z = (1 + s')/(1 − s'),
/// s' = t_s (1 + w)/(1 − w), so dλ_z/dλ_w = [2/(1 − s')²] [2 t_s/(1 − λ_w)²];
/// its two back-transformation steps round A' to ≤ 4n u cond(I − Â_w)
/// relatively (as above) and A_z = 2(I − A')⁻¹ − I amplifies a relative
/// change of A' by ≤ cond(I − A') and adds its own 4n u cond(I − A'):
/// 4n u cond(I − A') (1 + cond(I − Â_w)) ‖Â_z‖ κ(Â_z) on the poles.
/// DiscreteMethod::Orthogonal: s̃ = s'/t_s, dλ_z/dλ_s̃ = t_s · 2/(1 − s')², and
/// the one step s' → z: 4n u cond(I − A') ‖Â_z‖ κ(Â_z).
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "linalg.hpp"
#include "tolerance.hpp"

namespace fdsid::testing {

/// λ √(rows · cols) of the derivation above, λ = 10.
inline double frf_qr_constant(int F, int c, int r, int m, int p) {
  return 10.0 * std::sqrt(2.0 * F * c * double(r) * (m + p));
}

/// Inverse of bilinear_to_continuous (header of frf_id.hpp): with Ã = A/ω_s,
/// I − A_w = 2 (I + Ã)⁻¹, so A_w = (Ã − I)(Ã + I)⁻¹, B_w = √2 (I + Ã)⁻¹ B / ω_s,
/// C_w = √2 C (I + Ã)⁻¹, D_w = D − C (I + Ã)⁻¹ B / ω_s.
inline StateSpace continuous_to_bilinear(const StateSpace& c, double omega_scale) {
  const int n = c.order();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd At = c.A / omega_scale;
  const Eigen::MatrixXd IA = I + At;
  StateSpace w;
  w.domain = Domain::Discrete;
  w.sample_time = c.sample_time;
  w.A = solve(IA, Eigen::MatrixXd(At - I));  // (Ã + I)⁻¹(Ã − I) = (Ã − I)(Ã + I)⁻¹: the factors commute
  w.B = std::sqrt(2.0) * solve(IA, c.B) / omega_scale;
  w.C = std::sqrt(2.0) * c.C * inverse(IA);
  w.D = c.D - c.C * solve(IA, c.B) / omega_scale;
  return w;
}

/// w = (s̃ − 1)/(s̃ + 1), s̃ = jω/ω_s.
inline cplx bilinear_point(double omega, double omega_scale) {
  const cplx st(0.0, omega / omega_scale);
  return (st - 1.0) / (st + 1.0);
}

/// DiscreteMethod::Bilinear's w at z = e^{jω} (ω, ω_s in rad/sample): s' =
/// j tan(ω/2), w = (s'/t_s − 1)/(s'/t_s + 1), t_s = tan(ω_s/2) — typed here
/// from the definition, not from fast/.
inline cplx tustin_point(double omega, double omega_scale) {
  return bilinear_point(std::tan(omega / 2), std::tan(omega_scale / 2));
}

/// Inverse of bilinear_to_discrete: z → s' = (z − 1)/(z + 1) is
/// continuous_to_bilinear with scale 1 (read z as s), then s' → w with t_s.
inline StateSpace discrete_to_bilinear(const StateSpace& z, double omega_scale) {
  return continuous_to_bilinear(continuous_to_bilinear(z, 1.0), std::tan(omega_scale / 2));
}

inline double spectral_norm(const Eigen::MatrixXcd& X) {
  return X.size() == 0 ? 0.0 : fdsid::testing::singular_values(Eigen::MatrixXcd(X))(0);
}

/// s(ξ) of the derivation: first-order sensitivity of G(ξ) to relative
/// perturbations of A, B, C, D of size 1.
inline double transfer_sensitivity(const StateSpace& m, cplx xi) {
  Eigen::MatrixXcd M = -m.A.cast<cplx>();
  M.diagonal().array() += xi;
  const Eigen::MatrixXcd RB = solve(M, Eigen::MatrixXcd(m.B.cast<cplx>()));
  const Eigen::MatrixXcd CR =
      solve(Eigen::MatrixXcd(M.transpose()), Eigen::MatrixXcd(m.C.transpose().cast<cplx>())).transpose();
  const double nA = spectral_norm(m.A.cast<cplx>()), nB = spectral_norm(m.B.cast<cplx>()),
               nC = spectral_norm(m.C.cast<cplx>()), nD = spectral_norm(m.D.cast<cplx>());
  return spectral_norm(CR) * nA * spectral_norm(RB) + nC * spectral_norm(RB) + spectral_norm(CR) * nB + nD;
}

/// The same model with A and B divided by ω_s: G(s) = G̃(s/ω_s).
inline StateSpace scaled(const StateSpace& m, double omega_scale) {
  StateSpace s = m;
  s.A /= omega_scale;
  s.B /= omega_scale;
  return s;
}

/// Noise-free FRF data of `sys` at `omega` (frf_data form, c = m), unit weights
/// unless `variance` > 0 (then that variance for every entry, has_noise_model).
inline FrfData noise_free_frf(const StateSpace& sys, const Eigen::VectorXd& omega, double variance = 0) {
  std::vector<Eigen::MatrixXcd> G;
  std::vector<Eigen::MatrixXd> V;
  for (Eigen::Index k = 0; k < omega.size(); ++k) {
    G.push_back(frequency_response(sys, omega(k)));
    if (variance > 0) V.push_back(Eigen::MatrixXd::Constant(sys.outputs(), sys.inputs(), variance));
  }
  FrfData d = frf_data(sys.domain, omega, G, V);
  d.sample_time = sys.sample_time;
  return d;
}

/// Noise-free periodic input/output data (c = 1): Y = G U with the given U
/// (m × 1 each) and unit output variances.
inline FrfData noise_free_io(const StateSpace& sys, const Eigen::VectorXd& omega,
                             const std::vector<Eigen::MatrixXcd>& U) {
  FrfData d;
  d.domain = sys.domain;
  d.sample_time = sys.sample_time;
  d.omega = omega;
  for (Eigen::Index k = 0; k < omega.size(); ++k) {
    d.U.push_back(U[k]);
    d.Y.push_back(frequency_response(sys, omega(k)) * U[k]);
    d.variance.push_back(Eigen::MatrixXd::Ones(sys.outputs(), 1));
  }
  return d;
}

/// Worst errors of a noise-free identification, each as a ratio to its
/// tolerance (≤ 1 passes), with where they occurred.
struct NoiseFreeCheck {
  double g_ratio = 0, g_err = 0, g_tol = 0, g_omega = 0;
  double pole_ratio = 0, pole_err = 0, pole_tol = 0;
  double eps_A = 0;
  std::string describe() const {
    std::ostringstream s;
    s.precision(3);
    s << "eps_A = 10 sqrt(2Fc r(m+p)) error_estimate = " << eps_A << "; worst G error " << g_err << " at omega = "
      << g_omega << " vs tolerance eps_A s(xi) = " << g_tol << " (ratio " << g_ratio << "); worst pole error "
      << pole_err << " vs eps_A |A| kappa_i mapped = " << pole_tol << " (ratio " << pole_ratio << ")";
    return s.str();
  }
};

/// Checks G on every grid point and every midpoint between neighbours (in log ω
/// for continuous time), and every true pole against the nearest estimated one.
/// `truth_pole_accuracy`: absolute accuracy of the truth's computed poles; < 0
/// means 4n u ‖A‖ κ(A) (the eigensolver's backward error, truth given directly).
/// `discrete`: the basis of discrete-time data (ω_s read from res.omega_scale).
inline NoiseFreeCheck check_noise_free(const StateSpace& truth, const FrfResult& res, const FrfData& d,
                                       ContinuousMethod method = ContinuousMethod::Bilinear, double omega_scale = 0,
                                       double truth_pole_accuracy = -1,
                                       DiscreteMethod discrete = DiscreteMethod::Monomial) {
  NoiseFreeCheck out;
  const StateSpace& est = res.model;
  const int F = d.frequencies();
  out.eps_A = frf_qr_constant(F, d.columns(), res.r, d.inputs(), d.outputs()) * res.error_estimate;
  const bool cont = d.domain == Domain::Continuous;
  const double ws = cont ? (omega_scale > 0 ? omega_scale : std::sqrt(d.omega.minCoeff() * d.omega.maxCoeff())) : 1;
  const bool tustin = !cont && discrete == DiscreteMethod::Bilinear;
  const bool tustin_orth = !cont && discrete == DiscreteMethod::Orthogonal;
  const double ts = tustin || tustin_orth ? std::tan(res.omega_scale / 2) : 1;
  // The model in the domain where Algorithm 1 ran (where error_estimate applies).
  const StateSpace inner = tustin        ? discrete_to_bilinear(est, res.omega_scale)
                           : tustin_orth ? scaled(continuous_to_bilinear(est, 1.0), ts)
                           : !cont       ? est
                           : method == ContinuousMethod::Bilinear ? continuous_to_bilinear(est, ws)
                                                                  : scaled(est, ws);
  auto xi_of = [&](double w) -> cplx {
    if (tustin) return tustin_point(w, res.omega_scale);
    if (tustin_orth) return cplx(0.0, std::tan(w / 2) / ts);
    if (!cont) return std::polar(1.0, w);
    return method == ContinuousMethod::Bilinear ? bilinear_point(w, ws) : cplx(0.0, w / ws);
  };
  std::vector<double> pts(d.omega.data(), d.omega.data() + F);
  std::sort(pts.begin(), pts.end());
  std::vector<double> eval = pts;
  for (size_t i = 1; i < pts.size(); ++i)
    eval.push_back(cont ? std::sqrt(pts[i] * pts[i - 1]) : 0.5 * (pts[i] + pts[i - 1]));
  for (double w : eval) {
    const double err = (frequency_response(est, w) - frequency_response(truth, w)).norm();
    const double tol = out.eps_A * fdsid::testing::transfer_sensitivity(inner, xi_of(w));
    if (err / tol > out.g_ratio || out.g_tol == 0) {
      out.g_ratio = err / tol;
      out.g_err = err;
      out.g_tol = tol;
      out.g_omega = w;
    }
  }
  // Poles: |δμ_i| ≤ ε_A ‖Â‖ κ_i for each eigenvalue μ_i of the inner Â (κ_i =
  // ‖x_i‖ ‖y_i‖ / |y_iᴴ x_i|, first-order Bauer–Fike per eigenvalue), mapped to
  // the model's domain by the derivative of λ(μ).
  const Eigen::VectorXcd pt = poles(truth);
  const EigenDecomposition es = eigen_decomposition(inner.A);
  const Eigen::MatrixXcd& V = es.vectors;
  const Eigen::MatrixXcd& W = es.inverse_vectors;
  const double nA = spectral_norm(inner.A.cast<cplx>());
  const Eigen::Index n = inner.A.rows();
  // Rounding outside Algorithm 1 itself: the truth's poles, and for the
  // bilinear variant the back-transformation (relative ≤ 4n u cond(I − Â_w) in
  // Â_c, as in BilinearToContinuous.MatchesTheWDomainModelOnTheImaginaryAxis).
  const double truth_acc = truth_pole_accuracy >= 0 ? truth_pole_accuracy
                                                    : 4.0 * n * kU * spectral_norm(truth.A.cast<cplx>()) *
                                                          eigenvalue_condition(truth.A);
  double back = 0;
  if (cont && method == ContinuousMethod::Bilinear) {
    const Eigen::VectorXd sv =
        fdsid::testing::singular_values(Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n) - inner.A));
    back = 4.0 * n * kU * sv(0) / sv(n - 1) * spectral_norm(est.A.cast<cplx>()) * eigenvalue_condition(est.A);
  }
  if (tustin || tustin_orth) {
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd Ap = continuous_to_bilinear(est, 1.0).A;  // A' in s'
    const Eigen::VectorXd sp = fdsid::testing::singular_values(Eigen::MatrixXd(I - Ap));
    double first = 0;  // the w → s' step's relative error, amplified by the s' → z step
    if (tustin) {
      const Eigen::VectorXd sw = fdsid::testing::singular_values(Eigen::MatrixXd(I - inner.A));
      first = sw(0) / sw(n - 1);
    }
    back = 4.0 * n * kU * sp(0) / sp(n - 1) * (1 + first) * spectral_norm(est.A.cast<cplx>()) *
           eigenvalue_condition(est.A);
  }
  Eigen::VectorXcd lam(n);
  Eigen::VectorXd tol_i(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const cplx mu = es.values(i);
    const double kappa = V.col(i).norm() * W.row(i).norm();
    double d = 1;
    lam(i) = mu;
    if (tustin) {
      const cplx sp = ts * (1.0 + mu) / (1.0 - mu);
      lam(i) = (1.0 + sp) / (1.0 - sp);
      d = 2.0 / std::norm(1.0 - sp) * 2 * ts / std::norm(1.0 - mu);
    } else if (tustin_orth) {
      const cplx sp = ts * mu;
      lam(i) = (1.0 + sp) / (1.0 - sp);
      d = ts * 2.0 / std::norm(1.0 - sp);
    } else if (cont && method == ContinuousMethod::Bilinear) {
      lam(i) = ws * (1.0 + mu) / (1.0 - mu);
      d = 2 * ws / std::norm(1.0 - mu);
    } else if (cont) {
      lam(i) = ws * mu;
      d = ws;
    }
    tol_i(i) = out.eps_A * nA * kappa * d + back + truth_acc;
  }
  for (Eigen::Index i = 0; i < pt.size(); ++i) {
    Eigen::Index j = 0;
    const double err = (lam.array() - pt(i)).abs().minCoeff(&j);
    if (err / tol_i(j) > out.pole_ratio || out.pole_tol == 0) {
      out.pole_ratio = err / tol_i(j);
      out.pole_err = err;
      out.pole_tol = tol_i(j);
    }
  }
  return out;
}

/// Circular complex normal sample of variance v: real and imaginary parts N(0, v/2).
inline cplx complex_normal(std::mt19937_64& rng, double v) {
  std::normal_distribution<double> n(0.0, std::sqrt(v / 2));
  const double re = n(rng);
  return {re, n(rng)};
}

}  // namespace fdsid::testing
