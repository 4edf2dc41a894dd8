// Akçay (2011) Algorithm 1 in 50-digit arithmetic, transcribed from the paper.
//
// The file follows the paper: one function per step of Algorithm 1, named
// after it (step1_extend_spectrum … step9_B_D), each with a header giving its
// purpose, method (the paper's equations), numerical aspects, failures and
// references; identify_spectrum is the sequence of step calls.
//
// The Eigen decompositions over Real/Complex (JacobiSVD, EigenSolver,
// HouseholderQR, LLT over MatrixR; PartialPivLU over MatrixC) are called here
// and in frf_id.cpp only, and compiled once (eigen_instances.hpp): each costs
// seconds of compile time with a multiprecision scalar, so other files only
// call the functions declared in spectrum_id.hpp.
#include "fdsid/reference/spectrum_id.hpp"
#include "fdsid/reference/frf_id.hpp"  // frequency_response

#include "common.hpp"
#include "eigen_instances.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <random>
#include <limits>
#include <sstream>

namespace fdsid::reference {
namespace {

using detail::fmt;
using detail::kron;
using detail::unit_root;
using detail::UnitRoots;
using VectorR = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
using VectorC = Eigen::Matrix<Complex, Eigen::Dynamic, 1>;

// ---------------------------------------------------------------------------
// Input checks

void check_spectrum(const Spectrum& spectrum) {
  if (spectrum.m < 1) throw InputError("spectrum: m = " + std::to_string(spectrum.m) + " < 1");
  if (spectrum.M < 1) throw InputError("spectrum: M = " + std::to_string(spectrum.M) + " < 1");
  if (static_cast<int>(spectrum.S.size()) != spectrum.M + 1)
    throw InputError("spectrum: " + std::to_string(spectrum.S.size()) + " samples, M + 1 = " +
                     std::to_string(spectrum.M + 1) + " expected");
  for (std::size_t k = 0; k < spectrum.S.size(); ++k)
    if (spectrum.S[k].rows() != spectrum.m || spectrum.S[k].cols() != spectrum.m)
      throw InputError("spectrum: sample " + std::to_string(k + 1) + " is not " +
                       std::to_string(spectrum.m) + "x" + std::to_string(spectrum.m));
}

// The inequalities of step 2 that do not involve n.
void check_p_r(int p, int r, int N) {
  if (p < 1 || r < 1 || p + r > N)
    throw InputError("step 2: need p >= 1, r >= 1 and p + r <= N; got p = " + std::to_string(p) +
                     ", r = " + std::to_string(r) + ", N = " + std::to_string(N));
}

void check_model(const Model& model) {
  const auto n = model.A.rows();
  if (n < 1 || model.A.cols() != n) throw InputError("model: A must be n x n with n >= 1");
  if (model.B.rows() != n || model.C.cols() != n || model.D.rows() != model.C.rows() ||
      model.D.cols() != model.B.cols() || model.B.cols() < 1 || model.C.rows() < 1)
    throw InputError("model: shapes of A, B, C, D do not match (A n x n, B n x q, C p x n, D p x q)");
}

// ---------------------------------------------------------------------------
// Step 1

// Step 1: extend the M+1 samples to N = 2M samples on z_k = e^{i2π(k−1)/N}.
// Method: S_1 … S_{M+1} as given, S_{M+k} = conj S_{M−k+2} for k = 2 … M
// (S(z⁻¹) = conj S(z) for a real impulse response; the paper prints
// S_{M+k} = S_{M−k+2}, which is the same for real-valued samples).
// Numerical aspects: exact (copies and conjugations). Fails: never (the
// caller has checked the data). References: Akçay (2011) Algorithm 1 step 1.
std::vector<MatrixC> step1_extend_spectrum(const Spectrum& spectrum) {
  const int M = spectrum.M;
  std::vector<MatrixC> S(2 * M);
  for (int k = 1; k <= M + 1; ++k) S[k - 1] = spectrum.S[k - 1];  // S_1 … S_{M+1} as given
  for (int k = 2; k <= M; ++k)                                      // step 1
    S[M + k - 1] = spectrum.S[M - k + 1].conjugate();               // S_{M+k} = conj S_{M−k+2}
  return S;
}

// ---------------------------------------------------------------------------
// Step 2: the data matrices of Section 3

// Step 2, Eq. (20): ŝ_k = (1/N) Σ_{j=0}^{N−1} e^{i2πjk/N} S_{j+1}, k = 0 … N−1.
// Method: the direct sum for every k (no FFT), twiddles from one table of
// N-th roots of unity. Numerical aspects: O(N² m²); each ŝ_k is a sum of N
// terms, error ≈ N·u·max‖S‖. Fails: never. References: Akçay (2011) Eq. (20).
std::vector<MatrixC> step2_fourier_coefficients(const std::vector<MatrixC>& S, int m) {
  const int N = static_cast<int>(S.size());
  const UnitRoots z(N);
  std::vector<MatrixC> s_hat(N);
  for (int k = 0; k < N; ++k) {  // Eq. (20), direct sum
    MatrixC sum = MatrixC::Zero(m, m);
    for (int j = 0; j < N; ++j) sum += z(static_cast<long long>(j) * k) * S[j];
    s_hat[k] = sum / Real(N);
  }
  return s_hat;
}

// The matrices of Section 3 for data extended by step 1.
struct SectionThree {
  MatrixC G_hat;  // Ĝ_p  = (1/√N)[Ω_p(ω_1) ⊗ S_1 … Ω_p(ω_N) ⊗ S_N]
  MatrixC G_bar;  // 𝒢̄_p  = (1/√N)[Ω_p(ω_1) ⊗ S̄_1 … Ω_p(ω_N) ⊗ S̄_N]   (after Eq. 15)
  MatrixC F_r;    // F_r  = (1/√N)[z_j^l]_{j=1..N, l=1..r} ⊗ I_m
};

// Step 2, Section 3: Ĝ_p, 𝒢̄_p and F_r, from which Eqs. (13) and (16) are formed.
// Method: checks the data and p, r; extends it by step 1; builds the three
// matrices as written, with explicit Kronecker products Ω_p(ω_k) ⊗ S_k,
// Ω_p(ω) = [1 z … z^{p−1}]ᵀ, and [z_j^l] ⊗ I_m, each scaled by 1/√N.
// Numerical aspects: O(p N r m²) storage. Fails: InputError for malformed
// data or p < 1, r < 1, p + r > N. References: Akçay (2011) Section 3,
// Eqs. (12)-(15).
SectionThree step2_section_three(const Spectrum& spectrum, int p, int r) {
  check_spectrum(spectrum);
  const int m = spectrum.m;
  const int N = 2 * spectrum.M;
  check_p_r(p, r, N);
  const std::vector<MatrixC> S = step1_extend_spectrum(spectrum);
  const Real sqrtN = sqrt(Real(N));
  const MatrixC I_m = MatrixC::Identity(m, m);
  const UnitRoots z(N);  // z(q) = e^{i2πq/N}, so z_j^l = z((j−1)l)

  SectionThree s;
  // F_r: row j holds z_j, z_j^2, …, z_j^r (powers 1 … r), z_j = e^{i2π(j−1)/N}.
  MatrixC Z(N, r);
  for (int j = 0; j < N; ++j)
    for (int l = 0; l < r; ++l) Z(j, l) = z(static_cast<long long>(j) * (l + 1));
  s.F_r = kron(Z, I_m) / sqrtN;

  s.G_hat.resize(p * m, N * m);
  s.G_bar.resize(p * m, N * m);
  for (int k = 0; k < N; ++k) {
    MatrixC Omega_p(p, 1);  // Ω_p(ω_k) = [1 z_k … z_k^{p−1}]ᵀ (powers 0 … p−1)
    for (int i = 0; i < p; ++i) Omega_p(i, 0) = z(static_cast<long long>(k) * i);
    s.G_hat.middleCols(k * m, m) = kron(Omega_p, S[k]) / sqrtN;
    const MatrixC S_conj = S[k].conjugate();
    s.G_bar.middleCols(k * m, m) = kron(Omega_p, S_conj) / sqrtN;
  }
  return s;
}

// Ψ_k ∈ R^{km×km}: I_m blocks on the block anti-diagonal (Section 3, after Eq. 15).
MatrixC exchange(int k, int m) {
  MatrixC J = MatrixC::Zero(k, k);
  for (int i = 0; i < k; ++i) J(i, k - 1 - i) = Complex(1);
  return kron<MatrixC>(J, MatrixC::Identity(m, m));
}

// Step 2, Eq. (13): Van Overschee et al.'s matrix Ĝ_p F_r (pm × rm).
// Method: the product of the Section 3 matrices as written. Numerical
// aspects: O(p N r m³); its blocks are ŝ_{k+l−1} (real up to rounding for
// real S_1, S_{M+1}). Fails: never. References: Akçay (2011) Eq. (13);
// Van Overschee et al. (1997).
MatrixC step2_vo_matrix_GF(const SectionThree& s) { return s.G_hat * s.F_r; }

// Step 2, Eq. (16): Akçay's matrix 𝒴 = Ĝ_p F_r + Ψ_p 𝒢̄_p F_r Ψ_r (pm × rm).
// Method: Eq. (16) with explicit block exchange matrices Ψ_p, Ψ_r, given
// Ĝ_p F_r of Eq. (13); not the shortcut of Eq. (19), 𝒴_kl = ŝ_{k+l−1} +
// ŝ_{N−p−r+k+l−1}, which the tests check it against. Numerical aspects:
// O(p N r m³). Fails: never. References: Akçay (2011) Eqs. (16), (19).
MatrixC step2_akcay_matrix_Y(const SectionThree& s, const MatrixC& G_hat_F_r, int p, int r, int m) {
  const MatrixC Psi_p = exchange(p, m);
  const MatrixC Psi_r = exchange(r, m);
  return G_hat_F_r + Psi_p * s.G_bar * s.F_r * Psi_r;  // Eq. (16)
}

// Re 𝒴 (Eq. 16) and Re Ĝ_p F_r (Eq. 13).
struct DataMatrices {
  MatrixR Y, GF;
};

// Step 2: both data matrices, real parts kept. 𝒴 and Ĝ_p F_r are real up to
// rounding for data with real S_1, S_{M+1} extended by step 1 (their blocks
// are the real coefficients ŝ_k, Eq. 19). Fails: as step2_section_three.
// References: Akçay (2011) Eqs. (13), (16), (19).
DataMatrices step2_data_matrices(const Spectrum& spectrum, int p, int r) {
  const SectionThree s = step2_section_three(spectrum, p, r);
  const MatrixC GF = step2_vo_matrix_GF(s);
  const MatrixC Y = step2_akcay_matrix_Y(s, GF, p, r, spectrum.m);
  return {Y.real(), GF.real()};
}

// ---------------------------------------------------------------------------
// Steps 3-7: range space, order, shift equations, stable part

// The SVD of Eq. (21), as far as it is used.
struct RangeSpace {
  std::vector<Real> sigma;  // all singular values, largest first
  MatrixR U;                // thin left singular vectors
};

// Step 3: SVD 𝒴 = [U_2n U'][Σ_2n 0; 0 Σ'][V_2n V']ᵀ of Eq. (21) (applied to
// Ĝ_p F_r instead of 𝒴 for Van Overschee's method).
// Method: one-sided Jacobi (JacobiSVD), thin U. Numerical aspects: the most
// accurate SVD for small singular values; O(p r m³ min(p, r)) per sweep.
// Fails: never. References: Akçay (2011) step 3, Eq. (21).
RangeSpace step3_range_space(const MatrixR& H) {
  Eigen::JacobiSVD<MatrixR> svd(H, Eigen::ComputeThinU);
  RangeSpace range;
  range.sigma.assign(svd.singularValues().data(),
                     svd.singularValues().data() + svd.singularValues().size());
  range.U = svd.matrixU();
  return range;
}

// Step 4: the order n, `order` if given (> 0), else the n with the largest
// ratio σ_2n/σ_2n+1 among those with p > 2n, r ≥ 2n, 2n < min(pm, rm).
// Method: ratios with σ_2n+1 floored at ε·σ_1 (a zero singular value does not
// divide by zero); the first maximum wins. Fails: InputError when no n is
// admitted, or when the given n violates p > 2n, r ≥ 2n (the inequalities of
// step 2). References: Akçay (2011) steps 2, 4.
int step4_order(const std::vector<Real>& sigma, int order, int p, int r, int rank_limit) {
  int n = order;
  if (n == 0) {
    Real best_ratio = -1;
    for (int k = 1; 2 * k < p && 2 * k <= r && 2 * k + 1 <= rank_limit; ++k) {
      const Real zero_level = sigma[0] * std::numeric_limits<Real>::epsilon();
      const Real ratio = sigma[2 * k - 1] / std::max(sigma[2 * k], zero_level);
      if (ratio > best_ratio) {
        best_ratio = ratio;
        n = k;
      }
    }
    if (n == 0)
      throw InputError("step 4: p = " + std::to_string(p) + ", r = " + std::to_string(r) +
                       " admit no order n (need p > 2n, r >= 2n, 2n < min(pm, rm))");
  }
  if (!(p > 2 * n) || !(r >= 2 * n))
    throw InputError("step 2: order n = " + std::to_string(n) + " needs p > 2n and r >= 2n; got p = " +
                     std::to_string(p) + ", r = " + std::to_string(r));
  return n;
}

// Step 5: Ã = (J_d U_2n)^† J_u U_2n, 2n × 2n.
// Method: J_u = [0_{(p−1)m×m} I_{(p−1)m}], J_d = [I_{(p−1)m} 0_{(p−1)m×m}]
// formed as written; X^† = (XᵀX)⁻¹Xᵀ (Section 1.1) for X = J_d U_2n, the
// inverse applied by Householder QR of XᵀX. Numerical aspects: squares the
// condition of J_d U_2n, harmless at u ≈ 1e-50 for well-separated orders.
// Fails: not checked here; a rank-deficient J_d U_2n shows at step 6.
// References: Akçay (2011) step 5.
MatrixR step5_shift_equations(const MatrixR& U2n, int p, int m) {
  const int rows = (p - 1) * m;
  MatrixR Ju = MatrixR::Zero(rows, p * m);
  MatrixR Jd = MatrixR::Zero(rows, p * m);
  Ju.rightCols(rows) = MatrixR::Identity(rows, rows);
  Jd.leftCols(rows) = MatrixR::Identity(rows, rows);
  const MatrixR X = Jd * U2n;
  const MatrixR XtX = X.transpose() * X;
  const MatrixR X_dagger = XtX.householderQr().solve(X.transpose());  // (XᵀX)⁻¹Xᵀ
  return X_dagger * Ju * U2n;
}

// Eigenvalues and eigenvectors of Ã.
struct Eigensystem {
  VectorC lambda;
  MatrixC vectors;
};

// Step 6: Ã = [Π_c Π_ac] diag(Σ_c, Σ_ac) [Π_c Π_ac]⁻¹ with the eigenvalues of
// Σ_c inside the unit circle; exactly n of the 2n must be.
// Method: eigenvalues and eigenvectors of Ã (EigenSolver: real Schur form);
// the split itself is made in step 7. Numerical aspects: eigenvectors are
// as well conditioned as Ã's eigenvalues are separated. Fails: StepError(6)
// when the iteration does not converge or the count inside |z| < 1 is not n
// (the message lists all moduli). References: Akçay (2011) step 6.
Eigensystem step6_stable_split(const MatrixR& A_tilde, int n) {
  Eigen::EigenSolver<MatrixR> eig(A_tilde);
  if (eig.info() != Eigen::Success) throw StepError(6, "eigenvalue iteration for A~ did not converge");
  const Eigensystem e{eig.eigenvalues(), eig.eigenvectors()};
  int inside = 0;
  for (Eigen::Index i = 0; i < e.lambda.size(); ++i)
    if (abs(e.lambda(i)) < 1) ++inside;
  if (inside != n) {
    std::ostringstream what;
    what << "no stable/antistable split: " << inside << " of the 2n = " << 2 * n
         << " eigenvalues of A~ lie inside the unit circle, n = " << n << " needed (moduli";
    for (Eigen::Index i = 0; i < e.lambda.size(); ++i) what << ' ' << fmt(abs(e.lambda(i)), 10);
    what << ')';
    throw StepError(6, what.str());
  }
  return e;
}

// Â, Ĉ of step 7 and the poles (eigenvalues of Â).
struct StablePart {
  MatrixR A_hat, C_hat;
  std::vector<Complex> poles;
};

// Step 7: Â = Σ_c, Ĉ = J_f U_2n Π_c, J_f = [I_m 0_{m×(p−1)m}], in a real basis
// of the stable invariant subspace of Ã.
// Method: Π_c has columns v (real λ) or [Re w, Im w] (pair a ± ib, w an
// eigenvector of a + ib), so Ã Π_c = Π_c Σ_c with Σ_c block diagonal, blocks
// λ or [[a, b], [−b, a]]: the paper's complex Jordan form up to a similarity,
// so the identified spectrum is the same and every matrix is real. The
// solver's phase of v is arbitrary; w = e^{−i arg(vᵀv)/2} v has wᵀw real, i.e.
// Re w ⟂ Im w, the best-conditioned real basis of the pair.
// Fails: StepError(6) when the stable eigenvalues are not closed under
// conjugation (the split of step 6 then has no real form).
// References: Akçay (2011) steps 6-7; Akçay & Türkay (2004).
StablePart step7_A_C(const Eigensystem& eig, const MatrixR& U2n, int n, int m, int p) {
  StablePart out;
  MatrixR Pi_c(2 * n, n);
  MatrixR Sigma_c = MatrixR::Zero(n, n);
  int column = 0;
  for (Eigen::Index i = 0; i < eig.lambda.size(); ++i) {
    const Complex& l = eig.lambda(i);
    if (!(abs(l) < 1) || l.imag() < 0) continue;  // antistable, or the partner of a pair
    if (l.imag() == 0) {
      Pi_c.col(column) = eig.vectors.col(i).real();
      Sigma_c(column, column) = l.real();
      out.poles.push_back(l);
      column += 1;
    } else {
      const VectorC v = eig.vectors.col(i);
      const Complex vTv = (v.transpose() * v)(0, 0);
      const VectorC w = std::polar(Real(1), -std::arg(vTv) / 2) * v;
      Pi_c.col(column) = w.real();
      Pi_c.col(column + 1) = w.imag();
      Sigma_c(column, column) = l.real();
      Sigma_c(column, column + 1) = l.imag();
      Sigma_c(column + 1, column) = -l.imag();
      Sigma_c(column + 1, column + 1) = l.real();
      out.poles.push_back(l);
      out.poles.push_back(std::conj(l));
      column += 2;
    }
  }
  if (column != n) throw StepError(6, "stable eigenvalues of A~ do not form conjugate pairs");

  MatrixR Jf = MatrixR::Zero(m, p * m);  // J_f = [I_m 0_{m×(p−1)m}]
  Jf.leftCols(m) = MatrixR::Identity(m, m);
  out.A_hat = Sigma_c;          // Â = Σ_c
  out.C_hat = Jf * U2n * Pi_c;  // Ĉ = J_f U_2n Π_c
  return out;
}

// ---------------------------------------------------------------------------
// BackwardPerturbation: X moved by size × ‖X‖_F in a random direction
// (Gaussian entries, normalised; `symmetric` keeps X = Xᵀ).
void move(MatrixR& X, const Real& size, std::mt19937_64& rng, bool symmetric = false) {
  if (!(size > 0) || X.size() == 0) return;
  std::normal_distribution<double> normal(0.0, 1.0);
  MatrixR g(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < g.rows(); ++i)
    for (Eigen::Index j = 0; j < g.cols(); ++j) g(i, j) = Real(normal(rng));
  if (symmetric) g = (g + g.transpose()).eval();
  X += size * X.norm() / g.norm() * g;
}

// Step 8: Ê, F̂ by linear least squares

// The real linear least-squares problem L θ ≈ rhs of step 8.
struct LeastSquaresProblem {
  MatrixR L;
  VectorR rhs;
};

// Step 8, the design matrix: residual χ̂(z_k)F̂ + F̂ᵀχ̂ᵀ(z_k⁻¹) + Ê − S_k,
// χ̂(z) = Ĉ(zI − Σ_c)⁻¹, as a real linear function of θ.
// Method: unknowns θ = the m(m+1)/2 entries E_ij (i ≤ j, E = Eᵀ), then the n·m
// entries F_ij (row-major); rows: real and imaginary part of each entry (a, b)
// of each of the M+1 given samples; χ̂(z_k), χ̂(z_k⁻¹) by complex LU inverses.
// Numerical aspects: 2(M+1)m² × (m(m+1)/2 + nm); O(M n³) for the resolvents.
// Fails: never (z_k is not a pole: Σ_c is strictly stable).
// References: Akçay (2011) step 8.
LeastSquaresProblem step8_design_matrix(const Spectrum& spectrum, const MatrixR& A_hat,
                                        const MatrixR& C_hat) {
  const int m = spectrum.m, M = spectrum.M, N = 2 * M;
  const int n = static_cast<int>(A_hat.rows());
  const int n_E = m * (m + 1) / 2;
  const int n_unknowns = n_E + n * m;
  const int n_rows = 2 * (M + 1) * m * m;
  LeastSquaresProblem ls{MatrixR::Zero(n_rows, n_unknowns), VectorR(n_rows)};
  const MatrixC A_hat_c = A_hat.cast<Complex>();
  const MatrixC C_hat_c = C_hat.cast<Complex>();
  const MatrixC I_n = MatrixC::Identity(n, n);
  for (int k = 0; k <= M; ++k) {
    const Complex z = unit_root(k, N);          // z_k = e^{iπ(k−1)/M}
    const Complex z_inv = unit_root(-k, N);     // z_k⁻¹
    const MatrixC chi = C_hat_c * (z * I_n - A_hat_c).partialPivLu().inverse();  // χ̂(z_k)
    const MatrixC chi_inv = C_hat_c * (z_inv * I_n - A_hat_c).partialPivLu().inverse();  // χ̂(z_k⁻¹)
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) {
        const int row = 2 * ((k * m + a) * m + b);
        int unknown = 0;
        for (int i = 0; i < m; ++i)
          for (int j = i; j < m; ++j, ++unknown)  // E_ij = E_ji
            if ((a == i && b == j) || (a == j && b == i)) ls.L(row, unknown) = 1;
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < m; ++j, ++unknown) {  // F_ij: χ̂(z) e_i e_jᵀ + e_j e_iᵀ χ̂ᵀ(z⁻¹)
            Complex value(0);
            if (b == j) value += chi(a, i);
            if (a == j) value += chi_inv(b, i);
            ls.L(row, unknown) = value.real();
            ls.L(row + 1, unknown) = value.imag();
          }
        ls.rhs(row) = spectrum.S[k](a, b).real();
        ls.rhs(row + 1) = spectrum.S[k](a, b).imag();
      }
  }
  return ls;
}

