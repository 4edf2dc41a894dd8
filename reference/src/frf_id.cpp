// Pintelon (2002) frequency-domain subspace identification in 50-digit
// arithmetic, transcribed from Sections 2-5 of the paper.
//
// The file follows the paper: Algorithm 1 is one function per step, named
// after it (step1a_data_matrices, step1b_eliminate_input,
// step1c_noise_weighted_svd, step2_A_C, step3_B_D), each with a header giving
// its purpose, method (the paper's equations), numerical aspects, failures and
// references; algorithm1 is the sequence of those calls, Algorithms 2.1 and
// 2.2 (algorithm2_1_bilinear, algorithm2_2_orthogonal) wrap it, and
// identify_frf checks the input and dispatches.
//
// Decompositions used here (each costs seconds of compile time with the
// multiprecision scalar; compiled once, eigen_instances.hpp): LLT, JacobiSVD and
// ColPivHouseholderQR over MatrixR. Complex linear systems are solved in their
// real 2n × 2n form so that no complex decomposition is needed; eigenvalues
// come from eigenvalues() of spectrum_id.cpp.
#include "fdsid/reference/frf_id.hpp"

#include "common.hpp"
#include "eigen_instances.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace fdsid::reference {
namespace {

using detail::finite;
using detail::fmt;
using detail::kron;
using VectorR = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
using VectorC = Eigen::Matrix<Complex, Eigen::Dynamic, 1>;

const Real& unit_roundoff() {
  static const Real u = std::numeric_limits<Real>::epsilon();
  return u;
}

// 1000 u: the numerical-rank threshold of every column-pivoted QR here, and
// the relative size below which a Gram–Schmidt remainder counts as zero.
const Real& rank_tolerance() {
  static const Real tolerance = Real(1000) * unit_roundoff();
  return tolerance;
}

std::string at(std::size_t k) { return "frequency index " + std::to_string(k); }

// ---------------------------------------------------------------------------
// Input checks

// Dimensions of validated data.
struct Shape {
  int F = 0, m = 0, p = 0, c = 0;
};

template <class Matrix>
void check_shape(const char* name, const Matrix& X, int rows, int cols, std::size_t k) {
  if (X.rows() != rows || X.cols() != cols)
    throw InputError(std::string("data: ") + name + " at " + at(k) + " is " +
                     std::to_string(X.rows()) + "x" + std::to_string(X.cols()) + ", expected " +
                     std::to_string(rows) + "x" + std::to_string(cols));
}

void check_finite(const char* name, const Complex& x, int i, int j, std::size_t k) {
  if (!finite(x))
    throw InputError(std::string("data: ") + name + "(" + std::to_string(i) + "," +
                     std::to_string(j) + ") at " + at(k) + " is not finite");
}

// Frequency k: ω in range for the domain, shapes of U, Y, variance, finite
// entries and positive variances.
void check_frequency(const FrfData& d, const Shape& s, std::size_t k) {
  const Real pi = boost::math::constants::pi<Real>();
  const Real& w = d.omega[k];
  if (!finite(w)) throw InputError("data: omega at " + at(k) + " is not finite");
  if (d.domain == "discrete" && (w < 0 || w > pi))
    throw InputError("data: omega = " + fmt(w) + " at " + at(k) + " is outside [0, pi] (discrete)");
  if (d.domain == "continuous" && !(w > 0))
    throw InputError("data: omega = " + fmt(w) + " at " + at(k) + " is not > 0 (continuous)");
  check_shape("U", d.U[k], s.m, s.c, k);
  check_shape("Y", d.Y[k], s.p, s.c, k);
  check_shape("variance", d.variance[k], s.p, s.c, k);
  for (int i = 0; i < s.m; ++i)
    for (int j = 0; j < s.c; ++j) check_finite("U", d.U[k](i, j), i, j, k);
  for (int i = 0; i < s.p; ++i)
    for (int j = 0; j < s.c; ++j) {
      check_finite("Y", d.Y[k](i, j), i, j, k);
      const Real& v = d.variance[k](i, j);
      if (!finite(v) || !(v > 0))
        throw InputError("data: variance(" + std::to_string(i) + "," + std::to_string(j) +
                         ") = " + fmt(v) + " at " + at(k) + " is not a positive number");
    }
}

// The data of Eq. (3)/(15): domain, sizes, every frequency, distinct ω.
Shape check_data(const FrfData& d) {
  if (d.domain != "discrete" && d.domain != "continuous")
    throw InputError("data: domain \"" + d.domain + "\" is neither \"discrete\" nor \"continuous\"");
  Shape s;
  s.F = static_cast<int>(d.omega.size());
  if (s.F < 1) throw InputError("data: no frequencies");
  if (d.U.size() != d.omega.size() || d.Y.size() != d.omega.size() ||
      d.variance.size() != d.omega.size())
    throw InputError("data: " + std::to_string(d.omega.size()) + " frequencies but " +
                     std::to_string(d.U.size()) + " U, " + std::to_string(d.Y.size()) + " Y and " +
                     std::to_string(d.variance.size()) + " variance matrices");
  s.m = static_cast<int>(d.U[0].rows());
  s.c = static_cast<int>(d.U[0].cols());
  s.p = static_cast<int>(d.Y[0].rows());
  if (s.m < 1 || s.c < 1 || s.p < 1)
    throw InputError("data: U[0] is " + std::to_string(s.m) + "x" + std::to_string(s.c) +
                     " and Y[0] has " + std::to_string(s.p) + " rows; all must be >= 1");
  for (std::size_t k = 0; k < d.omega.size(); ++k) check_frequency(d, s, k);
  std::vector<std::pair<Real, std::size_t>> sorted;
  for (std::size_t k = 0; k < d.omega.size(); ++k) sorted.emplace_back(d.omega[k], k);
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i].first == sorted[i - 1].first)
      throw InputError("data: omega = " + fmt(sorted[i].first) + " is repeated (" +
                       at(sorted[i - 1].second) + " and " + at(sorted[i].second) + ")");
  return s;
}

