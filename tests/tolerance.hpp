#pragma once
/// Tolerances of the noise-free tests, each derived from unit roundoff and a
/// stated condition number (see the derivation beside each function).
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "fdsid/compare.hpp"
#include "linalg.hpp"

namespace fdsid::testing {


constexpr double kU = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff, 2^-53

/// Relative spectrum error of Algorithm 1 on noise-free data, measured as
/// max_z ||Ŝ(z) - S(z)||_F / max_z ||S(z)||_F on and between grid points:
/// 4 (p + r) m log2(N) u σ1/σ_2n, derived in fdsid/compare.hpp (the oracle
/// states the same bound to the users of `fdsid check`).
inline double spectrum_tolerance(int p, int r, int m, int N, double sigma1_over_sigma2n) {
  return double_precision_spectrum_tolerance(p, r, m, N, sigma1_over_sigma2n);
}

/// Eigenvalue condition number max_i ||x_i|| ||y_i|| / |y_i^H x_i| of A.
inline double eigenvalue_condition(const Eigen::MatrixXd& A) {
  const EigenDecomposition es = eigen_decomposition(A);
  const Eigen::MatrixXcd& V = es.vectors;
  const Eigen::MatrixXcd& W = es.inverse_vectors;
  double k = 1.0;
  for (Eigen::Index i = 0; i < A.rows(); ++i) k = std::max(k, V.col(i).norm() * W.row(i).norm());
  return k;
}

/// κ(V) = ||V|| ||V^{-1}|| of the eigenvector matrix of A (columns normalised):
/// ||A^k||_2 <= κ(V) ρ(A)^k for diagonalisable A.
inline double eigenvalue_condition_number_of_basis(const Eigen::MatrixXd& A) {
  Eigen::MatrixXcd V = eigen_decomposition(A).vectors;
  for (Eigen::Index i = 0; i < V.cols(); ++i) V.col(i).normalize();
  const Eigen::VectorXd s = fdsid::testing::singular_values(Eigen::MatrixXcd(V));
  return s(0) / s(s.size() - 1);
}

}  // namespace fdsid::testing
