// Akçay (2011) Algorithm 1 and Van Overschee et al. (1997), double precision.
#include "fdsid/spectrum_id.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <utility>

#include "fdsid/compare.hpp"
#include "fdsid/error.hpp"
#include "numerics/constants.hpp"
#include "numerics/fft.hpp"
#include "fdsid/format.hpp"
#include "numerics/qr.hpp"
#include "numerics/rank.hpp"
#include "numerics/riccati.hpp"

namespace fdsid {

namespace {

using numerics::kUnitRoundoff;
// Largest side of 𝒴 (p m, r m) whose SVD fdsid attempts (≈ 1 min of Jacobi sweeps here).
constexpr int kMaxSvdDimension = 2000;

// A block of the real block-diagonal form of Â: a 1x1 block (real eigenvalue a)
// or a 2x2 block [[a, b], [-b, a]] for the pair a ± ib.
struct Block {
  int start;
  int size;
  double a, b;
};

// 1/w without the overflow-guarded library division: |w| is bounded away from 0
// and infinity here (|z| = 1, |λ| < 1), so conj(w)/|w|^2 is accurate to a few u.
inline cplx reciprocal(cplx w) {
  const double d = w.real() * w.real() + w.imag() * w.imag();
  return cplx(w.real() / d, -w.imag() / d);
}

// χ(z) = Ĉ (zI - Â)^{-1} for block-diagonal Â, written into chi (m x n).
// 2x2 block: (zI - [[a,b],[-b,a]])^{-1} = [[z-a, b], [-b, z-a]] / ((z-a)^2 + b^2).
void resolvent_row(const Eigen::MatrixXd& C, const std::vector<Block>& blocks, cplx z, Eigen::MatrixXcd& chi) {
  for (const Block& bl : blocks) {
    if (bl.size == 1) {
      const cplx r = reciprocal(z - bl.a);
      for (Eigen::Index i = 0; i < C.rows(); ++i) chi(i, bl.start) = C(i, bl.start) * r;
    } else {
      const cplx za = z - bl.a;
      const cplx inv = reciprocal(za * za + bl.b * bl.b);
      const cplx r11 = za * inv, r12 = bl.b * inv;
      for (Eigen::Index i = 0; i < C.rows(); ++i) {
        const double c0 = C(i, bl.start), c1 = C(i, bl.start + 1);
        chi(i, bl.start) = c0 * r11 - c1 * r12;
        chi(i, bl.start + 1) = c0 * r12 + c1 * r11;
      }
    }
  }
}

// Step 8 as a real linear least-squares problem. Unknowns θ = [vec F̂ (n m,
// column-major), Ê_ab for a <= b]. The model Ŝ(z) = Ê + X + X^H, X = χ(z) F̂, is
// Hermitian on |z| = 1, so ||Ŝ - S_k||_F^2 = ||Ŝ - H_k||_F^2 + const with H_k the
// Hermitian part of S_k; per sample the equations are Re of the m diagonal
// entries and Re, Im of the m(m-1)/2 entries above it, the latter weighted by
// √2 because each stands for itself and its mirror image.
class SummandDesign {
 public:
  SummandDesign(const Eigen::MatrixXd& C, const std::vector<Block>& blocks, int m)
      : C_(C), blocks_(blocks), m_(m), n_(static_cast<int>(C.cols())), chi_(m, C.cols()) {}

  int unknowns() const { return n_ * m_ + m_ * (m_ + 1) / 2; }
  int rows_per_sample() const { return m_ * m_; }

