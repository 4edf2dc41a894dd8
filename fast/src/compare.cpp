#include "fdsid/compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <tuple>
#include <utility>

#include "fdsid/error.hpp"
#include "numerics/eigen_instances.hpp"

namespace fdsid {

double double_precision_spectrum_tolerance(int p, int r, int m, int N, double sigma1_over_sigma2n) {
  constexpr double u = std::numeric_limits<double>::epsilon() / 2;
  return 4.0 * (p + r) * m * std::log2(static_cast<double>(N)) * u * sigma1_over_sigma2n;
}

namespace {
double directed_distance(const Eigen::VectorXcd& from, const Eigen::VectorXcd& to) {
  double worst = 0;
  for (Eigen::Index i = 0; i < from.size(); ++i)
    worst = std::max(worst, to.size() ? (to.array() - from(i)).abs().minCoeff() : std::numeric_limits<double>::infinity());
  return worst;
}

double hausdorff(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  if (a.size() == 0 && b.size() == 0) return 0;
  return std::max(directed_distance(a, b), directed_distance(b, a));
}

// Relative Markov distance max_k ||X_c(k) - X_r(k)|| / max_k ||X_r(k)||, with
// X(0) = first and X(k) = left * A^{k-1} * right for k = 1..K.
struct MarkovSide {
  Eigen::MatrixXd first, left, A, right;
};
std::pair<double, int> markov_distance(const MarkovSide& c, const MarkovSide& r, int K) {
  Eigen::MatrixXd Lc = c.left, Lr = r.left;
  double scale = r.first.norm(), worst = (c.first - r.first).norm();
  int worst_k = 0;
  for (int k = 1; k <= K; ++k) {
    const Eigen::MatrixXd Xr = Lr * r.right;
    scale = std::max(scale, Xr.norm());
    const double e = (Lc * c.right - Xr).norm();
    if (e > worst) {
      worst = e;
      worst_k = k;
    }
    Lc = (Lc * c.A).eval();
    Lr = (Lr * r.A).eval();
  }
  return {scale > 0 ? worst / scale : worst, worst_k};
}

// The spectral factors: their zeros and the Markov parameters of G(z) D^T.
void compare_factors(const StateSpace& cand, const StateSpace& ref, int K, ModelComparison& c) {
  const Eigen::VectorXcd zc = zeros(cand), zr = zeros(ref);
  c.zero_distance = hausdorff(zc, zr);
  if (zc.size()) {
    Eigen::Index i;
    c.candidate_zero_modulus = zc.cwiseAbs().maxCoeff(&i);
    c.candidate_worst_zero = zc(i);
    if (zr.size()) {
      const cplx mirror = 1.0 / std::conj(zc(i));
      Eigen::Index j;
      (zr.array() - mirror).abs().minCoeff(&j);
      c.reference_zero_near_mirror = zr(j);
    }
  }
  if (zr.size()) c.reference_zero_modulus = zr.cwiseAbs().maxCoeff();
  const auto side = [](const StateSpace& s) {
    return MarkovSide{s.D * s.D.transpose(), s.C, s.A, s.B * s.D.transpose()};
  };
  std::tie(c.factor_markov_error, c.factor_markov_error_k) = markov_distance(side(cand), side(ref), K);
}
}  // namespace

ModelComparison compare_models(const StateSpace& cand, const StateSpace& ref, int grid, int markov) {
  if (cand.outputs() != ref.outputs() || cand.inputs() != cand.outputs())
    throw Error(ErrorKind::Input, "candidate", "has " + std::to_string(cand.outputs()) + " outputs and " +
                                                   std::to_string(cand.inputs()) + " inputs; the data need a square " +
                                                   std::to_string(ref.outputs()) + "-channel spectral factor");
  if (cand.domain != Domain::Discrete) throw Error(ErrorKind::Input, "candidate", "must be a discrete-time model");
  ModelComparison c;
  c.candidate_order = cand.order();
  c.reference_order = ref.order();
  const Eigen::VectorXcd pc = poles(cand), pr = poles(ref);
  c.pole_distance = hausdorff(pc, pr);
  c.candidate_pole_modulus = spectral_radius(cand);
  c.reference_pole_modulus = spectral_radius(ref);

  double scale = 0;
  for (int k = 0; k < grid; ++k) {
    const double w = M_PI * k / (grid - 1);
    const cplx z = std::polar(1.0, w);
    const Eigen::MatrixXcd Sr = power_spectrum(ref, z);
    const double e = (power_spectrum(cand, z) - Sr).norm();
    scale = std::max(scale, Sr.norm());
    if (e > c.spectrum_error) {
      c.spectrum_error = e;
      c.spectrum_error_omega = w;
    }
  }
  c.spectrum_error /= scale;

  const int K = markov > 0 ? markov : 2 * std::max(cand.order(), ref.order()) + 1;
  if (c.candidate_unstable()) {
    // An unstable candidate is a disagreement (a spectral factor is stable),
    // not bad input: its spectrum, zeros and H(k) are still compared; the
    // summands (a Stein equation in A) do not exist, so their distance is +inf.
    c.markov_error = std::numeric_limits<double>::infinity();
  } else {
    const SpectralSummands sc = spectral_summands(cand), sr = spectral_summands(ref);
    // R(0) = E, R(k) = C A^{k-1} F
    std::tie(c.markov_error, c.markov_error_k) =
        markov_distance({sc.E, sc.C, sc.A, sc.F}, {sr.E, sr.C, sr.A, sr.F}, K);
  }
  compare_factors(cand, ref, K, c);
  return c;
}

double eigenvalue_condition_number(const Eigen::MatrixXd& A) {
  double kappa = 1;
  if (A.rows() == 0) return kappa;
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  const Eigen::MatrixXcd V = es.eigenvectors(), W = V.inverse();
  for (Eigen::Index i = 0; i < A.rows(); ++i) kappa = std::max(kappa, V.col(i).norm() * W.row(i).norm());
  return kappa;
}

namespace {
double norm2(const Eigen::MatrixXcd& X) {
  return X.size() == 0 ? 0.0 : Eigen::JacobiSVD<Eigen::MatrixXcd>(X).singularValues()(0);
}
}  // namespace

double transfer_sensitivity(const StateSpace& m, cplx xi) {
  Eigen::MatrixXcd M = -m.A.cast<cplx>();
  M.diagonal().array() += xi;
  const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(M);
  const Eigen::MatrixXcd RB = lu.solve(m.B.cast<cplx>());
  const Eigen::MatrixXcd CR =
      Eigen::PartialPivLU<Eigen::MatrixXcd>(M.transpose()).solve(m.C.transpose().cast<cplx>()).transpose();
  if (!RB.allFinite() || !CR.allFinite()) return std::numeric_limits<double>::infinity();
  return norm2(CR) * norm2(m.A.cast<cplx>()) * norm2(RB) + norm2(m.C.cast<cplx>()) * norm2(RB) +
         norm2(CR) * norm2(m.B.cast<cplx>()) + norm2(m.D.cast<cplx>());
}

std::vector<StateSpace> randomly_moved(const StateSpace& model, double size, int count) {
  std::vector<StateSpace> out;
  for (int i = 1; i <= count; ++i) {
    std::mt19937_64 rng(i);
    std::normal_distribution<double> normal(0.0, 1.0);
    StateSpace moved = model;
    for (Eigen::MatrixXd* X : {&moved.A, &moved.B, &moved.C, &moved.D}) {
      if (X->size() == 0) continue;
      Eigen::MatrixXd g(X->rows(), X->cols());
      for (Eigen::Index k = 0; k < g.size(); ++k) g(k) = normal(rng);
      *X += size * X->norm() / g.norm() * g;
    }
    out.push_back(moved);
  }
  return out;
}

namespace {
double round_to_digits(double x, int digits) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*e", digits - 1, x);
  return std::strtod(buf, nullptr);
}
}  // namespace