// The spectral summands of step 8: S(z) ≈ χ̂(z)F̂ + F̂ᵀχ̂ᵀ(z⁻¹) + Ê.
struct SpectralSummands {
  MatrixR E, F;
};

// Step 8: min over Ê = Êᵀ, F̂ of Σ_{k=1}^{M+1} ‖χ̂(z_k)F̂ + F̂ᵀχ̂ᵀ(z_k⁻¹) + Ê − S_k‖²_F.
// Method: the design matrix above, solved by Householder QR (never the
// normal equations). Numerical aspects: rank deficiency is declared when
// min |R_ii| ≤ 1e-40 max |R_ii|. Fails: StepError(8) when rank deficient.
// References: Akçay (2011) step 8; Akçay & Türkay (2004).
SpectralSummands step8_least_squares_EF(const Spectrum& spectrum, const MatrixR& A_hat,
                                        const MatrixR& C_hat, const Real& perturbation = 0,
                                        std::mt19937_64* rng = nullptr) {
  const int m = spectrum.m;
  const int n = static_cast<int>(A_hat.rows());
  LeastSquaresProblem ls = step8_design_matrix(spectrum, A_hat, C_hat);
  if (rng && perturbation > 0) {  // BackwardPerturbation::least_squares, column by column
    for (Eigen::Index j = 0; j < ls.L.cols(); ++j) {
      MatrixR col = ls.L.col(j);
      move(col, perturbation, *rng);
      ls.L.col(j) = col;
    }
    MatrixR rhs = ls.rhs;
    move(rhs, perturbation, *rng);
    ls.rhs = rhs;
  }
  Eigen::HouseholderQR<MatrixR> qr(ls.L);
  {
    const VectorR diagonal = qr.matrixQR().diagonal().cwiseAbs();
    if (diagonal.minCoeff() <= Real("1e-40") * diagonal.maxCoeff())
      throw StepError(8, "least-squares problem for E, F is rank deficient (|R_ii| min/max = " +
                             fmt(diagonal.minCoeff() / diagonal.maxCoeff()) + ")");
  }
  const VectorR theta = qr.solve(ls.rhs);
  SpectralSummands out{MatrixR(m, m), MatrixR(n, m)};
  int unknown = 0;
  for (int i = 0; i < m; ++i)
    for (int j = i; j < m; ++j, ++unknown) out.E(i, j) = out.E(j, i) = theta(unknown);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j, ++unknown) out.F(i, j) = theta(unknown);
  return out;
}

