// Pintelon (2002) frequency-domain subspace identification, double precision.
#include "fdsid/frf_id.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>

#include <boost/math/distributions/chi_squared.hpp>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "numerics/complex.hpp"
#include "numerics/constants.hpp"
#include "numerics/fft.hpp"
#include "numerics/qr.hpp"
#include "numerics/rank.hpp"
#include "numerics/eigen_instances.hpp"
#include "rounding.hpp"

namespace fdsid {

namespace {

using numerics::kUnitRoundoff;
// Largest number of rows r (m + p) of Z that step 1 attempts.
constexpr int kMaxColumns = 4000;


[[noreturn]] void fail(ErrorKind kind, const std::string& where, const std::string& what) {
  throw Error(kind, where, what);
}

// ---------------------------------------------------------------------------
// C (ξI − A)⁻¹ at many ξ. When A is diagonalisable with a well-conditioned
// eigenvector basis V (κ(V) ≤ 100), C(ξI − A)⁻¹ = (C V) diag(1/(ξ − λ)) V⁻¹,
// O(p n²) per ξ with no allocation and an error ≤ κ(V) u relative to the LU
// route; otherwise one partial-pivoting LU of ξI − A per ξ (backward stable).
class Resolvent {
 public:
  Resolvent(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C) : A_(A), C_(C) {
    const Eigen::Index n = A.rows();
    if (n == 0) return;
    Eigen::EigenSolver<Eigen::MatrixXd> es(A);
    if (es.info() != Eigen::Success) return;
    Eigen::MatrixXcd V = es.eigenvectors();
    for (Eigen::Index i = 0; i < n; ++i) V.col(i).normalize();
    Eigen::PartialPivLU<Eigen::MatrixXcd> lu(V);
    const double rc = lu.rcond();
    if (!(rc > 0.01)) return;  // κ₁(V) > 100: use the LU route
    lambda_ = es.eigenvalues();
    CV_ = C.cast<cplx>() * V;
    Vinv_ = lu.inverse();
    diagonal_ = true;
  }
  /// K = C (ξI − A)⁻¹ (p × n). Returns false when ξI − A is singular. The
  /// diagonal route allocates nothing once K has its size (it runs once per
  /// frequency in step 3 and V_SUB: F = 10⁵ spent 12 % in malloc/free).
  bool left(cplx xi, Eigen::MatrixXcd& K) const {
    if (diagonal_) {
      K.setZero(CV_.rows(), CV_.cols());
      return add_modal_sum(xi, Vinv_, K);
    }
    Eigen::MatrixXcd M = -A_.transpose().cast<cplx>();
    M.diagonal().array() += xi;
    Eigen::PartialPivLU<Eigen::MatrixXcd> lu(M);
    K = lu.solve(C_.transpose().cast<cplx>()).transpose();
    return K.allFinite();
  }
  /// The B and D of response().
  void set_input(const Eigen::MatrixXd& B, const Eigen::MatrixXd& D) {
    B_ = B.cast<cplx>();
    D_ = D.cast<cplx>();
    if (diagonal_) VinvB_ = Vinv_ * B_;
  }
  /// G = C (ξI − A)⁻¹ B + D (p × m) for the B and D given to set_input; on the
  /// diagonal route Σ_e (CV)_{:,e} (V⁻¹B)_{e,:} / (ξ − λ_e) without forming
  /// K (O(n p m) per frequency, nothing allocated once G has its size).
  /// Returns false when ξI − A is singular.
  bool response(cplx xi, Eigen::MatrixXcd& G, Eigen::MatrixXcd& K) const {
    G = D_;
    if (A_.rows() == 0) return true;
    if (diagonal_) return add_modal_sum(xi, VinvB_, G);
    if (!left(xi, K)) return false;
    G.noalias() += K * B_;
    return G.allFinite();
  }

 private:
  // out (p × W.cols(), column-major) += Σ_e (CV)_{:,e} W_{e,:} / (ξ − λ_e), W
  // = V⁻¹ (left) or V⁻¹B (response). 1/(ξ − λ_e) as conj/|·|², not
  // std::complex's division (a libgcc call that guards against overflow: a
  // tenth of `reproduce fig1`); |ξ − λ|² underflows only for |ξ − λ| <
  // 1e-154, where ξI − A is singular anyway. False when it is.
  template <class W>
  bool add_modal_sum(cplx xi, const W& w, Eigen::MatrixXcd& out) const {
    const Eigen::Index p = CV_.rows(), n = CV_.cols(), cols = w.cols();
    cplx* o = out.data();
    for (Eigen::Index e = 0; e < n; ++e) {
      const double xr = xi.real() - lambda_(e).real(), xim = xi.imag() - lambda_(e).imag();
      const double x2 = xr * xr + xim * xim;
      const cplx de(xr / x2, -xim / x2);
      if (!(x2 > 0) || !std::isfinite(de.real()) || !std::isfinite(de.imag())) return false;
      for (Eigen::Index a = 0; a < p; ++a) {
        const cplx ce = numerics::multiply(CV_(a, e), de);
        for (Eigen::Index j = 0; j < cols; ++j) o[a + p * j] += numerics::multiply(ce, w(e, j));
      }
    }
    return out.allFinite();
  }

  Eigen::MatrixXd A_, C_;
  bool diagonal_ = false;
  Eigen::VectorXcd lambda_;
  Eigen::MatrixXcd CV_;
  Eigen::Matrix<cplx, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Vinv_;  // rows read by add_modal_sum
  Eigen::MatrixXcd B_, D_, VinvB_;  // set_input's
};

// cond₁(R) = ‖R‖₁ ‖R⁻¹‖₁ of an upper-triangular R (within a factor of its
// size of cond₂; O(n³/3) by one triangular inverse instead of an SVD).
double triangular_condition(const Eigen::MatrixXd& Rfull) {
  const Eigen::Index n = Rfull.rows();
  const Eigen::MatrixXd R = Rfull.triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(n, n));
  return R.cwiseAbs().colwise().sum().maxCoeff() * Rinv.cwiseAbs().colwise().sum().maxCoeff();
}

// ---------------------------------------------------------------------------
// Rows come in groups (one group per frequency): fill(g, rows) writes group
// g's `rows_per_group` rows. R of the whole tall matrix by the streamed QR of
// numerics/qr.hpp (default chunking: 2048 rows per chunk, blocks of ≥ 2^24
// flops, fixed by the dimensions so R does not depend on the core count).
using RowFill = std::function<void(int, Eigen::Ref<Eigen::MatrixXd>)>;

Eigen::MatrixXd tsqr(int groups, int rows_per_group, int cols, const RowFill& fill) {
  return numerics::streamed_qr_r(groups, rows_per_group, cols, [&](int g0, int g1, Eigen::Ref<Eigen::MatrixXd> rows) {
    for (int g = g0; g < g1; ++g) fill(g, rows.middleRows((g - g0) * rows_per_group, rows_per_group));
  });
}

// ---------------------------------------------------------------------------
// The row bases of Algorithm 1/2. Power bases (Algorithm 1, 2.1 and their
// Tustin variants): row i at ξ_k is ξ_k^i, generated where it is used (by
// repeated multiplication, i = 0 … r−1) and never stored — at F = 10⁶, r = 40
// the two r × F tables were 1.3 GB. Orthogonal bases (2.2): column k of Wu
// (Wy) holds the r polynomials at ξ_k for the input (output) rows of Z.
struct Bases {
  Eigen::MatrixXcd Wu, Wy;      // r × F, orthogonal bases only (empty for power bases)
  Eigen::VectorXcd xi;          // ξ_k used in step 3 (z, w or s/ω_s)
  bool orthogonal = false;
  Eigen::MatrixXd H;            // r × (r−1): s̃ q_j = Σ_i H(i, j) q_i (output basis)
  double q0 = 1;                // the constant q_0 of the output basis
  double omega_scale = 1;
  bool tustin = false;          // discrete data in Algorithm 2's bases on s' = j tan(ω/2) (omega_scale in rad/sample)

  // What steps 2-3 read of these bases at r ≤ their own: ξ, H's leading
  // block and the scalars. Wu and Wy (r × F, read by steps 1a-1c only) are
  // left empty. A field added above is copied here or left out on purpose.
  Bases for_steps_2_3(int r) const {
    Bases b;
    b.xi = xi;
    b.orthogonal = orthogonal;
    if (orthogonal) b.H = H.topLeftCorner(r, r - 1);
    b.q0 = q0;
    b.omega_scale = omega_scale;
    b.tustin = tustin;
    return b;
  }
};

double default_scale(const FrfData& d) {
  return std::sqrt(d.omega.minCoeff() * d.omega.maxCoeff());
}

// Row i of the input and output bases at ξ_{k0} … ξ_{k0+n−1}, for i = 0, 1,
// … in turn (next()). Power bases advance by one product per row, w ← w ξ
// from w = 1; orthogonal bases are read from Wu and Wy.
class BasisRow {
 public:
  BasisRow(const Bases& b, Eigen::Index k0, Eigen::Index n) : b_(b), k0_(k0), u_(n), y_(n) { load(); }
  void next() {  // past the last row (i = r) nothing is loaded: the caller's loop has ended
    if (++i_ < rows()) load();
  }
  const Eigen::VectorXcd& u() const { return u_; }
  const Eigen::VectorXcd& y() const { return b_.orthogonal ? y_ : u_; }

 private:
  int rows() const { return b_.orthogonal ? static_cast<int>(b_.Wu.rows()) : std::numeric_limits<int>::max(); }
  void load() {
    const Eigen::Index n = u_.size();
    if (b_.orthogonal) {
      u_ = b_.Wu.row(i_).segment(k0_, n).transpose();
      y_ = b_.Wy.row(i_).segment(k0_, n).transpose();
    } else if (i_ == 0) {
      u_.setOnes();
    } else {
      u_.array() *= b_.xi.segment(k0_, n).array();
    }
  }
  const Bases& b_;
  Eigen::Index k0_;
  int i_ = 0;
  Eigen::VectorXcd u_, y_;
};

// Orthonormal real-coefficient polynomials q_0 … q_{r−1} in s̃ for the real
// inner product ⟨p, q⟩ = Re Σ_k w_k p(s̃_k) conj q(s̃_k), by the Arnoldi
// (Stieltjes) process with full re-orthogonalisation: s̃ q_j = Σ_{i≤j+1} H(i,j) q_i.
// For s̃ on the imaginary axis H is tridiagonal with zero diagonal (Forsythe),
// but the full process costs nothing extra at these r and is robust.
Eigen::MatrixXcd arnoldi_basis(const Eigen::VectorXcd& s, const Eigen::VectorXd& w, int r, Eigen::MatrixXd* H,
                               double* q0) {
  const Eigen::Index F = s.size();
  auto inner = [&](const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
    double acc = 0;
    for (Eigen::Index k = 0; k < F; ++k) acc += w(k) * (a(k) * std::conj(b(k))).real();
    return acc;
  };
  Eigen::MatrixXcd Q(F, r);
  if (H) H->setZero(r, std::max(0, r - 1));
  const double total = w.sum();
  if (!(total > 0)) fail(ErrorKind::Numerical, "step 1a", "orthogonal basis: the weights are all zero");
  Q.col(0).setConstant(1.0 / std::sqrt(total));
  if (q0) *q0 = 1.0 / std::sqrt(total);
  for (int j = 0; j + 1 < r; ++j) {
    Eigen::VectorXcd v = s.cwiseProduct(Q.col(j));
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i <= j; ++i) {
        const double h = inner(v, Q.col(i));
        v -= h * Q.col(i);
        if (H) (*H)(i, j) += h;
      }
    const double nv = std::sqrt(std::max(0.0, inner(v, v)));
    if (!(nv > 0)) fail(ErrorKind::Numerical, "step 1a", "orthogonal basis breaks down at degree " + std::to_string(j + 1));
    if (H) (*H)(j + 1, j) = nv;
    Q.col(j + 1) = v / nv;
  }
  return Q.transpose();
}