int digits_carried(const StateSpace& model) {
  int most = 1;
  for (const Eigen::MatrixXd* X : {&model.A, &model.B, &model.C, &model.D})
    for (Eigen::Index k = 0; k < X->size(); ++k) {
      const double x = (*X)(k);
      if (!std::isfinite(x)) continue;
      int d = 1;
      while (d < 17 && round_to_digits(x, d) != x) ++d;
      most = std::max(most, d);
    }
  return most;
}

StateSpace rounded_to_digits(const StateSpace& model, int digits) {
  StateSpace out = model;
  for (Eigen::MatrixXd* X : {&out.A, &out.B, &out.C, &out.D})
    for (Eigen::Index k = 0; k < X->size(); ++k) (*X)(k) = round_to_digits((*X)(k), digits);
  return out;
}

Eigen::VectorXd dense_frequency_grid(Domain domain, const Eigen::VectorXd& data_omega, int points) {
  Eigen::VectorXd w(points);
  if (domain == Domain::Discrete) return Eigen::VectorXd::LinSpaced(points, 0.0, M_PI);
  const double lo = std::log10(data_omega.minCoeff() / 10), hi = std::log10(data_omega.maxCoeff() * 10);
  for (int k = 0; k < points; ++k) w(k) = std::pow(10.0, lo + (hi - lo) * k / (points - 1));
  return w;
}