// ---------------------------------------------------------------------------
// Step 9: the Riccati equation and B̂, D̂

Real frobenius(const MatrixR& X) { return X.norm(); }

// f(P) = ÂPÂᵀ + (F̂ − ÂPĈᵀ)(Ê − ĈPĈᵀ)⁻¹(F̂ − ÂPĈᵀ)ᵀ, the right-hand side of
// the Riccati equation of step 9, symmetrised; optionally the gain
// K = (F̂ − ÂPĈᵀ)(Ê − ĈPĈᵀ)⁻¹. W = Ê − ĈPĈᵀ is applied by Householder QR.
struct RiccatiMap {
  const MatrixR& A;
  const MatrixR& C;
  const MatrixR& E;
  const MatrixR& F;

  MatrixR operator()(const MatrixR& P, MatrixR* gain) const {
    const MatrixR W = E - C * P * C.transpose();
    const MatrixR L_P = F - A * P * C.transpose();
    const MatrixR W_inv_Lt = W.householderQr().solve(L_P.transpose());  // W⁻¹(F̂ − ÂP̂Ĉᵀ)ᵀ
    if (gain) *gain = W_inv_Lt.transpose();  // W symmetric: K = L W⁻¹ = (W⁻¹Lᵀ)ᵀ
    const MatrixR next = A * P * A.transpose() + L_P * W_inv_Lt;
    return MatrixR((next + next.transpose()) / 2);
  }
};