Bases make_bases(const FrfData& d, int r, ContinuousMethod method, double omega_scale, DiscreteMethod discrete) {
  Bases b;
  const Eigen::Index F = d.frequencies();
  b.xi.resize(F);
  if (d.domain == Domain::Discrete && discrete == DiscreteMethod::Monomial) {
    for (Eigen::Index k = 0; k < F; ++k) b.xi(k) = std::polar(1.0, d.omega(k));
    return b;
  }
  // Algorithm 2's frequency axis: x_k = ω_k/ω_s (continuous time) or
  // tan(ω_k/2)/t_s, t_s = tan(ω_s/2) (discrete data, Tustin: s' = j tan(ω/2)).
  Eigen::VectorXd x(F);
  if (d.domain == Domain::Discrete) {
    b.tustin = true;
    b.omega_scale = omega_scale > 0 ? omega_scale : default_discrete_scale(d.omega);
    if (!(b.omega_scale > 0 && b.omega_scale < M_PI))
      fail(ErrorKind::Input, "omega_scale", "discrete time: must lie in (0, pi) rad/sample, got " + fmt(b.omega_scale, 6));
    const double ts = std::tan(b.omega_scale / 2);
    if (discrete == DiscreteMethod::Bilinear) {
      // w = (jx − 1)/(jx + 1), written with sin and cos of ω/2 so that ω = π
      // (s' = ∞) gives w = 1.
      for (Eigen::Index k = 0; k < F; ++k) {
        const cplx st(0.0, std::sin(d.omega(k) / 2));
        const double ct = ts * std::cos(d.omega(k) / 2);
        b.xi(k) = (st - ct) / (st + ct);
      }
      return b;
    }
    for (Eigen::Index k = 0; k < F; ++k) {
      if (!(d.omega(k) < M_PI))
        fail(ErrorKind::Input, "omega", "the line at omega = pi maps to s' = tan(omega/2) = infinity, outside the "
                                        "orthogonal bases: drop it, or use --method bilinear");
      x(k) = std::tan(d.omega(k) / 2) / ts;
    }
  } else {
    b.omega_scale = omega_scale > 0 ? omega_scale : default_scale(d);
    if (!(b.omega_scale > 0) || !std::isfinite(b.omega_scale))
      fail(ErrorKind::Input, "omega_scale", "must be positive and finite, got " + fmt(b.omega_scale, 6));
    x = d.omega / b.omega_scale;
  }
  if (d.domain == Domain::Continuous && method == ContinuousMethod::Bilinear) {
    for (Eigen::Index k = 0; k < F; ++k) {
      const cplx st(0.0, x(k));
      b.xi(k) = (st - 1.0) / (st + 1.0);
    }
    return b;
  }
  b.orthogonal = true;
  for (Eigen::Index k = 0; k < F; ++k) b.xi(k) = cplx(0.0, x(k));
  Eigen::VectorXd wu(F), wy(F);
  for (Eigen::Index k = 0; k < F; ++k) {
    wu(k) = d.U[k].squaredNorm();
    wy(k) = d.Y[k].squaredNorm();
  }
  b.Wu = arnoldi_basis(b.xi, wu, r, nullptr, nullptr);
  b.Wy = arnoldi_basis(b.xi, wy, r, &b.H, &b.q0);
  return b;
}

// Step 1 (a-c): returns the whitened SVD and the factor L of C_Y.
struct Step1 {
  Eigen::MatrixXd L;       // C_Y = L Lᵀ
  Eigen::MatrixXd Usvd;    // left singular vectors of L⁻¹ R22ᵀ
  Eigen::VectorXd sigma;   // its singular values
  double r11_condition = 1; // cond₁(R11): conditioning of the input part (Π of Eq. 20)
  double noise_scale = 0;   // ‖L⁻¹‖₁ ‖R‖_F: rounding of the QR of all of Z, whitened
  Eigen::MatrixXd CY;       // C_Y of Eq. (18) (the rounding estimate moves it)
};

// Step 1's size checks.
//
// Purpose: refuse a Z = [𝐔^re; 𝐘^re] of r (m + p) rows and 2 F c columns that
// is too large or too short, before anything is allocated.
// Method: work and memory first: the bases (2 r F complex, orthogonal bases only), the TSQR work
// matrix and R (cols² + 2048·cols doubles per thread), C_Y and the SVD
// (3 ny² doubles), ny = r p.
// Fails: Error(Resource) above kMaxColumns rows or the memory limit,
// Error(Dimension) when Z has fewer columns than rows.
// References: Pintelon (2002) Algorithm 1 step 1.
void step1_check_size(const FrfData& d, const Bases& b, int r) {
  const int F = d.frequencies(), m = d.inputs(), p = d.outputs(), c = d.columns();
  const int ny = r * p, cols = r * m + ny;
  if (cols > kMaxColumns)
    fail(ErrorKind::Resource, "step 1b",
         "r (m + p) = " + std::to_string(cols) + " rows of Z exceed the supported " + std::to_string(kMaxColumns) +
             " (the QR and SVD of step 1 grow as r^3; use a smaller r)");
  require_memory((b.orthogonal ? 32.0 * r * F : 0.0) + 8.0 * (3.0 * cols * cols + 2048.0 * cols) + 24.0 * ny * ny, "identify-frf",
                 "step 1 with F = " + std::to_string(F) + ", r = " + std::to_string(r));
  if (2LL * F * c < cols)
    fail(ErrorKind::Dimension, "step 1b",
         "2 F c = " + std::to_string(2LL * F * c) + " real columns of Z are fewer than its r (m + p) = " +
             std::to_string(cols) + " rows: more frequencies or a smaller r (r = " + std::to_string(r) + ")");
}

// Where the data lie, for the messages of step 1 (review finding 13: a basis
// numerically dependent on a narrow band was reported as "variances too
// small"): the band and what to do about it.
std::string band_advice(const FrfData& d, const Bases& b, int r) {
  const double lo = d.omega.minCoeff(), hi = d.omega.maxCoeff();
  if (d.domain == Domain::Discrete && !b.tustin)
    return "the excited band omega = " + fmt(lo, 3) + " ... " + fmt(hi, 3) + " rad/sample covers " +
           fmt(100 * (hi - lo) / M_PI, 3) + " % of [0, pi], on which r = " + std::to_string(r) +
           " powers of z are numerically dependent; use a lower --r, or --method bilinear (a basis spread over the "
           "band), or --domain continuous with the frequencies in rad/s";
  if (d.domain == Domain::Discrete)
    return "the excited band omega = " + fmt(lo, 3) + " ... " + fmt(hi, 3) + " rad/sample, on the Tustin axis tan(omega/2) " +
           "a factor " + fmt(std::tan(hi / 2) / std::tan(std::max(lo, 1e-300) / 2), 3) + ", still makes r = " +
           std::to_string(r) + " basis functions numerically dependent; use a lower --r" +
           (b.orthogonal ? "" : ", or --method orthogonal");
  return "the band omega = " + fmt(lo, 3) + " ... " + fmt(hi, 3) + " rad/s spans a factor " + fmt(hi / lo, 3) +
         ", on which r = " + std::to_string(r) + " basis functions are numerically dependent; use a lower --r, or "
         "the other --method";
}

// The order of Zᵀ's columns. Blocked: Eqs. (9), (18)'s [𝐔^re; 𝐘^re], basis
// row i and input a in column i m + a, output a in r m + i p + a — what steps
// 1b-1c read (R11 and R22). Interleaved: basis row i's m inputs and p outputs
// together, columns i (m + p) + a and i (m + p) + m + a; the r search's
// order, in which Zᵀ at r is the first r (m + p) columns of Zᵀ at any larger
// r (the bases are nested in r: powers, and the Arnoldi polynomials q_0 …
// q_{r−1} do not depend on how many follow).
enum class ColumnOrder { Blocked, Interleaved };

// R of the QR of Zᵀ (r (m+p) square, upper triangular) with its columns in
// `order`. The chunk is filled column by column (basis row i, channel a), each column
// a contiguous run of the column-major work matrix: filled row by row it was
// 80 strided writes per row at r = 40 (a fifth of step 1 at F = 999).
Eigen::MatrixXd step1ab_r(const FrfData& d, const Bases& b, int r, ColumnOrder order) {
  const int F = d.frequencies(), m = d.inputs(), p = d.outputs(), c = d.columns();
  const int nu = r * m, ny = r * p, cols = nu + ny;
  const bool blocked = order == ColumnOrder::Blocked;
  // Group k's rows 2j, 2j + 1: Re and Im of column j; in column (i, a):
  // W_i(ξ_k) U_k(a, j) (input block) or W_i(ξ_k) Y_k(a, j) (output block).
  const auto column = [&](const ComplexMatrixStack& X, const Eigen::VectorXcd& w, int a, int g0, double* out) {
    for (Eigen::Index k = 0; k < w.size(); ++k)
      for (int j = 0; j < c; ++j, out += 2) {
        const cplx v = w(k) * X(g0 + k, a, j);
        out[0] = v.real();
        out[1] = v.imag();
      }
  };
  const numerics::ChunkFill fill = [&](int g0, int g1, Eigen::Ref<Eigen::MatrixXd> rows) {
    BasisRow w(b, g0, g1 - g0);
    for (int i = 0; i < r; ++i, w.next()) {
      const int u0 = blocked ? i * m : i * (m + p), y0 = blocked ? nu + i * p : i * (m + p) + m;
      for (int a = 0; a < m; ++a) column(d.U, w.u(), a, g0, rows.col(u0 + a).data());
      for (int a = 0; a < p; ++a) column(d.Y, w.y(), a, g0, rows.col(y0 + a).data());
    }
  };
  return numerics::streamed_qr_r(F, 2 * c, cols, fill);
}

// Assumption 3 on step 1b's R (blocked columns; R11 = its first r m rows and
// columns), as step1ab_qr checks it.
void check_input_excitation(const FrfData& d, const Bases& b, const Eigen::MatrixXd& R, int r) {
  const int nu = r * d.inputs();
  const Eigen::VectorXd r11 = R.topLeftCorner(nu, nu).diagonal().cwiseAbs();
  const double r11max = r11.maxCoeff();
  if (!numerics::numerically_full_rank(r11, std::sqrt(2.0 * d.frequencies() * d.columns()))) {
    const std::string ratio = r11max > 0 ? fmt(r11.minCoeff() / r11max, 3)
                                         : "0 / 0: R11 is zero, the input zero or so small that its squares underflow";
    fail(ErrorKind::Numerical, "step 1b",
         "the input data matrix U^re is rank deficient (min |R11_ii| / max = " + ratio +
             "): the input does not excite r = " + std::to_string(r) +
             " basis functions (Pintelon 2002 Assumption 3): " + band_advice(d, b, r) + ", or excite more lines");
  }
}

// Steps 1a-1b: R of the QR of Zᵀ.
//
// Purpose: the upper-triangular R (r (m+p) square) of Zᵀ = Q R, with the
// input block R11 (r m square) checked for persistence of excitation.
// Method: rows of Zᵀ for frequency k, column j: Re and Im of
// [W_u(k) ⊗ U_j(k); W_y(k) ⊗ Y_j(k)] (Eqs. 9, 11, 18), streamed into the TSQR.
// Numerical aspects: Assumption 3 (persistence of excitation): R11 must be
// non-singular. Its diagonal is |R11_ii|; rank deficiency shows as a diagonal
// entry at the rounding level, 100 · u · √(rows) · max |R11_ii| (Householder
// backward error; numerics/rank.hpp), rows = 2 F c.
// Fails: Error(Numerical) when 𝐔^re is rank deficient.
// References: Pintelon (2002) Eqs. (9), (11), (18), Assumption 3.
Eigen::MatrixXd step1ab_qr(const FrfData& d, const Bases& b, int r) {
  Eigen::MatrixXd R = step1ab_r(d, b, r, ColumnOrder::Blocked);
  check_input_excitation(d, b, R, r);
  return R;
}

