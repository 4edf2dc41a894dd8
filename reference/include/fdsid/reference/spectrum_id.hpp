// High-precision reference implementation of Akçay (2011) Algorithm 1.
//
// This is the oracle against which the double-precision implementation in
// fast/ is checked. It transcribes the paper: the matrices of Section 3 are
// built as written (explicit Kronecker products, 1/√N factors, DFTs as direct
// sums, the pseudo-inverse as (XᵀX)⁻¹Xᵀ) in 50-digit arithmetic, and it shares
// no code with fast/. It is slow on purpose: O(p N r m³) for 𝒴 alone.
//
// Scalar type. Real = boost::multiprecision::cpp_bin_float<50> with expression
// templates off:
//  - cpp_bin_float is header-only, so no MPFR/GMP is needed (only Debian's
//    Boost headers are allowed as dependencies); 50 decimal digits
//    (unit roundoff u ≈ 1e-50) leave ≥ 20 digits of margin for the 1e-30
//    tolerances the tests demand after the condition numbers of the SVD,
//    the eigenvector problem of step 6 and the Riccati equation of step 9;
//  - et_off: Eigen's expression templates and Boost's do not compose (auto
//    would capture Boost expressions); with et_off every operation returns a
//    plain number.
// Complex = std::complex<Real>: Eigen knows std::complex<T> for any T whose
// NumTraits exist (boost/multiprecision/eigen.hpp supplies them); Boost's own
// cpp_complex does not mix with std::complex, so it is not used anywhere.
// Boost 1.74's NumTraits lack infinity()/quiet_NaN(), so Eigen's BDCSVD does not
// compile: the SVD is JacobiSVD (one-sided Jacobi rotations, which is anyway
// the most accurate choice for small singular values).
//
// Decimal inputs must be parsed from strings (Real("0.8876")), never through a
// double literal: 0.8876 as a double differs from 0.8876 at 1e-17 relative,
// 33 orders of magnitude above the working precision.
#pragma once

#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/eigen.hpp>  // NumTraits for Real; must precede Eigen use
#include <Eigen/Core>

#include <complex>
#include <stdexcept>
#include <functional>
#include <string>
#include <vector>

namespace fdsid::reference {

#ifndef FDSID_REFERENCE_DIGITS
#define FDSID_REFERENCE_DIGITS 50  // CMake's FDSID_REFERENCE_DIGITS; 100 only for scripts/certify.sh
#endif
/// Decimal digits of Real: 50 (100 in the second build of scripts/certify.sh).
inline constexpr int kDigits = FDSID_REFERENCE_DIGITS;
using Real = boost::multiprecision::number<boost::multiprecision::cpp_bin_float<FDSID_REFERENCE_DIGITS>,
                                           boost::multiprecision::et_off>;
using Complex = std::complex<Real>;
using MatrixR = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic>;
using MatrixC = Eigen::Matrix<Complex, Eigen::Dynamic, Eigen::Dynamic>;

/// Base of every error the reference throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input: a malformed file (the message names file and line), a model with
/// inconsistent shapes, or parameters that violate the paper's inequalities.
class InputError : public Error {
 public:
  using Error::Error;
};

/// A step of Algorithm 1 failed on the given data (e.g. step 6: no
/// stable/antistable split). The message starts with "step <k>:".
class StepError : public Error {
 public:
  StepError(int step, const std::string& what)
      : Error("step " + std::to_string(step) + ": " + what), step_(step) {}
  int step() const { return step_; }

