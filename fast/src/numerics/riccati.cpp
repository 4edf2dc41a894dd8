#include "numerics/riccati.hpp"
#include "numerics/eigen_instances.hpp"

#include <algorithm>
#include <limits>

namespace fdsid::numerics {

namespace {

Eigen::MatrixXd riccati_map(const SpectralSummands& s, const Eigen::MatrixXd& P) {
  const Eigen::MatrixXd K = s.F - s.A * P * s.C.transpose();
  const Eigen::MatrixXd R = s.E - s.C * P * s.C.transpose();
  return s.A * P * s.A.transpose() + K * R.ldlt().solve(K.transpose());
}

bool riccati_sda(const SpectralSummands& s, const RiccatiOptions& o, Eigen::MatrixXd& P, int& iterations) {
  const auto n = s.A.rows();
  const Eigen::LDLT<Eigen::MatrixXd> Einv(s.E);
  Eigen::MatrixXd Ak = s.A.transpose() - s.C.transpose() * Einv.solve(s.F.transpose());
  Eigen::MatrixXd Gk = s.C.transpose() * Einv.solve(s.C);
  Eigen::MatrixXd Hk = -s.F * Einv.solve(s.F.transpose());
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  for (iterations = 1; iterations <= o.sda_max_iterations; ++iterations) {
    const Eigen::PartialPivLU<Eigen::MatrixXd> W(I + Gk * Hk);
    if (!(W.rcond() > o.min_rcond)) return false;
    const Eigen::MatrixXd WA = W.solve(Ak);  // W^{-1} A_k
    const Eigen::MatrixXd WG = W.solve(Gk);  // W^{-1} G_k
    const Eigen::MatrixXd Anext = Ak * WA;
    const Eigen::MatrixXd Gnext = Gk + Ak * WG * Ak.transpose();
    const Eigen::MatrixXd Hnext = Hk + Ak.transpose() * Hk * WA;
    const double change = (Hnext - Hk).norm();
    Ak = Anext;
    Gk = 0.5 * (Gnext + Gnext.transpose());
    Hk = 0.5 * (Hnext + Hnext.transpose());
    if (!Hk.allFinite()) return false;
    if (change <= o.step_tolerance * Hk.norm() || Ak.norm() <= kUnitRoundoff) break;
  }
  P = -Hk;
  return iterations <= o.sda_max_iterations;
}

bool riccati_kalman(const SpectralSummands& s, const RiccatiOptions& o, Eigen::MatrixXd& P, int& iterations) {
  P = Eigen::MatrixXd::Zero(s.A.rows(), s.A.rows());
  double window_start_change = std::numeric_limits<double>::infinity();
  for (iterations = 1; iterations <= o.kalman_max_iterations; ++iterations) {
    const Eigen::MatrixXd next = riccati_map(s, P);
    if (!next.allFinite()) return false;
    const double change = (next - P).norm();
    P = 0.5 * (next + next.transpose());
    if (change <= o.step_tolerance * std::max(P.norm(), 1e-300)) return true;
    if (!(P.norm() < o.kalman_divergence)) return false;
    if (iterations % o.kalman_window == 0) {
      if (!(change < 0.5 * window_start_change)) return false;
      window_start_change = change;
    }
  }
  return false;
}

}  // namespace

// 1e-300 guards the divisions against a zero P, F or E (any value far below
// every norm that occurs and above the underflow threshold would do).
double riccati_residual(const SpectralSummands& s, const Eigen::MatrixXd& P) {
  const double scale = std::max(P.norm(), s.F.norm() * s.F.norm() / std::max(s.E.norm(), 1e-300));
  return (P - riccati_map(s, P)).norm() / std::max(scale, 1e-300);
}

RiccatiSolution solve_spectral_riccati(const SpectralSummands& s, const RiccatiOptions& o) {
  RiccatiSolution r;
  r.ok = riccati_sda(s, o, r.P, r.iterations);
  r.method = "sda";
  if (r.ok) {
    const Eigen::MatrixXd Rinn = s.E - s.C * r.P * s.C.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eR(Rinn, Eigen::EigenvaluesOnly);
    r.ok = eR.eigenvalues()(0) > 0.0 && riccati_residual(s, r.P) <= o.accept_residual;
  }
  if (!r.ok) {
    r.ok = riccati_kalman(s, o, r.P, r.iterations);
    r.method = "riccati-difference-iteration";
  }
  return r;
}

}  // namespace fdsid::numerics