// The options against the data: n ≥ 1, r > n, enough equations for steps 1b
// and 3, a known continuous method, ω_scale ≥ 0.
void check_options(const FrfData& data, const Shape& s, const FrfOptions& options) {
  const int n = options.order, r = options.r;
  if (n < 1) throw InputError("options: order = " + std::to_string(n) + " < 1");
  if (r <= n)
    throw InputError("options: r = " + std::to_string(r) + " must exceed order = " + std::to_string(n));
  if (2 * s.F * s.c < r * (s.m + s.p))
    throw InputError("data: too few frequencies: 2 F c = " + std::to_string(2 * s.F * s.c) +
                     " < r (m + p) = " + std::to_string(r * (s.m + s.p)) +
                     " (step 1b needs Z^T to have at least as many rows as columns)");
  if (2 * s.F * s.c * s.p < n * s.m + s.p * s.m)
    throw InputError("data: too few frequencies: 2 F c p = " + std::to_string(2 * s.F * s.c * s.p) +
                     " equations < n m + p m = " + std::to_string(n * s.m + s.p * s.m) +
                     " unknowns of B, D (step 3)");
  const std::string& method = options.continuous_method;
  if (data.domain == "continuous" && method != "bilinear" && method != "orthogonal")
    throw InputError("options: continuous_method \"" + method +
                     "\" is neither \"bilinear\" nor \"orthogonal\"");
  const std::string& dm = options.discrete_method;
  if (data.domain == "discrete" && dm != "monomial" && dm != "bilinear" && dm != "orthogonal")
    throw InputError("options: discrete_method \"" + dm + "\" is not \"monomial\", \"bilinear\" or \"orthogonal\"");
  const Real pi = boost::math::constants::pi<Real>();
  if (data.domain == "discrete" && dm != "monomial" && options.omega_scale >= pi)
    throw InputError("options: omega_scale = " + fmt(options.omega_scale) + " rad/sample must be < pi");
  if (data.domain == "discrete" && dm == "orthogonal")
    for (const Real& w : data.omega)
      if (!(w < pi)) throw InputError("data: omega = pi maps to tan(omega/2) = infinity (discrete_method orthogonal)");
  if (!finite(options.omega_scale) || options.omega_scale < 0)
    throw InputError("options: omega_scale = " + fmt(options.omega_scale) +
                     " must be >= 0 (0 = automatic)");
}

// ---------------------------------------------------------------------------
// Linear algebra

// Solves (ξI − M)X = R for complex ξ and R through the real form
// [[aI − M, −bI], [bI, aI − M]] [Re X; Im X] = [Re R; Im R], ξ = a + jb.
// Returns false when the real matrix is numerically singular.
bool resolvent_solve(const MatrixR& M, const Complex& xi, const MatrixC& R, MatrixC* X) {
  const Eigen::Index n = M.rows();
  MatrixR big(2 * n, 2 * n);
  const MatrixR diag = xi.real() * MatrixR::Identity(n, n) - M;
  const MatrixR off = xi.imag() * MatrixR::Identity(n, n);
  big << diag, -off, off, diag;
  MatrixR rhs(2 * n, R.cols());
  rhs << R.real(), R.imag();
  Eigen::ColPivHouseholderQR<MatrixR> qr(big);
  qr.setThreshold(rank_tolerance());
  if (qr.rank() < 2 * n) return false;
  const MatrixR sol = qr.solve(rhs);
  X->resize(n, R.cols());
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < R.cols(); ++j) (*X)(i, j) = Complex(sol(i, j), sol(n + i, j));
  return true;
}

// Least-squares solution of X θ = Y (full column rank required): the
// Moore–Penrose solution (XᵀX)⁻¹XᵀY, computed by column-pivoted Householder
// QR (identical in exact arithmetic, without squaring the condition number).
bool least_squares(const MatrixR& X, const MatrixR& Y, MatrixR* theta) {
  Eigen::ColPivHouseholderQR<MatrixR> qr(X);
  qr.setThreshold(rank_tolerance());
  if (qr.rank() < X.cols()) return false;
  *theta = qr.solve(Y);
  return true;
}

// ---------------------------------------------------------------------------
// The rows W_r(k) of the data matrices

// Eq. (7): monomial rows, element (i, k) = ξ_k^i, i = 0 … r−1.
MatrixC monomial_rows(const std::vector<Complex>& xi, int r) {
  MatrixC W(r, xi.size());
  for (std::size_t k = 0; k < xi.size(); ++k) {
    Complex power(1);
    for (int i = 0; i < r; ++i) {
      W(i, k) = power;
      power *= xi[k];
    }
  }
  return W;
}

// Real polynomials q_0 … q_{r−1} (deg q_i = i, positive leading coefficient)
// orthonormal for ⟨p, q⟩ = Σ_k Re(p(ξ_k) w_k conj q(ξ_k)) (Alg. 2.2).
struct PolynomialBasis {
  MatrixC values;  // r × F: q_i(ξ_k)
  MatrixR T;       // r × r lower triangular: q_i(ξ) = Σ_l T_il ξ^l
  MatrixR H;       // r × (r−1): s̃ q_j = Σ_{i ≤ j+1} H_ij q_i
};

// Algorithm 2.2, the bases: q_0 … q_{r−1} orthonormal for the weights w_k.
// Method: Gram–Schmidt applied to ξ·q_{i−1} instead of ξ^i (the same space,
// hence the same orthonormal polynomial: the Arnoldi form), repeated once
// ("twice is enough"); the coefficients give the recurrence H.
// Numerical aspects: O(r² F). Fails: StepError(1) when all weights are zero or
// a degree is dependent on the lower ones (remainder ≤ 1000 u relative: too
// few frequencies with nonzero weight). References: Pintelon (2002)
// Algorithm 2.2; Van Overschee & De Moor (1996); Pintelon & Schoukens (2001).
PolynomialBasis algorithm2_2_orthonormal_basis(const std::vector<Complex>& xi,
                                               const std::vector<Real>& w, int r,
                                               const std::string& which) {
  const std::size_t F = xi.size();
  PolynomialBasis basis;
  basis.values = MatrixC::Zero(r, F);
  basis.T = MatrixR::Zero(r, r);
  basis.H = MatrixR::Zero(r, r - 1);
  auto inner = [&](const VectorC& a, const VectorC& b) {
    Real sum = 0;
    for (std::size_t k = 0; k < F; ++k) sum += w[k] * (a(k) * std::conj(b(k))).real();
    return sum;
  };
  Real total = 0;
  for (std::size_t k = 0; k < F; ++k) total += w[k];
  if (!(total > 0)) throw StepError(1, which + " weights ||.||^2 are all zero");
  const Real q0 = 1 / sqrt(total);
  for (std::size_t k = 0; k < F; ++k) basis.values(0, k) = Complex(q0);
  basis.T(0, 0) = q0;
  for (int i = 1; i < r; ++i) {
    VectorC v(F);
    for (std::size_t k = 0; k < F; ++k) v(k) = xi[k] * basis.values(i - 1, k);
    VectorR coef = VectorR::Zero(r);
    for (int l = 1; l <= i; ++l) coef(l) = basis.T(i - 1, l - 1);
    const Real norm_before = sqrt(inner(v, v));
    for (int pass = 0; pass < 2; ++pass) {
      for (int l = 0; l < i; ++l) {
        const VectorC ql = basis.values.row(l).transpose();
        const Real h = inner(v, ql);
        v -= h * ql;
        coef -= h * basis.T.row(l).transpose();
        basis.H(l, i - 1) += h;
      }
    }
    const Real norm = sqrt(inner(v, v));
    if (!(norm > rank_tolerance() * norm_before))
      throw StepError(1, which + " polynomial basis: degree " + std::to_string(i) +
                             " is dependent on lower degrees (too few frequencies with nonzero weight)");
    basis.H(i, i - 1) = norm;
    basis.values.row(i) = v.transpose() / Complex(norm);
    basis.T.row(i) = coef.transpose() / norm;
  }
  return basis;
}

