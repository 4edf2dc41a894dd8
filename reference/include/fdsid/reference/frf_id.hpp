// High-precision reference implementation of Pintelon (2002) frequency-domain
// subspace identification (Algorithms 1, 2.1 and 2.2; Sections 4.1 and 5).
//
// This is the oracle for the double-precision implementation in fast/; it
// shares only the scalar, matrix and Model types of spectrum_id.hpp with the
// Akçay reference and no code at all with fast/. The data matrices of Eq. (9)
// are built as written, with explicit Kronecker products W_r(k) ⊗ U[k].col(j)
// in 50-digit arithmetic (u ≈ 1e-50); slow is fine.
#pragma once

#include "fdsid/reference/spectrum_id.hpp"

#include <string>
#include <vector>

namespace fdsid::reference {

/// Frequency-domain data of Pintelon (2002) Eq. (3)/(15) at F distinct frequencies.
/// Each frequency k carries c "columns" (c is the same for all k): column j is one
/// input/output pair (U[k].col(j) ∈ C^m, Y[k].col(j) ∈ C^p). Periodic I/O data: c = 1.
/// FRF data: U[k] = I_m, Y[k] = G(ξ_k) (p × m), c = m.
struct FrfData {
  std::string domain = "discrete";  ///< "discrete": ξ_k = exp(jω_k), ω in rad/sample; "continuous": s_k = jω_k, ω in rad/s
  std::vector<Real> omega;          ///< F distinct frequencies: (0, ∞) continuous, [0, π] discrete
  std::vector<MatrixC> U;           ///< F matrices m × c
  std::vector<MatrixC> Y;           ///< F matrices p × c
  std::vector<MatrixR> variance;    ///< F matrices p × c: σ²_Y of each entry of Y; all > 0
};

/// Parameters of identify_frf.
struct FrfOptions {
  int order = 0;                               ///< n_a ≥ 1 (required)
  int r = 0;                                   ///< r > n_a (required)
  std::string continuous_method = "bilinear";  ///< "bilinear" (Alg. 2.1) or "orthogonal" (Alg. 2.2); ignored for discrete
  Real omega_scale = 0;                        ///< ω_scale; 0 = sqrt(ω_min ω_max)
  /// Discrete data: "monomial" (Algorithm 1, ξ = z), "bilinear" (Algorithm
  /// 2.1 on the Tustin frequencies: s' = (z − 1)/(z + 1) = j tan(ω/2), then
  /// w = (s'/t_s − 1)/(s'/t_s + 1) with t_s = tan(ω_scale/2), ω_scale in
  /// rad/sample; 0 = 2 atan √(tan(ω_lo/2) tan(ω_hi/2)) over the frequencies in
  /// (0, π), π/2 when there are none) or "orthogonal" (Algorithm 2.2 on the
  /// frequencies tan(ω/2) with the scale t_s; ω = π refused). Ignored for
  /// continuous data.
  std::string discrete_method = "monomial";
  /// Verification only (what `fdsid check` uses to measure how far rounding
  /// moves the result): > 0 moves each row of Z = [𝐔^re; 𝐘^re] of step 1a
  /// (a column of the Zᵀ that step 1b factors) by backward_perturbation times
  /// its norm, and C_Y by backward_perturbation times ‖C_Y‖_F (symmetrically),
  /// each in a random direction drawn from `perturbation_seed`: the
  /// column-wise backward error model of a Householder QR of Zᵀ and of a
  /// Cholesky factorisation of C_Y (Higham 2002, Thms 19.4 and 10.3); for
  /// Algorithm 2.2 also the recurrence matrix H of the orthogonal basis, by
  /// backward_perturbation times ‖H‖_F (the rounding of the inner products
  /// that give it). 0: none.
  Real backward_perturbation = 0;
  unsigned perturbation_seed = 1;
};

/// What identify_frf returns.
struct FrfResult {
  Model model;  ///< domain and real (A, B, C, D); continuous models in rad/s (s, not s/ω_scale), sample_time 0
  int order = 0, r = 0;
  std::vector<Real> singular_values;  ///< Σ of step 1c (all r·p of them, largest first)
  Real v_sub = 0;                     ///< Eq. (35) at the estimate, with the data's variance
  std::vector<Complex> poles;         ///< eigenvalues of Â
};

/// Pintelon (2002) Algorithm 1 (discrete time), Algorithm 2.1 (continuous time,
/// bilinear map) or Algorithm 2.2 (continuous time, orthogonal polynomials),
/// generalised to m inputs, p outputs and c columns per frequency.
///
/// Method: step 1a, the data matrices of Eq. (9)/(11) with one block column
/// W_r(k) ⊗ U[k].col(j) per (k, j) and C_Y = Σ_{k,j} Re((W_r W_rᴴ) ⊗ diag σ²(k,j))
/// (Eq. 18); step 1b, the projection of Eq. (20), 𝐘^re Π = 𝐘^re −
/// (𝐘^re𝐔^reᵀ)(𝐔^re𝐔^reᵀ)⁻¹𝐔^re, which has the Gram matrix of R22ᵀ (Π itself is
/// never formed); step 1c, C_Y = L Lᵀ (Cholesky), the SVD of
/// K = L⁻¹(𝐘^reΠ)(𝐘^reΠ)ᵀL⁻ᵀ = UΣ²Uᵀ (JacobiSVD), Ô_r = L U[:, 1:n];
/// step 2, Eq. (19) (generalised shift for Alg. 2.2); step 3, Eq. (17) with
/// W = 1/σ_Y as a real linear least-squares problem in (B, D)
/// (column-pivoted Householder QR of the stacked real and imaginary parts).
/// Alg. 2.1: ξ_k = w_k = (s̃_k − 1)/(s̃_k + 1), s̃ = jω/ω_scale, then the exact
/// bilinear back-transform A_c = (I − A_w)⁻¹(I + A_w), B_c = √2(I − A_w)⁻¹B_w,
/// C_c = √2 C_w(I − A_w)⁻¹, D_c = D_w + C_w(I − A_w)⁻¹B_w, and A = ω_scale A_c,
/// B = ω_scale B_c. Alg. 2.2: ξ = s̃, the monomial rows replaced by real
/// polynomials q_i (degree i) orthonormal for ⟨p,q⟩_u = Σ_k Re(p ‖U[k]‖² q̄),
/// resp. ⟨p,q⟩_y = Σ_k Re(p ‖Y[k]‖² q̄) (Frobenius norms), built by
/// Gram–Schmidt (twice) on s̃·q_{i−1} (the Arnoldi form of Gram–Schmidt on the
/// monomials: same basis, as q_i has degree i and a positive leading
/// coefficient), which also yields the recurrence s̃ q_j = Σ_i H_ij q_i.
///
/// Numerical aspects: 50-digit arithmetic; forming K squares the condition of
/// R22ᵀ, harmless for the leading n singular vectors at this precision, but
/// singular values below ≈ √u·σ_1 ≈ 1e-25·σ_1 are not resolved (noise-free
/// data show σ_{n+1} ≈ 1e-26·σ_1 instead of 0). On
/// noise-free data the identified G equals the true one to about u·κ, κ the
/// conditioning of the gap σ_n/σ_1 and of the shift equations.
/// Throws InputError for invalid data or options (message names index and
/// field), StepError(1) when 𝐔^re𝐔^reᵀ or C_Y is not positive definite or
/// (Alg. 2.2) the weights support fewer than r independent polynomials,
/// StepError(2) when Ô_r[1:r−1] has no full column rank, StepError(3) when the
/// (B, D) problem is rank deficient, StepError(4) when I − A_w is singular.
///
/// References: R. Pintelon, Automatica 38 (2002) 1295-1311, Sections 3-5;
/// T. McKelvey, H. Akçay & L. Ljung, IEEE TAC 41 (1996) 960-979;
/// Z.-J. Yang & S. Sanada (2000); P. Van Overschee & B. De Moor, Automatica 32
/// (1996) 1653-1666; M. Verhaegen, Automatica 30 (1994) 61-74.
FrfResult identify_frf(const FrfData& data, const FrfOptions& options);

/// Exact bilinear back-transform of Algorithm 2.1 (Yang & Sanada 2000): the
/// continuous model (rad/s) whose G(s) equals G_w(w) at w = (s/ω_scale − 1)/
/// (s/ω_scale + 1), for a w-domain model given as a "discrete" Model.
///
/// Method: s̃ = s/ω_scale = (1 + w)/(1 − w), so wI − A_w = (I − A_w)(s̃I − A_c)/(s̃ + 1)
/// with Q = (I − A_w)⁻¹, A_c = Q(I + A_w), B_c = √2 Q B_w, C_c = √2 C_w Q,
/// D_c = D_w + C_w Q B_w (using I + A_c = 2Q); then A = ω_scale A_c,
/// B = ω_scale B_c, C = C_c, D = D_c. Q by column-pivoted QR.
/// Throws InputError for ω_scale ≤ 0, StepError(4) when I − A_w is singular.
Model bilinear_to_continuous(const Model& w_model, const Real& omega_scale);

/// G(ξ) = C(ξI − A)⁻¹B + D at ξ = e^{jω} (discrete model, ω in rad/sample) or
/// ξ = jω (continuous, rad/s), Eq. (13). Method: one real 2n × 2n linear
/// solve (column-pivoted QR) of the real form of (ξI − A)X = B.
MatrixC frequency_response(const Model& model, const Real& omega);

/// Eq. (35): Σ_k Σ_columns Σ_outputs |Y − G U|² / σ², G = frequency_response.
Real v_sub(const Model& model, const FrfData& data);

/// Eq. (35)'s cost and its exact gradient with respect to every entry of
/// A, B, C, D (real matrices), in 50 digits: the oracle that a double-precision
/// optimiser of the maximum-likelihood (weighted least squares) cost stopped at
/// a stationary point.
struct CostGradient {
  Real cost;               ///< V at the model (equals v_sub)
  MatrixR dA, dB, dC, dD;  ///< ∂V/∂A_ab etc., same shapes as A, B, C, D
};

/// Gradient of V(θ) = Σ_k Σ_j Σ_i |Y_k − G(ξ_k) U_k|²_{ij} / σ²_{k,ij} (Eq. 35,
/// the frequency-domain ML cost for known noise variance) with respect to
/// θ = (A, B, C, D).
///
/// Method: X_k = (ξ_k I − A)⁻¹ (ξ = e^{jω} discrete, jω continuous, from
/// model.domain as in frequency_response and v_sub), G_k = D + C X_k B,
/// E_k = Y_k − G_k U_k (p × c), R_k = E_k ./ σ²_k (entrywise), so
/// V = Σ_k Re tr(E_kᴴ R_k). For real perturbations, d|e|²/σ² = 2 Re(conj(r) de),
/// hence dV = 2 Re Σ_k tr(R_kᴴ dE_k) = −2 Re Σ_k tr(U_k R_kᴴ dG_k), and
/// dG = dD + dC X B + C X dA X B + C X dB (from dX = X dA X). With
/// tr(M dZ) = Σ_ab M_ba dZ_ab and the cyclic property:
///   ∂V/∂D = −2 Re Σ_k (U_k R_kᴴ)ᵀ,            ∂V/∂C = −2 Re Σ_k (X_k B U_k R_kᴴ)ᵀ,
///   ∂V/∂B = −2 Re Σ_k (U_k R_kᴴ C X_k)ᵀ,      ∂V/∂A = −2 Re Σ_k (X_k B U_k R_kᴴ C X_k)ᵀ.
/// X_k by the real 2n × 2n column-pivoted QR solve of frequency_response with
/// right-hand side I_n.
/// Numerical aspects: cost O(F (n³ + n² (m + p) + n p c)); every term is exact
/// up to u·κ(ξ_k I − A), u ≈ 1e-50, but at a stationary point the terms cancel,
/// so judge the gradient absolutely (against Σ_k of the moduli of the terms, or
/// against V), not relative to its own size.
/// Throws InputError as v_sub for invalid data (message names index and
/// field), for a model whose A, B, C, D shapes disagree with each other or with
/// the data's m = U rows and p = Y rows (message names the matrix), and when
/// some ω_k lies on a pole of the model.
/// References: R. Pintelon, Automatica 38 (2002) 1295-1311, Eq. (35);
/// R. Pintelon & J. Schoukens, System Identification: A Frequency Domain
/// Approach (2012), Ch. 9 (Jacobian of the ML cost of state-space models).
CostGradient cost_gradient(const Model& model, const FrfData& data);

/// The errors-in-variables cost of SISO data (Pintelon & Schoukens 2012,
/// Ch. 10) and its gradient in θ = (A, B, C, D):
///   V = Σ_k |e_k|² / v_k,  e_k = Y_k − G_k U_k,
///   v_k = σ²_Y,k + |G_k|² σ²_U,k − 2 Re(σ_YU,k conj G_k)
/// (σ²_Y,k = data.variance, σ²_U,k = var_U[k], σ_YU,k = cov_YU[k]).
/// Derivation: dV = Σ_k [2 Re(conj(e) de)/v − |e|² dv/v²] with de = −dG U and
/// dv = 2 Re(dG (conj(G) σ²_U − conj(σ_YU))), so dV = 2 Re Σ_k w_k dG_k with
/// w_k = −U_k conj(e_k)/v_k − (|e_k|²/v_k²)(conj(G_k) σ²_U,k − conj(σ_YU,k)),
/// and with dG = dD + dC X B + C X dA X B + C X dB as in cost_gradient:
///   ∂V/∂D = 2 Re Σ w,  ∂V/∂C = 2 Re Σ (X B w)ᵀ,  ∂V/∂B = 2 Re Σ (w C X)ᵀ,
///   ∂V/∂A = 2 Re Σ (X B w C X)ᵀ.
/// Throws InputError as cost_gradient, for data that are not SISO with one
/// column, for var_U / cov_YU not of length F, and for v_k ≤ 0.
CostGradient eiv_cost_gradient(const Model& model, const FrfData& data, const std::vector<Real>& var_U,
                               const std::vector<Complex>& cov_YU);

/// Eq. (4): DFT Z(k) = (1/√N) Σ_t z(t) e^{−j2πkt/N} of each period of a record of
/// `periods` whole periods of length N = `period` (one std::vector<Real> per
/// channel, each of length periods·period), at the given lines k
/// (1 ≤ k ≤ period/2). Direct sums. Result [l][k] = column vector over channels.
/// Throws InputError on bad lengths or lines.
std::vector<std::vector<MatrixC>> period_spectra(const std::vector<std::vector<Real>>& channels,
                                                 int period, int periods,
                                                 const std::vector<int>& lines);

/// Sample statistics of Eq. (25) and (32) over M ≥ 2 experiments.
struct SampleStatistics {
  FrfData data;                ///< U = Û, Y = Ŷ (sample means), variance = σ̂²_Y / M (Section 4.1)
  std::vector<MatrixR> var_U;  ///< σ̂²_U(k) per input entry (1/(M−1)), not divided by M
  std::vector<MatrixC> cov_YU; ///< σ̂²_YU(k) of Eq. (32) (p × m), not divided by M
  int M = 0;
};

/// Eq. (25)/(32): sample means, variances and the input/output covariance of
/// M ≥ 2 experiments U_l[l][k] (m × 1), Y_l[l][k] (p × 1) at the F frequencies
/// `omega`. Direct sums. Throws InputError for M < 2 or shape mismatches.
SampleStatistics sample_statistics(const std::string& domain, const std::vector<Real>& omega,
                                   const std::vector<std::vector<MatrixC>>& U_l,
                                   const std::vector<std::vector<MatrixC>>& Y_l);

/// Section 5, errors-in-variables (SISO: m = p = 1): data replaced by U = 1,
/// Ĝ = Ŷ/Û and variance σ̂²_G/M with
/// σ̂²_G = |Ĝ|²(σ̂²_Y/|Ŷ|² + σ̂²_U/|Û|² − 2 Re(σ̂²_YU/(Ŷ·conj(Û)))).
/// Eq. (31) as printed has Ŷ Û in the last denominator; the first-order
/// expansion δG = G(δY/Y − δU/U) gives E[δY conj δU]/(Y conj U), so the
/// conjugate of Û is used here (corrected form). Evaluated as the identical
/// (σ̂²_Y + |Ĝ|²σ̂²_U − 2 Re(conj(Ĝ) σ̂²_YU)) / |Û|², which also holds at Ŷ = 0.
/// Throws InputError for non-SISO statistics or Û(k) = 0.
FrfData errors_in_variables(const SampleStatistics& stats);

/// The ratio estimates of Section 5 with the choices `fdsid identify-frf`
/// offers (what `fdsid check` repeats for --eiv and --improper candidates).
struct RatioOptions {
  Real min_input_snr = 0;         ///< Eq. (34): lines with |den|² ≤ min_input_snr σ̂²_den / M are left out
  const Model* first_pass = nullptr;  ///< Eq. (31) evaluated at this model's G instead of the ratio
  bool swap = false;              ///< improper G: Ĥ = Û/Ŷ (input and output exchanged)
};

/// errors_in_variables generalised: Ĝ = Ŷ/Û (or Û/Ŷ), the variance of the
/// corrected Eq. (31) with the roles of U and Y exchanged when swapped,
/// evaluated at the ratio or at `first_pass`; lines failing Eq. (34) or with a
/// variance ≤ 0 are left out and counted in `dropped`.
/// Throws InputError as errors_in_variables, and when every line is left out.
FrfData ratio_estimate(const SampleStatistics& stats, const RatioOptions& options, int* dropped = nullptr);

}  // namespace fdsid::reference
