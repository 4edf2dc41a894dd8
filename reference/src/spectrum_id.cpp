// Akçay (2011) Algorithm 1 in 50-digit arithmetic, transcribed from the paper.
//
// Every Eigen decomposition over Real/Complex is instantiated in this one
// translation unit (JacobiSVD, EigenSolver, HouseholderQR, LLT over MatrixR;
// PartialPivLU over MatrixC): each costs seconds
// of compile time with a multiprecision scalar, so other files only call the
// functions declared in spectrum_id.hpp.
#include "fdsid/reference/spectrum_id.hpp"

#include <boost/math/constants/constants.hpp>
#include <Eigen/Dense>

#include <algorithm>
#include <limits>
#include <sstream>

namespace fdsid::reference {
namespace {

using VectorR = Eigen::Matrix<Real, Eigen::Dynamic, 1>;

// z = e^{i 2π q / N} for any integer q. The exponent is reduced mod N first, so
// z_j^k = e^{i2π(j−1)k/N} is computed from one correctly reduced angle rather
// than by repeated multiplication.
Complex unit_root(long long q, int N) {
  long long reduced = q % N;
  if (reduced < 0) reduced += N;
  const Real angle = 2 * boost::math::constants::pi<Real>() * Real(reduced) / Real(N);
  return Complex(cos(angle), sin(angle));
}

// The N-th roots of unity, tabulated once: roots(q) = unit_root(q, N) for any
// integer q, without a cos/sin per matrix entry.
class UnitRoots {
 public:
  explicit UnitRoots(int N) : N_(N), roots_(N) {
    for (int q = 0; q < N; ++q) roots_[q] = unit_root(q, N);
  }
  const Complex& operator()(long long q) const {
    long long reduced = q % N_;
    if (reduced < 0) reduced += N_;
    return roots_[static_cast<std::size_t>(reduced)];
  }