  // Writes the rows of sample z into D (rows_per_sample() x unknowns()) and, when
  // data != nullptr, the matching right-hand side into y.
  void rows(cplx z, const SpectrumData* data, int k, Eigen::Ref<Eigen::MatrixXd> D, Eigen::Ref<Eigen::VectorXd> y) {
    if (m_ == 1) {
      scalar_row(z, D.data(), D.outerStride());
      if (data) y(0) = data->S(0, k).real();
      return;
    }
    resolvent_row(C_, blocks_, z, chi_);
    D.setZero();
    const double w = std::sqrt(2.0);
    int row = 0;
    for (int a = 0; a < m_; ++a) {
      for (int b = a; b < m_; ++b) {
        // Ŝ_ab = E_ab + sum_c χ_ac F_cb + sum_c conj(χ_bc) F_ca
        const int e_index = n_ * m_ + e_position(a, b);
        if (a == b) {
          for (int c = 0; c < n_; ++c) D(row, c + n_ * a) = 2.0 * chi_(a, c).real();
          D(row, e_index) = 1.0;
          if (data) y(row) = data->at(a, a, k).real();
          ++row;
        } else {
          for (int c = 0; c < n_; ++c) {
            D(row, c + n_ * b) += w * chi_(a, c).real();
            D(row, c + n_ * a) += w * chi_(b, c).real();
            D(row + 1, c + n_ * b) += w * chi_(a, c).imag();
            D(row + 1, c + n_ * a) -= w * chi_(b, c).imag();
          }
          D(row, e_index) = w;
          if (data) {
            const cplx h = 0.5 * (data->at(a, b, k) + std::conj(data->at(b, a, k)));
            y(row) = w * h.real();
            y(row + 1) = w * h.imag();
          }
          row += 2;
        }
      }
    }
  }

  // m = 1: the single row [2 Re χ(z), 1] into row[0], row[stride], ..., with only
  // the real parts computed (same formulas as resolvent_row).
  void scalar_row(cplx z, double* row, Eigen::Index stride) const {
    // In real arithmetic (std::complex products go through NaN-checking library
    // calls): with x + iy = z - a, a 2x2 block has det = u + iv, u = x^2 - y^2 + b^2,
    // v = 2xy, and Re((z-a)/det) = (xu + yv)/|det|^2, Re(b/det) = b u/|det|^2.
    const double zr = z.real(), zi = z.imag();
    for (const Block& bl : blocks_) {
      const double x = zr - bl.a, y = zi;
      if (bl.size == 1) {
        row[bl.start * stride] = 2.0 * C_(0, bl.start) * x / (x * x + y * y);
      } else {
        const double u = x * x - y * y + bl.b * bl.b, v = 2.0 * x * y;
        const double id = 1.0 / (u * u + v * v);
        const double r11 = (x * u + y * v) * id, r12 = bl.b * u * id;
        const double c0 = C_(0, bl.start), c1 = C_(0, bl.start + 1);
        row[bl.start * stride] = 2.0 * (c0 * r11 - c1 * r12);
        row[(bl.start + 1) * stride] = 2.0 * (c0 * r12 + c1 * r11);
      }
    }
    row[n_ * stride] = 1.0;
  }

  int e_position(int a, int b) const {  // a <= b, row-wise upper triangle
    return a * m_ - a * (a - 1) / 2 + (b - a);
  }

 private:
  const Eigen::MatrixXd& C_;
  const std::vector<Block>& blocks_;
  int m_, n_;
  Eigen::MatrixXcd chi_;
};

// The grid points z_k = e^{iπk/M}, k = k0, k0+1, ...: a rotation recurrence
// re-anchored on std::polar every 64 steps, so the error stays below ~64u while
// sin/cos are called once per 64 samples.
class GridWalker {
 public:
  GridWalker(int k0, int M) : k_(k0), M_(M), step_(std::polar(1.0, M_PI / M)) { anchor(); }
  cplx z() const { return z_; }
  void next() {
    ++k_;
    if (k_ % 64 == 0) anchor();
    else z_ *= step_;
  }

 private:
  void anchor() { z_ = std::polar(1.0, M_PI * k_ / M_); }
  int k_, M_;
  cplx step_, z_;
};

// Hermitian spectrum value from the summand coefficients θ at row block D.
Eigen::MatrixXcd unpack_hermitian(const Eigen::VectorXd& values, int m) {
  // values: the rows of the design times θ -- diagonal reals, then (Re, Im)·√2 pairs.
  Eigen::MatrixXcd S(m, m);
  int row = 0;
  const double w = std::sqrt(2.0);
  for (int a = 0; a < m; ++a)
    for (int b = a; b < m; ++b) {
      if (a == b) {
        S(a, a) = values(row++);
      } else {
        S(a, b) = cplx(values(row), values(row + 1)) / w;
        S(b, a) = std::conj(S(a, b));
        row += 2;
      }
    }
  return S;
}

double min_hermitian_eigenvalue(const Eigen::MatrixXcd& S) {
  if (S.rows() == 1) return S(0, 0).real();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(S, Eigen::EigenvaluesOnly).eigenvalues()(0);
}

// Symmetric square root and inverse square root of a symmetric positive-definite matrix.
void sqrt_spd(const Eigen::MatrixXd& X, Eigen::MatrixXd& root, Eigen::MatrixXd& inv_root) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(X);
  const Eigen::VectorXd l = es.eigenvalues().cwiseSqrt();
  root = es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
  inv_root = es.eigenvectors() * l.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
}

}  // namespace