namespace {

// The reference model in the domain where Algorithm 1 ran, with the map of
// frequencies to ξ there and of inner eigenvalues μ to poles λ (and dλ/dμ).
struct InnerModel {
  StateSpace model;
  Domain domain = Domain::Discrete;
  ContinuousMethod method = ContinuousMethod::Bilinear;
  double ws = 1;
  cplx xi(double omega) const {
    if (domain == Domain::Discrete) return std::polar(1.0, omega);
    const cplx st(0.0, omega / ws);
    return method == ContinuousMethod::Bilinear ? (st - 1.0) / (st + 1.0) : st;
  }
  cplx pole(cplx mu) const {
    if (domain == Domain::Discrete) return mu;
    return method == ContinuousMethod::Bilinear ? ws * (1.0 + mu) / (1.0 - mu) : ws * mu;
  }
  double derivative(cplx mu) const {
    if (domain == Domain::Discrete) return 1;
    return method == ContinuousMethod::Bilinear ? 2 * ws / std::norm(1.0 - mu) : ws;
  }
};

// Inverse of bilinear_to_continuous (frf_id.hpp): with Ã = A/ω_s,
// A_w = (Ã − I)(Ã + I)⁻¹, B_w = √2 (I + Ã)⁻¹ B/ω_s, C_w = √2 C (I + Ã)⁻¹,
// D_w = D − C (I + Ã)⁻¹ B/ω_s.
InnerModel inner_model(const StateSpace& ref, const FrfTolerance& t) {
  InnerModel in;
  in.domain = ref.domain;
  in.method = t.method;
  in.ws = ref.domain == Domain::Continuous ? t.omega_scale : 1.0;
  in.model = ref;
  if (ref.domain == Domain::Discrete) return in;
  in.model.domain = Domain::Discrete;
  const Eigen::MatrixXd At = ref.A / in.ws;
  if (t.method == ContinuousMethod::Orthogonal) {
    in.model.A = At;
    in.model.B = ref.B / in.ws;
    return in;
  }
  const Eigen::Index n = ref.A.rows();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(I + At);
  in.model.A = lu.solve(Eigen::MatrixXd(At - I));  // the factors commute
  in.model.B = std::sqrt(2.0) * lu.solve(ref.B) / in.ws;
  in.model.C = std::sqrt(2.0) *
               Eigen::PartialPivLU<Eigen::MatrixXd>((I + At).transpose()).solve(ref.C.transpose()).transpose();
  in.model.D = ref.D - ref.C * lu.solve(ref.B) / in.ws;
  return in;
}

constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;

// The ratio of a distance to its tolerance (a zero tolerance: 0 or +inf).
double ratio_of(double err, double tol) {
  if (tol > 0) return err / tol;
  return err > 0 || std::isnan(err) ? std::numeric_limits<double>::infinity() : 0.0;
}

// G on a grid: the largest ratio of ||G_c − G_r||_F to its tolerance.
OracleQuantity compare_transfer(const StateSpace& cand, const StateSpace& ref, const InnerModel& inner,
                                const Eigen::VectorXd& omega, const FrfTolerance& t, double* relative) {
  const std::vector<Eigen::MatrixXcd> Gc = frequency_response(cand, omega), Gr = frequency_response(ref, omega);
  std::vector<std::vector<Eigen::MatrixXcd>> Gp;
  if (t.given <= 0)
    for (const StateSpace& p : t.perturbed) Gp.push_back(frequency_response(p, omega));
  double scale = 0, worst_abs = 0;
  for (const auto& G : Gr) scale = std::max(scale, G.norm());
  const double floor = 4.0 * std::max(1, ref.order()) * kUnit;
  OracleQuantity q;
  q.ratio = -1;
  for (Eigen::Index k = 0; k < omega.size(); ++k) {
    const double err = (Gc[k] - Gr[k]).norm();
    worst_abs = std::max(worst_abs, err);
    double tol = t.given * scale;
    if (t.given <= 0) {
      double moved = 0;
      for (const auto& G : Gp) moved = std::max(moved, (G[k] - Gr[k]).norm());
      tol = FrfTolerance::kSafety * moved + floor * transfer_sensitivity(inner.model, inner.xi(omega(k)));
    }
    const double ratio = ratio_of(err, tol);
    if (ratio > q.ratio) q = {err, tol, ratio, omega(k)};
  }
  if (relative) *relative = scale > 0 ? worst_abs / scale : worst_abs;
  return q;
}

// Poles, each reference pole with its own tolerance.
OracleQuantity compare_frf_poles(const StateSpace& cand, const StateSpace& ref, const InnerModel& inner,
                                 const FrfTolerance& t) {
  OracleQuantity q;
  const Eigen::Index n = inner.model.A.rows();
  const Eigen::VectorXcd pc = poles(cand);
  if (n == 0 || pc.size() == 0) {
    q.ratio = n == pc.size() ? 0 : std::numeric_limits<double>::infinity();
    return q;
  }
  Eigen::EigenSolver<Eigen::MatrixXd> es(inner.model.A);
  const Eigen::MatrixXcd V = es.eigenvectors(), W = V.inverse();
  const double nA = norm2(inner.model.A.cast<cplx>());
  double back = 0;  // rounding of the bilinear back-transform (Algorithm 2.1)
  if (ref.domain == Domain::Continuous && t.method == ContinuousMethod::Bilinear) {
    const Eigen::VectorXd sv =
        Eigen::JacobiSVD<Eigen::MatrixXd>(Eigen::MatrixXd::Identity(n, n) - inner.model.A).singularValues();
    back = 4.0 * n * kUnit * sv(0) / sv(n - 1) * norm2(ref.A.cast<cplx>()) * eigenvalue_condition_number(ref.A);
  }
  std::vector<Eigen::VectorXcd> moved_poles;
  for (const StateSpace& p : t.perturbed) moved_poles.push_back(poles(p));
  Eigen::VectorXcd lambda(n);
  Eigen::VectorXd tol(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const cplx mu = es.eigenvalues()(j);
    lambda(j) = inner.pole(mu);
    if (t.given > 0) {
      tol(j) = t.given * (ref.domain == Domain::Continuous ? std::abs(lambda(j)) : 1.0);
      continue;
    }
    double moved = 0;
    for (const Eigen::VectorXcd& mp : moved_poles)
      if (mp.size()) moved = std::max(moved, (mp.array() - lambda(j)).abs().minCoeff());
    tol(j) = FrfTolerance::kSafety * moved + 4.0 * n * kUnit * nA * V.col(j).norm() * W.row(j).norm() *
                                                 inner.derivative(mu) + back;
  }
  auto consider = [&](double err, Eigen::Index j) {
    const double ratio = ratio_of(err, tol(j));
    if (ratio > q.ratio) q = {err, tol(j), ratio, 0.0};
  };
  for (Eigen::Index i = 0; i < pc.size(); ++i) {
    Eigen::Index j = 0;
    const double err = (lambda.array() - pc(i)).abs().minCoeff(&j);  // sets j before it is read
    consider(err, j);
  }
  for (Eigen::Index j = 0; j < n; ++j) consider((pc.array() - lambda(j)).abs().minCoeff(), j);
  return q;
}

}  // namespace