// Step 1c, first half: the noise covariance C_Y of the output rows of Z.
//
// Purpose: C_Y (r p square) = Σ Re((W_y W_yᴴ) ⊗ diag σ²): entry
// ((i,a),(i',a')) is δ_{aa'} Σ_{k,j} Re(W_i conj W_i') σ²_a(k, j).
// Method: one r x r block per output a. Power bases on the unit circle
// (ξ = z or w, |ξ| = 1): Re(ξ^i conj ξ^i') = Re ξ^{i−i'}, so the block is the
// symmetric Toeplitz matrix t(|i − i'|) with t(δ) = Σ_k σ²_k Re ξ_k^δ —
// O(F r), not O(F r²); orthogonal bases: the lower triangle summed directly.
// Fails: never.
// References: Pintelon (2002) Eq. (18).
Eigen::MatrixXd step1c_noise_covariance(const FrfData& d, const Bases& b, int r) {
  const int F = d.frequencies(), p = d.outputs(), ny = r * p;
  Eigen::MatrixXd CY = Eigen::MatrixXd::Zero(ny, ny);
  for (int a = 0; a < p; ++a) {
    Eigen::MatrixXd block = Eigen::MatrixXd::Zero(r, r);
    if (!b.orthogonal) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(r);
      for (int k = 0; k < F; ++k) {
        const double s2 = d.variance[k].row(a).sum();
        cplx v = 1;  // ξ_k^i, as BasisRow generates it
        for (int i = 0; i < r; ++i, v *= b.xi(k)) t(i) += s2 * v.real();
      }
      for (int i = 0; i < r; ++i)
        for (int i2 = 0; i2 < r; ++i2) block(i, i2) = t(std::abs(i - i2));
    } else {
      for (int k = 0; k < F; ++k) {
        const double s2 = d.variance[k].row(a).sum();
        for (int i = 0; i < r; ++i)
          for (int i2 = 0; i2 <= i; ++i2) block(i, i2) += s2 * (b.Wy(i, k) * std::conj(b.Wy(i2, k))).real();
      }
      block.triangularView<Eigen::StrictlyUpper>() = block.transpose();
    }
    for (int i = 0; i < r; ++i)
      for (int i2 = 0; i2 < r; ++i2) CY(i * p + a, i2 * p + a) = block(i, i2);
  }
  return CY;
}

// Step 1c, second half: the whitened SVD.
//
// Purpose: C_Y = L Lᵀ and the SVD of L⁻¹ R22ᵀ (R22 the output block of R).
// Method: Cholesky (Eigen::LLT), a triangular solve, Jacobi SVD (full U).
// Numerical aspects: the QR of step 1b is backward stable for all of Zᵀ: R22
// carries an error ~u‖Z‖ = u‖R‖_F however small R22 is (a weak dynamic part
// beside a large feedthrough D U), and whitening multiplies it by at most
// ‖L⁻¹‖; noise_scale = ‖L⁻¹‖₁ ‖R‖_F records it.
// Fails: Error(Numerical) when C_Y is not positive definite.
// References: Pintelon (2002) Algorithm 1 step 1c.
Step1 step1c_whitened_svd(const Eigen::MatrixXd& CY, const Eigen::MatrixXd& R, int r, const FrfData& d,
                          const Bases& b) {
  const Eigen::Index ny = CY.rows();
  const Eigen::MatrixXd R22t = R.bottomRightCorner(ny, ny).transpose();
  Step1 s;
  Eigen::LLT<Eigen::MatrixXd> llt(CY);
  if (llt.info() != Eigen::Success)
    fail(ErrorKind::Numerical, "step 1c",
         "C_Y = sum of sigma^2 W W^H (Eq. 18) is not positive definite: " + band_advice(d, b, r) +
             " (or the variances are zero or tiny: the FRF file's G_var column, or records that repeat from period "
             "to period)");  // records have no G_var column (review finding 7 of stop 47)
  s.L = llt.matrixL();
  const Eigen::MatrixXd K = s.L.triangularView<Eigen::Lower>().solve(R22t);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(K, Eigen::ComputeFullU);
  s.Usvd = svd.matrixU();
  s.sigma = svd.singularValues();
  const Eigen::MatrixXd Linv = s.L.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(ny, ny));
  s.noise_scale = Linv.cwiseAbs().colwise().sum().maxCoeff() * R.norm();
  return s;
}

// Step 1c on R of step 1b and C_Y of d's variances: the whitened SVD.
Step1 step1c(const FrfData& d, const Bases& b, const Eigen::MatrixXd& R, Eigen::MatrixXd CY, int r) {
  const int nu = r * d.inputs();
  const double r11_cond = triangular_condition(R.topLeftCorner(nu, nu));
  Step1 s = step1c_whitened_svd(CY, R, r, d, b);
  s.CY = std::move(CY);
  s.r11_condition = r11_cond;
  return s;
}

// Step 1 (a-c) on bases checked at r (checked_bases): R of Zᵀ (1a-1b), C_Y
// and the whitened SVD (1c).
Step1 step1(const FrfData& d, const Bases& b, int r) {
  return step1c(d, b, step1ab_qr(d, b, r), step1c_noise_covariance(d, b, r), r);
}

// Step 3, Eq. (17): (B, D) minimising Σ |Y − (C(ξI − A)⁻¹B + D)U|² / σ²
// as a real linear least-squares problem (Re and Im rows stacked).
void step3(const FrfData& d, const Bases& b, const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, Eigen::MatrixXd& B,
           Eigen::MatrixXd& D, double* condition = nullptr) {
  const int F = d.frequencies(), m = d.inputs(), p = d.outputs(), c = d.columns();
  const int n = static_cast<int>(A.rows());
  const int nb = n * m, nd = p * m, cols = nb + nd + 1;  // last column: right-hand side
  if (2LL * F * c * p < nb + nd)
    fail(ErrorKind::Dimension, "step 3",
         "2 F c p = " + std::to_string(2LL * F * c * p) + " equations for " + std::to_string(nb + nd) +
             " unknowns of B and D");
  // K_k = C (ξ_k I − A)⁻¹ (p × n), computed as the rows are filled (a
  // table of F of them was F small allocations). A singular ξ_k I − A leaves
  // its rows zero and is reported, the lowest such k, after the QR.
  const Resolvent res(A, C);
  std::atomic<int> singular{F};
  const RowFill fill = [&](int k, Eigen::Ref<Eigen::MatrixXd> rows) {
    thread_local Eigen::MatrixXcd K;
    rows.setZero();
    if (!res.left(b.xi(k), K)) {
      for (int s = singular.load(); k < s && !singular.compare_exchange_weak(s, k);) {
      }
      return;
    }
    int row = 0;
    for (int j = 0; j < c; ++j)
      for (int a = 0; a < p; ++a, row += 2) {
        const double wgt = 1.0 / std::sqrt(d.variance(k, a, j));
        // Coefficient of B(e, f) (column-major index e + n f): K(a, e) U(f, j).
        for (int f = 0; f < m; ++f) {
          const cplx u = d.U(k, f, j);
          for (int e = 0; e < n; ++e) {
            const cplx v = wgt * numerics::multiply(K(a, e), u);
            rows(row, e + n * f) = v.real();
            rows(row + 1, e + n * f) = v.imag();
          }
          // Coefficient of D(a, f) (column-major a + p f): U(f, j).
          const cplx v = wgt * u;
          rows(row, nb + a + p * f) = v.real();
          rows(row + 1, nb + a + p * f) = v.imag();
        }
        const cplx y = wgt * d.Y(k, a, j);
        rows(row, cols - 1) = y.real();
        rows(row + 1, cols - 1) = y.imag();
      }
  };
  const Eigen::MatrixXd R = tsqr(F, 2 * c * p, cols, fill);
  if (const int k = singular.load(); k < F)
    fail(ErrorKind::Numerical, "step 3", "ξ_k I − A is singular at frequency index " + std::to_string(k + 1) +
                                             " (a pole of the estimate lies on the data's frequency axis)");
  const Eigen::MatrixXd R1 = R.topLeftCorner(nb + nd, nb + nd);
  const Eigen::VectorXd rhs = R.topRightCorner(nb + nd, 1);
  // Rank check as in step 1b (Assumption 5 (ii): a unique minimiser).
  const Eigen::VectorXd diag = R1.diagonal().cwiseAbs();
  if (!numerics::numerically_full_rank(diag, std::sqrt(2.0 * F * c * p)))
    fail(ErrorKind::Numerical, "step 3", "B and D are not determined by the data (Eq. 17 is rank deficient, "
                                         "Pintelon 2002 Assumption 5 (ii))");
  const Eigen::VectorXd theta = R1.triangularView<Eigen::Upper>().solve(rhs);
  if (condition) *condition = triangular_condition(R1);
  B = Eigen::Map<const Eigen::MatrixXd>(theta.data(), n, m);
  D = Eigen::Map<const Eigen::MatrixXd>(theta.data() + nb, p, m);
}

// Refuses an r whose bases (2 r F complex) or step 1 would be too large.
// Only the orthogonal bases (Algorithm 2.2, continuous or on the Tustin axis)
// are stored; the power bases are generated where they are used.
bool stored_bases(Domain domain, ContinuousMethod continuous, DiscreteMethod discrete) {
  return domain == Domain::Continuous ? continuous == ContinuousMethod::Orthogonal
                                      : discrete == DiscreteMethod::Orthogonal;
}

void check_r_size(const FrfData& d, int r, bool stored) {
  const long long cols = static_cast<long long>(r) * (d.inputs() + d.outputs());
  if (cols > kMaxColumns)
    fail(ErrorKind::Resource, "r", "r (m + p) = " + std::to_string(cols) + " exceeds the supported " +
                                       std::to_string(kMaxColumns) + " (step 1 grows as r^3)");
  if (stored)
    require_memory(32.0 * r * d.frequencies(), "identify-frf", "the r = " + std::to_string(r) + " bases at " +
                                                                    std::to_string(d.frequencies()) + " frequencies");
}

// Step 1's bases at r, checked: their own memory before they are made, Z's
// size and memory after (step1_check_size).
Bases checked_bases(const FrfData& d, int r, ContinuousMethod continuous, double omega_scale, DiscreteMethod discrete) {
  check_r_size(d, r, stored_bases(d.domain, continuous, discrete));
  Bases b = make_bases(d, r, continuous, omega_scale, discrete);
  step1_check_size(d, b, r);
  return b;
}

int check_order_r(const FrfData& d, int order, int r) {
  if (order < 1) fail(ErrorKind::Order, "order", "n_a must be at least 1, got " + std::to_string(order));
  if (r <= order)
    fail(ErrorKind::Dimension, "r", "r = " + std::to_string(r) + " must exceed the order n_a = " +
                                        std::to_string(order) + " (Pintelon 2002 step 1a)");
  if (order > r * d.outputs())
    fail(ErrorKind::Dimension, "r", "order " + std::to_string(order) + " exceeds r p = " +
                                        std::to_string(r * d.outputs()));
  return r;
}

}  // namespace

const NameTable<ContinuousMethod>& continuous_method_names() {
  static const NameTable<ContinuousMethod> names{{"bilinear", ContinuousMethod::Bilinear},
                                                 {"orthogonal", ContinuousMethod::Orthogonal}};
  return names;
}

const NameTable<DiscreteMethod>& discrete_method_names() {
  static const NameTable<DiscreteMethod> names{{"monomial", DiscreteMethod::Monomial},
                                               {"bilinear", DiscreteMethod::Bilinear},
                                               {"orthogonal", DiscreteMethod::Orthogonal}};
  return names;
}

const char* to_string(ContinuousMethod m) { return name_of(continuous_method_names(), m); }
const char* to_string(DiscreteMethod m) { return name_of(discrete_method_names(), m); }

double default_discrete_scale(const Eigen::VectorXd& omega) {
  double lo = M_PI, hi = 0;
  for (Eigen::Index k = 0; k < omega.size(); ++k)
    if (omega(k) > 0 && omega(k) < M_PI) {
      lo = std::min(lo, omega(k));
      hi = std::max(hi, omega(k));
    }
  if (!(hi > 0)) return M_PI / 2;
  return 2 * std::atan(std::sqrt(std::tan(lo / 2) * std::tan(hi / 2)));
}