const char* to_string(Method m) { return m == Method::Akcay2011 ? "akcay2011" : "vo1997"; }
const char* to_string(Extension e) { return e == Extension::HermitianPart ? "hermitian-part" : "conjugate"; }

void default_pr(int M, int n, int& p, int& r) {
  const int N = 2 * M;
  if (n <= 0) {
    p = r = std::min(50, M);
  } else {
    p = std::max(2 * n + 1, std::min(50, M));
    r = std::max(2 * n, std::min(50, N - p));
  }
}

void check_pr(int N, int n, int p, int r) {
  auto fail = [&](const std::string& what) {
    throw Error(ErrorKind::Dimension, "step 2",
                what + " (p = " + std::to_string(p) + ", r = " + std::to_string(r) + ", n = " + std::to_string(n) +
                    ", N = 2M = " + std::to_string(N) + "; Algorithm 1 needs p > 2n, r >= 2n, p + r <= N)");
  };
  if (p < 1 || r < 1) fail("p and r must be positive");
  if (p <= 2 * n) fail("p must exceed 2n");
  if (r < 2 * n) fail("r must be at least 2n");
  if (static_cast<long long>(p) + r > N) fail("data too short: p + r exceeds N");
}

namespace {

// Buffers of the transforms, kept per thread and grown on demand: a second
// identification of the same size then touches no fresh pages (at M = 10^6 the
// page faults of two new 16 MB arrays cost about half an FFT).
struct FftWorkspace {
  numerics::ComplexBuffer in;
  numerics::RealBuffer out;
  size_t in_size = 0, out_size = 0;
};

// Steps 1-2 without the 1/N factor: returns the (m*m) x N column-major array
// N ŝ_k (valid until the next call on this thread).
const double* unscaled_fourier_coefficients(const SpectrumData& data, Extension ext) {
  const int m = data.m, M = data.M, N = 2 * M, mm = m * m;
  if (M < 1) throw Error(ErrorKind::Dimension, "step 1", "need at least 2 spectrum samples (M >= 1)");
  thread_local FftWorkspace ws;
  const size_t in_size = static_cast<size_t>(mm) * (M + 1), out_size = static_cast<size_t>(mm) * N;
  if (ws.in_size < in_size) {
    ws.in = numerics::alloc_complex(in_size);
    ws.in_size = ws.in ? in_size : 0;
  }
  if (ws.out_size < out_size) {
    ws.out = numerics::alloc_real(out_size);
    ws.out_size = ws.out ? out_size : 0;
  }
  if (!ws.in || !ws.out)
    throw Error(ErrorKind::Numerical, "step 1", "out of memory for the FFT of length " + std::to_string(N));
  // Input of the complex-to-real transforms: M+1 Hermitian-extended samples per entry.
  for (int k = 0; k <= M; ++k)
    for (int b = 0; b < m; ++b)
      for (int a = 0; a < m; ++a) {
        const cplx v = ext == Extension::HermitianPart ? 0.5 * (data.at(a, b, k) + std::conj(data.at(b, a, k)))
                                                       : data.at(a, b, k);
        ws.in[static_cast<size_t>(k) * mm + a + m * b] = v;
      }
  // Eq. (20): ŝ_k = (1/N) sum_j e^{+i 2π jk/N} S_j is FFTW's unnormalised backward
  // transform; c2r reads samples 0..M and supplies S_{N-j} = conj(S_j).
  // Plans are cached per (N, m^2) by numerics::c2r_many and executed on these
  // (FFTW-aligned) arrays with the new-array interface, which is thread-safe.
  numerics::c2r_many(N, mm, ws.in.get(), ws.out.get(), "step 2");
  return ws.out.get();
}

// Block (k, l), 1-based, is ŝ_{offset + k + l - 1}; shat is (m*m) x N column-major.
Eigen::MatrixXd hankel(const double* shat, int m, int p, int r, int offset) {
  Eigen::MatrixXd H(p * m, r * m);
  const auto mm = static_cast<size_t>(m) * m;
  for (int l = 0; l < r; ++l)
    for (int k = 0; k < p; ++k)
      H.block(k * m, l * m, m, m) = Eigen::Map<const Eigen::MatrixXd>(shat + mm * (offset + k + l + 1), m, m);
  return H;
}

// Eq. (19) and Eq. (13) on a raw coefficient array of N columns.
Eigen::MatrixXd akcay_matrix(const double* shat, int N, int m, int p, int r) {
  return hankel(shat, m, p, r, 0) + hankel(shat, m, p, r, N - p - r);
}

}  // namespace

