#pragma once
/// Similarity-invariant comparison of two state-space models: what the oracle
/// (`fdsid check`) measures between a candidate and the reference's model.
#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"

#include <vector>

namespace fdsid {

/// Accuracy a backward-stable double-precision Algorithm 1 reaches on
/// noise-free data, relative to max ||S||: 4 (p + r) m log2(N) u σ1/σ_2n.
/// Derivation (first order): each Fourier coefficient is accurate to
/// log2(N) u ||S||; 𝒴 sums two per entry, so ||δ𝒴|| <= (p + r) m log2(N) u ||S||;
/// the range U_2n moves by ||δ𝒴||/σ_2n (Wedin), and every later quantity is a
/// smooth function of U_2n with derivative O(σ1/||S||); 4 covers the
/// least-squares and Riccati steps. Measured errors lie 10-1000 times below.
double double_precision_spectrum_tolerance(int p, int r, int m, int N, double sigma1_over_sigma2n);

/// Purpose: the eigenvalue condition number of A, max_i ||v_i|| ||w_i|| over
/// right eigenvectors v_i and the rows w_i of V⁻¹ (1 for a normal matrix).
/// Method: Eigen::EigenSolver; at least 1.
/// Fails: never (an empty A gives 1).
double eigenvalue_condition_number(const Eigen::MatrixXd& A);

struct ModelComparison {
  int candidate_order = 0, reference_order = 0;
  /// Hausdorff distance between the pole sets (each pole to the nearest of the other set).
  double pole_distance = 0;
  /// Largest pole modulus of each model (0 for order 0).
  double candidate_pole_modulus = 0, reference_pole_modulus = 0;
  /// A spectral factor is stable; an unstable candidate disagrees (its
  /// summands' distance is +inf: they do not exist).
  bool candidate_unstable() const { return candidate_pole_modulus >= 1.0; }
  /// max over the grid of ||S_c - S_r||_F / max ||S_r||_F.
  double spectrum_error = 0;
  double spectrum_error_omega = 0;  ///< where it is largest (rad/sample)
  /// max over k of ||R_c(k) - R_r(k)||_F / max_k ||R_r(k)||_F, with R(0) = E and
  /// R(k) = C A^{k-1} F the Markov parameters of the spectral summand, k = 1..K.
  double markov_error = 0;
  int markov_error_k = 0;