FrfData frf_data(Domain domain, const Eigen::VectorXd& omega, const std::vector<Eigen::MatrixXcd>& G,
                 const std::vector<Eigen::MatrixXd>& variance) {
  return frf_data(domain, omega, ComplexMatrixStack(G), RealMatrixStack(variance));
}

FrfData frf_data(Domain domain, const Eigen::VectorXd& omega, ComplexMatrixStack G, RealMatrixStack variance) {
  FrfData d;
  d.domain = domain;
  d.omega = omega;
  d.has_noise_model = !variance.empty();
  const Eigen::Index F = G.size(), p = G.rows(), m = G.cols();
  if (variance.empty()) {
    variance.resize(F, p, m);
    for (Eigen::Index k = 0; k < F; ++k) variance[k].setOnes();
  }
  d.U.resize(F, m, m);
  for (Eigen::Index k = 0; k < F; ++k) d.U[k].setIdentity();
  d.Y = std::move(G);
  d.variance = std::move(variance);
  return d;
}

void validate(const FrfData& d, const std::string& where) {
  const int F = d.frequencies();
  if (F < 1) fail(ErrorKind::Input, where, "no frequencies");
  if (static_cast<int>(d.U.size()) != F || static_cast<int>(d.Y.size()) != F ||
      static_cast<int>(d.variance.size()) != F)
    fail(ErrorKind::Input, where, "U, Y and variance must have one entry per frequency (" + std::to_string(F) + ")");
  const int m = d.inputs(), p = d.outputs(), c = d.columns();
  if (m < 1 || p < 1 || c < 1) fail(ErrorKind::Input, where, "needs at least one input, output and column");
  if (d.Y.cols() != c || d.variance.rows() != p || d.variance.cols() != c)
    fail(ErrorKind::Input, where, "inconsistent shapes of U (m x c), Y and variance (p x c)");
  if (d.domain == Domain::Discrete && (!(d.sample_time > 0) || !std::isfinite(d.sample_time)))
    fail(ErrorKind::Input, where, "sample time must be positive and finite, got " + fmt(d.sample_time, 6));
  bool increasing = true;  // the usual grid: no sort needed for the repeat check
  for (int k = 0; k < F; ++k) {
    const auto at_k = [&] { return where + " frequency " + std::to_string(k + 1); };
    const double w = d.omega(k);
    if (!std::isfinite(w)) fail(ErrorKind::Input, at_k(), "omega is not finite");
    if (d.domain == Domain::Discrete && (w < 0 || w > M_PI))
      fail(ErrorKind::Grid, at_k(), "omega = " + fmt(w, 6) + " rad/sample is outside [0, pi]");
    if (d.domain == Domain::Continuous && !(w > 0))
      fail(ErrorKind::Grid, at_k(), "omega = " + fmt(w, 6) + " rad/s must be positive for continuous time");
    if (k > 0 && !(w > d.omega(k - 1))) increasing = false;
    if (!d.U[k].allFinite()) fail(ErrorKind::Input, at_k(), "input is NaN or Inf");
    if (!d.Y[k].allFinite()) fail(ErrorKind::Input, at_k(), "output (FRF) is NaN or Inf");
    for (int a = 0; a < p; ++a)
      for (int j = 0; j < c; ++j) {
        const double v = d.variance(k, a, j);
        if (!(v > 0) || !std::isfinite(v))
          fail(ErrorKind::Input, at_k(), "variance " + fmt(v, 6) + " must be positive and finite");
      }
  }
  if (increasing) return;
  std::vector<std::pair<double, int>> sorted;
  for (int k = 0; k < F; ++k) sorted.emplace_back(d.omega(k), k);
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i].first == sorted[i - 1].first)
      fail(ErrorKind::Grid, where + " frequency " + std::to_string(sorted[i].second + 1),
           "omega = " + fmt(sorted[i].first, 17) + " repeats frequency " + std::to_string(sorted[i - 1].second + 1));
}

StateSpace fit_input_matrices(const FrfData& data, const Eigen::MatrixXd& A, const Eigen::MatrixXd& C) {
  validate(data);
  if (A.rows() != A.cols() || C.cols() != A.rows() || C.rows() != data.outputs())
    fail(ErrorKind::Input, "fit_input_matrices", "A must be n x n and C p x n");
  Bases b;
  b.xi.resize(data.frequencies());
  for (int k = 0; k < data.frequencies(); ++k)
    b.xi(k) = data.domain == Domain::Discrete ? std::polar(1.0, data.omega(k)) : cplx(0.0, data.omega(k));
  StateSpace m;
  m.domain = data.domain;
  m.sample_time = data.domain == Domain::Discrete ? data.sample_time : 0.0;  // as identify_frf's
  m.A = A;
  m.C = C;
  step3(data, b, A, C, m.B, m.D);
  return m;
}

Eigen::MatrixXcd frequency_response(const StateSpace& model, double omega) {
  return transfer(model, model.domain == Domain::Discrete ? std::polar(1.0, omega) : cplx(0.0, omega));
}

namespace {

// G(ξ) = C (ξI − A)⁻¹ B + D at ω, one frequency after another, into G
// (allocation-free once G and the work have their sizes); G is infinite where
// ξI − A is singular.
class ResponseAt {
 public:
  explicit ResponseAt(const StateSpace& model) : discrete_(model.domain == Domain::Discrete), res_(model.A, model.C) {
    res_.set_input(model.B, model.D);
  }
  void operator()(double omega, Eigen::MatrixXcd& G) {
    const cplx xi = discrete_ ? std::polar(1.0, omega) : cplx(0.0, omega);
    if (!res_.response(xi, G, K_)) G.setConstant(cplx(std::numeric_limits<double>::infinity(), 0.0));
  }

 private:
  bool discrete_;
  Resolvent res_;
  Eigen::MatrixXcd K_;
};

}  // namespace

std::vector<Eigen::MatrixXcd> frequency_response(const StateSpace& model, const Eigen::VectorXd& omega) {
  std::vector<Eigen::MatrixXcd> G(omega.size());
  ResponseAt response(model);
  for (Eigen::Index k = 0; k < omega.size(); ++k) response(omega(k), G[k]);
  return G;
}

Eigen::VectorXcd frequency_response(const StateSpace& model, const Eigen::VectorXd& omega, int output, int input) {
  if (output < 0 || output >= model.outputs() || input < 0 || input >= model.inputs())
    fail(ErrorKind::Input, "frequency_response", "no entry (" + std::to_string(output) + ", " + std::to_string(input) +
                                                     ") in a " + std::to_string(model.outputs()) + " x " +
                                                     std::to_string(model.inputs()) + " model");
  Eigen::VectorXcd g(omega.size());
  ResponseAt response(model);
  Eigen::MatrixXcd G;
  for (Eigen::Index k = 0; k < omega.size(); ++k) {
    response(omega(k), G);
    g(k) = G(output, input);
  }
  return g;
}

namespace {
// Visits the weighted residuals |Y − G U|²/σ² of frequency k as a p × c array.
// Written as loops over the entries (numerics::multiply, no product
// dispatch per frequency): 4 % of BM_IdentifyFrf at r = 8 and of the r
// search, F = 999 and 10⁵ (stop 66, the two builds alternated).
template <class Visit>
void for_each_weighted_residual(const StateSpace& model, const FrfData& d, Visit visit) {
  ResponseAt response(model);
  const int p = d.outputs(), m = d.inputs(), c = d.columns();
  Eigen::MatrixXcd G;
  Eigen::ArrayXXd t(p, c);
  for (int k = 0; k < d.frequencies(); ++k) {
    response(d.omega(k), G);
    for (int j = 0; j < c; ++j)
      for (int a = 0; a < p; ++a) {
        cplx e = d.Y(k, a, j);
        for (int f = 0; f < m; ++f) e -= numerics::multiply(G(a, f), d.U(k, f, j));
        // NaN only where G is infinite (ξI − A singular; the data are finite):
        // an infinite residual, so that no comparison of V_SUB prefers it.
        const double e2 = std::norm(e);
        t(a, j) = (std::isnan(e2) ? std::numeric_limits<double>::infinity() : e2) / d.variance(k, a, j);
      }
    visit(k, t);
  }
}
}  // namespace

double v_sub(const StateSpace& model, const FrfData& d) {
  double v = 0;
  for_each_weighted_residual(model, d, [&v](int, const Eigen::ArrayXXd& t) { v += t.sum(); });
  return v;
}

Eigen::VectorXd v_sub_terms(const StateSpace& model, const FrfData& d) {
  const Eigen::Index block = static_cast<Eigen::Index>(d.outputs()) * d.columns();
  Eigen::VectorXd terms(d.frequencies() * block);
  for_each_weighted_residual(model, d, [&](int k, const Eigen::ArrayXXd& t) {
    terms.segment(k * block, block) = Eigen::Map<const Eigen::VectorXd>(t.data(), block);
  });
  return terms;
}

StateSpace bilinear_to_continuous(const StateSpace& w, double omega_scale) {
  const int n = w.order();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  Eigen::PartialPivLU<Eigen::MatrixXd> lu(I - w.A);
  // Condition of I − A_w: a w-domain pole near w = 1 is a continuous pole near
  // s = ∞; refuse when it is singular to working precision.
  const double rcond = lu.rcond();
  if (!(rcond > numerics::kMinRcond))  // 10·u, numerics/rank.hpp
    fail(ErrorKind::Numerical, "bilinear back-transformation",
         "I - A_w is singular (reciprocal condition " + fmt(rcond, 3) +
             "): the estimate has a pole at s = infinity; try another omega_scale");
  const Eigen::MatrixXd IAinvB = lu.solve(w.B);
  const Eigen::MatrixXd CIAinv = w.C * lu.inverse();
  StateSpace c;
  c.domain = Domain::Continuous;
  c.sample_time = 0;  // a continuous-time model has no sample period (identify_frf)
  c.A = omega_scale * lu.solve(I + w.A);
  c.B = omega_scale * std::sqrt(2.0) * IAinvB;
  c.C = std::sqrt(2.0) * CIAinv;
  c.D = w.D + w.C * IAinvB;
  return c;
}

StateSpace tustin_to_discrete(const StateSpace& s) {
  StateSpace z;
  try {
    z = bilinear_to_continuous(s, 1.0);
  } catch (const Error&) {
    fail(ErrorKind::Numerical, "Tustin back-transformation",
         "I - A' is singular: the estimate has a pole at z = infinity; try another omega_scale or --method monomial");
  }
  z.domain = Domain::Discrete;
  z.sample_time = 1.0;
  return z;
}

StateSpace bilinear_to_discrete(const StateSpace& w, double omega_scale) {
  StateSpace s;
  try {
    s = bilinear_to_continuous(w, std::tan(omega_scale / 2));
  } catch (const Error&) {
    fail(ErrorKind::Numerical, "bilinear back-transformation",
         "I - A_w is singular: the estimate has a pole at w = 1 (z = -1); try another omega_scale or --method monomial");
  }
  return tustin_to_discrete(s);
}

Eigen::VectorXd frf_singular_values(const FrfData& data, int r, ContinuousMethod continuous, double omega_scale,
                                    DiscreteMethod discrete) {
  validate(data);
  if (r < 2) fail(ErrorKind::Dimension, "r", "r must be at least 2, got " + std::to_string(r));
  return step1(data, checked_bases(data, r, continuous, omega_scale, discrete), r).sigma;
}

// The warning for an unstable estimate, or "" (issue 14: identify-frf said
// nothing; unstable_poles_text names them). The subspace estimate
// interpolates the data and does not enforce stability, so this is a
// property of the result, not an error.
std::string instability_warning(Domain domain, const Eigen::VectorXcd& poles) {
  const std::string unstable = unstable_poles_text(domain, poles);
  if (unstable.empty()) return "";
  return "the identified model is unstable: " + unstable +
         "; it fits the data's frequency response but must not be simulated: try another --order or --r";
}

