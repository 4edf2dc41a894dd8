// High-precision reference of the sim-to-real gap statistic of `fdsid gap`
// (shared/CONTRACTS.md): how far a model's response is from periodic
// input/output records, measured in units of the record's own noise.
//
// This is the oracle for the double-precision gap statistic in fast/; it shares
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

}  // namespace fdsid::reference