// Step 9(a): Riccati difference iteration P_{k+1} = f(P_k) from P_0 = 0.
// Method: P_k increases monotonically to the minimal, stabilising solution
// (the forward innovation covariance); the error contracts by ρ(Â − KĈ)² per
// step, ρ the largest modulus of the zeros of Ĝ. It only has to bring P into
// Newton's (stabilising) basin, so it stops at a relative change ≤ 1e-12 or
// after 2000 steps (slow when the zeros approach the circle); *iterations
// counts the steps taken. Fails: StepError(9) when the iterates diverge.
// References: Akçay (2011) step 9.
MatrixR step9a_difference_iteration(const RiccatiMap& f, int n, int* iterations) {
  MatrixR P = MatrixR::Zero(n, n);
  const Real difference_tolerance("1e-12");
  const int max_difference_iterations = 2000;
  for (; *iterations < max_difference_iterations; ++*iterations) {
    const MatrixR next = f(P, nullptr);
    const Real change = frobenius(next - P);
    const Real size = frobenius(next);
    P = next;
    if (!boost::multiprecision::isfinite(change))
      throw StepError(9, "Riccati difference iteration diverged");
    if (change <= difference_tolerance * size) break;
  }
  return P;
}

// I − A_K ⊗ A_K, the Kronecker form of the Stein operator Δ ↦ Δ − A_K Δ A_Kᵀ
// (the derivative of P ↦ P − f(P)) at the gain K of P.
MatrixR stein_operator(const RiccatiMap& f, const MatrixR& K) {
  const MatrixR A_K = f.A - K * f.C;
  const Eigen::Index n = A_K.rows();
  return MatrixR(MatrixR::Identity(n * n, n * n) - kron<MatrixR>(A_K, A_K));
}