namespace {

// Steps 2 and 3 on an extended observability matrix Ô (r p × n): the
// estimate in the variable of the bases (ξ), before any back-transformation.
// top_sv: the singular values of Ô[1:r−1] (step 2's conditioning).
StateSpace steps_2_3(const FrfData& d, const Bases& b, const Eigen::MatrixXd& O, int n, int r,
                     Eigen::VectorXd* top_sv = nullptr, double* step3_condition = nullptr) {
  const int p = d.outputs();
  // Step 2, Eq. (19): Ô[1:r−1] A = Ô[2:r] (power bases) or the generalised
  // shift Ô_⊥[0:r−2] A = (Hᵀ ⊗ I_p) Ô_⊥ (orthogonal bases: row block i is
  // C q_i(A), and s̃ q_j(s̃) = Σ_i H(i, j) q_i(s̃) holds for A as for s̃).
  const Eigen::MatrixXd top = O.topRows((r - 1) * p);
  Eigen::MatrixXd rhs;
  if (b.orthogonal) {
    rhs = Eigen::MatrixXd::Zero((r - 1) * p, n);
    for (int j = 0; j + 1 < r; ++j)
      for (int i = 0; i <= j + 1; ++i)
        if (b.H(i, j) != 0) rhs.middleRows(j * p, p) += b.H(i, j) * O.middleRows(i * p, p);
  } else {
    rhs = O.bottomRows((r - 1) * p);
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(top);
  if (top_sv) *top_sv = Eigen::JacobiSVD<Eigen::MatrixXd>(top).singularValues();
  if (qr.rank() < n)
    fail(ErrorKind::Numerical, "step 2", "the shifted observability matrix has rank " + std::to_string(qr.rank()) +
                                             " < n_a = " + std::to_string(n));
  StateSpace est;
  est.domain = Domain::Discrete;
  est.sample_time = d.sample_time;
  est.A = qr.solve(rhs);
  est.C = O.topRows(p) / (b.orthogonal ? b.q0 : 1.0);
  step3(d, b, est.A, est.C, est.B, est.D, step3_condition);
  if (!est.A.allFinite() || !est.B.allFinite() || !est.C.allFinite() || !est.D.allFinite())
    fail(ErrorKind::Numerical, "step 3", "the estimate is not finite");
  return est;
}

// The estimate of steps 2-3 in the data's domain: Algorithm 2's
// back-transformation (continuous time), or the Tustin one (discrete data on
// the bilinear or orthogonal bases).
StateSpace in_data_domain(StateSpace est, const FrfData& d, const Bases& b) {
  if (d.domain == Domain::Continuous) {
    // sample_time 0: a continuous-time model has no sample period, whatever
    // the data's (rad/s from an FRF file, or records at meta's Ts) — the
    // value the 50-digit reference writes; 1.0 here read as "sampled at 1 s".
    est.sample_time = 0;
    if (b.orthogonal) {
      est.domain = Domain::Continuous;
      est.A *= b.omega_scale;
      est.B *= b.omega_scale;
    } else {
      est = bilinear_to_continuous(est, b.omega_scale);
    }
  } else if (b.tustin) {
    if (b.orthogonal) {  // s̃ = s'/t_s → s', then z
      const double ts = std::tan(b.omega_scale / 2);
      est.A *= ts;
      est.B *= ts;
      est = tustin_to_discrete(est);
    } else {
      est = bilinear_to_discrete(est, b.omega_scale);
    }
    est.sample_time = d.sample_time;
  }
  return est;
}

// Purpose: the relative rounding error of what the estimate is used for — Ĝ
// on the data's frequencies and the poles — rather than of Â's entries, which
// depend on the basis the subspace happens to fix (review finding 2 of stop
// 48: the F-16 at order 10 had "UNUSABLE", estimate 13.8 for A's entries,
// while its G differed from the 50-digit estimate's by 0.33 % RMS and its
// poles by 3.4e-4).
// Method: statistical condition estimation (Kenney & Laub, SIAM J. Sci.
// Comput. 15 (1994) 36–61): the inputs of step 1c are moved by random
// perturbations of their rounding's size, steps 1c-3 and the back-
// transformation rerun, and the largest relative change over
// kRoundingSamples draws is kept.
//  - R: step 1b's Householder QR (TSQR: a tree of them) is columnwise
//    backward stable (Higham, Accuracy and Stability, 2nd ed., Thm 19.4): R̂
//    is the exact R of Zᵀ + ΔZ with ‖ΔZ(:, j)‖ ≤ γ ‖Zᵀ(:, j)‖ = γ ‖R(:, j)‖
//    (one basis function's row of Z per column). Each column of R moves by a
//    random vector of norm γ ‖R(:, j)‖, γ = u √(2 F c) (rounding errors that
//    add up as a random walk over a column's 2 F c entries, not the worst
//    case ~2Fc·u), and R is re-triangularised.
//  - C_Y: each entry is a sum over the F frequencies of σ² Re(w_i w̄_j),
//    whose absolute terms add up to at most √(C_ii C_jj) (Cauchy–Schwarz);
//    the sum's rounding (random walk: u √F of that) and the Cholesky
//    factorisation's backward error (|ΔC| ≤ γ |L||Lᵀ|, again ≤ √(C_ii C_jj)
//    entrywise) move C_ij by u √F √(C_ii C_jj) × a standard normal. An
//    ill-conditioned C_Y (many basis functions on a narrow band) reweights
//    step 1c by far more than its entries move: the F-16's order-10 estimate
//    at r = 48 differs from the 50-digit one mainly through it (moving R
//    alone gave 6e-9, the distance is 3.3e-3).
// Changes are measured by RoundingEffect (rounding.hpp): G on the data's
// frequencies and each pole; a pole that moves by its own size or more is
// "set by rounding" (an order above what the data determine leaves such
// poles beside a G that is right to the last digits). A moved estimate that
// fails (C_Y not positive definite, step 2 rank deficient) makes both
// infinite: rounding alone decides whether there is an estimate. Steps 2-3
// are backward stable; their rounding perturbs Ô by ~u relative, inside
// these moves. An estimate of the typical error, not a bound; measured
// against the 50-digit reference on the F-16 (orders 10 at r = 30, 48: 5-20
// times the distance) and in the tests.
RoundingEffect rounding_effect(const FrfData& d, const Bases& b, const Eigen::MatrixXd& R, const Eigen::MatrixXd& CY,
                               int n, int r, const StateSpace& est) {
  const int F = d.frequencies();
  const double gamma = kUnitRoundoff * std::sqrt(2.0 * F * d.columns());
  const double gamma_cy = kUnitRoundoff * std::sqrt(static_cast<double>(F));
  const Eigen::Index ny = CY.rows(), cols = R.cols();
  RoundingEffect out(est, d.omega);
  std::mt19937_64 rng(0x5ca1ab1eULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int sample = 0; sample < kRoundingSamples; ++sample) {
    Eigen::MatrixXd moved_R = R.triangularView<Eigen::Upper>();
    for (Eigen::Index j = 0; j < cols; ++j) {
      Eigen::VectorXd e(cols);
      for (Eigen::Index i = 0; i < cols; ++i) e(i) = normal(rng);
      moved_R.col(j) += gamma * R.col(j).norm() / e.norm() * e;
    }
    const Eigen::MatrixXd R2 = Eigen::HouseholderQR<Eigen::MatrixXd>(moved_R).matrixQR().triangularView<Eigen::Upper>();
    Eigen::MatrixXd moved_CY = CY;
    for (Eigen::Index i = 0; i < ny; ++i)
      for (Eigen::Index j = 0; j <= i; ++j)
        moved_CY(j, i) = moved_CY(i, j) += gamma_cy * std::sqrt(CY(i, i) * CY(j, j)) * normal(rng);
    try {
      Eigen::LLT<Eigen::MatrixXd> llt(moved_CY);
      if (llt.info() != Eigen::Success)
        fail(ErrorKind::Numerical, "step 1c", "C_Y moved by rounding is not positive definite");
      const Eigen::MatrixXd L = llt.matrixL();
      const Eigen::MatrixXd K =
          L.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd(R2.bottomRightCorner(ny, ny).transpose()));
      const Eigen::MatrixXd U = Eigen::JacobiSVD<Eigen::MatrixXd>(K, Eigen::ComputeThinU).matrixU().leftCols(n);
      out.add(in_data_domain(steps_2_3(d, b, L.triangularView<Eigen::Lower>() * U, n, r), d, b));
    } catch (const Error& e) {  // the moved estimate fails where this one did not: nothing is determined
      out.fail(e.what());
      return out;
    }
  }
  return out;
}

// identify_frf_fixed from step 1c on: the estimate of order n from R of step
// 1b and C_Y of d's variances.
// assess_rounding: measure the rounding's effect on Ĝ and the poles (when
// A's bound exceeds the warning level); the r search leaves it to its choice.
FrfResult estimate_from_r(const FrfData& d, const Bases& b, const Eigen::MatrixXd& R, Eigen::MatrixXd CY, int order,
                          int r, bool assess_rounding) {
  const int n = order;
  const Step1 s1 = step1c(d, b, R, std::move(CY), r);
  if (!(s1.sigma(n - 1) > 0))
    fail(ErrorKind::Order, "step 1c", "singular value " + std::to_string(n) + " is zero: the data hold no order-" +
                                          std::to_string(n) + " model");
  // Ô_r = C_Y^{1/2} U[:, 1:n_a] with the same factor L (step 1c).
  const Eigen::MatrixXd O = s1.L.triangularView<Eigen::Lower>() * s1.Usvd.leftCols(n);
  Eigen::VectorXd top_sv;
  double step3_condition = 1;
  FrfResult res;
  const StateSpace est = res.model = in_data_domain(steps_2_3(d, b, O, n, r, &top_sv, &step3_condition), d, b);
  if (d.domain == Domain::Continuous || b.tustin) res.omega_scale = b.omega_scale;
  res.order = n;
  res.r = r;
  res.order_r = r;
  res.singular_values = s1.sigma;
  // First-order sensitivity of Â to rounding: the subspace of step 1c moves
  // by ~u σ_1/σ_n (Wedin), and the least-squares solve of step 2 multiplies
  // that by cond(Ô_top).
  // The projection Π of Eq. (20) amplifies perturbations of the input rows by
  // cond(R11) = cond(𝐔^re) (narrow-band or short grids make it large).
  // Wedin: the subspace of step 1c moves by (rounding of L⁻¹R22ᵀ)/σ_n, with
  // that rounding ≤ u ‖L⁻¹‖ ‖R‖ (noise_scale) — at least σ_1.
  const double subspace = std::max(s1.sigma(0), s1.noise_scale) / s1.sigma(n - 1);
  res.condition = subspace * (top_sv(0) / top_sv(n - 1)) * s1.r11_condition;
  // B̂, D̂ (and so Ĝ) also carry the conditioning of step 3's least squares.
  res.condition = std::max(res.condition, step3_condition);
  res.error_estimate = kUnitRoundoff * res.condition;
  res.poles = poles(est);
  // What the model is used for, G and the poles, only where A's entries may
  // have lost accuracy (the warning's threshold): below it, moving the
  // inputs of step 1c costs 3 reruns of steps 1c-3 for nothing the user
  // would be told.
  if (assess_rounding && res.error_estimate > kPrecisionWarningLevel) {
    const RoundingEffect e = rounding_effect(d, b, R, s1.CY, n, r, est);
    res.rounding_assessed = true;
    res.g_error_estimate = e.g;
    res.pole_error_estimate = e.poles;
    if (const std::string w = rounding_warning(e, "step 1b's R and step 1c's C_Y",
                                               "A's entries in the estimate's basis: bound " + fmt(res.error_estimate, 3));
        !w.empty())
      res.warnings.push_back(w);
  }
  res.v_sub = v_sub(est, d);
  const std::string unstable = instability_warning(est.domain, res.poles);
  if (!unstable.empty()) res.warnings.push_back(unstable);
  const double lo = d.omega.minCoeff(), hi = d.omega.maxCoeff();
  const std::string outside =
      out_of_band_warning(resonances_outside_band(res.poles, est.domain, lo, hi), est.domain, lo, hi, "the data's frequencies");
  if (!outside.empty()) res.warnings.push_back(outside);
  return res;
}

}  // namespace