// ---------------------------------------------------------------------------
// Algorithm 1, steps 1a-3

// The matrices of step 1a.
struct FrfDataMatrices {
  MatrixR U_re, Y_re;  // 𝐔^re, 𝐘^re of Eq. (11): [Re 𝐔, Im 𝐔], [Re 𝐘, Im 𝐘]
  MatrixR C_Y;         // C_Y = Re(𝐂𝐂ᴴ) of Eq. (18)
};

// Step 1a, initialisation: Z = [𝐔^re; 𝐘^re] and C_Y = Re(𝐂𝐂ᴴ) (Eq. 18).
// Method: one block column W_r(k) ⊗ U[k].col(j), W_r(k) ⊗ Y[k].col(j) per
// frequency k and data column j (Eq. 9 with rows rows_u, rows_y), real and
// imaginary parts side by side (Eq. 11); C_Y = Σ_{k,j} Re((W_r W_rᴴ) ⊗
// diag σ²(k, j)). Numerical aspects: O(F c r² p) for C_Y. Fails: never.
// References: Pintelon (2002) Eqs. (9), (11), (18).
FrfDataMatrices step1a_data_matrices(const FrfData& d, const Shape& s, const MatrixC& rows_u,
                                  const MatrixC& rows_y, int r) {
  const int F = s.F, m = s.m, p = s.p, c = s.c;
  const int cols = F * c;  // complex block columns of Eq. (9)
  FrfDataMatrices z{MatrixR(r * m, 2 * cols), MatrixR(r * p, 2 * cols), MatrixR::Zero(r * p, r * p)};
  for (int k = 0; k < F; ++k) {
    const MatrixC wu = rows_u.col(k), wy = rows_y.col(k);
    for (int j = 0; j < c; ++j) {
      const int q = k * c + j;
      const MatrixC Uc = kron<MatrixC>(wu, d.U[k].col(j));  // W_r(k) ⊗ U[k].col(j)
      const MatrixC Yc = kron<MatrixC>(wy, d.Y[k].col(j));  // W_r(k) ⊗ Y[k].col(j)
      z.U_re.col(q) = Uc.real();
      z.U_re.col(cols + q) = Uc.imag();
      z.Y_re.col(q) = Yc.real();
      z.Y_re.col(cols + q) = Yc.imag();
      // C_Y += Re((W_r W_rᴴ) ⊗ diag σ²(k, j))
      for (int a = 0; a < r; ++a)
        for (int b = 0; b < r; ++b) {
          const Real re = (wy(a) * std::conj(wy(b))).real();
          for (int i = 0; i < p; ++i) z.C_Y(a * p + i, b * p + i) += re * d.variance[k](i, j);
        }
    }
  }
  return z;
}

// The backward-error model of FrfOptions::backward_perturbation: each row of
// Z moved by size × its norm, C_Y by size × ‖C_Y‖_F, in random directions (a
// fixed-seed Mersenne twister; the directions need no decimal constants).
struct Perturbation {
  Real size = 0;
  unsigned seed = 1;
};