// ‖f(P) − P‖_F / max(‖P‖_F, 1), and the gain K of P.
Real relative_residual(const RiccatiMap& f, const MatrixR& P, MatrixR* K) {
  return frobenius(MatrixR(f(P, K) - P)) / std::max(frobenius(P), Real(1));
}

// Step 9(b): Newton's method for P = f(P) from a stabilising P.
// Method: the derivative of f at P is Δ ↦ A_K Δ A_Kᵀ, A_K = Â − KĈ, so a step
// solves the Stein equation Δ = A_K Δ A_Kᵀ + (f(P) − P), here through its
// Kronecker form (I − A_K ⊗ A_K) vec Δ = vec(f(P) − P) by Householder QR;
// quadratic convergence from any stabilising P (Hewer 1971). It stops at a
// relative residual ≤ 1e-45, or — once the best residual is ≤ 1e-25, i.e. past
// the quadratic phase (farther out Newton may raise the residual on its way
// in) — after three steps without a new best: Newton at the accuracy it can
// reach. With the zeros of Ĝ near the circle (pole radius 0.999–0.9999) the
// residual bottoms out near 1e-34 and further steps amplify it (measured:
// 7.6e-35, then 4e-32, 2e-29, … until the iterate left the basin, so the former
// rule — stop when the step is ≤ 1e-45 — never stopped). Returns the iterate
// of smallest residual, which step9_check_solution judges. At most 200 steps,
// each counted in *iterations. Fails: StepError(9) when the iterates are not finite.
// References: G. A. Hewer, IEEE TAC 16 (1971) 382-384.
MatrixR step9b_newton(const RiccatiMap& f, MatrixR P, int* iterations) {
  const Real newton_tolerance("1e-45");
  MatrixR best = P;
  Real best_residual = -1;
  for (int newton = 0, stalled = 0; newton < 200 && stalled < 3; ++newton, ++*iterations) {
    MatrixR K;
    const Real residual = relative_residual(f, P, &K);
    if (!boost::multiprecision::isfinite(residual))
      throw StepError(9, "Newton iteration for the Riccati equation diverged");
    if (best_residual < 0 || residual < best_residual) {
      best = P;
      best_residual = residual;
      stalled = 0;
    } else if (best_residual <= Real("1e-25")) {
      ++stalled;
    }
    if (residual <= newton_tolerance) break;
    const MatrixR rhs = f(P, nullptr) - P;
    const VectorR delta_vec =
        stein_operator(f, K).householderQr().solve(Eigen::Map<const VectorR>(rhs.data(), rhs.size()));
    const MatrixR delta = Eigen::Map<const MatrixR>(delta_vec.data(), P.rows(), P.cols());
    P += (delta + delta.transpose()) / 2;
  }
  return best;
}

