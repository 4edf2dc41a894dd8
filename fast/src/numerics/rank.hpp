#pragma once
// The rank test on the diagonal of a triangular factor (internal header).
#include <Eigen/Dense>

#include "numerics/constants.hpp"

namespace fdsid::numerics {

/// A square matrix is numerically invertible when its reciprocal condition
/// number exceeds a small multiple of the unit roundoff: rcond(W) > 10·u.
/// Derivation: LU with partial pivoting solves W x = b with relative error
/// ≲ κ(W)·u·(growth factor) (Higham, Accuracy and Stability, 2nd ed., Thm 9.4
/// and §7.1), so for rcond = 1/κ ≤ O(u) the solution carries no correct digit;
/// 10 allows for the 1-norm estimate's factor-of-n slack (Higham §15.3).
/// Callers: frf_id (I − A_w), riccati.hpp (SDA's W = I + G_k H_k).
constexpr double kMinRcond = 10 * kUnitRoundoff;

/// Safety constant c of the rank floor below (see rank_floor).
constexpr double kRankSafety = 100;

/// Rounding level of the diagonal of R from a Householder QR:
///   floor = c · u · s · max_i |r_ii|.
/// Derivation: the computed R is the exact R of A + ΔA with
/// ‖ΔA e_j‖₂ ≤ γ̃_{rows} ‖A e_j‖₂ (Higham, Accuracy and Stability, 2nd ed.,
/// Thm 19.4); with rounding errors that behave as independent random
/// variables γ̃_rows ≈ u·√rows (Higham §2.8, "rule of thumb"), so the size
/// factor s of a tall problem is √rows. A diagonal entry at or below
/// u·s·max|r_ii| is indistinguishable from one that an O(u) perturbation of the
/// data makes zero: the columns are numerically dependent. c = 100 allows for
/// the constants dropped from γ̃ and for the scaling of the columns.
/// Callers: frf_id steps 1b and 3 (s = √(rows), rows = 2·F·c·(1 or p));
/// spectrum_id step 8 (s = 10, see there).
inline double rank_floor(double max_diagonal, double size_factor, double safety = kRankSafety) {
  return safety * kUnitRoundoff * size_factor * max_diagonal;
}

/// True when the upper-triangular R's leading diagonal |r_ii| (given as their
/// absolute values) has max > 0 and min > rank_floor(max, size_factor):
/// R is numerically of full rank.
inline bool numerically_full_rank(const Eigen::VectorXd& abs_diagonal, double size_factor,
                                  double safety = kRankSafety) {
  const double rmax = abs_diagonal.maxCoeff();
  return rmax > 0 && abs_diagonal.minCoeff() > rank_floor(rmax, size_factor, safety);
}

}  // namespace fdsid::numerics