void perturb(FrfDataMatrices& z, const Perturbation& pert) {
  std::mt19937_64 rng(pert.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto direction = [&](Eigen::Index rows, Eigen::Index cols) {
    MatrixR g(rows, cols);
    for (Eigen::Index i = 0; i < rows; ++i)
      for (Eigen::Index j = 0; j < cols; ++j) g(i, j) = Real(normal(rng));
    return g;
  };
  for (MatrixR* X : {&z.U_re, &z.Y_re})
    for (Eigen::Index i = 0; i < X->rows(); ++i) {
      const MatrixR g = direction(1, X->cols());
      X->row(i) += pert.size * X->row(i).norm() / g.norm() * g;
    }
  const MatrixR g = direction(z.C_Y.rows(), z.C_Y.cols());
  const MatrixR e = g + g.transpose();
  z.C_Y += pert.size * z.C_Y.norm() / e.norm() * e;
}

// Algorithm 2.2's recurrence s̃ q_j = Σ_i H_ij q_i moved by size × ‖H‖_F in a
// random direction on its Hessenberg pattern: the rounding of the inner
// products that give H when the basis is computed in floating point.
void perturb_recurrence(MatrixR& H, const Perturbation& pert) {
  std::mt19937_64 rng(pert.seed + 1000);
  std::normal_distribution<double> normal(0.0, 1.0);
  MatrixR g = MatrixR::Zero(H.rows(), H.cols());
  for (Eigen::Index j = 0; j < H.cols(); ++j)
    for (Eigen::Index i = 0; i <= j + 1 && i < H.rows(); ++i) g(i, j) = Real(normal(rng));
  H += pert.size * H.norm() / g.norm() * g;
}

// Step 1b, elimination of the input term: 𝐘^re Π of Eq. (20), which has the
// Gram matrix of R22ᵀ of the QR factorisation Zᵀ = QR.
// Method: 𝐘^re Π = 𝐘^re − (𝐘^re𝐔^reᵀ)(𝐔^re𝐔^reᵀ)⁻¹𝐔^re with Π never formed,
// the inverse applied by Cholesky of 𝐔^re𝐔^reᵀ (Verhaegen's QR is the stable
// way in double precision; 50 digits absorb the squared condition).
// Numerical aspects: numerical rank deficiency is declared when the squared
// ratio of the extreme pivots of the Cholesky factor (a lower bound on
// 1/cond; LLT::rcond needs NumTraits<Real>::infinity(), which Boost 1.74
// lacks) is ≤ 100 r m u. Fails: StepError(1) for rank-deficient input data.
// References: Pintelon (2002) step 1b, Eq. (20); Verhaegen (1994).
MatrixR step1b_eliminate_input(const MatrixR& U_re, const MatrixR& Y_re, int r, int m) {
  const MatrixR Gu = U_re * U_re.transpose();
  Eigen::LLT<MatrixR> llt_u(Gu);
  Real pivot_ratio = 0;
  if (llt_u.info() == Eigen::Success) {
    const VectorR diag = MatrixR(llt_u.matrixL()).diagonal();
    pivot_ratio = diag.minCoeff() / diag.maxCoeff();
  }
  if (!(pivot_ratio * pivot_ratio > Real(100) * r * m * unit_roundoff()))
    throw StepError(1, "U^re U^re^T is not positive definite (rank-deficient input data; "
                       "pivot ratio " + fmt(pivot_ratio) + ")");
  const MatrixR X = llt_u.solve(U_re * Y_re.transpose());  // (𝐔𝐔ᵀ)⁻¹𝐔𝐘ᵀ
  return Y_re - X.transpose() * U_re;                       // 𝐘^re Π, stand-in for R22ᵀ
}

// Ô_r and the singular values of step 1c.
struct ObservabilityEstimate {
  MatrixR O;                          // Ô_r, r p × n
  std::vector<Real> singular_values;  // Σ of C_Y^{−1/2} R22ᵀ, all r p, largest first
};

// Step 1c, reduction of the noise influence: SVD of C_Y^{−1/2} R22ᵀ = UΣVᵀ,
// Ô_r = C_Y^{1/2} U[:, 1:n].
// Method: C_Y = L Lᵀ (Cholesky; L is the square root), the SVD of
// K = L⁻¹(𝐘^reΠ)(𝐘^reΠ)ᵀL⁻ᵀ = UΣ²Uᵀ (JacobiSVD, full U), Σ = √ of its
// singular values. Numerical aspects: forming K squares the condition, so
// singular values below ≈ √u σ_1 are not resolved; the leading n singular
// vectors are. Fails: StepError(1) when C_Y is not positive definite. Too
// few frequencies (2F < r columns) are refused by step 1b before this, so the
// cause here is numerical: the r basis rows at the data's frequencies are
// dependent to the working precision (review finding 6 of stop 47: the F-16's
// 267 lines, a bilinear basis at r = 48 on a band covering ~28 % of the unit
// circle, were reported as "too few frequencies").
// References: Pintelon (2002) step 1c; McKelvey et al. (1996).
ObservabilityEstimate step1c_noise_weighted_svd(const MatrixR& C_Y, const MatrixR& YPi, int n) {
  Eigen::LLT<MatrixR> llt_c(C_Y);
  if (llt_c.info() != Eigen::Success)
    throw StepError(1, "C_Y (" + std::to_string(C_Y.rows()) + " x " + std::to_string(C_Y.rows()) +
                           ") is singular to " + std::to_string(std::numeric_limits<Real>::digits10) +
                           " digits (Cholesky fails): the r basis rows are numerically dependent on the data's "
                           "frequencies (r too large for the band); a smaller --r");
  const MatrixR L = llt_c.matrixL();
  const MatrixR M1 = llt_c.matrixL().solve(YPi);
  const MatrixR K = M1 * M1.transpose();
  Eigen::JacobiSVD<MatrixR> svd(K, Eigen::ComputeFullU);
  ObservabilityEstimate out;
  for (Eigen::Index i = 0; i < svd.singularValues().size(); ++i)
    out.singular_values.push_back(sqrt(svd.singularValues()(i)));
  out.O = L * svd.matrixU().leftCols(n);
  return out;
}

// Step 2: Â = Ô_r[1:r−1]⁺ Ô_r[2:r], Ĉ = Ô_r[1] (Eq. 19), or, for Alg. 2.2,
// the generalised shift Ô_r[1:r−1] Â = [Σ_{i ≤ j+1} H_ij Ô_r[i]]_j with
// Ĉ = Ô_r[1] / q_0 (H == nullptr: monomials).
// Method: least squares by column-pivoted Householder QR (block rows of p).
// Fails: StepError(2) when Ô_r[1:r−1] has no full column rank n.
// References: Pintelon (2002) step 2, Eqs. (12), (19); Van Overschee & De
// Moor (1996) for the generalised shift.
void step2_A_C(const MatrixR& O, int p, int r, int n, const MatrixR* H, const Real& q0,
               MatrixR* A, MatrixR* C) {
  const MatrixR O_up = O.topRows((r - 1) * p);
  MatrixR rhs;
  if (H == nullptr) {
    rhs = O.bottomRows((r - 1) * p);  // Ô_r[2:r]
    *C = O.topRows(p);
  } else {
    rhs = MatrixR::Zero((r - 1) * p, n);
    for (int j = 0; j < r - 1; ++j)
      for (int i = 0; i <= j + 1; ++i) rhs.middleRows(j * p, p) += (*H)(i, j) * O.middleRows(i * p, p);
    *C = O.topRows(p) / q0;
  }
  if (!least_squares(O_up, rhs, A))
    throw StepError(2, "O_r[1:r-1] does not have full column rank " + std::to_string(n));
}

// Step 3: B̂, D̂ minimising Eq. (17) with W(k) = 1/σ_Y(k), given Â, Ĉ.
// Method: the residual Y − (Ĉ(ξ_kI − Â)⁻¹B + D)U is linear in
// θ = [vec B; vec D] (column-major); one weighted row per real and imaginary
// part of each output, column and frequency; (ξ_kI − Âᵀ)⁻¹Ĉᵀ by the real form
// of the complex solve; θ by column-pivoted Householder QR.
// Numerical aspects: 2Fcp × (n + p)m. Fails: StepError(3) when ξ_k is an
// eigenvalue of Â or the problem is rank deficient.
// References: Pintelon (2002) step 3, Eq. (17).
void step3_B_D(const FrfData& d, const Shape& s, const std::vector<Complex>& xi,
               const MatrixR& A, const MatrixR& C, MatrixR* B, MatrixR* D) {
  const int m = s.m, p = s.p, c = s.c;
  const int n = static_cast<int>(A.rows());
  const int n_theta = n * m + p * m;
  MatrixR Phi_re(2 * s.F * c * p, n_theta), rhs_re(2 * s.F * c * p, 1);
  int row = 0;
  for (int k = 0; k < s.F; ++k) {
    MatrixC PhiT;  // (ξI − Aᵀ)⁻¹Cᵀ = (C(ξI − A)⁻¹)ᵀ
    if (!resolvent_solve(A.transpose(), xi[k], C.transpose().cast<Complex>(), &PhiT))
      throw StepError(3, "xi at " + at(k) + " is an eigenvalue of the estimated A");
    for (int j = 0; j < c; ++j)
      for (int i = 0; i < p; ++i, ++row) {
        const Real weight = 1 / sqrt(d.variance[k](i, j));
        Eigen::Matrix<Complex, 1, Eigen::Dynamic> a = Eigen::Matrix<Complex, 1, Eigen::Dynamic>::Zero(n_theta);
        for (int b = 0; b < m; ++b) {
          const Complex ub = d.U[k](b, j);
          for (int l = 0; l < n; ++l) a(l + n * b) = PhiT(l, i) * ub;  // ∂/∂B(l,b)
          a(n * m + i + p * b) = ub;                                    // ∂/∂D(i,b)
        }
        Phi_re.row(2 * row) = weight * a.real();
        Phi_re.row(2 * row + 1) = weight * a.imag();
        rhs_re(2 * row, 0) = weight * d.Y[k](i, j).real();
        rhs_re(2 * row + 1, 0) = weight * d.Y[k](i, j).imag();
      }
  }
  MatrixR theta;
  if (!least_squares(Phi_re, rhs_re, &theta))
    throw StepError(3, "the least-squares problem for B, D is rank deficient");
  B->resize(n, m);
  D->resize(p, m);
  for (int b = 0; b < m; ++b) {
    for (int l = 0; l < n; ++l) (*B)(l, b) = theta(l + n * b, 0);
    for (int i = 0; i < p; ++i) (*D)(i, b) = theta(n * m + i + p * b, 0);
  }
}

// State-space matrices of one run of Algorithm 1 (or 2.1, 2.2).
struct Estimate {
  MatrixR A, B, C, D;
  std::vector<Real> singular_values;
};

// An estimate's (A, B, C, D) as a Model (for the back-transformations), and back.
Model model_of(const Estimate& e) {
  Model m;
  m.A = e.A;
  m.B = e.B;
  m.C = e.C;
  m.D = e.D;
  return m;
}
Estimate estimate_of(const Model& m, const std::vector<Real>& singular_values) {
  return Estimate{m.A, m.B, m.C, m.D, singular_values};
}

// Algorithm 1 (steps 1-3) with general real polynomial rows: rows_u/rows_y
// (r × F) hold the basis polynomials at ξ_k; H == nullptr means monomials
// (shift property Eq. 12), otherwise the generalised shift with
// s̃ q_j = Σ_i H_ij q_i and Ĉ = Ô[block 0] / q0.
Estimate algorithm1(const FrfData& d, const Shape& s, const std::vector<Complex>& xi,
                    const MatrixC& rows_u, const MatrixC& rows_y, const MatrixR* H, const Real& q0,
                    int n, int r, const Perturbation& pert) {
  FrfDataMatrices z = step1a_data_matrices(d, s, rows_u, rows_y, r);
  if (pert.size > 0) perturb(z, pert);
  const MatrixR YPi = step1b_eliminate_input(z.U_re, z.Y_re, r, s.m);
  const ObservabilityEstimate O = step1c_noise_weighted_svd(z.C_Y, YPi, n);
  Estimate est;
  est.singular_values = O.singular_values;
  step2_A_C(O.O, s.p, r, n, H, q0, &est.A, &est.C);
  step3_B_D(d, s, xi, est.A, est.C, &est.B, &est.D);
  return est;
}

// ---------------------------------------------------------------------------
// Algorithms 1, 2.1, 2.2: the choice of ξ and of the rows

// Algorithm 1, discrete time: ξ_k = z_k = e^{jω_k}, monomial rows (Eq. 7).
Estimate algorithm1_discrete(const FrfData& data, const Shape& s, int n, int r, const Perturbation& pert) {
  std::vector<Complex> xi(s.F);
  for (int k = 0; k < s.F; ++k) xi[k] = Complex(cos(data.omega[k]), sin(data.omega[k]));
  const MatrixC W = monomial_rows(xi, r);
  return algorithm1(data, s, xi, W, W, nullptr, Real(1), n, r, pert);
}

// Algorithm 2.1: Algorithm 1 with ξ = w = (s̃ − 1)/(s̃ + 1), s̃ = jω/ω_scale
// (|w| = 1), then the bilinear back-transform to s (bilinear_to_continuous).
// Fails: as Algorithm 1, and StepError(4) when I − A_w is singular.
// References: Pintelon (2002) Algorithm 2.1; Yang & Sanada (2000).
Estimate algorithm2_1_bilinear(const FrfData& data, const Shape& s, const Real& scale, int n, int r,
                               const Perturbation& pert) {
  std::vector<Complex> xi(s.F);
  for (int k = 0; k < s.F; ++k) {
    const Complex st(Real(0), data.omega[k] / scale);
    xi[k] = (st - Real(1)) / (st + Real(1));
  }
  const MatrixC W = monomial_rows(xi, r);
  const Estimate w = algorithm1(data, s, xi, W, W, nullptr, Real(1), n, r, pert);
  return estimate_of(bilinear_to_continuous(model_of(w), scale), w.singular_values);
}

// Algorithm 2.1 for discrete data (FrfOptions::discrete_method "bilinear"):
// the Tustin map s' = (z − 1)/(z + 1) takes z = e^{jω} to s' = j tan(ω/2) and
// a rational G_d(z) to G'(s') = G_d((1 + s')/(1 − s')) of the same order, so
// Algorithm 2.1 runs on the frequencies tan(ω/2) with the scale
// t_s = tan(ω_scale/2): ξ = w = (s'/t_s − 1)/(s'/t_s + 1), written as
// (j sin(ω/2) − t_s cos(ω/2))/(j sin(ω/2) + t_s cos(ω/2)) so that ω = π gives 1.
// Back: w → s' (bilinear_to_continuous, scale t_s), then s' → z: with
// s' = (z − 1)/(z + 1), s'I − A' = (I − A')(zI − A_z)/(z + 1) where
// A_z = (I − A')⁻¹(I + A') — the formulas of bilinear_to_continuous with
// scale 1 (z plays the part of s, s' that of w).
// Fails: as Algorithm 1, StepError(4) when I − A_w or I − A' is singular.
Estimate algorithm2_1_tustin(const FrfData& data, const Shape& s, const Real& scale, int n, int r,
                             const Perturbation& pert) {
  const Real ts = tan(scale / 2);
  std::vector<Complex> xi(s.F);
  for (int k = 0; k < s.F; ++k) {
    const Complex st(Real(0), sin(data.omega[k] / 2));
    const Real ct = ts * cos(data.omega[k] / 2);
    xi[k] = (st - ct) / (st + ct);
  }
  const MatrixC W = monomial_rows(xi, r);
  const Estimate w = algorithm1(data, s, xi, W, W, nullptr, Real(1), n, r, pert);
  const Model tustin = bilinear_to_continuous(model_of(w), ts);
  return estimate_of(bilinear_to_continuous(tustin, Real(1)), w.singular_values);
}

// Algorithm 2.2: Algorithm 1 with ξ = s̃ = jω/ω_scale and the monomial rows
// replaced by the orthonormal bases of the inputs (weights ‖U[k]‖²_F) and of
// the outputs (‖Y[k]‖²_F); A, B are rescaled from s̃ to s.
// References: Pintelon (2002) Algorithm 2.2; Van Overschee & De Moor (1996).
Estimate algorithm2_2_orthogonal(const FrfData& data, const Shape& s, const Real& scale, int n, int r,
                                 const Perturbation& pert) {
  std::vector<Complex> xi(s.F);
  std::vector<Real> weight_u(s.F), weight_y(s.F);
  for (int k = 0; k < s.F; ++k) {
    xi[k] = Complex(Real(0), data.omega[k] / scale);
    weight_u[k] = data.U[k].squaredNorm();
    weight_y[k] = data.Y[k].squaredNorm();
  }
  const PolynomialBasis bu = algorithm2_2_orthonormal_basis(xi, weight_u, r, "input");
  PolynomialBasis by = algorithm2_2_orthonormal_basis(xi, weight_y, r, "output");
  if (pert.size > 0) perturb_recurrence(by.H, pert);
  Estimate est = algorithm1(data, s, xi, bu.values, by.values, &by.H, by.T(0, 0), n, r, pert);
  est.A *= scale;
  est.B *= scale;
  return est;
}

// Algorithm 2.2 for discrete data (discrete_method "orthogonal"): the same
// Tustin map, Algorithm 2.2 on the frequencies tan(ω/2) with the scale
// t_s = tan(ω_scale/2) (its result is in s'), then s' → z as above.
Estimate algorithm2_2_tustin(const FrfData& data, const Shape& s, const Real& scale, int n, int r,
                             const Perturbation& pert) {
  FrfData tan_axis = data;
  for (Real& w : tan_axis.omega) w = tan(w / 2);
  const Estimate sp = algorithm2_2_orthogonal(tan_axis, s, tan(scale / 2), n, r, pert);
  return estimate_of(bilinear_to_continuous(model_of(sp), Real(1)), sp.singular_values);
}

}  // namespace

