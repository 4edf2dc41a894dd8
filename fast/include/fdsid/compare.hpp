#pragma once
/// Similarity-invariant comparison of two state-space models: what the oracle
/// (`fdsid check`) measures between a candidate and the reference's model.
#include "fdsid/model.hpp"

namespace fdsid {

/// Accuracy a backward-stable double-precision Algorithm 1 reaches on
/// noise-free data, relative to max ||S||: 4 (p + r) m log2(N) u σ1/σ_2n.
/// Derivation (first order): each Fourier coefficient is accurate to
/// log2(N) u ||S||; 𝒴 sums two per entry, so ||δ𝒴|| <= (p + r) m log2(N) u ||S||;
/// the range U_2n moves by ||δ𝒴||/σ_2n (Wedin), and every later quantity is a
/// smooth function of U_2n with derivative O(σ1/||S||); 4 covers the
/// least-squares and Riccati steps. Measured errors lie 10-1000 times below.
double double_precision_spectrum_tolerance(int p, int r, int m, int N, double sigma1_over_sigma2n);

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

}  // namespace fdsid
