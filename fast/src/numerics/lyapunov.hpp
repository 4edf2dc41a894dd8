#pragma once
// The discrete Lyapunov (Stein) equation (internal header).
#include <Eigen/Dense>

namespace fdsid::numerics {

struct SteinOptions {
  /// Smith doubling stops when ‖A_k‖²_F ≤ tail_tolerance. After k steps the
  /// neglected tail Σ_{j ≥ 2^k} A^j Q A^{jT} = A_k P A_kᵀ is bounded by
  /// ‖A_k‖²_F ‖P‖_F, so any value ≤ u already gives P to working accuracy;
  /// 1e-32 (< u² = 1.2e-32) is stricter than needed, but because ‖A_k‖ is
  /// squared every step it costs at most one more doubling than u would, and
  /// it is the value fdsid has always used (results unchanged).
  double tail_tolerance = 1e-32;
  /// 2^64 terms: more than any ρ(A) < 1 representable below 1 needs.
  int max_doublings = 64;
};

/// Purpose: the solution P of the Stein equation P = A P Aᵀ + Q for a stable
/// A (spectral radius < 1), P = Σ_j A^j Q A^{jT}.
/// Method: Smith doubling, P ← P + A_k P A_kᵀ, A_{k+1} = A_k²; P symmetrised.
/// Numerical aspects: O(n³) per doubling, log₂ of the number of terms needed
/// doublings; the error grows like 1/(1 − ρ²), the condition of the operator.
/// Fails: Error(Numerical, "lyapunov") when ρ(A) ≥ 1.
/// References: Smith, SIAM J. Appl. Math. 16 (1968) 198-201; Higham,
/// Accuracy and Stability §16.
Eigen::MatrixXd stein_smith(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q, const SteinOptions& options = {});

}  // namespace fdsid::numerics
