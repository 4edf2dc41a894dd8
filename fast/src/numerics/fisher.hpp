#pragma once
// Fisher's combination of weighted residuals (internal header): the noise
// law behind identify-frf's fit verdict and the gap's tests.
#include <Eigen/Dense>

namespace fdsid::numerics {

/// Purpose: X = −2 Σ ln S(t_k) for independent weighted residuals t_k whose
/// survival function S is exact under a right model: Exp(1) terms |e|²/σ²
/// with known variances (`periods` = 0: S(t) = e^{−t}, X = 2 Σ t) and
/// F(2, 2M − 2) terms with the sample variances of M = `periods` periods
/// (S(t) = (1 + t/(M−1))^{−(M−1)}, X = 2 (M−1) Σ ln(1 + t/(M−1))). Each
/// −2 ln S(t) is χ²₂, so X ~ χ²_{2K} for K terms.
/// References: Fisher (1932), Statistical Methods for Research Workers, §21.1.
double fisher_statistic(const Eigen::Ref<const Eigen::VectorXd>& t, int periods);

/// The upper tail P(χ²_{2K−q} ≥ X): small when the residuals are larger than
/// the noise (1 for no terms or 2K ≤ q). q = 0 at the true model; q real
/// parameters fitted by least squares remove about q χ²₁ terms (see below).
double fisher_p(const Eigen::Ref<const Eigen::VectorXd>& t, int periods, int q = 0);

/// The lower tail P(χ²_{2K−q} ≤ X) when q real parameters were fitted to the
/// 2K real residual components (1 for no terms or 2K ≤ q). A least-squares fit
/// of q parameters removes about q χ²₁ terms from the sum (exactly so for a
/// linear fit of the residuals; X's terms are ≈ 2t for the small t a fit
/// leaves, so the same count), hence χ² with 2K − q degrees of freedom: with
/// fewer degrees the tail is smaller, so the test errs towards not flagging.
double fisher_p_below(const Eigen::Ref<const Eigen::VectorXd>& t, int periods, int q);

}  // namespace fdsid::numerics