// Step 9, acceptance: P is the stabilising solution to the reference's
// accuracy. Method: ρ(Â − KĈ) < 1 (stabilising), and the first-order error
// bound of P, ‖(I − A_K ⊗ A_K)⁻¹‖₂ · ‖f(P) − P‖_F (the inverse norm from the
// smallest singular value of the Kronecker matrix, Jacobi SVD), relative to
// max(‖P‖_F, 1), at most 1e-30: fourteen orders below double precision's
// u = 1.1e-16, so that the reference's B̂, D̂ (smooth functions of P, no
// worse conditioned than P itself through W^{±1/2}) are exact for any double
// comparison. (The former rule, residual ≤ 1e-35, refused the radius-0.999
// cases whose best residual is 7.6e-35 with an error bound of 1.6e-31.)
// Fails: StepError(9) naming the bound or the offending |eig(A − K C)|.
void step9_check_solution(const RiccatiMap& f, const MatrixR& P) {
  MatrixR K;
  const Real residual = relative_residual(f, P, &K);
  for (const Complex& mu : eigenvalues(MatrixR(f.A - K * f.C)))
    if (!(abs(mu) < 1))
      throw StepError(9, "Riccati solution is not stabilising: |eig(A - K C)| = " + fmt(abs(mu)));
  const MatrixR L = stein_operator(f, K);
  const Real sigma_min = Eigen::JacobiSVD<MatrixR>(L).singularValues()(L.rows() - 1);
  const Real bound = residual / sigma_min;
  if (!(bound <= Real("1e-30")))
    throw StepError(9, "Riccati solution error bound " + fmt(bound) + " (residual " + fmt(residual) +
                           ") above 1e-30");
}

// Step 9: the stabilising solution of
// P̂ = ÂP̂Âᵀ + (F̂ − ÂP̂Ĉᵀ)(Ê − ĈP̂Ĉᵀ)⁻¹(F̂ − ÂP̂Ĉᵀ)ᵀ.
// Method: difference iteration (9a), then Newton (9b), then the acceptance
// check; *iterations = difference steps + Newton steps. Numerical aspects:
// 50 digits carry the Stein solves even at condition 1e20. Fails:
// StepError(9) as its parts. References: Akçay (2011) step 9; G. A. Hewer,
// IEEE TAC 16 (1971) 382-384 (Newton for the Riccati equation).
MatrixR step9_riccati(const RiccatiMap& f, int n, int* iterations) {
  *iterations = 0;
  MatrixR P = step9a_difference_iteration(f, n, iterations);
  P = step9b_newton(f, P, iterations);
  step9_check_solution(f, P);
  return P;
}

