#include "linalg.hpp"

#include <Eigen/Dense>

// Every decomposition used below is one fast/ instantiates once
// (fast/src/numerics/eigen_instances.hpp): declared extern here, the tests use
// fast/'s compiled copy (the same Eigen template code) instead of compiling
// their own — 43 s of each CI build's compile, ~3 s now.
#include "numerics/eigen_instances.hpp"

namespace fdsid::testing {

Eigen::VectorXd singular_values(const Eigen::MatrixXd& X) { return Eigen::JacobiSVD<Eigen::MatrixXd>(X).singularValues(); }
Eigen::VectorXd singular_values(const Eigen::MatrixXcd& X) { return Eigen::JacobiSVD<Eigen::MatrixXcd>(X).singularValues(); }
Eigen::MatrixXd left_singular_vectors(const Eigen::MatrixXd& X, int k) {
  return Eigen::JacobiSVD<Eigen::MatrixXd>(X, Eigen::ComputeThinU).matrixU().leftCols(k);
}

EigenDecomposition eigen_decomposition(const Eigen::MatrixXd& A) {
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  EigenDecomposition d;
  d.values = es.eigenvalues();
  d.vectors = es.eigenvectors();
  d.inverse_vectors = d.vectors.inverse();
  return d;
}
Eigen::VectorXcd eigenvalues(const Eigen::MatrixXd& A) { return A.eigenvalues(); }
Eigen::VectorXd symmetric_eigenvalues(const Eigen::MatrixXd& A) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
}

Eigen::MatrixXd inverse(const Eigen::MatrixXd& A) { return A.inverse(); }
Eigen::MatrixXcd inverse(const Eigen::MatrixXcd& A) { return A.inverse(); }
Eigen::MatrixXd solve(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) { return Eigen::PartialPivLU<Eigen::MatrixXd>(A).solve(B); }
Eigen::MatrixXcd solve(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B) {
  return Eigen::PartialPivLU<Eigen::MatrixXcd>(A).solve(B);
}
Eigen::MatrixXd least_squares(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) { return A.householderQr().solve(B); }
Eigen::MatrixXd thin_q(const Eigen::MatrixXd& X) {
  return Eigen::HouseholderQR<Eigen::MatrixXd>(X).householderQ() * Eigen::MatrixXd::Identity(X.rows(), X.cols());
}

}  // namespace fdsid::testing