Eigen::MatrixXd fourier_coefficients(const SpectrumData& data, Extension ext) {
  const int N = 2 * data.M;
  return Eigen::Map<const Eigen::MatrixXd>(unscaled_fourier_coefficients(data, ext), data.m * data.m, N) /
         static_cast<double>(N);
}

Eigen::MatrixXd akcay_matrix(const Eigen::MatrixXd& shat, int m, int p, int r) {
  return akcay_matrix(shat.data(), static_cast<int>(shat.cols()), m, p, r);
}

Eigen::MatrixXd van_overschee_matrix(const Eigen::MatrixXd& shat, int m, int p, int r) {
  return hankel(shat.data(), m, p, r, 0);
}

Eigen::MatrixXd shift_matrix(const Eigen::MatrixXd& U2n, int m) {
  const auto rows = U2n.rows() - m;  // (p - 1) m: J_d drops the last block row, J_u the first
  return U2n.topRows(rows).householderQr().solve(U2n.bottomRows(rows));
}

int order_from_singular_values(const Eigen::VectorXd& sv, int n_max, int& gap_index, double& gap_ratio) {
  int best = 0;
  gap_ratio = 0.0;
  // Singular values below the rounding level of the SVD, sqrt(size) u sigma_1,
  // are zero to working precision; ratios between them carry no information.
  const double floor = std::sqrt(static_cast<double>(sv.size())) * kUnitRoundoff * (sv.size() ? sv(0) : 0.0);
  for (int n = 1; n <= n_max && 2 * n < sv.size(); ++n) {
    const double ratio = std::max(sv(2 * n - 1), floor) / std::max({sv(2 * n), floor, std::numeric_limits<double>::min()});
    if (ratio > gap_ratio) {
      gap_ratio = ratio;
      best = n;
    }
  }
  if (best == 0) throw Error(ErrorKind::Order, "step 4", "too few singular values to read an order from");
  gap_index = 2 * best;
  return best;
}

