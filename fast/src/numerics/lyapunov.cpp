#include "numerics/lyapunov.hpp"

#include <string>

#include "fdsid/error.hpp"
#include "numerics/eigen_instances.hpp"

namespace fdsid::numerics {

Eigen::MatrixXd stein_smith(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q, const SteinOptions& o) {
  const auto n = A.rows();
  if (n == 0) return Eigen::MatrixXd(0, 0);
  const double rho = A.eigenvalues().cwiseAbs().maxCoeff();
  if (!(rho < 1.0))
    throw Error(ErrorKind::Numerical, "lyapunov", "A is not stable (spectral radius " + std::to_string(rho) + ")");
  Eigen::MatrixXd P = Q, Ak = A;
  for (int it = 0; it < o.max_doublings; ++it) {
    P += Ak * P * Ak.transpose();
    Ak = (Ak * Ak).eval();
    if (Ak.squaredNorm() <= o.tail_tolerance) break;
  }
  return 0.5 * (P + P.transpose());
}

}  // namespace fdsid::numerics
