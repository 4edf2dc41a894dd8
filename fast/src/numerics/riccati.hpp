#pragma once
// The discrete algebraic Riccati equation of spectral factorisation (internal
// header): Akçay (2011) Algorithm 1 step 9.
#include <Eigen/Dense>
#include <string>

#include "fdsid/model.hpp"
#include "numerics/constants.hpp"
#include "numerics/rank.hpp"

namespace fdsid::numerics {

/// Decision constants of solve_spectral_riccati, each with its derivation.
struct RiccatiOptions {
  /// SDA stops, failed, when W = I + G_k H_k is numerically singular,
  /// rcond₁(W) ≤ min_rcond = kMinRcond = 10·u (rank.hpp: W is numerically
  /// invertible when its reciprocal condition number exceeds a small multiple
  /// of the unit roundoff; Higham, Accuracy and Stability, §7.1, Thm 9.4).
  /// It replaces |det W| > 1e-12, which is scale dependent (the determinant of
  /// a well-conditioned W with eigenvalues 0.01 is 1e-12 at n = 6) and then
  /// sent step 9 silently to the slow fall-back.
  double min_rcond = kMinRcond;
  /// SDA converges quadratically (Chu, Fan, Lin & Wang 2004): the error after
  /// k doublings is O(ρ^{2^k}), ρ < 1 the spectral radius of the closed loop,
  /// so 100 doublings (2^100 ≈ 1.3e30 terms) reach u whenever
  /// 1 − ρ ≥ 53·ln 2 / 2^100 ≈ 3e-29, far below the ≈ u to which double
  /// precision resolves ρ: more doublings mean no convergence.
  int sda_max_iterations = 100;
  /// Convergence: ‖H_{k+1} − H_k‖_F ≤ step_tolerance·‖H_{k+1}‖_F (or
  /// ‖A_k‖_F ≤ u, the doubling term gone). 4·u: a few rounding errors of the
  /// sum H_k + A_kᵀ H_k W⁻¹ A_k, below which the update is noise.
  double step_tolerance = 4 * kUnitRoundoff;
  /// The SDA solution is accepted when E − C P Cᵀ > 0 and the relative
  /// residual (riccati_residual) is ≤ accept_residual. 1e-8 ≈ √u (1.05e-8,
  /// rounded down to the decade): at least half the working digits; the
  /// residual of a backward-stable solver is O(κ·u), so a residual above √u
  /// means κ ≳ 1/√u or a wrong branch, and the monotone fall-back is tried.
  double accept_residual = 1e-8;
  /// Fall-back: the Riccati difference (Kalman filter) iteration converges
  /// linearly, the change shrinking by ρ² per step. It is stopped as failed
  /// when the change has not halved over `kalman_window` steps (ρ > 0.99965:
  /// a pole of the factor within 3.5e-4 of the circle, beyond what double
  /// precision resolves anyway), after kalman_max_iterations steps, or when
  /// ‖P‖_F ≥ kalman_divergence (1e150: P²-sized products still below the
  /// overflow threshold 1.8e308).
  int kalman_max_iterations = 100000;
  int kalman_window = 1000;
  double kalman_divergence = 1e150;
};

/// Outcome of solve_spectral_riccati.
struct RiccatiSolution {
  bool ok = false;       ///< a stabilising solution was found
  Eigen::MatrixXd P;     ///< the solution (valid when ok)
  std::string method;    ///< "sda" or "riccati-difference-iteration"
  int iterations = 0;    ///< of the method that produced P
};

/// The relative residual ‖P − 𝓡(P)‖_F / max(‖P‖_F, ‖F‖²_F/‖E‖_F) of
///   𝓡(P) = A P Aᵀ + (F − A P Cᵀ)(E − C P Cᵀ)⁻¹(F − A P Cᵀ)ᵀ.
double riccati_residual(const SpectralSummands& s, const Eigen::MatrixXd& P);

/// Purpose: the stabilising solution P of
///   P = A P Aᵀ + (F − A P Cᵀ)(E − C P Cᵀ)⁻¹(F − A P Cᵀ)ᵀ
/// (Akçay 2011 step 9), which makes the spectral factor minimum phase.
/// Method: structure-preserving doubling (SDA) on the control-type DARE in
/// X = −P, X = Âᵀ X (I + G X)⁻¹ Â + H with Â = Aᵀ − Cᵀ E⁻¹ Fᵀ,
/// G = Cᵀ E⁻¹ C, H = −F E⁻¹ Fᵀ:
///   W = I + G_k H_k, A_{k+1} = A_k W⁻¹ A_k, G_{k+1} = G_k + A_k W⁻¹ G_k A_kᵀ,
///   H_{k+1} = H_k + A_kᵀ H_k W⁻¹ A_k,  H_k → X quadratically;
/// accepted when E − C P Cᵀ > 0 and the residual ≤ accept_residual, otherwise
/// the Riccati difference iteration from P = 0, which increases monotonically
/// to the minimal solution when the spectrum is positive on the circle.
/// Numerical aspects: O(n³) per step; G_k, H_k symmetrised each step.
/// Fails: ok = false when neither method converges (no Error thrown).
/// References: Chu, Fan, Lin & Wang, J. Phys. A 37 (2004); Lancaster &
/// Rodman, Algebraic Riccati Equations (1995) ch. 13; Akçay (2011).
RiccatiSolution solve_spectral_riccati(const SpectralSummands& s, const RiccatiOptions& options = {});

}  // namespace fdsid::numerics