FrfModelComparison compare_frf_models(const StateSpace& cand, const StateSpace& ref, const Eigen::VectorXd& data_omega,
                                      const Eigen::VectorXd& dense_omega, const FrfTolerance& t) {
  if (cand.outputs() != ref.outputs() || cand.inputs() != ref.inputs())
    throw Error(ErrorKind::Input, "candidate",
                "has " + std::to_string(cand.outputs()) + " outputs and " + std::to_string(cand.inputs()) +
                    " inputs; the data have " + std::to_string(ref.outputs()) + " and " +
                    std::to_string(ref.inputs()));
  if (cand.domain != ref.domain)
    throw Error(ErrorKind::Input, "candidate", std::string("is a ") + to_string(cand.domain) +
                                                   "-time model; the data were identified in " +
                                                   to_string(ref.domain) + " time");
  if (t.given <= 0 && t.perturbed.empty())
    throw Error(ErrorKind::Input, "compare_frf_models", "needs perturbed reference models or a tolerance");
  FrfModelComparison c;
  c.candidate_order = cand.order();
  c.reference_order = ref.order();
  const InnerModel inner = inner_model(ref, t);
  c.g_data = compare_transfer(cand, ref, inner, data_omega, t, &c.g_relative);
  c.g_dense = compare_transfer(cand, ref, inner, dense_omega, t, nullptr);
  c.poles = compare_frf_poles(cand, ref, inner, t);
  return c;
}

}  // namespace fdsid