FrfResult identify_frf(const FrfData& data, const FrfOptions& options) {
  const Shape s = check_data(data);
  check_options(data, s, options);
  const int n = options.order, r = options.r;
  const bool continuous = data.domain == "continuous";
  Real scale = options.omega_scale;
  if (continuous && scale == 0) {  // automatic: the geometric mean of the band edges
    const auto [lo, hi] = std::minmax_element(data.omega.begin(), data.omega.end());
    scale = sqrt(*lo * *hi);
  }

  const bool tustin = !continuous && options.discrete_method != "monomial";
  if (tustin && scale == 0) {  // automatic: the geometric mean of tan(ω/2) at the band edges inside (0, π)
    const Real pi = boost::math::constants::pi<Real>();
    Real lo = pi, hi = 0;
    for (const Real& w : data.omega)
      if (w > 0 && w < pi) {
        if (w < lo) lo = w;
        if (w > hi) hi = w;
      }
    scale = hi > 0 ? Real(2 * atan(sqrt(tan(lo / 2) * tan(hi / 2)))) : Real(pi / 2);
  }

  const Perturbation pert{options.backward_perturbation, options.perturbation_seed};
  Estimate est;
  if (tustin && options.discrete_method == "bilinear")
    est = algorithm2_1_tustin(data, s, scale, n, r, pert);
  else if (tustin)
    est = algorithm2_2_tustin(data, s, scale, n, r, pert);
  else if (!continuous)
    est = algorithm1_discrete(data, s, n, r, pert);
  else if (options.continuous_method == "bilinear")
    est = algorithm2_1_bilinear(data, s, scale, n, r, pert);
  else
    est = algorithm2_2_orthogonal(data, s, scale, n, r, pert);

  FrfResult result;
  result.model.domain = data.domain;
  result.model.sample_time = continuous ? Real(0) : Real(1);
  result.model.A = est.A;
  result.model.B = est.B;
  result.model.C = est.C;
  result.model.D = est.D;
  result.order = n;
  result.r = r;
  result.singular_values = est.singular_values;
  result.v_sub = v_sub(result.model, data);
  result.poles = eigenvalues(result.model.A);
  return result;
}

