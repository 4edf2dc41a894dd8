#pragma once
/// Identification of minimum-phase spectral factors from power-spectrum samples
/// on a uniform grid: Akçay (2011) Algorithm 1 and, for comparison,
/// Van Overschee et al. (1997) (the same pipeline with the range space of
/// Ĝ_p F_r, Akçay Eq. (13)).
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/model.hpp"
#include "fdsid/names.hpp"

namespace fdsid {

/// M+1 samples S_k of an m x m power spectrum at omega_k = pi (k-1)/M,
/// k = 1..M+1 (Akçay Eq. (7)). Column k-1 of S holds vec(S_k), column-major.
struct SpectrumData {
  int m = 1;
  int M = 0;
  Eigen::MatrixXcd S;
  /// Optional (the CSV's S_var column): the variance of each sample's noise,
  /// E|ΔS_ab(k)|², one value per sample k (M+1), the same for every entry.
  /// Empty when not given. Only the refinement (refine_spectrum) uses it.
  Eigen::VectorXd variance;
  /// Entry (a, b) of sample k (0-based a, b, k).
  cplx at(int a, int b, int k) const { return S(a + m * b, k); }
};

enum class Method { Akcay2011, VanOverschee1997 };
const char* to_string(Method m);

/// How the M+1 samples are extended to N = 2M (Algorithm 1, step 1).
enum class Extension {
  /// S_{M+k} = S_{M-k+2}^T as the paper and S(e^{-iw}) = S(e^{iw})^T prescribe,
  /// keeping the real part of the Fourier coefficients (the realisation must be
  /// real). Equivalent to replacing each sample by its Hermitian part
  /// (S + S^H)/2 -- for m = 1, by Re S -- and extending it Hermitian-symmetrically.
  /// The imaginary part of scalar noise is discarded.
  HermitianPart,
  /// S_{M+k} = conj(S_{M-k+2}) entry by entry: the Fourier coefficients are real
  /// and the imaginary part of the noise enters them through the sine terms.
  Conjugate
};
const char* to_string(Extension e);
/// The names of Method's and Extension's values (akcay2011, vo1997;
/// hermitian-part, conjugate): to_string's, the CLI's and the JSON fields'.
const NameTable<Method>& method_names();
const NameTable<Extension>& extension_names();

struct SpectrumOptions {
  Method method = Method::Akcay2011;
  int order = 0;  ///< n; 0 reads it from the singular values (step 4)
  int p = 0;      ///< block rows of 𝒴; 0 applies default_pr()
  int r = 0;      ///< block columns of 𝒴; 0 applies default_pr()
  Extension extension = Extension::HermitianPart;
};

/// Default p and r. Rule: p = r = min(50, M) for an order read from the data
/// (so orders up to 24 are detectable and p + r <= N = 2M always holds); for a
/// given order n, p = max(2n + 1, min(50, M)) and r = max(2n, min(50, N - p)).
/// 50 is the paper's Table 2 choice; it keeps the SVD at 50m x 50m.
void default_pr(int M, int n, int& p, int& r);

/// Throws Error(Dimension) unless p > 2n, r >= 2n and p + r <= N (Algorithm 1 step 2).
void check_pr(int N, int n, int p, int r);

/// Algorithm 1 steps 1-2: the N-point inverse DFT (Eq. 20) of the extended data,
/// by one FFTW complex-to-real transform per matrix entry.
/// Returns (m*m) x N real: column k holds vec(ŝ_k), k = 0..N-1.
Eigen::MatrixXd fourier_coefficients(const SpectrumData& data, Extension ext);

/// Eq. (19): 𝒴_{kl} = ŝ_{k+l-1} + ŝ_{N-p-r+k+l-1}, a sum of two block Hankel
/// matrices of the Fourier coefficients (pm x rm).
Eigen::MatrixXd akcay_matrix(const Eigen::MatrixXd& shat, int m, int p, int r);

/// Ĝ_p F_r of Eq. (13): its block (k, l) is ŝ_{k+l-1} (pm x rm), the first Hankel
/// term of Eq. (19) alone.
Eigen::MatrixXd van_overschee_matrix(const Eigen::MatrixXd& shat, int m, int p, int r);

/// Algorithm 1 step 5: Ã = (J_d U_{2n})^† J_u U_{2n}, the shift equations of the
/// observability range U_{2n} (pm x 2n) with block size m, by Householder QR.
/// For any orthogonal Q, shift_matrix(U Q) = Q^T shift_matrix(U) Q.
Eigen::MatrixXd shift_matrix(const Eigen::MatrixXd& U2n, int m);

/// Everything Algorithm 1 produced.
struct SpectrumResult {
  StateSpace model;             ///< (Â, B̂, Ĉ, D̂): the minimum-phase spectral factor
  SpectralSummands summands;    ///< Â, Ĉ, Ê, F̂ of step 8 and P̂ of step 9
  Method method = Method::Akcay2011;
  Extension extension = Extension::HermitianPart;
  int order = 0, p = 0, r = 0, N = 0;
  Eigen::VectorXd singular_values;  ///< of 𝒴 (akcay2011) or Ĝ_p F_r (vo1997)
  bool order_from_data = false;
  int gap_index = 0;         ///< 2n: the order was read at sigma_{2n} / sigma_{2n+1}
  double gap_ratio = 0.0;    ///< that ratio
  double split_margin = 0.0; ///< min over the 2n eigenvalues of | |λ| - 1 | (step 6)
  std::string riccati_method;
  int riccati_iterations = 0;
  double riccati_residual = 0.0;  ///< ||P - Ric(P)||_F / ||P||_F
  double min_spectrum = 0.0;      ///< min over the grid of λ_min(Ŝ(z_k)) (step 8 fit)
  double max_zero_modulus = 0.0;  ///< largest |zero| of Ĝ, eig(Â - B̂D̂^{-1}Ĉ): < 1 (minimum phase)
  /// Relative accuracy double precision can promise for Ŝ on this problem
  /// (first order, not a proven bound): 4 (p + r) m log2(N) u σ1/σ_2n
  /// (fdsid/compare.hpp) times 1/(1 − ρ(Â)²), the conditioning of the
  /// Stein/Riccati operators of steps 8-9 near the unit circle.
  double error_estimate = 0.0;
  /// Plain-language warnings where fast/ may lose accuracy (an error estimate
  /// above 1e-6, poles within 1e-3 of the unit circle, a Riccati residual above
  /// 1e-8, an order read from the data with σ_{2n+1}/σ_1 above the estimate). Empty when none applies; printed by the CLI and written to the JSON.
  std::vector<std::string> warnings;
};

/// Akçay (2011) Algorithm 1, steps 1-10: minimum-phase spectral factor from
/// M+1 power-spectrum samples on the uniform grid ω_k = π(k-1)/M.
///
/// Method: 𝒴 by Eq. (19) from the inverse DFT (Eq. 20) of the extended data
/// (FFTW); range space by Jacobi SVD (step 3); A from the shift equations (step 5) by
/// Householder QR; stable/antistable split by the eigen-decomposition of Ã
/// (step 6), expressed in a real block-diagonal basis (1x1 blocks for real
/// eigenvalues, [[a, b], [-b, a]] for a ± ib) so that all of Â, Ĉ, Ê, F̂, B̂, D̂
/// are real; Ê (symmetric) and F̂ by least squares over all M+1 samples
/// (step 8), accumulated by a chunked Householder QR (TSQR) so that the
/// condition number is not squared; Riccati (step 9) by the structure-preserving
/// doubling algorithm (SDA) with a fall-back to the Riccati difference
/// (Kalman filter) iteration.
/// With options.method = VanOverschee1997, step 3 uses Ĝ_p F_r instead of 𝒴.
/// Numerical aspects: cost O(m^2 N log N + (pm)^2 (rm) + M n m^2 (nm + m^2)).
/// Fails (Error) with kind Split when Ã has not exactly n eigenvalues inside the
/// unit circle or one lies within its own rounding error (10 κ_i u ||Ã||) of it,
/// Positivity when Ŝ is not positive on the grid or Ê - ĈP̂Ĉ^T is not positive
/// definite, Riccati when no stabilising solution is found.
/// References: Akçay, Automatica 47 (2011) 363-367; Van Overschee et al.,
/// Automatica 33 (1997) 2147-2157; Chu, Fan, Lin, Linear Algebra Appl. 396 (2005)
/// 55-80 (SDA).
SpectrumResult identify_spectrum(const SpectrumData& data, const SpectrumOptions& options);

/// The minimum-phase factor of the spectrum S(z) = G(z) Gᵀ(1/z) of a stable
/// factor G = (A, B, C, D) (discrete): the spectral summands of G
/// (spectral_summands, a Lyapunov equation) and Algorithm 1 step 9 (Riccati,
/// B̂, D̂). The poles are G's; zeros outside the circle move to their
/// reflections 1/z̄, and D̂ is symmetric positive definite. Writes the largest
/// |zero| of the result (< 1) to *max_zero_modulus when given.
/// Fails as step 9 does: Error(Positivity) or Error(Riccati) when S is singular
/// somewhere on the circle (G has a zero on it).
StateSpace minimum_phase_factor(const StateSpace& factor, double* max_zero_modulus = nullptr);

/// Reads the order from singular values: the n (1 <= n <= n_max) maximising
/// sigma_{2n} / sigma_{2n+1} (Algorithm 1 step 4; 𝒴 has rank 2n).
int order_from_singular_values(const Eigen::VectorXd& sv, int n_max, int& gap_index, double& gap_ratio);

}  // namespace fdsid