// Matrix square roots W^{1/2}, W^{-1/2} of a symmetric positive definite W.
// Positive definiteness is checked by Cholesky (it succeeds iff W > 0). The
// roots use the right singular vectors V of W: WᵀW = VΣ²Vᵀ, so VΣ^{1/2}Vᵀ =
// (WᵀW)^{1/4} = W^{1/2} for W > 0, also when singular values repeat.
// (SelfAdjointEigenSolver would be the textbook choice, but it needs
// NumTraits<Real>::infinity(), which Boost 1.74 does not provide.)
// Fails: StepError(9) when W is not positive definite.
void symmetric_roots(const MatrixR& W, MatrixR* root, MatrixR* inverse_root) {
  if (Eigen::LLT<MatrixR>(W).info() != Eigen::Success) {
    Real smallest = 0;
    for (const Complex& mu : eigenvalues(W)) smallest = std::min(smallest, mu.real());
    throw StepError(9, "E - C P C^T is not positive definite (smallest eigenvalue " + fmt(smallest) + ")");
  }
  Eigen::JacobiSVD<MatrixR> svd(W, Eigen::ComputeFullV);
  const VectorR& sigma = svd.singularValues();
  const MatrixR& V = svd.matrixV();
  VectorR s(sigma.size()), s_inv(sigma.size());
  for (Eigen::Index i = 0; i < sigma.size(); ++i) {
    s(i) = sqrt(sigma(i));
    s_inv(i) = 1 / s(i);
  }
  *root = V * s.asDiagonal() * V.transpose();
  *inverse_root = V * s_inv.asDiagonal() * V.transpose();
}

// Step 9, second half: B̂ = (F̂ − ÂP̂Ĉᵀ)(Ê − ĈP̂Ĉᵀ)^{−1/2}, D̂ = (Ê − ĈP̂Ĉᵀ)^{1/2}.
// Method: symmetric roots (above). Fails: StepError(9) when Ê − ĈP̂Ĉᵀ is not
// positive definite. References: Akçay (2011) step 9.
void step9_B_D(const RiccatiMap& f, const MatrixR& P, MatrixR* B, MatrixR* D) {
  MatrixR root, inverse_root;
  symmetric_roots(MatrixR(f.E - f.C * P * f.C.transpose()), &root, &inverse_root);
  *B = (f.F - f.A * P * f.C.transpose()) * inverse_root;
  *D = root;
}

}  // namespace

// ---------------------------------------------------------------------------
// Spectra of models (Eqs. 2, 3)

MatrixC spectrum_of(const Model& model, const Complex& z) {
  check_model(model);
  const auto n = model.A.rows();
  const MatrixC A = model.A.cast<Complex>();
  const MatrixC B = model.B.cast<Complex>();
  const MatrixC C = model.C.cast<Complex>();
  const MatrixC D = model.D.cast<Complex>();
  const MatrixC I = MatrixC::Identity(n, n);
  const Complex z_inv = Complex(1) / z;
  const MatrixC G_z = D + C * (z * I - A).partialPivLu().solve(B);              // Eq. (2)
  const MatrixC G_z_inv = D + C * (z_inv * I - A).partialPivLu().solve(B);      // G(z⁻¹)
  return G_z * G_z_inv.transpose();                                             // Eq. (3)
}

Spectrum sample_spectrum(const Model& model, int M) {
  check_model(model);
  if (model.domain != "discrete")
    throw InputError("sample_spectrum: model domain is \"" + model.domain + "\", need \"discrete\"");
  if (M < 1) throw InputError("sample_spectrum: M = " + std::to_string(M) + " < 1");
  Spectrum spectrum;
  spectrum.m = static_cast<int>(model.C.rows());
  spectrum.M = M;
  for (int k = 0; k <= M; ++k)  // z_k = e^{iπ(k−1)/M} = e^{i2π(k−1)/N}, Eq. (7)
    spectrum.S.push_back(spectrum_of(model, unit_root(k, 2 * M)));
  return spectrum;
}

// ---------------------------------------------------------------------------
// Steps 1-2 on their own (for the tests and the golden fixtures)

std::vector<MatrixC> extend_spectrum(const Spectrum& spectrum) {
  check_spectrum(spectrum);
  return step1_extend_spectrum(spectrum);
}

std::vector<MatrixC> fourier_coefficients(const Spectrum& spectrum) {
  return step2_fourier_coefficients(extend_spectrum(spectrum), spectrum.m);
}

MatrixC vo_GF(const Spectrum& spectrum, int p, int r) {
  return step2_vo_matrix_GF(step2_section_three(spectrum, p, r));
}

MatrixC akcay_Y(const Spectrum& spectrum, int p, int r) {
  const SectionThree s = step2_section_three(spectrum, p, r);
  return step2_akcay_matrix_Y(s, step2_vo_matrix_GF(s), p, r, spectrum.m);
}

std::vector<Real> singular_values(const MatrixR& X) {
  Eigen::JacobiSVD<MatrixR> svd(X);
  const VectorR& s = svd.singularValues();
  return std::vector<Real>(s.data(), s.data() + s.size());
}