 private:
  int step_;
};

/// State-space model x[t+1] = A x[t] + B u[t], y[t] = C x[t] + D u[t] (Eq. 1).
/// Only domain "discrete" is used by this file; sample_time is carried along.
struct Model {
  std::string domain = "discrete";
  Real sample_time = 1;
  MatrixR A, B, C, D;
};

/// M+1 power-spectrum samples S_k ∈ C^{m×m} at ω_k = π(k−1)/M, k = 1 … M+1
/// (Eq. 7). S[k-1] holds S_k.
struct Spectrum {
  int m = 1;
  int M = 0;
  std::vector<MatrixC> S;
};

/// Power spectrum S(z) = G(z) Gᵀ(z⁻¹) (Eq. 3) with G(z) = D + C(zI − A)⁻¹B
/// (Eq. 2), evaluated at one complex z in high precision.
///
/// Method: two complex LU solves of order n. Valid for any z that is not an
/// eigenvalue of A and whose inverse is not one either.
MatrixC spectrum_of(const Model& model, const Complex& z);

/// The M+1 samples S(e^{iπ(k−1)/M}), k = 1 … M+1, of the spectrum of `model`
/// (noise-free data of Eq. 7). Throws InputError for M < 1 or a non-discrete
/// model.
Spectrum sample_spectrum(const Model& model, int M);

/// Step 1 of Algorithm 1: the N = 2M samples S_1 … S_N on z_k = e^{i2π(k−1)/N},
/// S_{M+k} = conj(S_{M−k+2}) entrywise for k = 2 … M, i.e. S(z⁻¹) = conj S(z)
/// (real impulse response; for Hermitian samples this is S_{M−k+2}ᵀ). The
/// returned vector is 0-based: element j holds S_{j+1}.
std::vector<MatrixC> extend_spectrum(const Spectrum& spectrum);

/// Eq. (20): the N-point inverse DFT ŝ_k = (1/N) Σ_{j=0}^{N−1} e^{i2πjk/N} S_{j+1}
/// of the step-1 extension, for k = 0 … N−1, each by the direct sum.
std::vector<MatrixC> fourier_coefficients(const Spectrum& spectrum);

/// Van Overschee et al.'s matrix Ĝ_p F_r (the left-hand side of Eqs. 12/13),
/// pm × rm, from the step-1 extension of `spectrum`.
///
/// Method: F_r = (1/√N)[z_j^l]_{j=1..N, l=1..r} ⊗ I_m and
/// Ĝ_p = (1/√N)[Ω_p(ω_1) ⊗ S_1 … Ω_p(ω_N) ⊗ S_N], Ω_p(ω) = [1 … z^{p−1}]ᵀ,
/// built explicitly and multiplied. Block (k, l) equals ŝ_{k+l−1}. Real up to
/// rounding for data extended by step 1 with real S_1 and S_{M+1}.
/// Numerical aspects: cost O(p m · N m · r m) complex operations.
/// Throws InputError unless p ≥ 1, r ≥ 1 and p + r ≤ N.
MatrixC vo_GF(const Spectrum& spectrum, int p, int r);

/// Akçay's matrix 𝒴 = Ĝ_p F_r + Ψ_p 𝒢̄_p F_r Ψ_r of Eq. (16), pm × rm.
///
/// Method: as vo_GF, plus 𝒢̄_p = (1/√N)[Ω_p(ω_1) ⊗ S̄_1 … Ω_p(ω_N) ⊗ S̄_N] and
/// the block exchange matrices Ψ_k (ones on the block anti-diagonal), all
/// explicit. Not the shortcut of Eq. (19) (which the tests check it against).
MatrixC akcay_Y(const Spectrum& spectrum, int p, int r);

/// Singular values, largest first (JacobiSVD).
std::vector<Real> singular_values(const MatrixR& X);

/// Eigenvalues of a real square matrix (Eigen's EigenSolver: real Schur form),
/// in the order the solver returns them.
std::vector<Complex> eigenvalues(const MatrixR& X);

/// The zeros of a square factor G(z) = D + C(zI − A)⁻¹B with D nonsingular:
/// the eigenvalues of A − B D⁻¹C (D⁻¹C by Householder QR).
std::vector<Complex> transmission_zeros(const Model& model);

/// Whether a square D is nonsingular in this precision: σ_min > m ε σ_max, the
/// rank threshold of Eigen's FullPivLU (m ε relative to the largest pivot) on
/// the singular values.
bool nonsingular(const MatrixR& D);

/// G(e^{iω}) Q with Q = V Uᵀ from D = U Σ Vᵀ (JacobiSVD): the factor in the
/// normalisation of fdsid::normalised_factor (fast/, compare.hpp), in which two
/// realisations of one spectral factor agree entry by entry. Discrete models.
MatrixC normalised_factor_response(const Model& model, const Real& omega);

/// What identify_spectrum returns.
struct Result {
  /// (Â, B̂, Ĉ, D̂), real; Â is block diagonal: 1×1 blocks λ for real poles,
  /// 2×2 blocks [[a, b], [−b, a]] for pairs a ± ib (the real form of the
  /// paper's Jordan form Σ_c).
  Model model;
  int order = 0;  ///< n (given, or read from the singular values)
  int p = 0, r = 0;
  std::vector<Real> singular_values_Y;   ///< of Re 𝒴 (Eq. 16), largest first
  std::vector<Real> singular_values_vo;  ///< of Re Ĝ_p F_r (Eq. 13), largest first
  MatrixR E, F;                          ///< spectral summands Ê (symmetric), F̂ of step 8
  MatrixR P;                             ///< stabilising Riccati solution P̂ of step 9
  std::vector<Complex> poles;            ///< eigenvalues of Â (the stable ones of Ã)
  int riccati_iterations = 0;            ///< difference iterations + Newton steps of step 9
};

/// Akçay (2011) Algorithm 1, steps 1-10: minimum-phase spectral factor
/// (Â, B̂, Ĉ, D̂) from M+1 power-spectrum samples on ω_k = π(k−1)/M.
///
/// Arguments: order = n, or 0 to read n from the largest ratio σ_{2n}/σ_{2n+1}
/// over the n with p > 2n, r ≥ 2n; p, r block rows/columns with p > 2n,
/// r ≥ 2n, p + r ≤ N = 2M; van_overschee = true takes the range space from
/// Ĝ_p F_r (Eq. 13, Van Overschee et al. 1997) instead of 𝒴 (Eq. 16).
///
/// Method: step 1 extension to N = 2M; 𝒴 from Eq. (16) with explicit Kronecker
/// products (real part kept: 𝒴 is real for real S_1, S_{M+1}); step 3 SVD
/// (JacobiSVD); step 5 Ã = (J_d U_2n)^† J_u U_2n with X^† = (XᵀX)⁻¹Xᵀ as
/// written; step 6 eigenvectors of Ã (EigenSolver), exactly n eigenvalues
/// must lie inside the unit circle; step 7 Â = Σ_c, Ĉ = J_f U_2n Π_c in the
/// real basis [Re v, Im v] of each stable pair; step 8 Ê = Êᵀ, F̂ by linear
/// least squares (Householder QR of the stacked real and imaginary parts)
/// over all M+1 samples; step 9 the Riccati equation by the Riccati
/// difference iteration from P = 0 (monotone, converges to the stabilising
/// solution) until its change is below 1e-12 relative (at most 2000 steps),
/// then Newton steps (each a Stein equation solved through its Kronecker
/// form) until the change is below 1e-45 relative, or stalls with the
/// residual below 1e-35 relative; B̂ = (F̂ − ÂP̂Ĉᵀ)(Ê − ĈP̂Ĉᵀ)^{−1/2},
/// D̂ = (Ê − ĈP̂Ĉᵀ)^{1/2}, symmetric roots.
///
/// Numerical aspects: 50-digit arithmetic throughout; on noise-free data the
/// identified spectrum equals the true one to about u·κ, u ≈ 1e-50, κ the
/// product of the conditioning of σ_2n and of the eigenvectors of Ã.
/// Throws InputError for inconsistent data or parameters, StepError(6) when
/// the split fails (message lists the moduli), StepError(8) for a rank
/// deficient least-squares problem, StepError(9) when Ê − ĈP̂Ĉᵀ is not
/// positive definite or the Riccati iteration does not converge.
///
/// References: H. Akçay, Automatica 47 (2011) 363-367, Algorithm 1;
/// H. Akçay & S. Türkay, Automatica 40 (2004) 1333-1347 (steps 4-10);
/// P. Van Overschee et al., Automatica 33 (1997) 2147-2157.
/// Verification only (what `fdsid check` uses to measure how far the rounding
/// of a correct double-precision implementation moves the result; fdsid/
/// compare.hpp): relative sizes of backward errors put into Algorithm 1, each
/// in a random direction drawn from `seed`. 0: none.
struct BackwardPerturbation {
  Real data_matrix = 0;    ///< 𝒴 (or Ĝ_p F_r) of step 2 moved by this × its Frobenius norm
  Real least_squares = 0;  ///< every column of step 8's design matrix and its right-hand side, × their norms
  Real riccati = 0;        ///< Ê (symmetrically) and F̂ entering step 9, × their norms
  unsigned seed = 1;
  /// Step 9 by Newton's method from this stabilising solution of the
  /// unperturbed problem (nullptr: the difference iteration first, as always):
  /// a rounding-size perturbation leaves it inside Newton's basin.
  const MatrixR* riccati_start = nullptr;
};

Result identify_spectrum(const Spectrum& spectrum, int order, int p, int r,
                         bool van_overschee = false, const BackwardPerturbation* perturbation = nullptr);

/// identify_spectrum, then steps 3-9 again for each perturbation that
/// `perturbations_for` returns for the unperturbed result, steps 1-2 (the
/// expensive direct sums) computed once. A perturbed rerun whose step fails
/// is left out and its message listed in `failures`.
struct PerturbedResults {
  Result base;
  std::vector<Result> perturbed;
  std::vector<std::string> failures;
};
PerturbedResults identify_spectrum_perturbed(
    const Spectrum& spectrum, int order, int p, int r, bool van_overschee,
    const std::function<std::vector<BackwardPerturbation>(const Result&)>& perturbations_for);

}  // namespace fdsid::reference
