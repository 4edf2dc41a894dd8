#pragma once
// Constants of double-precision arithmetic shared by fast/ (internal header).
#include <limits>

namespace fdsid::numerics {

/// Unit roundoff u = ε/2 = 2^-53 ≈ 1.11e-16 of IEEE double with rounding to
/// nearest: fl(x op y) = (x op y)(1 + δ), |δ| ≤ u (Higham, Accuracy and
/// Stability of Numerical Algorithms, 2nd ed., §2.2).
constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() / 2;

/// A relative size below which a quantity computed from O(10³)-term sums in
/// double precision is rounding noise: 1e-12 ≈ 9·10³ u. A sum of L terms has
/// relative error ≤ γ_L ≈ L u (Higham §4.2); with the ≤ 10⁴ lines/terms of the
/// records fdsid handles that is ≤ 10⁴ u ≈ 1.1e-12, rounded to the decade
/// 1e-12 (the value the gap diagnosis has always used, so results are unchanged).
/// Uses: the floor added to an F ratio before its logarithm in the leakage
/// test (an F ratio is ≈ 1 under the null; F < 1e-12 is the rounding noise of
/// V0 − V1 and log F is kept finite at F = 0), and Nelder–Mead's stopping test.
constexpr double kNegligibleRelative = 1e-12;

/// The square of kNegligibleRelative, for ratios of squared amplitudes
/// (variances against powers): a sample variance below 1e-24·|mean|² means
/// periods that agree to ≈ 1e-12 relative amplitude, the rounding level of
/// simulating and transforming them, i.e. no measured noise.
constexpr double kNegligibleVarianceRatio = 1e-24;

}  // namespace fdsid::numerics