Model bilinear_to_continuous(const Model& w_model, const Real& omega_scale) {
  if (!finite(omega_scale) || !(omega_scale > 0))
    throw InputError("bilinear_to_continuous: omega_scale = " + fmt(omega_scale) + " is not > 0");
  const Eigen::Index n = w_model.A.rows();
  // wI − A_w = (I − A_w)(s̃I − A_c)/(s̃ + 1) with Q = (I − A_w)⁻¹, A_c = Q(I + A_w);
  // G = D_w + C_w Q B_w + 2 C_w Q (s̃I − A_c)⁻¹ Q B_w (Q commutes with A_c).
  const MatrixR I = MatrixR::Identity(n, n);
  MatrixR Q;
  if (!least_squares(I - w_model.A, I, &Q))
    throw StepError(4, "I - A_w is singular (an estimated w-domain pole at w = 1, s = infinity)");
  const Real root2 = sqrt(Real(2));
  Model model;
  model.domain = "continuous";
  model.sample_time = 0;
  model.A = omega_scale * (Q * (I + w_model.A));  // s = ω_scale s̃
  model.B = (omega_scale * root2) * (Q * w_model.B);
  model.C = root2 * (w_model.C * Q);
  model.D = w_model.D + w_model.C * Q * w_model.B;
  return model;
}

MatrixC frequency_response(const Model& model, const Real& omega) {
  const Eigen::Index n = model.A.rows();
  if (model.A.cols() != n || model.B.rows() != n || model.C.cols() != n ||
      model.D.rows() != model.C.rows() || model.D.cols() != model.B.cols())
    throw InputError("model: inconsistent shapes of A, B, C, D");
  Complex xi;
  if (model.domain == "discrete")
    xi = Complex(cos(omega), sin(omega));
  else if (model.domain == "continuous")
    xi = Complex(Real(0), omega);
  else
    throw InputError("model: domain \"" + model.domain + "\" is neither discrete nor continuous");
  MatrixC X;  // (ξI − A)⁻¹B
  if (!resolvent_solve(model.A, xi, model.B.cast<Complex>(), &X))
    throw InputError("frequency_response: omega = " + fmt(omega) + " is on a pole of the model");
  return model.C.cast<Complex>() * X + model.D.cast<Complex>();
}

Real v_sub(const Model& model, const FrfData& data) {
  check_data(data);
  Real sum = 0;
  for (std::size_t k = 0; k < data.omega.size(); ++k) {
    const MatrixC E = data.Y[k] - frequency_response(model, data.omega[k]) * data.U[k];
    for (Eigen::Index i = 0; i < E.rows(); ++i)
      for (Eigen::Index j = 0; j < E.cols(); ++j) sum += std::norm(E(i, j)) / data.variance[k](i, j);
  }
  return sum;
}