FrfResult identify_frf_fixed(const FrfData& d, int order, int r, ContinuousMethod continuous, double omega_scale,
                             DiscreteMethod discrete, bool assess_rounding) {
  validate(d);
  check_order_r(d, order, r);
  const Bases b = checked_bases(d, r, continuous, omega_scale, discrete);
  return estimate_from_r(d, b, step1ab_qr(d, b, r), step1c_noise_covariance(d, b, r), order, r, assess_rounding);
}

std::vector<FrfResult> identify_frf_fixed(const std::vector<FrfData>& data, int order, int r,
                                          ContinuousMethod continuous, double omega_scale, DiscreteMethod discrete,
                                          bool assess_rounding) {
  if (data.empty()) return {};
  const FrfData& d0 = data[0];
  for (size_t v = 0; v < data.size(); ++v) {
    const FrfData& d = data[v];
    validate(d, "noise model " + std::to_string(v + 1));
    const auto same_stack = [](const ComplexMatrixStack& a, const ComplexMatrixStack& b) {
      return a.size() == b.size() && a.rows() == b.rows() && a.cols() == b.cols() && a.entries() == b.entries();
    };
    const bool same = d.domain == d0.domain && d.sample_time == d0.sample_time && d.omega.size() == d0.omega.size() &&
                      d.omega == d0.omega && same_stack(d.U, d0.U) && same_stack(d.Y, d0.Y);
    if (!same)
      fail(ErrorKind::Input, "noise model " + std::to_string(v + 1),
           "differs from noise model 1 in more than the variances (U, Y, omega, domain or sample time)");
  }
  check_order_r(d0, order, r);
  const Bases b = checked_bases(d0, r, continuous, omega_scale, discrete);
  const Eigen::MatrixXd R = step1ab_qr(d0, b, r);
  std::vector<FrfResult> out;
  out.reserve(data.size());
  for (const FrfData& d : data)
    out.push_back(estimate_from_r(d, b, R, step1c_noise_covariance(d, b, r), order, r, assess_rounding));
  return out;
}

namespace {

// Section 5, the order: read from the step-1c singular values at r = order_r.
struct AutomaticOrder {
  int order = 0, order_r = 0;
  Eigen::VectorXd sigma;  // the singular values it was read from
  double edge = 0;        // Marchenko–Pastur edge of whitened noise (0 without a noise model)
  std::string capped;     // a warning when it stopped at the top of its range, else empty
  std::string lowered;    // a note when the default r was lowered to one step 1 can use, else empty
};

// Purpose: n_a when the options leave it to the data.
// Method: with a noise model, the count of singular values whose square
// exceeds twice the Marchenko–Pastur edge (below); without one, the largest
// gap σ_n/σ_{n+1}; n ≤ n_max = max_order or min(20, r p − 1).
// Fails: Error(Dimension) with too few frequencies for r = 2; Error(Order)
// when nothing rises above the noise level.
AutomaticOrder automatic_order(const FrfData& d, const FrfOptions& o, int r_feasible) {
  const int F = d.frequencies(), p = d.outputs(), c = d.columns();
  AutomaticOrder a;
  a.order_r = o.r > 0 ? o.r : std::min(20, r_feasible);
  if (a.order_r < 2)
    fail(ErrorKind::Dimension, "order", "too few frequencies (" + std::to_string(F) + ") to read an order");
  // The default r = 20 can exceed what the band carries: 20 powers of z on
  // half of the unit circle are numerically dependent (C_Y, a Toeplitz matrix
  // of them, loses positive definiteness; the cubic-feedback circuit's oddms
  // record, 49.8 % of [0, pi]). Step 1 fails only through that dependence
  // (C_Y or R11; Error(Numerical)), so the default steps down to the largest r
  // it can use and says so; an r the user gave is never changed.
  const int r_default = a.order_r;
  for (;;) {
    try {
      a.sigma = frf_singular_values(d, a.order_r, o.continuous, o.omega_scale, o.discrete);
      break;
    } catch (const Error& e) {
      if (o.r > 0 || e.kind() != ErrorKind::Numerical || a.order_r == 2) throw;
      // The failure's first clause ("step 1c: C_Y ... is not positive definite"), without its advice to lower r.
      if (a.lowered.empty()) a.lowered = e.where() + ": " + e.message().substr(0, e.message().find(": "));
      --a.order_r;
    }
  }
  if (!a.lowered.empty())
    a.lowered = "the order was read at r = " + std::to_string(a.order_r) + ", not the default " +
                std::to_string(r_default) + ": step 1 failed at r = " + std::to_string(a.order_r + 1) +
                (a.order_r + 1 < r_default ? " ... " + std::to_string(r_default) : std::string()) +
                ", where the basis functions are numerically dependent on the data's band (at r = " +
                std::to_string(r_default) + ", " + a.lowered + ")";
  const int n_max = o.max_order > 0 ? std::min(o.max_order, a.order_r * p - 1) : std::min(20, a.order_r * p - 1);
  const Eigen::VectorXd& sv = a.sigma;
  if (d.has_noise_model) {
    // Whitened noise (C_Y = E[𝐍^re 𝐍^reᵀ]) has squared singular values
    // spread over the Marchenko–Pastur law of ratio γ = r p / (F c) (F c
    // complex columns; the Re/Im halves of one column are not independent);
    // its upper edge (1 + √γ)² is the noise level. A component counts as
    // model when its square exceeds twice that edge (margin for the
    // sample-variance weighting and the projection Π).
    const double gamma = double(a.order_r) * p / (double(F) * c);
    const double edge = a.edge = std::pow(1 + std::sqrt(gamma), 2);
    while (a.order < n_max && sv(a.order) * sv(a.order) > 2 * edge) ++a.order;
    // Review finding 4: on real data (model error above the noise) the
    // order stopped at the cap and was reported as "read from the singular
    // values". Say so when σ_{n_max+1} is still above the noise level too.
    if (a.order == n_max && n_max < sv.size() && sv(n_max) * sv(n_max) > 2 * edge)
      a.capped = "order " + std::to_string(a.order) + " is the top of the searched range (n <= " +
                 std::to_string(n_max) + " at r = " + std::to_string(a.order_r) +
                 (o.r > 0 ? std::string() : ", the r the order is read at; the model's r is then chosen by V_SUB") +
                 "), not where the singular values reach the noise level (sigma_" + std::to_string(n_max + 1) +
                 "^2 = " + fmt(sv(n_max) * sv(n_max), 3) + " > 2 x edge " + fmt(2 * edge, 3) +
                 "): the data need a larger --max-order (and --r), or the noise model is too optimistic";
    if (a.order == 0)
      fail(ErrorKind::Order, "order", "no singular value of step 1c rises above the noise level (largest " +
                                          fmt(sv(0) * sv(0), 3) + " vs edge " + fmt(edge, 3) +
                                          "): the data hold no identifiable dynamics at this noise level");
  } else {
    // Without a noise model: the largest gap σ_n / σ_{n+1}, n = 1 … n_max.
    double best = -1;
    for (int n = 1; n <= n_max && n < sv.size(); ++n) {
      const double ratio = sv(n - 1) / std::max(sv(n), sv(0) * kUnitRoundoff);
      if (ratio > best) {
        best = ratio;
        a.order = n;
      }
    }
  }
  return a;
}

// ---------------------------------------------------------------------------
// Section 5's r search, screened from one factorisation.
//
// Purpose: V_SUB (Eq. 35) at every r of [r_lo, r_hi] without a QR of Zᵀ per r
// (Σ_r O(F r²): 19 QRs of Zᵀ at n_a = 4, 46 at n_a = 10).
// Method: with Zᵀ's columns interleaved (ColumnOrder), Zᵀ at r is the first
// r (m + p) columns of Zᵀ at r_hi, so its R (interleaved) is the leading
// r (m + p) block of the one R at r_hi. Its columns are permuted back to the
// blocked order of steps 1b-1c and re-triangularised by a Householder QR of
// that square block: O(r³ (m + p)³) per r instead of O(F r² (m + p)²). C_Y
// at r is the leading r p block of C_Y at r_hi (rows i p + a), and step 2's
// H the leading r × (r − 1) block — bit for bit what identify_frf_fixed
// builds at r.
// Numerical aspects: R at r_hi is the exact R of Zᵀ + ΔZ with the streamed
// QR's columnwise bound ‖ΔZ(:, j)‖ ≲ γ ‖Zᵀ(:, j)‖ (Higham Thm 19.4); the
// second QR, backward stable for the permuted block, adds ≲ γ' ‖R(:, j)‖ =
// γ' ‖Zᵀ(:, j)‖ per column: the same columnwise bound as identify_frf_fixed's
// own R, with a larger constant. The screened estimate at r therefore differs
// from identify_frf_fixed's by rounding only (≈ its error_estimate,
// relative), and choose_r recomputes the ones it may choose as
// identify_frf_fixed does.
class ScreenedStep1 {
 public:
  ScreenedStep1(const FrfData& d, int r_hi, const FrfOptions& o) {
    b_ = checked_bases(d, r_hi, o.continuous, o.omega_scale, o.discrete);
    R_ = step1ab_r(d, b_, r_hi, ColumnOrder::Interleaved);
    CY_ = step1c_noise_covariance(d, b_, r_hi);
  }
  // identify_frf_fixed(d, order, r, ..., false) up to rounding, for r ≤ r_hi.
  FrfResult estimate(const FrfData& d, int order, int r) const {
    check_order_r(d, order, r);
    const int m = d.inputs(), p = d.outputs(), cols = r * (m + p);
    const Eigen::MatrixXd lead = R_.topLeftCorner(cols, cols).triangularView<Eigen::Upper>();
    Eigen::MatrixXd blocked(cols, cols);
    for (int i = 0; i < r; ++i) {
      for (int a = 0; a < m; ++a) blocked.col(i * m + a) = lead.col(i * (m + p) + a);
      for (int a = 0; a < p; ++a) blocked.col(r * m + i * p + a) = lead.col(i * (m + p) + m + a);
    }
    const Eigen::MatrixXd R =
        Eigen::HouseholderQR<Eigen::MatrixXd>(blocked).matrixQR().triangularView<Eigen::Upper>();
    const Bases b = b_.for_steps_2_3(r);  // steps 1a-1c, the readers of Wu and Wy, are done
    check_input_excitation(d, b, R, r);
    return estimate_from_r(d, b, R, CY_.topLeftCorner(r * p, r * p), order, r, false);
  }