  // The spectral factor G(z) = D + C (zI - A)^{-1} B itself, not only its
  // spectrum G(z) G(1/z)^T: a factor with a zero reflected outside the unit
  // circle (the anti-stabilising root of the step-9 Riccati equation) has the
  // same poles, spectrum and summands, and only these quantities see it.
  // Both are invariant under similarity and under G -> G Q, Q orthogonal.
  /// Hausdorff distance between the factors' transmission zeros (zeros()).
  double zero_distance = 0;
  /// Largest |zero| of each factor (>= 1: not minimum phase; 0 without zeros).
  double candidate_zero_modulus = 0, reference_zero_modulus = 0;
  /// The candidate's zero of largest modulus, and the reference zero nearest its
  /// mirror image 1 / conj(z) (what a reflected zero should have been).
  cplx candidate_worst_zero{0, 0}, reference_zero_near_mirror{0, 0};
  /// max over k of ||H_c(k) - H_r(k)||_F / max_k ||H_r(k)||_F with H(0) = D D^T,
  /// H(k) = C A^{k-1} B D^T (k = 1..K): the Markov parameters of G(z) G(inf)^T.
  double factor_markov_error = 0;
  int factor_markov_error_k = 0;
  /// True when the candidate's factor has a zero on or outside the unit circle.
  bool candidate_not_minimum_phase() const { return candidate_zero_modulus >= 1.0; }
};

/// Compares candidate and reference on `grid` points of [0, π] (ends
/// included), on the Markov parameters R(0..markov) of their spectral
/// summands, and their spectral factors: zeros and H(0..markov).
/// Both models must be discrete and square (else Error(Input)); the reference
/// stable. An unstable candidate is compared (candidate_unstable(), summand
/// distance +inf), not refused.
ModelComparison compare_models(const StateSpace& candidate, const StateSpace& reference, int grid = 4097,
                               int markov = 0 /* 0: 2n + 1 */);

// ---------------------------------------------------------------------------
// Models identified from FRF samples or periodic records (Pintelon 2002):
// what `fdsid check --frf` / `--data --meta` measures.

/// One compared quantity: the candidate's distance from the reference, the
/// tolerance at the same place and their ratio (<= 1 agrees), with the
/// frequency (G) where the ratio is largest.
struct OracleQuantity {
  double distance = 0, tolerance = 0, ratio = 0;
  double omega = 0;  ///< G: where the ratio is largest (the data's units); poles: unused
  bool agrees() const { return ratio <= 1.0; }
};

/// Purpose: copies of a model with A, B, C, D each moved by `size` times its
/// Frobenius norm in independent random directions (fixed seeds 1..count):
/// the rounding model of the oracle's tolerances.
/// Fails: never.
std::vector<StateSpace> randomly_moved(const StateSpace& model, double size, int count);

/// Purpose: how many significant decimal digits a model file carries — the
/// most any entry of A, B, C, D needs to be read back exactly (its shortest
/// round-trip decimal: 17 for a double written with %.17g, 8 for one
/// written with %.8g). An oracle's candidate written with fewer digits than
/// its comparison resolves disagrees for that reason alone.
/// Fails: never (an empty model carries 1).
int digits_carried(const StateSpace& model);

/// Purpose: the model with every entry of A, B, C, D rounded to `digits`
/// significant decimal digits (what writing it with %.{digits}g does).
/// Fails: never.
StateSpace rounded_to_digits(const StateSpace& model, int digits);

/// Purpose: first-order sensitivity s(ξ) of G(ξ) = D + C (ξI − A)⁻¹ B to
/// relative perturbations of size 1 in each of A, B, C, D (‖δX‖ ≤ ‖X‖).
/// Method: with R = (ξI − A)⁻¹, δG = δD + δC R B + C R δB + C R δA R B, so
/// ‖δG‖ ≤ ‖C R‖ ‖A‖ ‖R B‖ + ‖C‖ ‖R B‖ + ‖C R‖ ‖B‖ + ‖D‖ (2-norms, by SVD).
/// Fails: never (ξ an eigenvalue of A gives +inf).
double transfer_sensitivity(const StateSpace& model, cplx xi);

/// Purpose: the tolerance rule of compare_frf_models.
/// Method (statistical condition estimation, Kenney & Laub 1994, with the
/// backward-error model of a correct double implementation): `perturbed` are
/// the reference's identifications of the same data with Z and C_Y moved by
/// their backward errors γ = √(rows · cols) u (reference::FrfOptions::
/// backward_perturbation; rows × cols = 2Fc × r(m+p), the shape of Zᵀ: the
/// probabilistic size of Householder QR's column-wise backward error, Higham &
/// Mary 2019, λ = 1) in independent random directions. How far each moves G
/// and the poles is what rounding of that size does on these data, to first
/// order. The tolerance is kSafety = 10 times the largest of them: a
/// candidate's own rounding is a perturbation of the same law, and the norm of
/// a Gaussian perturbation's effect exceeds 10 times the largest of 3
/// independent samples with probability < 1e-5 (Rayleigh magnitudes:
/// P = E[exp(−50 M²)] ≈ 0.75/50³ for M the largest of 3), plus the rounding
/// of the candidate's numbers and of evaluating them: 4n u s(ξ) for G,
/// 4n u ‖Â‖ κ_j |dλ/dμ| for the poles (and, Algorithm 2.1, the back-transform's
/// 4n u cond(I − Â_w) ‖Â_c‖ κ(Â_c)).
struct FrfTolerance {
  static constexpr double kSafety = 10;
  std::vector<StateSpace> perturbed;  ///< the reference at perturbed Z, C_Y (at least one)
  double given = 0;                   ///< > 0: the user's relative tolerance instead of the rule
  ContinuousMethod method = ContinuousMethod::Bilinear;
  double omega_scale = 1;             ///< ω_s of Algorithm 2 (continuous models)
};

/// The comparison of a candidate with the reference's FRF model.
struct FrfModelComparison {
  int candidate_order = 0, reference_order = 0;
  OracleQuantity g_data;   ///< G on the data's frequencies
  OracleQuantity g_dense;  ///< G on a dense grid (see compare_frf_models)
  OracleQuantity poles;    ///< poles, each against its own tolerance
  /// max over the data grid of ||G_c − G_r||_F / max ||G_r||_F (for reading).
  double g_relative = 0;
  bool agree() const {
    return candidate_order == reference_order && g_data.agrees() && g_dense.agrees() && poles.agrees();
  }
};

/// Purpose: compare a candidate model with the reference's model of the same
/// FRF data in terms invariant under similarity: G and the poles.
/// Method: G at each frequency ω of both grids, ||G_c(ω) − G_r(ω)||_F against
/// its own tolerance (FrfTolerance); each reference pole λ_j against its own
/// tolerance, every candidate pole measured against its nearest reference pole
/// and every reference pole against its nearest candidate pole (a Hausdorff
/// distance in ratios). s(ξ), κ_j and dλ/dμ are those of the reference model
/// taken to the domain where Algorithm 1 ran (the w-plane of Algorithm 2.1,
/// s̃ = s/ω_s for 2.2, z itself in discrete time).
/// With a given tolerance: G relative to max ||G_r|| on the grid, poles
/// absolutely (discrete) or relative to |λ_j| (continuous).
/// Fails: Error(Input) when the shapes or domains differ, or no perturbed
/// models are given without a tolerance.
FrfModelComparison compare_frf_models(const StateSpace& candidate, const StateSpace& reference,
                                      const Eigen::VectorXd& data_omega, const Eigen::VectorXd& dense_omega,
                                      const FrfTolerance& tolerance);

/// The dense grid of compare_frf_models: 2049 points on [0, π] (discrete),
/// or log-spaced from ω_min/10 to 10 ω_max of the data (continuous: a decade
/// beyond the band each side, where an extrapolating model still must agree).
Eigen::VectorXd dense_frequency_grid(Domain domain, const Eigen::VectorXd& data_omega, int points = 2049);

}  // namespace fdsid
