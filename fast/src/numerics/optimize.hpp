#pragma once
// Derivative-free minimisers used by the gap diagnosis (internal header).
#include <Eigen/Dense>
#include <functional>
#include <utility>

#include "numerics/constants.hpp"

namespace fdsid::numerics {

struct Minimize1dOptions {
  /// Bits of precision Brent's method is asked for: 40 of double's 53, i.e. a
  /// relative tolerance 2^-40 ≈ 9e-13 ≈ 8·10³ u on x. Near a minimum f changes
  /// only quadratically, so x is determined to ≈ √u ≈ 1e-8 by f alone
  /// (Brent 1973 ch. 5; Press et al. §10.1); asking for more than ≈ 26 bits
  /// gains nothing in f, and 40 keeps the historical results of gap.cpp.
  int brent_bits = 40;
};

/// Purpose: the minimum (x, f(x)) of f over [lo, hi].
/// Method: f on a uniform grid of n ≥ 2 points, then Brent's method (Boost's
/// brent_find_minima) between the neighbours of the best grid point; the
/// better of the grid point and Brent's result.
/// Numerical aspects: n + O(brent_bits) evaluations; finds the global
/// minimum when the grid resolves the basins of f.
/// References: Brent, Algorithms for Minimization without Derivatives (1973).
std::pair<double, double> minimize_1d(const std::function<double(double)>& f, double lo, double hi, int n,
                                      const Minimize1dOptions& options = {});

struct NelderMeadOptions {
  int iterations = 200;
  /// Stops when the simplex values agree: |f_worst − f_best| ≤
  /// relative_tolerance·|f_best| + absolute_tolerance. The relative tolerance
  /// kNegligibleRelative = 1e-12 (≈ 9·10³ u): the differences of f below it
  /// are rounding noise of f's sums; 1e-300 only keeps the test true at
  /// f_best = 0 (any value above the underflow threshold would do).
  double relative_tolerance = kNegligibleRelative;
  double absolute_tolerance = 1e-300;
};

/// Purpose: a local minimiser of f: R² → R from x0.
/// Method: Nelder–Mead simplex (reflection 1, expansion 2, contraction ½,
/// shrink ½) from the simplex {x0, x0 + step(0) e₁, x0 + step(1) e₂}; no
/// Debian library offers one (Boost.Math has one-dimensional minimisers only).
/// Numerical aspects: 1–2 evaluations per iteration (3 on a shrink); no
/// convergence guarantee (Lagarias et al. 1998); returns the best vertex.
/// References: Nelder & Mead, Comput. J. 7 (1965) 308-313.
Eigen::Vector2d nelder_mead(const std::function<double(const Eigen::Vector2d&)>& f, Eigen::Vector2d x0,
                            Eigen::Vector2d step, const NelderMeadOptions& options = {});

}  // namespace fdsid::numerics
