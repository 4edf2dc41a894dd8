#include "fdsid/compare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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
  c.pole_distance = std::max(directed_distance(pc, pr), directed_distance(pr, pc));
  if (pc.size() && pc.cwiseAbs().maxCoeff() >= 1.0)
    throw Error(ErrorKind::Input, "candidate", "is not stable (pole modulus " + std::to_string(pc.cwiseAbs().maxCoeff()) + ")");

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

  const SpectralSummands sc = spectral_summands(cand), sr = spectral_summands(ref);
  const int K = markov > 0 ? markov : 2 * std::max(cand.order(), ref.order()) + 1;
  Eigen::MatrixXd Rc = sc.E, Rr = sr.E, CAc = sc.C, CAr = sr.C;  // R(0) = E, then C A^{k-1} F
  double rscale = Rr.norm(), worst = (Rc - Rr).norm();
  for (int k = 1; k <= K; ++k) {
    Rc = CAc * sc.F;
    Rr = CAr * sr.F;
    rscale = std::max(rscale, Rr.norm());
    const double e = (Rc - Rr).norm();
    if (e > worst) {
      worst = e;
      c.markov_error_k = k;
    }
    CAc = (CAc * sc.A).eval();
    CAr = (CAr * sr.A).eval();
  }
  c.markov_error = worst / rscale;
  return c;
}

}  // namespace fdsid
