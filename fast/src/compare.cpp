#include "fdsid/compare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "fdsid/error.hpp"

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
  if (pc.size()) c.candidate_pole_modulus = pc.cwiseAbs().maxCoeff();
  if (pr.size()) c.reference_pole_modulus = pr.cwiseAbs().maxCoeff();

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

}  // namespace fdsid