CostGradient cost_gradient(const Model& model, const FrfData& data) {
  const Shape s = check_data(data);
  const Eigen::Index n = model.A.rows();
  // Each matrix against the shape that A (n) and the data (m = U rows, p = Y
  // rows) imply, so that the message names the offending matrix.
  const auto expect = [](const char* name, const MatrixR& X, Eigen::Index rows, Eigen::Index cols) {
    if (X.rows() != rows || X.cols() != cols)
      throw InputError(std::string("model: ") + name + " is " + std::to_string(X.rows()) + "x" +
                       std::to_string(X.cols()) + ", expected " + std::to_string(rows) + "x" +
                       std::to_string(cols) + " (n from A, m from data U, p from data Y)");
  };
  expect("A", model.A, n, n);
  expect("B", model.B, n, s.m);
  expect("C", model.C, s.p, n);
  expect("D", model.D, s.p, s.m);
  if (model.domain != "discrete" && model.domain != "continuous")
    throw InputError("model: domain \"" + model.domain + "\" is neither discrete nor continuous");

  const MatrixC B = model.B.cast<Complex>(), C = model.C.cast<Complex>(),
                D = model.D.cast<Complex>();
  const MatrixC I = MatrixC::Identity(n, n);
  // Σ_k of U Rᴴ (m × p), X B U Rᴴ (n × p), U Rᴴ C X (m × n), X B U Rᴴ C X (n × n).
  MatrixC sum_D = MatrixC::Zero(s.m, s.p), sum_C = MatrixC::Zero(n, s.p),
          sum_B = MatrixC::Zero(s.m, n), sum_A = MatrixC::Zero(n, n);
  CostGradient g;
  g.cost = 0;
  for (std::size_t k = 0; k < data.omega.size(); ++k) {
    const Real& w = data.omega[k];
    const Complex xi = model.domain == "discrete" ? Complex(cos(w), sin(w)) : Complex(Real(0), w);
    MatrixC X;  // X_k = (ξ_k I − A)⁻¹
    if (!resolvent_solve(model.A, xi, I, &X))
      throw InputError("cost_gradient: omega = " + fmt(w) + " at " + at(k) + " is on a pole of the model");
    const MatrixC XB = X * B, CX = C * X;
    const MatrixC E = data.Y[k] - (D + C * XB) * data.U[k];  // E_k, p × c
    MatrixC R(s.p, s.c);                                      // R_k = E_k ./ σ²_k
    for (int i = 0; i < s.p; ++i)
      for (int j = 0; j < s.c; ++j) {
        R(i, j) = E(i, j) / data.variance[k](i, j);
        g.cost += std::norm(E(i, j)) / data.variance[k](i, j);
      }
    const MatrixC URh = data.U[k] * R.adjoint();  // U_k R_kᴴ, m × p
    const MatrixC XBURh = XB * URh;               // X_k B U_k R_kᴴ, n × p
    sum_D += URh;
    sum_C += XBURh;
    sum_B += URh * CX;
    sum_A += XBURh * CX;
  }
  g.dD = Real(-2) * sum_D.real().transpose();
  g.dC = Real(-2) * sum_C.real().transpose();
  g.dB = Real(-2) * sum_B.real().transpose();
  g.dA = Real(-2) * sum_A.real().transpose();
  return g;
}

CostGradient eiv_cost_gradient(const Model& model, const FrfData& data, const std::vector<Real>& var_U,
                               const std::vector<Complex>& cov_YU) {
  const Shape s = check_data(data);
  if (s.m != 1 || s.p != 1 || s.c != 1) throw InputError("eiv_cost_gradient: the data must be SISO with one column");
  if (var_U.size() != data.omega.size() || cov_YU.size() != data.omega.size())
    throw InputError("eiv_cost_gradient: var_U and cov_YU need one value per frequency");
  const Eigen::Index n = model.A.rows();
  if (model.B.rows() != n || model.B.cols() != 1 || model.C.rows() != 1 || model.C.cols() != n ||
      model.D.rows() != 1 || model.D.cols() != 1)
    throw InputError("model: A, B, C, D are not the shapes of an order-" + std::to_string(n) + " SISO model");
  const MatrixC B = model.B.cast<Complex>(), C = model.C.cast<Complex>();
  const MatrixC I = MatrixC::Identity(n, n);
  Complex sum_D(0);
  MatrixC sum_C = MatrixC::Zero(n, 1), sum_B = MatrixC::Zero(1, n), sum_A = MatrixC::Zero(n, n);
  CostGradient g;
  g.cost = 0;
  for (std::size_t k = 0; k < data.omega.size(); ++k) {
    const Real& w = data.omega[k];
    const Complex xi = model.domain == "discrete" ? Complex(cos(w), sin(w)) : Complex(Real(0), w);
    MatrixC X;
    if (!resolvent_solve(model.A, xi, I, &X))
      throw InputError("eiv_cost_gradient: omega = " + fmt(w) + " at " + at(k) + " is on a pole of the model");
    const MatrixC XB = X * B, CX = C * X;
    const Complex G = Complex(model.D(0, 0)) + (C * XB)(0, 0), U = data.U[k](0, 0);
    const Complex e = data.Y[k](0, 0) - G * U;
    const Real v = data.variance[k](0, 0) + std::norm(G) * var_U[k] - 2 * (cov_YU[k] * std::conj(G)).real();
    if (!(v > 0)) throw InputError("eiv_cost_gradient: the variance of the residual at " + at(k) + " is not positive");
    g.cost += std::norm(e) / v;
    const Complex wk = -U * std::conj(e) / v - (std::norm(e) / (v * v)) * (std::conj(G) * var_U[k] - std::conj(cov_YU[k]));
    sum_D += wk;
    sum_C += XB * wk;
    sum_B += wk * CX;
    sum_A += XB * wk * CX;
  }
  g.dD = MatrixR::Constant(1, 1, 2 * sum_D.real());
  g.dC = Real(2) * sum_C.real().transpose();
  g.dB = Real(2) * sum_B.real().transpose();
  g.dA = Real(2) * sum_A.real().transpose();
  return g;
}

std::vector<std::vector<MatrixC>> period_spectra(const std::vector<std::vector<Real>>& channels,
                                                 int period, int periods,
                                                 const std::vector<int>& lines) {
  if (channels.empty()) throw InputError("period_spectra: no channels");
  if (period < 2) throw InputError("period_spectra: period = " + std::to_string(period) + " < 2");
  if (periods < 1) throw InputError("period_spectra: periods = " + std::to_string(periods) + " < 1");
  const std::size_t length = static_cast<std::size_t>(period) * periods;
  for (std::size_t ch = 0; ch < channels.size(); ++ch)
    if (channels[ch].size() != length)
      throw InputError("period_spectra: channel " + std::to_string(ch) + " has " +
                       std::to_string(channels[ch].size()) + " samples, periods * period = " +
                       std::to_string(length));
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i] < 1 || lines[i] > period / 2)
      throw InputError("period_spectra: line " + std::to_string(lines[i]) + " (entry " +
                       std::to_string(i) + ") is outside 1 ... period/2 = " + std::to_string(period / 2));
  const int N = period;
  const detail::UnitRoots z(N);  // e^{−j2πkt/N} = conj z(kt)
  const Real scale = 1 / sqrt(Real(N));
  std::vector<std::vector<MatrixC>> out(periods, std::vector<MatrixC>(lines.size()));
  for (int l = 0; l < periods; ++l)
    for (std::size_t i = 0; i < lines.size(); ++i) {
      MatrixC Z(channels.size(), 1);
      for (std::size_t ch = 0; ch < channels.size(); ++ch) {
        Complex sum(0);
        for (int t = 0; t < N; ++t)
          sum += channels[ch][static_cast<std::size_t>(l) * N + t] *
                 std::conj(z(static_cast<long long>(lines[i]) * t));
        Z(ch, 0) = scale * sum;  // Eq. (4)
      }
      out[l][i] = Z;
    }
  return out;
}

