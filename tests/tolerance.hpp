#pragma once
/// Tolerances of the noise-free tests, each derived from unit roundoff and a
/// stated condition number (see the derivation beside each function).
#include <cmath>
#include <limits>

#include <Eigen/Dense>

namespace fdsid::testing {

constexpr double kU = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff, 2^-53

/// Relative spectrum error of Algorithm 1 on noise-free data, measured as
/// max_z ||Ŝ(z) - S(z)||_F / max_z ||S(z)||_F on and between grid points.
///
/// Derivation (first order). The samples S_k carry a relative error <= u
/// ||S||. Each Fourier coefficient (Eq. 20, FFT) is accurate to
/// log2(N) u ||S||_inf; 𝒴 (Eq. 19) adds two of them per entry, so
/// ||δ𝒴||_2 <= ||δ𝒴||_F <= 2 sqrt(p r) m log2(N) u ||S||_inf <= (p + r) m log2(N) u ||S||_inf.
/// The range estimate U_{2n} then moves by sin Θ <= ||δ𝒴|| / σ_{2n}(𝒴) (Wedin),
/// and Ã, Ĉ, the least-squares summands and Ŝ are smooth functions of U_{2n}
/// whose derivative is bounded by σ_1(𝒴)/||S||_inf (the scale of the Fourier
/// coefficients that U_{2n} multiplies). Hence
///   rel. error <= C (p + r) m log2(N) u σ_1/σ_{2n},
/// and we take C = 4 for the remaining O(1) factors (the LS step on well-separated
/// poles, the Riccati step that leaves Ŝ unchanged). Measured errors on the
/// paper's system and random MIMO systems sit 10-1000 times below this bound.
inline double spectrum_tolerance(int p, int r, int m, int N, double sigma1_over_sigma2n) {
  return 4.0 * (p + r) * m * std::log2(static_cast<double>(N)) * kU * sigma1_over_sigma2n;
}

/// Eigenvalue condition number max_i ||x_i|| ||y_i|| / |y_i^H x_i| of A.
inline double eigenvalue_condition(const Eigen::MatrixXd& A) {
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  const Eigen::MatrixXcd V = es.eigenvectors();
  const Eigen::MatrixXcd W = V.inverse();
  double k = 1.0;
  for (Eigen::Index i = 0; i < A.rows(); ++i) k = std::max(k, V.col(i).norm() * W.row(i).norm());
  return k;
}

/// κ(V) = ||V|| ||V^{-1}|| of the eigenvector matrix of A (columns normalised):
/// ||A^k||_2 <= κ(V) ρ(A)^k for diagonalisable A.
inline double eigenvalue_condition_number_of_basis(const Eigen::MatrixXd& A) {
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  Eigen::MatrixXcd V = es.eigenvectors();
  for (Eigen::Index i = 0; i < V.cols(); ++i) V.col(i).normalize();
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXcd>(V).singularValues();
  return s(0) / s(s.size() - 1);
}

}  // namespace fdsid::testing