SpectrumResult identify_spectrum(const SpectrumData& data, const SpectrumOptions& opt) {
  const int m = data.m, M = data.M, N = 2 * M;
  if (m < 1) throw Error(ErrorKind::Input, "spectrum", "need at least one channel");
  if (data.S.rows() != m * m || data.S.cols() != M + 1)
    throw Error(ErrorKind::Input, "spectrum", "sample matrix is not (m*m) x (M+1)");
  if (!data.S.allFinite()) throw Error(ErrorKind::Input, "spectrum", "a sample is NaN or infinite");
  if (opt.order < 0) throw Error(ErrorKind::Order, "step 4", "order must be positive");

  SpectrumResult res;
  res.method = opt.method;
  res.extension = opt.extension;
  res.N = N;
  int p = opt.p, r = opt.r;
  {
    int dp, dr;
    default_pr(M, opt.order, dp, dr);
    if (p == 0) p = dp;
    if (r == 0) r = dr;
  }
  check_pr(N, std::max(opt.order, 1), p, r);
  // Work and memory before anything large is allocated: the SVD of step 3 is
  // O((pm)² rm) and holds 𝒴 and its factors (3 (pm)(rm) doubles); steps 1-2
  // hold N m² complex inputs and real outputs; step 8 works on M+1 samples.
  {
    const double pm = double(p) * m, rm = double(r) * m;
    if (pm > kMaxSvdDimension || rm > kMaxSvdDimension)
      throw Error(ErrorKind::Resource, "step 3",
                  "the SVD of a " + std::to_string(static_cast<long long>(pm)) + " x " +
                      std::to_string(static_cast<long long>(rm)) + " matrix is beyond the supported " +
                      std::to_string(kMaxSvdDimension) + " (p m and r m; its O((pm)^2 rm) work would not finish)");
    require_memory(8.0 * (3 * pm * rm + 3.0 * N * m * m + 4.0 * (M + 1) * m * m), "identify-spectrum",
                   "Algorithm 1 with M = " + std::to_string(M) + ", m = " + std::to_string(m) + ", p = " +
                       std::to_string(p) + ", r = " + std::to_string(r));
  }
  res.p = p;
  res.r = r;

  // Steps 1-2: extension and inverse DFT (Eq. 20).
  const double* shat_N = unscaled_fourier_coefficients(data, opt.extension);  // N ŝ_k
  // ŝ_0 is the zero-lag covariance R_0 = E + aliasing (Eq. 20 at k = 0): a power
  // spectrum has a positive definite one. Individual noisy samples may dip below
  // zero where S is small (Section 4's data do), so this is the check on the data.
  {
    const Eigen::Map<const Eigen::MatrixXd> s0(shat_N, m, m);
    const Eigen::MatrixXd h = 0.5 * (s0 + s0.transpose());
    const double l0 = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(h, Eigen::EigenvaluesOnly).eigenvalues()(0);
    if (!(l0 > 0.0))
      throw Error(ErrorKind::Positivity, "step 2",
                  "data are not a power spectrum: the mean of the samples (zero-lag covariance) is not positive "
                  "definite (smallest eigenvalue " + fmt(l0, 4) + ")");
  }
  // Step 3: SVD of 𝒴 (Eq. 19) or of Ĝ_p F_r (Eq. 13).
  const Eigen::MatrixXd Y = (opt.method == Method::Akcay2011 ? akcay_matrix(shat_N, N, m, p, r)
                                                             : hankel(shat_N, m, p, r, 0)) /
                            static_cast<double>(N);
  // One-sided Jacobi (with QR preconditioning), not BDCSVD: Eigen 3.4.0's
  // divide-and-conquer returned σ_{2n} wrong in the 4th digit on a 100 x 100 𝒴
  // with pairs of equal singular values (a symmetric MIMO case found by the
  // property suite), which ruined interpolation. Jacobi is accurate to high
  // relative accuracy and costs ~1 ms at 50 x 50.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Y, Eigen::ComputeThinU);
  res.singular_values = svd.singularValues();

  // Step 4: order.
  int n = opt.order;
  if (n == 0) {
    const int n_max = std::min((p - 1) / 2, r / 2);
    n = order_from_singular_values(res.singular_values, n_max, res.gap_index, res.gap_ratio);
    res.order_from_data = true;
  } else {
    res.gap_index = 2 * n;
    res.gap_ratio = 2 * n < res.singular_values.size()
                        ? res.singular_values(2 * n - 1) / std::max(res.singular_values(2 * n), 1e-300)
                        : std::numeric_limits<double>::infinity();
  }
  check_pr(N, n, p, r);
  res.order = n;
  const Eigen::MatrixXd U = svd.matrixU().leftCols(2 * n);

  // Step 5: Ã from the shift equations.
  const Eigen::MatrixXd Atilde = shift_matrix(U, m);
  if (!Atilde.allFinite()) throw Error(ErrorKind::Numerical, "step 5", "shift equations gave a non-finite A");

  // Step 6: eigen-decomposition of Ã and the split |λ| < 1 (causal) / > 1.
  Eigen::EigenSolver<Eigen::MatrixXd> es(Atilde);
  if (es.info() != Eigen::Success) throw Error(ErrorKind::Split, "step 6", "eigen-decomposition of A did not converge");
  const Eigen::VectorXcd lambda = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();
  const Eigen::MatrixXcd W = V.inverse();  // rows: left eigenvectors with y_i^H x_i = 1
  const double normA = Atilde.norm();
  std::vector<int> stable;
  double margin = std::numeric_limits<double>::infinity();
  std::ostringstream moduli;
  for (int i = 0; i < 2 * n; ++i) {
    const double mod = std::abs(lambda(i));
    const double kappa = V.col(i).norm() * W.row(i).norm();  // eigenvalue condition number
    // |λ| can only be trusted to about κ u ||Ã||: a split closer than 10 times that
    // to the circle is not a split.
    const double resolution = 10.0 * kappa * kUnitRoundoff * normA;
    margin = std::min(margin, std::abs(mod - 1.0));
    if (std::abs(mod - 1.0) <= resolution || !std::isfinite(mod)) {
      throw Error(ErrorKind::Split, "step 6",
                  "eigenvalue " + fmt(lambda(i).real(), 10) + (lambda(i).imag() < 0 ? "" : "+") +
                      fmt(lambda(i).imag(), 10) + "i of A has modulus " + fmt(mod, 12) +
                      ", within its rounding error " + fmt(resolution, 3) + " of the unit circle");
    }
    moduli << (i ? ", " : "") << fmt(mod, 4);
    if (mod < 1.0) stable.push_back(i);
  }
  res.split_margin = margin;
  if (static_cast<int>(stable.size()) != n)
    throw Error(ErrorKind::Split, "step 6",
                "no stable/antistable split: " + std::to_string(stable.size()) + " of the 2n = " +
                    std::to_string(2 * n) + " eigenvalues of A lie inside the unit circle, n = " + std::to_string(n) +
                    " needed (moduli " + moduli.str() + ")");

  // Step 7: Â = Σ_c and Ĉ = J_f U_{2n} Π_c, in the real block-diagonal basis
  // T = [x] for real λ, [Re x, Im x] for λ = a + ib, b > 0 (Ã x = λ x gives
  // Ã [Re x, Im x] = [Re x, Im x] [[a, b], [-b, a]]).
  Eigen::MatrixXd T(2 * n, n);
  std::vector<Block> blocks;
  Eigen::MatrixXd Ahat = Eigen::MatrixXd::Zero(n, n);
  int col = 0;
  for (int i : stable) {
    const cplx l = lambda(i);
    if (l.imag() == 0.0) {
      Eigen::VectorXd x = V.col(i).real();
      T.col(col) = x / x.norm();
      Ahat(col, col) = l.real();
      blocks.push_back({col, 1, l.real(), 0.0});
      ++col;
    } else if (l.imag() > 0.0) {
      if (col + 2 > n)
        throw Error(ErrorKind::Split, "step 6", "complex eigenvalue without its conjugate among the stable ones");
      const double s = V.col(i).norm();
      T.col(col) = V.col(i).real() / s;
      T.col(col + 1) = V.col(i).imag() / s;
      Ahat(col, col) = l.real();
      Ahat(col, col + 1) = l.imag();
      Ahat(col + 1, col) = -l.imag();
      Ahat(col + 1, col + 1) = l.real();
      blocks.push_back({col, 2, l.real(), l.imag()});
      col += 2;
    }
  }
  if (col != n) throw Error(ErrorKind::Split, "step 6", "stable eigenvalues do not form conjugate pairs");
  const Eigen::MatrixXd Chat = U.topRows(m) * T;

  // Step 8: Ê, F̂ by least squares over all M+1 samples (chunked Householder QR).
  SummandDesign design(Chat, blocks, m);
  const int q = design.unknowns(), rps = design.rows_per_sample();
  // R of the augmented design [Φ | y] by the streamed QR (numerics/qr.hpp), one
  // group per grid sample, one block (the fill walks the grid per chunk) and
  // 1024 rows per chunk, the chunking this step has always used.
  if (static_cast<long long>(M + 1) * rps < q)
    throw Error(ErrorKind::Dimension, "step 8", "fewer equations than unknowns in the E, F fit");
  numerics::StreamedQrOptions qr_options;
  qr_options.rows_per_chunk = 1024;
  qr_options.flops_per_block = 0;
  const numerics::ChunkFill fill = [&](int k0, int k1, Eigen::Ref<Eigen::MatrixXd> rows) {
    Eigen::VectorXd y(rps);
    GridWalker grid(k0, M);
    for (int j = 0; j < k1 - k0; ++j, grid.next()) {
      auto blk = rows.middleRows(j * rps, rps);
      design.rows(grid.z(), &data, k0 + j, blk.leftCols(q), y);
      blk.col(q) = y;
    }
  };
  const Eigen::MatrixXd R = numerics::streamed_qr_r(M + 1, rps, q + 1, fill, qr_options);
  const Eigen::MatrixXd Rq = R.topLeftCorner(q, q);
  const Eigen::VectorXd rdiag = Rq.diagonal().cwiseAbs();
  const double rmax = rdiag.maxCoeff(), rmin = rdiag.minCoeff();
  // Rank test of numerics/rank.hpp with size factor 10 (floor 1e3·u·max|r_ii|,
  // the value this step has always used). The √rows factor of the Householder
  // bound would be √((M+1)·rps), larger than 10 whenever (M+1)·rps > 100; it is
  // kept at 10 so that no result changes (see the numerics layer's report).
  if (!numerics::numerically_full_rank(rdiag, 10.0))
    throw Error(ErrorKind::Numerical, "step 8", "E, F least-squares problem is rank deficient (|r_min|/|r_max| = " +
                                                    fmt(rmin / rmax, 3) + ")");
  const Eigen::VectorXd theta = Rq.triangularView<Eigen::Upper>().solve(R.col(q).head(q));

  SpectralSummands& s = res.summands;
  s.A = Ahat;
  s.C = Chat;
  s.F = Eigen::Map<const Eigen::MatrixXd>(theta.data(), n, m);
  s.E.resize(m, m);
  for (int a = 0; a < m; ++a)
    for (int b = a; b < m; ++b) s.E(a, b) = s.E(b, a) = theta(n * m + design.e_position(a, b));

  // Ŝ must be positive on the grid, or no spectral factor exists.
  {
    Eigen::MatrixXd D(rps, q);
    Eigen::VectorXd values(rps);
    double worst = std::numeric_limits<double>::infinity();
    int worst_k = 0;
    GridWalker grid(0, M);
    for (int k = 0; k <= M; ++k, grid.next()) {
      double v;
      if (m == 1) {  // Ŝ(z_k) = row · θ, without the general path's temporaries
        design.scalar_row(grid.z(), D.data(), 1);
        v = D.row(0).dot(theta);
      } else {
        design.rows(grid.z(), nullptr, k, D, values);
        values.noalias() = D * theta;
        v = min_hermitian_eigenvalue(unpack_hermitian(values, m));
      }
      if (v < worst) {
        worst = v;
        worst_k = k;
      }
    }
    res.min_spectrum = worst;
    if (!(worst > 0.0))
      throw Error(ErrorKind::Positivity, "step 8",
                  "estimated spectrum is not positive on the grid: smallest eigenvalue " + fmt(worst, 4) +
                      " at omega = " + fmt(M_PI * worst_k / M, 6) + " rad/sample (k = " + std::to_string(worst_k + 1) +
                      ")");
  }
  {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eE(s.E, Eigen::EigenvaluesOnly);
    if (!(eE.eigenvalues()(0) > 0.0))
      throw Error(ErrorKind::Positivity, "step 9", "E is not positive definite (smallest eigenvalue " +
                                                       fmt(eE.eigenvalues()(0), 4) + ")");
  }

  // Step 9: Riccati equation (numerics/riccati.hpp: SDA, else the Riccati
  // difference iteration).
  const numerics::RiccatiOptions riccati_options;
  numerics::RiccatiSolution sol = numerics::solve_spectral_riccati(s, riccati_options);
  res.riccati_method = sol.method;
  const int its = sol.iterations;
  if (!sol.ok) throw Error(ErrorKind::Riccati, "step 9", "no stabilising solution found (SDA and Kalman iteration failed)");
  const Eigen::MatrixXd P = std::move(sol.P);
  s.P = P;
  res.riccati_iterations = its;
  res.riccati_residual = numerics::riccati_residual(s, P);
  const Eigen::MatrixXd Rinn = s.E - s.C * P * s.C.transpose();
  {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eR(Rinn, Eigen::EigenvaluesOnly);
    if (!(eR.eigenvalues()(0) > 0.0))
      throw Error(ErrorKind::Positivity, "step 9",
                  "E - C P C^T is not positive definite (smallest eigenvalue " + fmt(eR.eigenvalues()(0), 4) + ")");
  }
  Eigen::MatrixXd Dhat, Dinv;
  sqrt_spd(Rinn, Dhat, Dinv);
  StateSpace& g = res.model;
  g.domain = Domain::Discrete;
  g.sample_time = 1.0;
  g.A = Ahat;
  g.C = Chat;
  g.B = (s.F - Ahat * P * Chat.transpose()) * Dinv;
  g.D = Dhat;
  if (!g.B.allFinite() || !g.D.allFinite())
    throw Error(ErrorKind::Numerical, "step 9", "B or D is not finite");
  // The stabilising solution makes Ĝ minimum phase: the zeros, eig(Â - B̂ D̂^{-1} Ĉ),
  // lie inside the circle. If they do not, the Riccati equation had no stabilising
  // solution -- the fitted spectrum is not positive on the whole circle, only on
  // the grid -- and no spectral factor exists.
  {
    const Eigen::MatrixXd Z = Ahat - g.B * Dinv * Chat;
    const double zmax = n > 0 ? Z.eigenvalues().cwiseAbs().maxCoeff() : 0.0;
    res.max_zero_modulus = zmax;
    if (!(zmax < 1.0))
      throw Error(ErrorKind::Riccati, "step 9",
                  "no stabilising solution: the spectral factor has a zero of modulus " + fmt(zmax, 12) +
                      " (the estimated spectrum is not positive between the grid points)");
  }
  // Step 10's companion: say where double precision may have lost accuracy.
  {
    const Eigen::Index i2n = std::min<Eigen::Index>(2 * n, res.singular_values.size()) - 1;
    const double ratio = i2n >= 0 && res.singular_values(i2n) > 0 ? res.singular_values(0) / res.singular_values(i2n)
                                                                  : std::numeric_limits<double>::infinity();
    // Steps 8-9 solve Stein/Riccati-type equations in Â, whose operator
    // P ↦ P − Â P Âᵀ has condition ≥ 1/(1 − ρ(Â)²) (its smallest singular value
    // is at most 1 − ρ²): near the circle that amplifies the error of 𝒴's range.
    double kappa = 1.0;
    if (n > 0) {
      const double rho = Ahat.eigenvalues().cwiseAbs().maxCoeff();
      kappa = rho < 1.0 ? 1.0 / (1.0 - rho * rho) : std::numeric_limits<double>::infinity();
    }
    res.error_estimate = double_precision_spectrum_tolerance(p, r, m, N, ratio) * kappa;
    if (!(res.error_estimate <= 1e-6))
      res.warnings.push_back("double precision may have lost accuracy: estimated relative error " +
                             fmt(res.error_estimate, 3) + " (sigma_1/sigma_2n = " + fmt(ratio, 3) +
                             ", 1/(1 - rho^2) = " + fmt(kappa, 3) + "); compare with --precision high");
    if (res.order_from_data && 2 * n < res.singular_values.size() &&
        res.singular_values(2 * n) / res.singular_values(0) > res.error_estimate)
      res.warnings.push_back("order read from the data: sigma_" + std::to_string(2 * n + 1) + "/sigma_1 = " +
                             fmt(res.singular_values(2 * n) / res.singular_values(0), 3) +
                             " is above the accuracy estimate, so a weak mode may have been left out");
    if (n > 0 && res.split_margin < 1e-3)
      res.warnings.push_back("poles within " + fmt(res.split_margin, 3) +
                             " of the unit circle: the split of step 6 and the poles are ill-conditioned");
    // The text names the default accept_residual, 1e-8 (riccati.hpp).
    if (res.riccati_residual > riccati_options.accept_residual)
      res.warnings.push_back("Riccati residual " + fmt(res.riccati_residual, 3) + " above 1e-8 (step 9)");
  }
  return res;
}

}  // namespace fdsid