 private:
  int N_;
  std::vector<Complex> roots_;
};

// X ⊗ Y as defined in Section 1.1 of the paper.
template <class Matrix>
Matrix kron(const Matrix& X, const Matrix& Y) {
  Matrix K(X.rows() * Y.rows(), X.cols() * Y.cols());
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index j = 0; j < X.cols(); ++j)
      K.block(i * Y.rows(), j * Y.cols(), Y.rows(), Y.cols()) = X(i, j) * Y;
  return K;
}

// Ψ_k ∈ R^{km×km}: I_m blocks on the block anti-diagonal (Section 3, after Eq. 15).
MatrixC exchange(int k, int m) {
  MatrixC J = MatrixC::Zero(k, k);
  for (int i = 0; i < k; ++i) J(i, k - 1 - i) = Complex(1);
  return kron<MatrixC>(J, MatrixC::Identity(m, m));
}

std::string fmt(const Real& x, int digits = 6) {
  return x.str(digits, std::ios_base::scientific);
}

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

// The matrices of Section 3 for data extended by step 1.
struct SectionThree {
  MatrixC G_hat;  // Ĝ_p  = (1/√N)[Ω_p(ω_1) ⊗ S_1 … Ω_p(ω_N) ⊗ S_N]
  MatrixC G_bar;  // 𝒢̄_p  = (1/√N)[Ω_p(ω_1) ⊗ S̄_1 … Ω_p(ω_N) ⊗ S̄_N]   (after Eq. 15)
  MatrixC F_r;    // F_r  = (1/√N)[z_j^l]_{j=1..N, l=1..r} ⊗ I_m
};

SectionThree section_three(const Spectrum& spectrum, int p, int r) {
  check_spectrum(spectrum);
  const int m = spectrum.m;
  const int N = 2 * spectrum.M;
  check_p_r(p, r, N);
  const std::vector<MatrixC> S = extend_spectrum(spectrum);  // step 1
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

// Y of Eq. (16) and Ĝ_p F_r of Eq. (13), sharing the Section 3 matrices.
void build_Y_and_GF(const Spectrum& spectrum, int p, int r, MatrixC* Y, MatrixC* GF) {
  const SectionThree s = section_three(spectrum, p, r);
  const MatrixC G_hat_F_r = s.G_hat * s.F_r;  // Eq. (13), left-hand side
  if (GF) *GF = G_hat_F_r;
  if (Y) {
    const MatrixC Psi_p = exchange(p, spectrum.m);
    const MatrixC Psi_r = exchange(r, spectrum.m);
    *Y = G_hat_F_r + Psi_p * s.G_bar * s.F_r * Psi_r;  // Eq. (16)
  }
}

// Matrix square roots W^{1/2}, W^{-1/2} of a symmetric positive definite W.
// Positive definiteness is checked by Cholesky (it succeeds iff W > 0). The
// roots use the right singular vectors V of W: WᵀW = VΣ²Vᵀ, so VΣ^{1/2}Vᵀ =
// (WᵀW)^{1/4} = W^{1/2} for W > 0, also when singular values repeat.
// (SelfAdjointEigenSolver would be the textbook choice, but it needs
// NumTraits<Real>::infinity(), which Boost 1.74 does not provide.)
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

Real frobenius(const MatrixR& X) { return X.norm(); }

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
// Steps 1-2 and the matrices of Section 3

std::vector<MatrixC> extend_spectrum(const Spectrum& spectrum) {
  check_spectrum(spectrum);
  const int M = spectrum.M;
  std::vector<MatrixC> S(2 * M);
  for (int k = 1; k <= M + 1; ++k) S[k - 1] = spectrum.S[k - 1];  // S_1 … S_{M+1} as given
  for (int k = 2; k <= M; ++k)                                      // step 1
    S[M + k - 1] = spectrum.S[M - k + 1].conjugate();               // S_{M+k} = conj S_{M−k+2}
  return S;
}

std::vector<MatrixC> fourier_coefficients(const Spectrum& spectrum) {
  const std::vector<MatrixC> S = extend_spectrum(spectrum);
  const int N = static_cast<int>(S.size());
  const int m = spectrum.m;
  const UnitRoots z(N);
  std::vector<MatrixC> s_hat(N);
  for (int k = 0; k < N; ++k) {  // Eq. (20), direct sum
    MatrixC sum = MatrixC::Zero(m, m);
    for (int j = 0; j < N; ++j) sum += z(static_cast<long long>(j) * k) * S[j];
    s_hat[k] = sum / Real(N);
  }
  return s_hat;
}

MatrixC vo_GF(const Spectrum& spectrum, int p, int r) {
  MatrixC GF;
  build_Y_and_GF(spectrum, p, r, nullptr, &GF);
  return GF;
}

MatrixC akcay_Y(const Spectrum& spectrum, int p, int r) {
  MatrixC Y;
  build_Y_and_GF(spectrum, p, r, &Y, nullptr);
  return Y;
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

// ---------------------------------------------------------------------------
// Algorithm 1

Result identify_spectrum(const Spectrum& spectrum, int order, int p, int r, bool van_overschee) {
  check_spectrum(spectrum);
  const int m = spectrum.m;
  const int M = spectrum.M;
  const int N = 2 * M;
  check_p_r(p, r, N);
  if (order < 0) throw InputError("step 4: order " + std::to_string(order) + " < 0");

  Result result;
  result.p = p;
  result.r = r;

  // Steps 1-3. 𝒴 (Eq. 16) and Ĝ_p F_r (Eq. 13) are real up to rounding for data
  // with real S_1, S_{M+1} extended by step 1 (their blocks are the real
  // coefficients ŝ_k, Eq. 19); the real part is kept.
  MatrixC Y_complex, GF_complex;
  build_Y_and_GF(spectrum, p, r, &Y_complex, &GF_complex);
  const MatrixR Y = Y_complex.real();
  const MatrixR GF = GF_complex.real();
  const MatrixR& H = van_overschee ? GF : Y;

  // Step 3: SVD of Eq. (21) (of Ĝ_p F_r instead of 𝒴 for Van Overschee's method).
  Eigen::JacobiSVD<MatrixR> svd(H, Eigen::ComputeThinU);
  const std::vector<Real> sigma(svd.singularValues().data(),
                                svd.singularValues().data() + svd.singularValues().size());
  result.singular_values_Y = van_overschee ? singular_values(Y) : sigma;
  result.singular_values_vo = van_overschee ? sigma : singular_values(GF);

  // Step 4: the order, given or at the largest ratio σ_2n/σ_2n+1 among the n
  // that the inequalities p > 2n, r ≥ 2n admit.
  const int rank_limit = static_cast<int>(std::min(H.rows(), H.cols()));
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
  result.order = n;

  // U_2n of Eq. (21): the 2n leading left singular vectors.
  const MatrixR U2n = svd.matrixU().leftCols(2 * n);

  // Step 5: J_u = [0_{(p−1)m×m} I_{(p−1)m}], J_d = [I_{(p−1)m} 0_{(p−1)m×m}],
  // Ã = (J_d U_2n)^† J_u U_2n with X^† = (XᵀX)⁻¹Xᵀ (Section 1.1).
  const int rows = (p - 1) * m;
  MatrixR Ju = MatrixR::Zero(rows, p * m);
  MatrixR Jd = MatrixR::Zero(rows, p * m);
  Ju.rightCols(rows) = MatrixR::Identity(rows, rows);
  Jd.leftCols(rows) = MatrixR::Identity(rows, rows);
  const MatrixR X = Jd * U2n;
  const MatrixR XtX = X.transpose() * X;
  const MatrixR X_dagger = XtX.householderQr().solve(X.transpose());  // (XᵀX)⁻¹Xᵀ
  const MatrixR A_tilde = X_dagger * Ju * U2n;

  // Step 6: Ã = [Π_c Π_ac] diag(Σ_c, Σ_ac) [Π_c Π_ac]⁻¹, eigenvalues of Σ_c inside
  // the unit circle; exactly n of the 2n must be.
  Eigen::EigenSolver<MatrixR> eig(A_tilde);
  if (eig.info() != Eigen::Success) throw StepError(6, "eigenvalue iteration for A~ did not converge");
  const auto& lambda = eig.eigenvalues();
  const auto& vectors = eig.eigenvectors();
  int inside = 0;
  for (Eigen::Index i = 0; i < lambda.size(); ++i)
    if (abs(lambda(i)) < 1) ++inside;
  if (inside != n) {
    std::ostringstream what;
    what << "no stable/antistable split: " << inside << " of the 2n = " << 2 * n
         << " eigenvalues of A~ lie inside the unit circle, n = " << n << " needed (moduli";
    for (Eigen::Index i = 0; i < lambda.size(); ++i) what << ' ' << fmt(abs(lambda(i)), 10);
    what << ')';
    throw StepError(6, what.str());
  }

  // Step 7 in a real basis of the stable invariant subspace: Π_c has columns v
  // (real λ) or [Re w, Im w] (pair a ± ib, w an eigenvector of a + ib); then
  // Ã Π_c = Π_c Σ_c with Σ_c block diagonal, blocks λ or [[a, b], [−b, a]].
  // This is the paper's complex Jordan form up to a similarity, so the
  // identified spectrum is the same and every matrix below is real.
  MatrixR Pi_c(2 * n, n);
  MatrixR Sigma_c = MatrixR::Zero(n, n);
  int column = 0;
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    const Complex& l = lambda(i);
    if (!(abs(l) < 1) || l.imag() < 0) continue;  // antistable, or the partner of a pair
    if (l.imag() == 0) {
      Pi_c.col(column) = vectors.col(i).real();
      Sigma_c(column, column) = l.real();
      result.poles.push_back(l);
      column += 1;
    } else {
      // The solver's phase of v is arbitrary; w = e^{−i arg(vᵀv)/2} v has wᵀw
      // real, i.e. Re w ⟂ Im w, the best-conditioned real basis of the pair.
      const Eigen::Matrix<Complex, Eigen::Dynamic, 1> v = vectors.col(i);
      const Complex vTv = (v.transpose() * v)(0, 0);
      const Eigen::Matrix<Complex, Eigen::Dynamic, 1> w = std::polar(Real(1), -std::arg(vTv) / 2) * v;
      Pi_c.col(column) = w.real();
      Pi_c.col(column + 1) = w.imag();
      Sigma_c(column, column) = l.real();
      Sigma_c(column, column + 1) = l.imag();
      Sigma_c(column + 1, column) = -l.imag();
      Sigma_c(column + 1, column + 1) = l.real();
      result.poles.push_back(l);
      result.poles.push_back(std::conj(l));
      column += 2;
    }
  }
  if (column != n) throw StepError(6, "stable eigenvalues of A~ do not form conjugate pairs");

  MatrixR Jf = MatrixR::Zero(m, p * m);  // J_f = [I_m 0_{m×(p−1)m}]
  Jf.leftCols(m) = MatrixR::Identity(m, m);
  const MatrixR A_hat = Sigma_c;          // Â = Σ_c
  const MatrixR C_hat = Jf * U2n * Pi_c;  // Ĉ = J_f U_2n Π_c

  // Step 8: min over Ê = Êᵀ, F̂ of Σ_{k=1}^{M+1} ‖χ̂(z_k)F̂ + F̂ᵀχ̂ᵀ(z_k⁻¹) + Ê − S_k‖²_F,
  // χ̂(z) = Ĉ(zI − Σ_c)⁻¹. Unknowns: the m(m+1)/2 entries E_ij (i ≤ j), then
  // the n·m entries F_ij; residual rows: real and imaginary part of each entry
  // (a, b) of each sample. Solved by Householder QR (never the normal equations).
  const int n_E = m * (m + 1) / 2;
  const int n_unknowns = n_E + n * m;
  const int n_rows = 2 * (M + 1) * m * m;
  MatrixR L = MatrixR::Zero(n_rows, n_unknowns);
  VectorR rhs(n_rows);
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
            if ((a == i && b == j) || (a == j && b == i)) L(row, unknown) = 1;
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < m; ++j, ++unknown) {  // F_ij: χ̂(z) e_i e_jᵀ + e_j e_iᵀ χ̂ᵀ(z⁻¹)
            Complex value(0);
            if (b == j) value += chi(a, i);
            if (a == j) value += chi_inv(b, i);
            L(row, unknown) = value.real();
            L(row + 1, unknown) = value.imag();
          }
        rhs(row) = spectrum.S[k](a, b).real();
        rhs(row + 1) = spectrum.S[k](a, b).imag();
      }
  }
  Eigen::HouseholderQR<MatrixR> qr(L);
  {
    const VectorR diagonal = qr.matrixQR().diagonal().cwiseAbs();
    if (diagonal.minCoeff() <= Real("1e-40") * diagonal.maxCoeff())
      throw StepError(8, "least-squares problem for E, F is rank deficient (|R_ii| min/max = " +
                             fmt(diagonal.minCoeff() / diagonal.maxCoeff()) + ")");
  }
  const VectorR theta = qr.solve(rhs);
  MatrixR E_hat(m, m), F_hat(n, m);
  {
    int unknown = 0;
    for (int i = 0; i < m; ++i)
      for (int j = i; j < m; ++j, ++unknown) E_hat(i, j) = E_hat(j, i) = theta(unknown);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j, ++unknown) F_hat(i, j) = theta(unknown);
  }

  // Step 9: P̂ = ÂP̂Âᵀ + (F̂ − ÂP̂Ĉᵀ)(Ê − ĈP̂Ĉᵀ)⁻¹(F̂ − ÂP̂Ĉᵀ)ᵀ.
  // (a) Riccati difference iteration P_{k+1} = f(P_k) from P_0 = 0: P_k increases
  //     monotonically to the minimal, stabilising solution (the forward
  //     innovation covariance); the error contracts by ρ(Â − KĈ)² per step,
  //     K = (F̂ − ÂP̂Ĉᵀ)(Ê − ĈP̂Ĉᵀ)⁻¹, ρ the largest modulus of the zeros of Ĝ.
  // (b) Newton steps: the derivative of f at P is Δ ↦ (Â − KĈ)Δ(Â − KĈ)ᵀ, so the
  //     step solves the Stein equation Δ = A_K Δ A_Kᵀ + (f(P) − P), here through
  //     its Kronecker form (I − A_K ⊗ A_K) vec Δ = vec(f(P) − P) (Householder QR).
  const MatrixR& A = A_hat;
  const MatrixR& C = C_hat;
  auto riccati_map = [&](const MatrixR& P, MatrixR* gain) {
    const MatrixR W = E_hat - C * P * C.transpose();
    const MatrixR L_P = F_hat - A * P * C.transpose();
    const MatrixR W_inv_Lt = W.householderQr().solve(L_P.transpose());  // W⁻¹(F̂ − ÂP̂Ĉᵀ)ᵀ
    if (gain) *gain = W_inv_Lt.transpose();  // W symmetric: K = L W⁻¹ = (W⁻¹Lᵀ)ᵀ
    const MatrixR next = A * P * A.transpose() + L_P * W_inv_Lt;
    return MatrixR((next + next.transpose()) / 2);
  };
  MatrixR P = MatrixR::Zero(n, n);
  // The difference iteration only has to bring P into Newton's (stabilising)
  // basin; when the zeros of Ĝ approach the circle it contracts slowly (ρ² per
  // step), so it stops at 1e-12 or after 2000 steps and Newton, which converges
  // quadratically from any stabilising P_k (Hewer 1971), does the rest.
  const Real difference_tolerance("1e-12");
  const Real newton_tolerance("1e-45");
  const int max_difference_iterations = 2000;
  int iterations = 0;
  for (; iterations < max_difference_iterations; ++iterations) {
    const MatrixR next = riccati_map(P, nullptr);
    const Real change = frobenius(next - P);
    const Real size = frobenius(next);
    P = next;
    if (!boost::multiprecision::isfinite(change))
      throw StepError(9, "Riccati difference iteration diverged");
    if (change <= difference_tolerance * size) break;
  }
  // Newton stops at 1e-45, or -- when the zeros of Ĝ are near the circle and the
  // Stein solve (condition ~1/(1 - ρ(A_K)^2)) cannot reach it -- once its steps
  // stop shrinking with the residual already below 1e-35 relative.
  bool converged = false;
  Real previous_step = -1;
  for (int newton = 0; newton < 200 && !converged; ++newton, ++iterations) {
    MatrixR K;
    const MatrixR residual = riccati_map(P, &K) - P;
    const MatrixR A_K = A - K * C;
    const MatrixR I_nn = MatrixR::Identity(n * n, n * n);
    const MatrixR stein = I_nn - kron<MatrixR>(A_K, A_K);
    const VectorR delta_vec = stein.householderQr().solve(
        Eigen::Map<const VectorR>(residual.data(), residual.size()));
    MatrixR delta = Eigen::Map<const MatrixR>(delta_vec.data(), n, n);
    delta = (delta + delta.transpose()) / 2;
    P += delta;
    if (!boost::multiprecision::isfinite(frobenius(delta)))
      throw StepError(9, "Newton iteration for the Riccati equation diverged");
    const Real step = frobenius(delta);
    converged = step <= newton_tolerance * frobenius(P);
    if (!converged && previous_step >= 0 && step > previous_step / 2) {
      const Real res = frobenius(MatrixR(riccati_map(P, nullptr) - P)) / std::max(frobenius(P), Real(1));
      converged = res <= Real("1e-35");
    }
    previous_step = step;
  }
  if (!converged) throw StepError(9, "Riccati equation: Newton iteration did not converge");
  {
    MatrixR K;
    const MatrixR residual = riccati_map(P, &K) - P;
    const Real relative = frobenius(residual) / std::max(frobenius(P), Real(1));
    if (relative > Real("1e-35"))
      throw StepError(9, "Riccati residual " + fmt(relative) + " too large");
    for (const Complex& mu : eigenvalues(MatrixR(A - K * C)))
      if (!(abs(mu) < 1))
        throw StepError(9, "Riccati solution is not stabilising: |eig(A - K C)| = " + fmt(abs(mu)));
  }
  result.riccati_iterations = iterations;

  // B̂ = (F̂ − ÂP̂Ĉᵀ)(Ê − ĈP̂Ĉᵀ)^{−1/2},  D̂ = (Ê − ĈP̂Ĉᵀ)^{1/2}.
  MatrixR root, inverse_root;
  symmetric_roots(MatrixR(E_hat - C * P * C.transpose()), &root, &inverse_root);
  result.model.A = A_hat;
  result.model.B = (F_hat - A * P * C.transpose()) * inverse_root;
  result.model.C = C_hat;
  result.model.D = root;
  result.E = E_hat;
  result.F = F_hat;
  result.P = P;
  // Step 10: Ĝ(z), Ŝ_M(z) follow from result.model (Eqs. 10, 8; spectrum_of).
  return result;
}

}  // namespace fdsid::reference
