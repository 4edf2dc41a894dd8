#pragma once
// Autoregressive prewhitening (internal header).
#include <Eigen/Dense>

namespace fdsid::numerics {

/// Purpose: the prediction-error (whitening) filter a = (1, a₁, …, a_p) of the
/// autoregression that fits the autocovariances r(0), r(1), …, r(p_max) of a
/// stationary sequence, ε(t) = Σ_i a_i x(t − i) white; the order p ≤ p_max
/// chosen by Schwarz's criterion N ln σ²_p + p ln N (σ²_p the order-p
/// prediction-error variance, N the number of samples behind r).
/// Method: the Levinson–Durbin recursion (all orders at once); r need only be
/// known up to a positive factor.
/// Numerical aspects: O(p_max²); the reflection coefficients of a positive
/// definite sequence lie in (−1, 1), so σ²_p decreases and stays > 0 (the
/// recursion stops at the first order where it would not: a sequence that an
/// order-p filter predicts exactly).
/// References: Durbin, Rev. Inst. Int. Stat. 28 (1960) 233-244; Schwarz, Ann.
/// Statist. 6 (1978) 461-464; Brockwell & Davis, Time Series: Theory and
/// Methods (1991) §8.2.
Eigen::VectorXd whitening_filter(const Eigen::VectorXd& r, int p_max, double N);

}  // namespace fdsid::numerics