 private:
  Bases b_;               // at r_hi
  Eigen::MatrixXd R_;     // R of Zᵀ at r_hi, interleaved columns
  Eigen::MatrixXd CY_;    // C_Y at r_hi
};

// Section 5's choice among the screened r.
//
// Purpose: the r of least V_SUB whose estimate is usable in double precision,
// its estimate exactly what identify_frf_fixed gives at that r (so --r
// reproduces it) and assessed for rounding.
// Method: repeatedly take the least V_SUB not yet ruled out; a screened value
// is replaced by identify_frf_fixed's at its r (assessed), which rules the r
// out when its estimate is unusable or drops it when the estimate fails; the
// first least value that is a usable recomputed estimate is the choice. At
// the one r of a clear minimum this is one more identification; every listed
// V_SUB below the choice belongs to an unusable estimate, recomputed.
// An unusable least V_SUB (the F-16's Voltage → Acceleration3 FRF,
// continuous time, order 12, had r = 46, where rounding-size moves of C_Y
// make step 1c fail; r = 44 gives a usable model with V_SUB 0.07 % higher): a
// model rounding alone decides is not one a user can reproduce or rely on;
// the choice names both. When none is usable, the least V_SUB's estimate
// stays with its warning and one more saying every r was tried.
// Fails: Error(Numerical) when every recomputed estimate fails.
FrfResult choose_r(const FrfData& d, const FrfOptions& o, int order, std::vector<std::pair<int, double>>& scan) {
  const auto by_v_sub = [](const std::pair<int, double>& a, const std::pair<int, double>& b) {
    return a.second < b.second;
  };
  std::map<int, FrfResult> recomputed;
  std::set<int> unusable;
  std::string last_error;
  for (;;) {
    auto least = scan.end();
    for (auto it = scan.begin(); it != scan.end(); ++it)
      if (!unusable.count(it->first) && (least == scan.end() || by_v_sub(*it, *least))) least = it;
    if (least == scan.end()) break;
    const int r = least->first;
    if (const auto done = recomputed.find(r); done != recomputed.end()) {
      FrfResult res = std::move(done->second);
      // The least V_SUB listed, when it is not this one, is an unusable estimate's.
      const auto overall = std::min_element(scan.begin(), scan.end(), by_v_sub);
      if (overall->first != r) {
        const FrfResult& u = recomputed.at(overall->first);
        const double error = u.usability_estimate();
        res.notes.push_back(
            "r = " + std::to_string(r) + " chosen, the least V_SUB (Eq. 35) of the r whose estimate is usable " +
            "in double precision: r = " + std::to_string(u.r) + " has the least V_SUB (" + fmt(u.v_sub, 6) + "; " +
            fmt(res.v_sub, 6) + " at r = " + std::to_string(r) + ", " + fmt(100 * (res.v_sub / u.v_sub - 1), 2) +
            " % more) but its estimate is unusable (" +
            (std::isfinite(error) ? "estimated relative error of G or the poles " + fmt(error, 2)
                                  : std::string("a rounding-size move of its inputs made the estimate fail")) +
            ")");
        res.r_unusable_least_v_sub = u.r;
      }
      return res;
    }
    try {
      FrfResult res = identify_frf_fixed(d, order, r, o.continuous, o.omega_scale, o.discrete, true);
      least->second = res.v_sub;
      if (!usable_precision(res.usability_estimate())) unusable.insert(r);
      recomputed.emplace(r, std::move(res));
    } catch (const Error& e) {  // rounding decides whether there is an estimate at r: not one to list
      last_error = e.what();
      scan.erase(least);
    }
  }
  if (scan.empty())
    fail(ErrorKind::Numerical, "r selection", "every r the search screened failed when recomputed; last: " + last_error);
  const auto overall = std::min_element(scan.begin(), scan.end(), by_v_sub);
  FrfResult res = std::move(recomputed.at(overall->first));
  res.warnings.push_back("no r the search tried (" + std::to_string(scan.size()) +
                         " values) gives an estimate usable in double precision; the least V_SUB's is kept");
  return res;
}

}  // namespace

FrfResult identify_frf(const FrfData& d, const FrfOptions& o) {
  validate(d);
  const int F = d.frequencies(), m = d.inputs(), p = d.outputs(), c = d.columns();
  // The largest r for which Z has at least as many columns as rows (step 1b).
  const int r_feasible = static_cast<int>(2LL * F * c / (m + p));
  AutomaticOrder automatic;
  if (o.order == 0) automatic = automatic_order(d, o, r_feasible);
  const int order = o.order > 0 ? o.order : automatic.order;
  FrfResult best;
  if (o.r > 0) {
    best = identify_frf_fixed(d, order, o.r, o.continuous, o.omega_scale, o.discrete);
  } else {
    // Section 5: r minimising V_SUB (Eq. 35) over [1.5 n_a, 6 n_a], a craggy
    // function of r, so every r is tried.
    const int r_lo = o.r_min > 0 ? o.r_min : std::max(order + 1, (3 * order + 1) / 2);
    const int r_hi = std::min(r_feasible, o.r_max > 0 ? o.r_max : std::max(r_lo, 6 * order));
    if (r_hi < r_lo)
      fail(ErrorKind::Dimension, "r", "no r in [" + std::to_string(r_lo) + ", " + std::to_string(r_hi) +
                                          "] fits " + std::to_string(F) + " frequencies (need 2 F c >= r (m + p))");
    // Screened from one factorisation at r_hi; where that cannot be made
    // (memory, or the Arnoldi basis breaking down below r_hi), each r on its
    // own, as identify_frf_fixed, and its own failure is the one reported.
    std::optional<ScreenedStep1> screened;
    try {
      screened.emplace(d, r_hi, o);
    } catch (const Error&) {
    }
    std::string last_error;
    std::vector<std::pair<int, double>> scan;
    for (int r = r_lo; r <= r_hi; ++r) {
      try {
        scan.emplace_back(r, (screened ? screened->estimate(d, order, r)
                                       : identify_frf_fixed(d, order, r, o.continuous, o.omega_scale, o.discrete, false))
                                 .v_sub);
      } catch (const Error& e) {
        last_error = e.what();
      }
    }
    if (scan.empty())
      fail(ErrorKind::Numerical, "r selection",
           "every r in [" + std::to_string(r_lo) + ", " + std::to_string(r_hi) + "] failed; last: " + last_error);
    best = choose_r(d, o, order, scan);
    best.r_scan = std::move(scan);
  }
  if (automatic.sigma.size() > 0) {
    best.singular_values = automatic.sigma;
    best.order_r = automatic.order_r;
  }
  best.noise_edge = automatic.edge;
  if (!automatic.lowered.empty()) best.notes.push_back(automatic.lowered);
  if (!automatic.capped.empty()) {
    best.warnings.push_back(automatic.capped);
    best.order_at_search_cap = true;
  }
  return best;
}

// ---------------------------------------------------------------------------

std::vector<std::vector<Eigen::VectorXcd>> period_spectra(const Eigen::MatrixXd& samples, int period, int periods,
                                                          const std::vector<int>& lines) {
  if (period < 2) fail(ErrorKind::Input, "meta field \"period\"", "must be at least 2, got " + std::to_string(period));
  if (periods < 1) fail(ErrorKind::Input, "meta field \"periods\"", "must be at least 1, got " + std::to_string(periods));
  if (samples.rows() != static_cast<Eigen::Index>(period) * periods)
    fail(ErrorKind::Input, "data",
         std::to_string(samples.rows()) + " samples are not " + std::to_string(periods) + " whole periods of " +
             std::to_string(period) + " (expected " + std::to_string(static_cast<long long>(period) * periods) + ")");
  if (!samples.allFinite()) fail(ErrorKind::Input, "data", "contains NaN or Inf");
  for (int k : lines)
    if (k < 1 || k > period / 2)
      fail(ErrorKind::Input, "meta field \"excited_lines\"",
           "line " + std::to_string(k) + " is outside 1 ... P/2 = " + std::to_string(period / 2));
  const int channels = static_cast<int>(samples.cols());
  numerics::RealFft fft(period);
  const double scale = 1.0 / std::sqrt(static_cast<double>(period));  // Eq. (4)
  std::vector<std::vector<Eigen::VectorXcd>> res(periods, std::vector<Eigen::VectorXcd>(lines.size(),
                                                                                       Eigen::VectorXcd(channels)));
  for (int l = 0; l < periods; ++l)
    for (int ch = 0; ch < channels; ++ch) {
      for (int t = 0; t < period; ++t) fft.time()[t] = samples(static_cast<Eigen::Index>(l) * period + t, ch);
      fft.forward();
      for (size_t i = 0; i < lines.size(); ++i) res[l][i](ch) = scale * fft.freq()[lines[i]];
    }
  return res;
}

SampleStatistics sample_statistics(Domain domain, const Eigen::VectorXd& omega,
                                   const std::vector<std::vector<Eigen::VectorXcd>>& U_l,
                                   const std::vector<std::vector<Eigen::VectorXcd>>& Y_l) {
  const int M = static_cast<int>(Y_l.size());
  if (M < 2)
    fail(ErrorKind::Input, "periods",
         "M = " + std::to_string(M) + ": a sample variance needs M >= 2 periods (Pintelon 2002 Eq. 25)");
  if (static_cast<int>(U_l.size()) != M) fail(ErrorKind::Input, "periods", "input and output period counts differ");
  const int F = static_cast<int>(omega.size());
  SampleStatistics st;
  st.M = M;
  FrfData& d = st.data;
  d.domain = domain;
  d.omega = omega;
  const Eigen::Index m = F > 0 && !U_l[0].empty() ? U_l[0][0].size() : 0;
  const Eigen::Index p = F > 0 && !Y_l[0].empty() ? Y_l[0][0].size() : 0;
  for (int l = 0; l < M; ++l) {
    if (static_cast<int>(U_l[l].size()) != F || static_cast<int>(Y_l[l].size()) != F)
      fail(ErrorKind::Input, "period " + std::to_string(l + 1), "needs one input and one output vector per frequency");
    for (int k = 0; k < F; ++k)
      if (U_l[l][k].size() != m || Y_l[l][k].size() != p)
        fail(ErrorKind::Input, "period " + std::to_string(l + 1) + " frequency " + std::to_string(k + 1),
             "inconsistent numbers of inputs or outputs");
  }
  d.U.resize(F, m, 1);
  d.Y.resize(F, p, 1);
  d.variance.resize(F, p, 1);
  st.var_U.resize(F, m, 1);
  st.cov_YU.resize(F, p, m);
  // Entry by entry into the stacks: no temporaries (a Monte Carlo run calls
  // this per run; dynamic-size vector arithmetic per line was a tenth of
  // `reproduce fig1`).
  for (int k = 0; k < F; ++k) {
    for (int l = 0; l < M; ++l) {  // Eq. (25): Û, Ŷ
      for (int a = 0; a < m; ++a) d.U(k, a, 0) += U_l[l][k](a);
      for (int a = 0; a < p; ++a) d.Y(k, a, 0) += Y_l[l][k](a);
    }
    for (int a = 0; a < m; ++a) d.U(k, a, 0) /= M;
    for (int a = 0; a < p; ++a) d.Y(k, a, 0) /= M;
    for (int l = 0; l < M; ++l)
      for (int a = 0; a < p; ++a) {
        const cplx dy = Y_l[l][k](a) - d.Y(k, a, 0);
        d.variance(k, a, 0) += std::norm(dy);
        for (int b = 0; b < m; ++b)  // Eq. (32): (Y − Ŷ) conj(U − Û)
          st.cov_YU(k, a, b) += dy * std::conj(U_l[l][k](b) - d.U(k, b, 0));
      }
    for (int l = 0; l < M; ++l)
      for (int b = 0; b < m; ++b) st.var_U(k, b, 0) += std::norm(U_l[l][k](b) - d.U(k, b, 0));
    for (int a = 0; a < p; ++a) {
      d.variance(k, a, 0) /= double(M - 1) * M;  // σ̂²_Y / M, Section 4.1
      for (int b = 0; b < m; ++b) st.cov_YU(k, a, b) /= double(M - 1);
    }
    for (int b = 0; b < m; ++b) st.var_U(k, b, 0) /= double(M - 1);
  }
  return st;
}