SampleStatistics sample_statistics(const std::string& domain, const std::vector<Real>& omega,
                                   const std::vector<std::vector<MatrixC>>& U_l,
                                   const std::vector<std::vector<MatrixC>>& Y_l) {
  const int M = static_cast<int>(U_l.size());
  if (M < 2) throw InputError("sample_statistics: M = " + std::to_string(M) + " experiments, need >= 2");
  if (Y_l.size() != U_l.size())
    throw InputError("sample_statistics: " + std::to_string(U_l.size()) + " input and " +
                     std::to_string(Y_l.size()) + " output experiments");
  const std::size_t F = omega.size();
  if (F < 1) throw InputError("sample_statistics: no frequencies");
  const Eigen::Index m = U_l[0][0].rows(), p = Y_l[0][0].rows();
  for (int l = 0; l < M; ++l) {
    if (U_l[l].size() != F || Y_l[l].size() != F)
      throw InputError("sample_statistics: experiment " + std::to_string(l) + " has " +
                       std::to_string(U_l[l].size()) + " U and " + std::to_string(Y_l[l].size()) +
                       " Y spectra, expected " + std::to_string(F));
    for (std::size_t k = 0; k < F; ++k)
      if (U_l[l][k].rows() != m || U_l[l][k].cols() != 1 || Y_l[l][k].rows() != p ||
          Y_l[l][k].cols() != 1)
        throw InputError("sample_statistics: experiment " + std::to_string(l) + ", " + at(k) +
                         ": U must be " + std::to_string(m) + "x1 and Y " + std::to_string(p) + "x1");
  }
  SampleStatistics st;
  st.M = M;
  st.data.domain = domain;
  st.data.omega = omega;
  const Real inv_M = 1 / Real(M), inv_M1 = 1 / Real(M - 1);
  for (std::size_t k = 0; k < F; ++k) {
    MatrixC U_mean = MatrixC::Zero(m, 1), Y_mean = MatrixC::Zero(p, 1);
    for (int l = 0; l < M; ++l) {
      U_mean += U_l[l][k];
      Y_mean += Y_l[l][k];
    }
    U_mean *= Complex(inv_M);  // Eq. (25)
    Y_mean *= Complex(inv_M);
    MatrixR var_Y = MatrixR::Zero(p, 1), var_U = MatrixR::Zero(m, 1);
    MatrixC cov = MatrixC::Zero(p, m);
    for (int l = 0; l < M; ++l) {
      const MatrixC dU = U_l[l][k] - U_mean, dY = Y_l[l][k] - Y_mean;
      for (Eigen::Index i = 0; i < p; ++i) var_Y(i, 0) += std::norm(dY(i, 0));
      for (Eigen::Index i = 0; i < m; ++i) var_U(i, 0) += std::norm(dU(i, 0));
      cov += dY * dU.adjoint();  // Eq. (32): (Y − Ŷ) conj(U − Û)
    }
    st.data.U.push_back(U_mean);
    st.data.Y.push_back(Y_mean);
    st.data.variance.push_back(var_Y * (inv_M1 * inv_M));  // σ̂²_Y / M
    st.var_U.push_back(var_U * inv_M1);
    st.cov_YU.push_back(cov * Complex(inv_M1));
  }
  return st;
}

FrfData errors_in_variables(const SampleStatistics& stats) { return ratio_estimate(stats, RatioOptions{}); }

FrfData ratio_estimate(const SampleStatistics& stats, const RatioOptions& o, int* dropped) {
  const FrfData& d = stats.data;
  if (stats.M < 2) throw InputError("errors_in_variables: M = " + std::to_string(stats.M) + " < 2");
  const std::size_t F = d.omega.size();
  if (d.U.size() != F || d.Y.size() != F || d.variance.size() != F || stats.var_U.size() != F ||
      stats.cov_YU.size() != F)
    throw InputError("errors_in_variables: sizes of U, Y, variance, var_U, cov_YU differ from F");
  FrfData out;
  out.domain = d.domain;
  const Real M = Real(stats.M);
  int drop = 0;
  for (std::size_t k = 0; k < F; ++k) {
    if (d.U[k].rows() != 1 || d.U[k].cols() != 1 || d.Y[k].rows() != 1 || d.Y[k].cols() != 1 ||
        stats.var_U[k].size() != 1 || stats.cov_YU[k].size() != 1 || d.variance[k].size() != 1)
      throw InputError("errors_in_variables: " + at(k) + ": only SISO (m = p = 1, c = 1) data");
    const Real var_Y = d.variance[k](0, 0) * M;  // σ̂²_Y (data holds σ̂²_Y / M)
    const Real& var_U = stats.var_U[k](0, 0);
    const Complex& cov = stats.cov_YU[k](0, 0);  // E[δY conj δU]
    // Numerator and denominator of the ratio: Y/U, or U/Y for the inverse system.
    const Complex num = o.swap ? d.U[k](0, 0) : d.Y[k](0, 0), den = o.swap ? d.Y[k](0, 0) : d.U[k](0, 0);
    const Real var_num = o.swap ? var_U : var_Y, var_den = o.swap ? var_Y : var_U;
    const Complex cross = o.swap ? std::conj(cov) : cov;  // E[δnum conj δden]
    if (o.min_input_snr == 0 && std::norm(den) == 0)
      throw InputError("errors_in_variables: mean input is zero at " + at(k));
    // Eq. (34): a line whose denominator is not above the noise is left out.
    if (!(std::norm(den) > o.min_input_snr * var_den / M)) {
      ++drop;
      continue;
    }
    const Complex G = num / den;
    // Eq. (31), corrected: |G|²(σ²_num/|num|² + σ²_den/|den|² − 2Re(σ²_nd/(num conj den)));
    // since |G|²/(num conj den) = conj(G)/|den|², this equals the form below (also at
    // num = 0), evaluated at the first-pass model's G when one is given.
    const Complex Gv = o.first_pass ? frequency_response(*o.first_pass, d.omega[k])(0, 0) : G;
    const Real var_G = (var_num + std::norm(Gv) * var_den - 2 * (std::conj(Gv) * cross).real()) / std::norm(den);
    if (!(var_G > 0)) {
      ++drop;
      continue;
    }
    out.omega.push_back(d.omega[k]);
    out.U.push_back(MatrixC::Constant(1, 1, Complex(1)));
    out.Y.push_back(MatrixC::Constant(1, 1, G));
    out.variance.push_back(MatrixR::Constant(1, 1, var_G / M));
  }
  if (dropped) *dropped = drop;
  if (out.omega.empty()) throw InputError("errors_in_variables: every line is below the input SNR rule");
  return out;
}

}  // namespace fdsid::reference
