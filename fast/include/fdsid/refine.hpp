#pragma once
/// Maximum-likelihood refinement of a frequency-domain subspace estimate
/// (issue 15): Pintelon (2002) presents its estimates as starting values of
/// the frequency-domain ML estimator (Pintelon & Schoukens, System
/// Identification: A Frequency Domain Approach, 2nd ed. 2012, Ch. 9–10);
/// this is that estimator for output noise, solved by Ceres Solver.
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid {

/// The noise model the data's `variance` stands for.
enum class RefineNoise {
  Known,   ///< known variances: the cost is the negative log-likelihood (weighted least squares)
  Sample,  ///< sample variances σ̂²/M over M periods: the sample ML estimator (SML)
  None     ///< unit weights (an FRF file without G_var): least squares, no likelihood, no uncertainties
};
const char* to_string(RefineNoise n);

struct RefineOptions {
  RefineNoise noise = RefineNoise::Known;
  int periods = 0;             ///< M (Sample): the expected cost and the SML loss factor need it, M ≥ 4
  bool allow_unstable = false; ///< keep unstable starting poles and do not constrain the poles
  int max_iterations = 200;    ///< Levenberg–Marquardt iterations (Ceres)
  /// Errors-in-variables (SISO periodic data, U = Û ≠ 1; empty: output noise
  /// only): per line k the variance σ²_U,k of Û_k and the covariance
  /// σ_YU,k = E[δŶ conj δÛ] of the means (eiv_input_noise). The cost is then
  /// V = Σ_k |Ŷ_k − G Û_k|² / (σ²_Y,k + |G|² σ²_U,k − 2 Re(σ_YU,k conj G)),
  /// the frequency-domain EIV ML cost (Pintelon & Schoukens 2012, Ch. 10; its
  /// SML form when the variances are sample variances over M periods: each
  /// denominator is then the sample variance of (Y_l − G U_l)/M over the
  /// periods, positive, and each term F(2, 2M − 2) at the true G).
  Eigen::VectorXd input_variance;
  Eigen::VectorXcd input_output_covariance;
};

/// The errors-in-variables noise of SISO sample statistics for RefineOptions:
/// σ̂²_U/M and σ̂_YU/M per line (the variances of the means).
void eiv_input_noise(const SampleStatistics& stats, RefineOptions& options);

/// The cost refine_ml minimises, for a model: v_sub (Eq. 35) for output noise,
/// the errors-in-variables cost of RefineOptions when it has input noise.
double refine_cost(const FrfData& data, const StateSpace& model, const RefineOptions& options);

/// One pole of the refined model with its standard deviation from the
/// Cramér–Rao bound. Frequency and damping are read in s (continuous time;
/// discrete poles as s = log z / T): ω_n = |s|, ζ = −Re s / |s|.
struct PoleUncertainty {
  cplx pole;                 ///< the model's pole (z or s); pairs by their member with Im ≥ 0
  double frequency = 0;      ///< ω_n: rad/s (continuous, or discrete with T) — rad/sample for T = 1
  double damping = 0;        ///< ζ
  double frequency_sd = 0;   ///< standard deviation of ω_n (0 without a noise model)
  double damping_sd = 0;     ///< standard deviation of ζ
};

struct RefineResult {
  StateSpace model;             ///< the refined model in real modal form (2×2 blocks [a b; −b a], 1×1 real poles)
  StateSpace start;             ///< the starting value: the subspace estimate with unstable poles reflected
  std::vector<cplx> reflected;  ///< subspace poles that were unstable and reflected into the stable region
  double cost_subspace = 0;     ///< V (Eq. 35) at the subspace estimate as given
  double cost_start = 0;        ///< V at the starting value
  double cost = 0;              ///< V at the refined model
  int terms = 0;                ///< T = F p c complex residuals
  int parameters = 0;           ///< real parameters of the modal form
  int free_parameters = 0;      ///< parameters − gauge (1 per real pole, 2 per complex pair): what the data determine
  /// Goodness of fit (not for RefineNoise::None). Known variance: 2V ~ χ²(2T − q) under a right model, Gaussian
  /// noise, first order in the q free parameters: E V = T − q/2, p = P(χ² ≥ 2V). Sample variance: each term
  /// ~ F(2, 2M−2) (mean d/(d−2), d = 2M − 2), E V = (T − q/2) d/(d−2); p = P(χ²(2T − q) ≥ X) with X Fisher's
  /// combination of the terms (2V for known variances; numerics/fisher.hpp).
  double expected_cost = 0;
  double p_value = 1;
  int iterations = 0;
  std::string termination;      ///< Ceres's termination: "convergence", "no_convergence", ...
  bool at_stability_bound = false;  ///< a pole sits on the stability margin (the constraint is active)
  /// Cramér–Rao bound of the modal parameters: Cov = ½ (JᵀJ)⁺ with J the Jacobian of the whitened residuals
  /// (each real part of a whitened residual has variance ½), rank q; times (M−2)/(M−3) for the SML.
  Eigen::MatrixXd covariance;
  /// κ = σ_1/σ_q of the Jacobian on the determined directions: u κ is the first-order relative
  /// rounding error of the parameters (the Gauss–Newton normal equations solved by QR).
  double condition = 0;
  /// The rounding's effect on what the model is used for (statistical: the residuals and the Jacobian at the
  /// optimum moved by their rounding in random directions, one Gauss–Newton step each): the relative error of Ĝ
  /// on the data's frequencies, ‖ΔG‖_F/‖G‖_F, and the largest relative pole error |Δλ|/|λ|. They decide
  /// whether the model is usable (a warning above 1e-6), not u κ, which the least determined parameter sets.
  double g_error_estimate = 0;
  double pole_error_estimate = 0;
  /// How far short of the optimum the optimiser stopped: the same relative changes of Ĝ and the poles along the
  /// Gauss–Newton direction −(JᵀJ)⁺Jᵀr from the result (zero at a stationary point), at the largest step
  /// 2⁻ᵏ of it (k ≤ 40) whose V stays within 1e-14 relative of the result's: an estimate along that one
  /// direction, not a bound. Infinite when the direction is not finite. A warning above 1e-6.
  double g_stopping_estimate = 0;
  double pole_stopping_estimate = 0;
  std::vector<PoleUncertainty> poles;
  /// Standard deviation of |G_ij| and ∠G_ij (rad) at each of the data's frequencies, [k](i, j).
  std::vector<Eigen::MatrixXd> magnitude_sd, phase_sd;
  std::vector<std::string> warnings;
};

/// Purpose: the maximum-likelihood model for the data's noise model, started
/// from `start` (a subspace estimate of the same order).
///
/// Method: (1) unstable poles of `start` are reflected (s → −s̄ in continuous
/// time, z → 1/z̄ in discrete time: the same |G| shape, stable), and B, D
/// refitted by Pintelon's step 3 with A, C fixed; (2) the model is brought to
/// real modal form, G = D + Σ_i C_i (ξI − A_i)⁻¹ B_i, each mode a 1×1 real
/// pole or a 2×2 block [a b; −b a]; (3) Levenberg–Marquardt (Ceres, dense QR,
/// analytic Jacobian) minimises V = Σ_k Σ_j Σ_i |Y − G U|²_ij / σ²_ij over the
/// pole parameters and every entry of B_i, C_i, D; (4) the Cramér–Rao bound
/// from the Jacobian at the optimum, propagated to the poles and to G.
///
/// Parametrisation and why: modal coordinates keep each lightly damped mode's
/// parameters local to its band, so JᵀJ stays well conditioned with many
/// modes (a polynomial or companion parametrisation's condition grows
/// exponentially with the order); continuous time works in s̃ = s/ω_s
/// (ω_s = √(ω_min ω_max)), discrete pairs in polar form ρ[cos φ  sin φ; −sin φ
/// cos φ]. Stability is kept by bounds, a box Ceres projects onto: Re s̃ ≤
/// −1e-8 (continuous), ρ ≤ 1 − 1e-8 and real poles in [−1 + 1e-8, 1 − 1e-8]
/// (discrete). The margin 1e-8 binds only on a resonance of half-power width
/// 1e-8 ω_s, which no record shorter than 1e8/ω_s resolves, and keeps the
/// model stable in double (1 − 1e-8 is 4.5e7 u from 1). The modal form has a
/// gauge (each mode's B_i, C_i may be scaled, pairs rotated): it leaves G
/// unchanged, so J has a null space of that dimension; Levenberg–Marquardt's
/// damping handles it, and the covariance is the pseudo-inverse on the rank q.
///
/// Numerical aspects: O(F c p (n + m + p) q) flops per Jacobian; stops at
/// relative cost change 1e-14 (≈ 50 u: changes below are the rounding of
/// V's sum) or parameter change 1e-12 relative. Fails with Error(Numerical)
/// when the starting model's eigenvectors are ill-conditioned (κ(T) > 1e8:
/// (nearly) repeated poles, no modal form) and Error(Input) when shapes differ.
/// References: Pintelon & Schoukens (2012) Ch. 9 (ML), 10 (SML; Schoukens,
/// Pintelon, Vandersteen & Guillaume, Automatica 33 (1997) 1073–1086);
/// Agarwal, Mierle et al., Ceres Solver.
RefineResult refine_ml(const FrfData& data, const StateSpace& start, const RefineOptions& options = {});

/// Reflects unstable poles of a model into the stable region (s → −s̄, z →
/// 1/z̄) and refits B, D by step 3 (fit_input_matrices) for the reflected A
/// and the same C. Returns the model unchanged when it is stable; `reflected`
/// receives the poles that moved. Works on the real modal form.
StateSpace reflect_unstable_poles(const FrfData& data, const StateSpace& model, std::vector<cplx>* reflected);

/// What refine_spectrum returns.
struct SpectrumRefineResult {
  StateSpace model;            ///< the refined minimum-phase factor (stable, zeros inside the circle)
  StateSpace start;            ///< the factor it started from
  bool weighted = false;       ///< residuals weighted by the data's variance (S_var); else unit weights
  double cost_start = 0;       ///< V at the start
  double cost = 0;             ///< V at the refined factor
  int terms = 0;               ///< real residuals: (M+1) m²
  int parameters = 0;          ///< of the modal parametrisation
  int iterations = 0;          ///< Levenberg–Marquardt iterations
  int max_iterations = 0;      ///< the iteration limit it ran under
  std::string termination;     ///< "convergence", "no_convergence" or "stopped"
  bool at_stability_bound = false;
  double max_zero_modulus = 0; ///< largest |zero| of the refined factor (< 1)
  std::vector<std::string> warnings;
};

/// Weighted nonlinear least squares of a spectral factor on the spectrum
/// samples (issue 15, item 2): the refinement of Akçay's Algorithm 1 estimate.
///
/// Purpose: the factor G = (A, B, C, D) of order n minimising
///   V = Σ_k Σ_{a ≤ b} |Herm(Ŝ_k)_ab − (G(z_k) G(z_k)ᴴ)_ab|² / σ²_k,
/// z_k = e^{iπk/M}, Herm(Ŝ) = (Ŝ + Ŝᴴ)/2 (a power spectrum is Hermitian; the
/// anti-Hermitian part of the samples is noise, as in Algorithm 1's default
/// reading), σ²_k the data's `variance` or 1 (unit weights, the default: then
/// V is the squared L2 error against the samples). With the noise's variance
/// the estimate is the Gaussian maximum-likelihood one; the cost's law is not
/// stated (spectral estimates are not Gaussian in general), so no p-value.
///
/// Method: the factor is parametrised in real modal form with stable poles
/// kept by bounds, exactly as refine_ml (the same layout and analytic
/// Jacobian of G; ∂S = ∂G Gᴴ + G ∂Gᴴ), and minimised by Levenberg–Marquardt
/// (Ceres). Fitting G rather than the summands keeps S = G Gᴴ ≥ 0 on the whole
/// circle by construction; the result is brought to minimum phase by
/// minimum_phase_factor (the summands of G and Algorithm 1 step 9), which
/// leaves S unchanged.
/// Fails: Error(Input) for a start of another size or domain, Error(Numerical)
/// as refine_ml, step 9's errors when the refined S is singular on the circle.
SpectrumRefineResult refine_spectrum(const SpectrumData& data, const StateSpace& start, int max_iterations = 200);

/// The cost V of refine_spectrum for a factor (its weights: the data's variance when given).
double spectrum_cost(const SpectrumData& data, const StateSpace& factor);

}  // namespace fdsid