void require_input_power(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta) {
  const int M = meta.periods, F = static_cast<int>(meta.excited_lines.size());
  if (M < 2 || F == 0 || inputs < 1) return;  // nothing to judge by; the callers refuse these cases
  const Eigen::MatrixXd u = samples.leftCols(inputs);
  const auto sp = period_spectra(u, meta.period, M, meta.excited_lines);
  // Rounding floor: an unexcited line of a noise-free input keeps
  // |U|^2 ~ (u log2 P)^2 E (E = energy of one period, Parseval), < 1e-29 E for
  // P <= 2^24; an excited line of a multisine over at most P/2 lines has
  // |U|^2 >= E/P >= 6e-8 E. 1e-20 E lies far from both.
  const double energy = u.squaredNorm() / M;
  // Noise floor: on a line without input, |mean U|^2 / (s^2_U / M) is F(2, 2M-2)
  // distributed (Gaussian noise; mean and sample variance independent), whose
  // survival function is (1 + t/(M-1))^{-(M-1)}: its upper 1 % point q.
  const double q = (M - 1) * (std::pow(0.01, -1.0 / (M - 1)) - 1);
  int quiet = 0, first_quiet = -1;
  double first_ratio = 0, first_power = 0;
  for (int j = 0; j < F; ++j) {
    bool powered = false;
    double best = 0, strongest = 0;
    for (int i = 0; i < inputs; ++i) {
      cplx mean = 0;
      for (int l = 0; l < M; ++l) mean += sp[l][j](i);
      mean /= double(M);
      double var = 0;
      for (int l = 0; l < M; ++l) var += std::norm(sp[l][j](i) - mean);
      var /= (M - 1);
      const double power = std::norm(mean);
      const double ratio = var > 0 ? power / (var / M) : std::numeric_limits<double>::infinity();
      best = std::max(best, ratio);
      strongest = std::max(strongest, power);
      if (power > 1e-20 * energy && ratio > q) powered = true;
    }
    if (!powered && ++quiet == 1) first_quiet = meta.excited_lines[j], first_ratio = best, first_power = strongest;
  }
  // An excited line is never quiet (its mean over the periods stands above
  // the period-to-period scatter by its input's SNR × M); a line without
  // input is quiet with probability >= 99 %. So one quiet line is a meta that
  // lists a line without input: more than half of them, the wrong lines
  // (0-based, shifted, another period); a few, a list shifted by one over a
  // contiguous band (a user review: the F-16's lines 41-307 given as 40-306
  // were accepted) or a line the excitation leaves out.
  if (quiet == 0) return;
  // The example line's reason: at the rounding floor (a noise-free record's
  // unexcited line, whose ratio may be 0/0 or inf: review finding 8 of stop
  // 47 printed "= inf, below the 1 % point"), or below the noise's 1 % point.
  const std::string why = first_power <= 1e-20 * energy
                              ? "|U|^2 = " + sci(first_power / energy) +
                                    " of one period's energy, at the rounding floor 1e-20"
                              : "|U|^2 / (s^2_U / M) = " + sci(first_ratio) + ", below the 1 % point " + sci(q) +
                                    " of noise alone";
  const bool most = 2 * quiet > F;  // the wrong lines altogether
  fail(ErrorKind::Input, "meta field \"excited_lines\"",
       std::to_string(quiet) + " of the " + std::to_string(F) + " listed lines " +
           (most || quiet > 1 ? "carry" : "carries") + " no input power (" + (most ? "e.g. " : "") + "line " +
           std::to_string(first_quiet) + ": " + why + "): " +
           (most ? "the excitation is on other lines; are the lines 1-based DFT indices k = 1 ... P/2 (frequency k / "
                   "(P Ts))?"
                 : "list only the excited lines, as 1-based DFT indices k = 1 ... P/2 (frequency k / (P Ts)); a list "
                   "shifted by one (0-based) over a contiguous band leaves its first or last line without input"));
}

int repeated_line(const std::vector<int>& lines) {
  std::set<int> seen;
  for (int k : lines)
    if (!seen.insert(k).second) return k;
  return -1;
}

namespace {

// What both record readers check: lines, sample time, channels, input power.
void check_records(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta) {
  if (meta.excited_lines.empty()) fail(ErrorKind::Input, "meta field \"excited_lines\"", "no excited lines");
  if (const int k = repeated_line(meta.excited_lines); k >= 0)
    fail(ErrorKind::Input, "meta field \"excited_lines\"", "line " + std::to_string(k) + " is listed twice");
  if (!(meta.sample_time > 0) || !std::isfinite(meta.sample_time))
    fail(ErrorKind::Input, "meta field \"sample_time\"", "must be positive, got " + fmt(meta.sample_time, 6));
  if (inputs < 1 || inputs >= samples.cols())
    fail(ErrorKind::Input, "data", "needs at least one input and one output column");
  require_input_power(samples, inputs, meta);
}

}  // namespace

Eigen::VectorXd line_frequencies(const RecordMeta& meta, Domain domain) {
  const int F = static_cast<int>(meta.excited_lines.size());
  Eigen::VectorXd omega(F);
  for (int k = 0; k < F; ++k)
    omega(k) = 2 * M_PI * meta.excited_lines[k] / meta.period / (domain == Domain::Continuous ? meta.sample_time : 1.0);
  return omega;
}

SampleStatistics record_statistics(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta,
                                   Domain domain) {
  if (meta.periods < 2)
    fail(ErrorKind::Input, "meta field \"periods\"",
         "M = " + std::to_string(meta.periods) +
             ": the sample variance needs at least 2 periods (a known noise level: identify-frf --noise-std)");
  check_records(samples, inputs, meta);
  const auto spectra = period_spectra(samples, meta.period, meta.periods, meta.excited_lines);
  const int F = static_cast<int>(meta.excited_lines.size());
  const Eigen::VectorXd omega = line_frequencies(meta, domain);
  std::vector<std::vector<Eigen::VectorXcd>> U_l(meta.periods), Y_l(meta.periods);
  const int outputs = static_cast<int>(samples.cols()) - inputs;
  for (int l = 0; l < meta.periods; ++l)
    for (int k = 0; k < F; ++k) {
      U_l[l].push_back(spectra[l][k].head(inputs));
      Y_l[l].push_back(spectra[l][k].tail(outputs));
    }
  SampleStatistics st = sample_statistics(domain, omega, U_l, Y_l);
  st.data.sample_time = meta.sample_time;
  for (int k = 0; k < F; ++k)
    for (int a = 0; a < outputs; ++a)
      if (!(st.data.variance[k](a, 0) > 0))
        fail(ErrorKind::Input, "data line " + std::to_string(meta.excited_lines[k]),
             "output " + std::to_string(a + 1) +
                 " has zero sample variance over the periods (noise-free or repeated records): no noise model");
  return st;
}

FrfData record_known_noise(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta, Domain domain,
                           const std::vector<double>& noise_std, std::vector<std::string>* warnings) {
  if (meta.periods < 1)
    fail(ErrorKind::Input, "meta field \"periods\"", "M = " + std::to_string(meta.periods) + ": no period");
  check_records(samples, inputs, meta);
  const int outputs = static_cast<int>(samples.cols()) - inputs;
  if (noise_std.size() != 1 && static_cast<int>(noise_std.size()) != outputs)
    fail(ErrorKind::Input, "--noise-std",
         "give one noise std for every output, or one per output (" + std::to_string(outputs) + "), not " +
             std::to_string(noise_std.size()));
  for (double s : noise_std)
    if (!(s > 0) || !std::isfinite(s))
      fail(ErrorKind::Input, "--noise-std", "must be positive and finite, got " + fmt(s, 6));
  const auto std_of = [&](int a) { return noise_std.size() == 1 ? noise_std[0] : noise_std[static_cast<size_t>(a)]; };
  // Eq. (4)'s 1/√P keeps white noise's E|V(k)|² = σ²; the mean of M periods: σ²/M, the same at every line.
  Eigen::MatrixXd var(outputs, 1);
  for (int a = 0; a < outputs; ++a) var(a, 0) = std_of(a) * std_of(a) / meta.periods;
  const auto spectra = period_spectra(samples, meta.period, meta.periods, meta.excited_lines);
  const int F = static_cast<int>(meta.excited_lines.size());
  FrfData d;
  d.domain = domain;
  d.sample_time = meta.sample_time;
  d.omega = line_frequencies(meta, domain);
  for (int k = 0; k < F; ++k) {
    Eigen::VectorXcd mean = Eigen::VectorXcd::Zero(samples.cols());
    for (int l = 0; l < meta.periods; ++l) mean += spectra[l][k];
    mean /= meta.periods;
    d.U.push_back(mean.head(inputs));
    d.Y.push_back(mean.tail(outputs));
    d.variance.push_back(var);
  }
  d.has_noise_model = true;
  if (warnings && meta.periods >= 2) {
    // The scatter test of the header: T_a = 2 S_a / σ_a², S_a the squared
    // deviations from the period mean over every line and period.
    const double nu = 2.0 * F * (meta.periods - 1);
    const boost::math::chi_squared law(nu);
    const double level = 1e-3;
    const double lo = boost::math::quantile(law, level / 2), hi = boost::math::quantile(boost::math::complement(law, level / 2));
    for (int a = 0; a < outputs; ++a) {
      const double s = std_of(a);
      double S = 0;
      for (int k = 0; k < F; ++k)
        for (int l = 0; l < meta.periods; ++l) S += std::norm(spectra[l][k](inputs + a) - d.Y[k](a));
      const double T = 2 * S / (s * s);
      if (T >= lo && T <= hi) continue;
      const double implied = std::sqrt(S / (F * (meta.periods - 1)));  // E|V(k) − V̄(k)|² = σ² (M − 1)/M per period
      warnings->push_back(
          "--noise-std " + fmt(s, 4) + (outputs > 1 ? " of output " + std::to_string(a + 1) : std::string()) +
          " disagrees with the record: the output's scatter over the " + std::to_string(meta.periods) +
          " periods at the excited lines is that of a noise std of " + fmt(implied, 4) + " (variance ratio " +
          fmt(T / nu, 3) + ", outside its 99.9 % interval " + fmt(lo / nu, 3) + " ... " + fmt(hi / nu, 3) +
          " under white noise of the std given); the fit verdict and any refinement weigh the residuals by "
          "--noise-std: check its units (a std per sample, not a variance) and whether the first periods hold a transient "
          "(--skip-periods), or drop it to use the sample variance (M >= 4 periods)");
    }
  }
  return d;
}

double eiv_residual_variance(double var_y, double var_u, cplx cov_yu, cplx G) {
  return var_y + std::norm(G) * var_u - 2 * (cov_yu * std::conj(G)).real();
}

namespace {

// Ratio data with the first-order variance of Eq. (31) (corrected) for
// num / den, where (num, den) = (Y, U) or (U, Y). Lines with a denominator
// SNR below min_snr are dropped (the practical form of Eq. 34).
FrfData ratio_data(const SampleStatistics& st, bool swap, const StateSpace* first_pass, double min_snr,
                   int* dropped) {
  const FrfData& s = st.data;
  if (s.inputs() != 1 || s.outputs() != 1)
    fail(ErrorKind::Input, "errors-in-variables", "Section 5's ratio estimate is implemented for SISO data only");
  FrfData d;
  d.domain = s.domain;
  d.sample_time = s.sample_time;
  std::vector<double> omega;
  int drop = 0;
  const double M = st.M;
  for (int k = 0; k < s.frequencies(); ++k) {
    const cplx Y = s.Y[k](0, 0), U = s.U[k](0, 0);
    const double vY = s.variance[k](0, 0) * M;  // σ̂²_Y (not divided by M)
    const double vU = st.var_U[k](0);
    const cplx cYU = st.cov_YU[k](0, 0);
    const cplx num = swap ? U : Y, den = swap ? Y : U;
    const double vnum = swap ? vU : vY, vden = swap ? vY : vU;
    const cplx cnd = swap ? std::conj(cYU) : cYU;  // E[δnum conj δden]
    if (!(std::norm(den) > min_snr * vden / M)) {
      ++drop;
      continue;
    }
    const cplx G = num / den;
    double var;
    if (first_pass && !swap) {
      const cplx G1 = frequency_response(*first_pass, s.omega(k))(0, 0);
      var = eiv_residual_variance(vnum, vden, cnd, G1) / std::norm(den);
    } else {
      // Eq. (31) with the conjugate of the denominator in the cross term.
      var = std::norm(G) * (vnum / std::norm(num) + vden / std::norm(den) - 2 * (cnd / (num * std::conj(den))).real());
    }
    var /= M;
    if (!(var > 0) || !std::isfinite(var)) {
      ++drop;
      continue;
    }
    omega.push_back(s.omega(k));
    d.U.push_back(Eigen::MatrixXcd::Ones(1, 1));
    d.Y.push_back(Eigen::MatrixXcd::Constant(1, 1, G));
    d.variance.push_back(Eigen::MatrixXd::Constant(1, 1, var));
  }
  d.omega = Eigen::Map<Eigen::VectorXd>(omega.data(), static_cast<Eigen::Index>(omega.size()));
  if (dropped) *dropped = drop;
  if (omega.empty())
    fail(ErrorKind::Input, "errors-in-variables", "every line has an input SNR below " + fmt(min_snr, 3));
  return d;
}

}  // namespace

FrfData errors_in_variables(const SampleStatistics& st, const StateSpace* first_pass, double min_snr, int* dropped) {
  return ratio_data(st, false, first_pass, min_snr, dropped);
}

FrfData swap_input_output(const SampleStatistics& st, double min_snr, int* dropped) {
  return ratio_data(st, true, nullptr, min_snr, dropped);
}

}  // namespace fdsid