std::vector<Complex> eigenvalues(const MatrixR& X) {
  if (X.rows() != X.cols()) throw InputError("eigenvalues: matrix is not square");
  Eigen::EigenSolver<MatrixR> eig(X, /*computeEigenvectors=*/false);
  if (eig.info() != Eigen::Success) throw Error("eigenvalues: real Schur iteration did not converge");
  const auto& lambda = eig.eigenvalues();
  return std::vector<Complex>(lambda.data(), lambda.data() + lambda.size());
}

std::vector<Complex> transmission_zeros(const Model& model) {
  if (model.D.rows() != model.D.cols()) throw InputError("transmission_zeros: D is not square");
  return eigenvalues(model.A - model.B * model.D.householderQr().solve(model.C));
}

bool nonsingular(const MatrixR& D) {
  if (D.rows() != D.cols() || D.rows() == 0) return false;
  const std::vector<Real> s = singular_values(D);
  return s.back() > Real(D.rows()) * std::numeric_limits<Real>::epsilon() * s.front();
}

MatrixC normalised_factor_response(const Model& model, const Real& omega) {
  Eigen::JacobiSVD<MatrixR> svd(model.D, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const MatrixR Q = svd.matrixV() * svd.matrixU().transpose();
  return frequency_response(model, omega) * Q.cast<Complex>();
}

// ---------------------------------------------------------------------------
// Algorithm 1

namespace {

// Steps 3-9 from the data matrices of step 2 (shared by identify_spectrum and
// its perturbed reruns), with a backward perturbation when `pert` has one.
Result steps_3_to_9(const Spectrum& spectrum, DataMatrices data, int order, int p, int r, bool van_overschee,
                    const BackwardPerturbation& pert) {
  const int m = spectrum.m;
  std::mt19937_64 rng(pert.seed);
  Result result;
  result.p = p;
  result.r = r;
  move(van_overschee ? data.GF : data.Y, pert.data_matrix, rng);
  const MatrixR& H = van_overschee ? data.GF : data.Y;

  // Step 3 (of Ĝ_p F_r instead of 𝒴 for Van Overschee's method); both sets of
  // singular values are reported.
  const RangeSpace range = step3_range_space(H);
  // (A perturbed rerun reports only what it estimates: the other matrix's SVD is skipped.)
  const bool rerun = pert.data_matrix > 0 || pert.least_squares > 0 || pert.riccati > 0;
  result.singular_values_Y = van_overschee ? (rerun ? std::vector<Real>{} : singular_values(data.Y)) : range.sigma;
  result.singular_values_vo = van_overschee ? range.sigma : (rerun ? std::vector<Real>{} : singular_values(data.GF));

  // Step 4.
  const int n = step4_order(range.sigma, order, p, r, static_cast<int>(std::min(H.rows(), H.cols())));
  result.order = n;
  const MatrixR U2n = range.U.leftCols(2 * n);  // U_2n of Eq. (21)

  // Steps 5-7.
  const MatrixR A_tilde = step5_shift_equations(U2n, p, m);
  const StablePart stable = step7_A_C(step6_stable_split(A_tilde, n), U2n, n, m, p);
  result.poles = stable.poles;

  // Steps 8-9.
  SpectralSummands EF = step8_least_squares_EF(spectrum, stable.A_hat, stable.C_hat, pert.least_squares, &rng);
  move(EF.E, pert.riccati, rng, true);
  move(EF.F, pert.riccati, rng);
  const RiccatiMap f{stable.A_hat, stable.C_hat, EF.E, EF.F};
  if (pert.riccati_start && pert.riccati_start->rows() == n) {
    result.P = step9b_newton(f, *pert.riccati_start, &result.riccati_iterations);
    step9_check_solution(f, result.P);
  } else {
    result.P = step9_riccati(f, n, &result.riccati_iterations);
  }
  result.model.A = stable.A_hat;
  step9_B_D(f, result.P, &result.model.B, &result.model.D);
  result.model.C = stable.C_hat;
  result.E = EF.E;
  result.F = EF.F;
  // Step 10: Ĝ(z), Ŝ_M(z) follow from result.model (Eqs. 10, 8; spectrum_of).
  return result;
}

// Steps 1-2: extension, Section 3 matrices, 𝒴 (Eq. 16) and Ĝ_p F_r (Eq. 13).
DataMatrices steps_1_2(const Spectrum& spectrum, int order, int p, int r) {
  check_spectrum(spectrum);
  check_p_r(p, r, 2 * spectrum.M);
  if (order < 0) throw InputError("step 4: order " + std::to_string(order) + " < 0");
  return step2_data_matrices(spectrum, p, r);
}

}  // namespace

Result identify_spectrum(const Spectrum& spectrum, int order, int p, int r, bool van_overschee,
                         const BackwardPerturbation* perturbation) {
  const BackwardPerturbation none;
  return steps_3_to_9(spectrum, steps_1_2(spectrum, order, p, r), order, p, r, van_overschee,
                      perturbation ? *perturbation : none);
}

PerturbedResults identify_spectrum_perturbed(
    const Spectrum& spectrum, int order, int p, int r, bool van_overschee,
    const std::function<std::vector<BackwardPerturbation>(const Result&)>& perturbations_for) {
  const DataMatrices data = steps_1_2(spectrum, order, p, r);
  PerturbedResults out;
  out.base = steps_3_to_9(spectrum, data, order, p, r, van_overschee, BackwardPerturbation{});
  for (BackwardPerturbation pert : perturbations_for(out.base)) {
    pert.riccati_start = &out.base.P;
    try {
      out.perturbed.push_back(steps_3_to_9(spectrum, data, out.base.order, p, r, van_overschee, pert));
    } catch (const StepError& e) {
      out.failures.push_back(e.what());
    }
  }
  return out;
}

}  // namespace fdsid::reference
