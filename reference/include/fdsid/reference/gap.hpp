// High-precision reference of the sim-to-real gap statistic of `fdsid gap`
// (shared/CONTRACTS.md): how far a model's response is from periodic
// input/output records, measured in units of the record's own noise.
//
// This is the oracle for the double-precision gap statistic and period tests in fast/; it shares
// only the scalar and Model types with the rest of the reference and no code at
// all with fast/. The per-period DFTs are the direct sums of Pintelon (2002)
// Eq. (4) in 50-digit arithmetic (u ≈ 1e-50): no FFT, slow is fine.
#pragma once

#include "fdsid/reference/io.hpp"  // read_records_csv
#include "fdsid/reference/spectrum_id.hpp"

#include <functional>
#include <string>
#include <vector>

namespace fdsid::reference {

/// t(k) and p(k) of gap_statistic at one list of DFT lines (same order as given).
struct LineStatistics {
  std::vector<int> lines;               ///< DFT lines k, as given (1 ≤ k ≤ P/2)
  std::vector<Complex> mean_residual;   ///< Ē(k) = (1/M) Σ_l E_l(k)
  std::vector<Real> variance;           ///< s²(k) = 1/(M−1) Σ_l |E_l(k) − Ē(k)|² (of one period, not of Ē)
  std::vector<Real> t;                  ///< t(k) = M |Ē(k)|² / s²(k)
  std::vector<Real> p;                  ///< p(k) = (1 + t(k)/(M−1))^{−(M−1)} = P[F(2, 2M−2) > t(k)]
};

/// What gap_statistic returns.
struct GapStatistic {
  LineStatistics excited;    ///< at the K excited lines (those the gap averages over)
  LineStatistics unexcited;  ///< at the unexcited lines given (nonlinearity detection); may be empty
  Real gap = 0;              ///< ((M−2)/(M−1)) (1/K) Σ_{excited k} t(k); E[gap] = 1 under H0
  int M = 0;                 ///< number of periods
};

/// Sim-to-real gap statistic of a SISO response G′ against a periodic record
/// u, y of M = `periods` whole periods of P = `period` samples.
///
/// Arguments: u, y, P·M consecutive samples each; excited_lines, the K ≥ 1
/// distinct DFT lines the excitation drives, and unexcited_lines, distinct
/// lines (possibly none, disjoint from the excited ones) where only t and p
/// are wanted, all in 1 … P/2; response(k) = G′ at line k, called once per
/// line of either list (so augmented models can be tested, not only Models).
///
/// Method: per-period DFTs U_l(k), Y_l(k) of Pintelon (2002) Eq. (4),
/// (1/√P) Σ_{t=0}^{P−1} z(lP + t) e^{−j2πkt/P}, by direct sums (period_spectra
/// of frf_id.hpp, twiddles from cos/sin of 2πq/P with π in 50 digits);
/// residual E_l(k) = Y_l(k) − G′(k) U_l(k); Ē(k), s²(k) two-pass as in
/// LineStatistics; t(k) = M|Ē|²/s²; gap = ((M−2)/(M−1)) mean_k t(k).
/// Statistics: if the model is right and the noise is circular complex
/// Gaussian, independent over the periods, with variance σ² at line k, then
/// 2M|Ē|²/σ² ~ χ²_2 and 2(M−1)s²/σ² ~ χ²_{2M−2}, independent, so
/// t(k) = [2M|Ē|²/σ²/2] / [2(M−1)s²/σ²/(2M−2)] ~ F(2, 2M−2), whose mean is
/// (2M−2)/(2M−4) = (M−1)/(M−2): hence the factor (M−2)/(M−1) and E[gap] = 1.
/// p(k) = P[F(2, 2M−2) > t(k)]: with F = X/W, X = χ²_2/2 ~ Exp(1) and
/// W = χ²_{d}/d (d = 2M−2) independent, P[F > t] = E[P(X > tW | W)] =
/// E[e^{−tW}] = (1 + 2t/d)^{−d/2} (the moment generating function of χ²_d at
/// −t/d), i.e. (1 + t/(M−1))^{−(M−1)}.
///
/// Numerical aspects: 50-digit arithmetic; t is exact up to a few u relative
/// unless s² is itself a rounding residue (a noise-free record gives
/// s² ≈ u²|Y|², and t is then meaningless — only s² == 0 exactly is refused).
/// At k = P/2 (even P) all DFTs are real, so E is not circular: there
/// t ~ F(1, M−1) under H0, not F(2, 2M−2), and p(k) is only nominal.
/// Throws InputError for sizes ≠ P·M, P < 2, M < 3, no excited line, a line
/// outside 1 … P/2, a repeated line, a line in both lists, a non-finite
/// response, and s²(k) == 0 (message names the line).
///
/// References: R. Pintelon, Automatica 38 (2002) 1295-1311, Eq. (4) and
/// Section 4.1 (sample mean and variance over periods); R. Pintelon &
/// J. Schoukens, System Identification: A Frequency Domain Approach (2012),
/// Ch. 2-3 (periodic excitation, detection of nonlinear distortions at
/// unexcited lines); the F distribution of the Hotelling T² statistic.
GapStatistic gap_statistic(const std::vector<Real>& u, const std::vector<Real>& y, int period,
                           int periods, const std::vector<int>& excited_lines,
                           const std::vector<int>& unexcited_lines,
                           const std::function<Complex(int)>& response);

/// gap_statistic for a SISO Model: G′(k) = D + C(ξI − A)⁻¹B at
/// ξ = e^{j2πk/P} (domain "discrete"; sample_time unused) or
/// ξ = j2πk/(P·Ts) (domain "continuous", Ts = `sample_time` in s, the record's
/// sampling interval from the meta file, not model.sample_time), evaluated by
/// frequency_response of frf_id.hpp. Throws InputError for a non-SISO model,
/// Ts ≤ 0 (continuous), a line on a pole, or as gap_statistic.
GapStatistic gap_statistic(const std::vector<Real>& u, const std::vector<Real>& y, int period,
                           int periods, const std::vector<int>& excited_lines,
                           const std::vector<int>& unexcited_lines, const Model& model,
                           const Real& sample_time);

/// Survival function of F(2, 2M−2): P[F > t] = (1 + t/(M−1))^{−(M−1)} (derived
/// above). Throws InputError for M < 2 or t < 0.
Real gap_p_value(const Real& t, int M);

// ---------------------------------------------------------------------------
// The period tests of `fdsid gap` (issue 17: real noise is not stationary),
// on the residual spectra r_m(k) = Y_m(k) − G(k) U_m(k) of R periods
// (residuals[m], m = 0 … R−1) at K consecutive DFT lines (residuals[m][i]:
// line k₀ + i). Both tests difference the lines in disjoint adjacent pairs,
//   e_m(j) = r_m(2j) − r_m(2j + 1),  j = 0 … J − 1,  J = ⌊K/2⌋
// (the leakage term of one period's DFT of coloured noise is smooth in k and
// cancels to first order), and take the deviations from the periods' mean,
//   d_m(j) = e_m(j) − (1/R) Σ_{m'} e_{m'}(j);
// a pair with Σ_m |d_m(j)|² = 0 (no noise there) is left out; J' counts the
// pairs used.

/// Equal noise power in every period. Per pair the shares
/// q_m(j) = |d_m(j)|² / Σ_{m'} |d_{m'}(j)|² (which a periodic model error, the
/// line's noise level and a common scale leave alone); Q_m = (1/J') Σ_j q_m(j);
/// v = (1/(J' R)) Σ_j Σ_m (q_m(j) − 1/R)²;
///   S = J' (R − 1) / (v R) · Σ_m (Q_m − 1/R)²,
/// p = P[χ²_{R−1} > S] = Q((R − 1)/2, S/2) (the regularised upper incomplete
/// gamma function); relative_m = R Q_m. With independent noise of equal power
/// the q_m(j) are exchangeable with Σ_m q_m = 1, so E q_m = 1/R and
/// Cov q = v R/(R − 1) (I − 11ᵀ/R) (v = Var q_m); the mean over J' independent
/// pairs is normal for large J' and S, the quadratic form in the
/// pseudo-inverse of that covariance, is χ²_{R−1}. tested = R ≥ 3, J' ≥ 30
/// and v > 0; otherwise p = 1 and relative is empty.
struct PeriodPowerStatistic {
  bool tested = false;
  int pairs = 0;                ///< J'
  Real S = 0, p = 1, v = 0;
  std::vector<Real> relative;   ///< R Q_m
};
PeriodPowerStatistic period_power_statistic(const std::vector<std::vector<Complex>>& residuals);

/// Independent noise from period to period: per pair the circular lag-one
/// correlation c(j) = Σ_m Re(d_m d̄_{(m+1) mod R}) / Σ_m |d_m|², its mean c̄
/// over the J' pairs and their sample variance (divisor J' − 1). For
/// independent periods of equal power E c = −1/(R − 1) exactly: d is then
/// isotropic in the (R − 1)-dimensional subspace Σ_m d_m = 0 and its direction
/// independent of its norm, so E c = tr(B Π)/(R − 1), B = (L + Lᵀ)/2 the
/// symmetrised circular shift (zero diagonal, rows summing to 1) and
/// Π = I − 11ᵀ/R: tr(B Π) = tr B − 1ᵀB1/R = −1. tested = R ≥ 4
/// and J' ≥ 30 (with R = 3, c ≡ −1/2).
struct PeriodCorrelation {
  bool tested = false;
  int pairs = 0;  ///< J'
  Real mean = 0, variance = 0;
};
PeriodCorrelation period_lag_correlation(const std::vector<std::vector<Complex>>& residuals);

}  // namespace fdsid::reference
