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
  /// max over the grid of ||S_c - S_r||_F / max ||S_r||_F.
  double spectrum_error = 0;
  double spectrum_error_omega = 0;  ///< where it is largest (rad/sample)
  /// max over k of ||R_c(k) - R_r(k)||_F / max_k ||R_r(k)||_F, with R(0) = E and
  /// R(k) = C A^{k-1} F the Markov parameters of the spectral summand, k = 1..K.
  double markov_error = 0;
  int markov_error_k = 0;
};

/// Compares candidate and reference on `grid` points of [0, π] (ends
/// included) and on the Markov parameters R(0..markov) of their spectral summands.
/// Both models must be discrete, square and stable.
ModelComparison compare_models(const StateSpace& candidate, const StateSpace& reference, int grid = 4097,
                               int markov = 0 /* 0: 2n + 1 */);

}  // namespace fdsid
