#pragma once
/// Dense linear algebra for the tests and properties, compiled once
/// (tests/linalg.cpp) instead of instantiating Eigen's decompositions in every
/// test translation unit: EigenSolver, JacobiSVD and the LU/QR solvers cost
/// 5-15 s of compile time each per unit that uses them. Each function is the
/// Eigen call named beside it, nothing more, so a test reads the same.
#include <Eigen/Core>

namespace fdsid::testing {

/// JacobiSVD(X).singularValues(), largest first.
Eigen::VectorXd singular_values(const Eigen::MatrixXd& X);
Eigen::VectorXd singular_values(const Eigen::MatrixXcd& X);
/// The first k columns of the thin U of JacobiSVD(X, ComputeThinU).
Eigen::MatrixXd left_singular_vectors(const Eigen::MatrixXd& X, int k);

/// EigenSolver(A): eigenvalues, eigenvectors (unit columns, Eigen's own
/// normalisation) and the inverse of the eigenvector matrix.
struct EigenDecomposition {
  Eigen::VectorXcd values;
  Eigen::MatrixXcd vectors;
  Eigen::MatrixXcd inverse_vectors;
};
EigenDecomposition eigen_decomposition(const Eigen::MatrixXd& A);
/// A.eigenvalues() (EigenSolver without eigenvectors).
Eigen::VectorXcd eigenvalues(const Eigen::MatrixXd& A);
/// SelfAdjointEigenSolver(A).eigenvalues(), ascending.
Eigen::VectorXd symmetric_eigenvalues(const Eigen::MatrixXd& A);

/// A.inverse() (PartialPivLU).
Eigen::MatrixXd inverse(const Eigen::MatrixXd& A);
Eigen::MatrixXcd inverse(const Eigen::MatrixXcd& A);
/// PartialPivLU(A).solve(B).
Eigen::MatrixXd solve(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B);
Eigen::MatrixXcd solve(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B);
/// A.householderQr().solve(B): least squares for tall A.
Eigen::MatrixXd least_squares(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B);
/// The first X.cols() columns of the Q of HouseholderQR(X).
Eigen::MatrixXd thin_q(const Eigen::MatrixXd& X);

}  // namespace fdsid::testing
