// Akçay (2011) Algorithm 1 and Van Overschee et al. (1997), double precision.
#include "fdsid/spectrum_id.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "fdsid/compare.hpp"
#include "fdsid/error.hpp"
#include "numerics/complex.hpp"
#include "numerics/constants.hpp"
#include "numerics/fft.hpp"
#include "fdsid/format.hpp"
#include "numerics/qr.hpp"
#include "numerics/rank.hpp"
#include "numerics/riccati.hpp"
#include "numerics/eigen_instances.hpp"

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

// 1/w: numerics::reciprocal; |w| is bounded away from 0 and infinity here
// (|z| = 1, |λ| < 1).
using numerics::reciprocal;

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

  // m = 1: rows j = 0 … count−1 of D, the rows [2 Re χ(z_j), 1] of the
  // points z_j = re[j] + i im[j], written column by column (D column-major:
  // each column's loop over the points is contiguous and vectorises).
  // In real arithmetic (std::complex products go through NaN-checking library
  // calls): with x + iy = z - a, a 2x2 block has det = u + iv, u = x^2 - y^2 + b^2,
  // v = 2xy, and Re((z-a)/det) = (xu + yv)/|det|^2, Re(b/det) = b u/|det|^2
  // (the formulas of resolvent_row).
  void scalar_rows(const double* re, const double* im, int count, Eigen::Ref<Eigen::MatrixXd> D) const {
    for (const Block& bl : blocks_) {
      double* __restrict out0 = &D(0, bl.start);
      if (bl.size == 1) {
        const double c = 2.0 * C_(0, bl.start), a = bl.a;
        for (int j = 0; j < count; ++j) {
          const double x = re[j] - a, y = im[j];
          out0[j] = c * x / (x * x + y * y);
        }
      } else {
        double* __restrict out1 = &D(0, bl.start + 1);
        const double c0 = C_(0, bl.start), c1 = C_(0, bl.start + 1), a = bl.a, b = bl.b;
        for (int j = 0; j < count; ++j) {
          const double x = re[j] - a, y = im[j];
          const double u = x * x - y * y + b * b, v = 2.0 * x * y;
          const double id = 1.0 / (u * u + v * v);
          const double r11 = (x * u + y * v) * id, r12 = b * u * id;
          out0[j] = 2.0 * (c0 * r11 - c1 * r12);
          out1[j] = 2.0 * (c0 * r12 + c1 * r11);
        }
      }
    }
    D.col(n_).head(count).setOnes();
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

// The grid points z_k = e^{iπk/M} as z_k = a_b t_j, k = 64 b + j, with
// a_b = e^{iπ·64b/M} and t_j = e^{iπj/M} from std::polar: sin and cos run
// once per 64 points (and 64 times per grid for the table), each z_k is within
// ~3u of e^{iπk/M}, and it depends on k alone, not on where a range of points
// starts: a split of the grid between threads computes the same z_k.
class UnitGrid {
 public:
  explicit UnitGrid(int M) : M_(M) {
    for (int j = 0; j < 64; ++j) table_[j] = std::polar(1.0, M_PI * j / M);
  }
  // z_k for k = k0 … k0 + count − 1 into re[0 …], im[0 …].
  void points(int k0, int count, double* re, double* im) const {
    for (int k = k0; k < k0 + count;) {
      const int base = k & ~63, end = std::min(k0 + count, base + 64);
      const cplx a = std::polar(1.0, M_PI * base / M_);
      for (; k < end; ++k) {
        const cplx t = table_[k - base];
        re[k - k0] = a.real() * t.real() - a.imag() * t.imag();
        im[k - k0] = a.real() * t.imag() + a.imag() * t.real();
      }
    }
  }

 private:
  int M_;
  cplx table_[64];
};

// The points of a range of the grid in pieces of at most kGridPiece: the
// arrays of UnitGrid::points, kept per object (one per thread).
constexpr int kGridPiece = 1024;
struct GridPiece {
  double re[kGridPiece], im[kGridPiece];
  cplx z(int j) const { return {re[j], im[j]}; }
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

const NameTable<Method>& method_names() {
  static const NameTable<Method> names{{"akcay2011", Method::Akcay2011}, {"vo1997", Method::VanOverschee1997}};
  return names;
}
const NameTable<Extension>& extension_names() {
  static const NameTable<Extension> names{{"hermitian-part", Extension::HermitianPart},
                                          {"conjugate", Extension::Conjugate}};
  return names;
}
const char* to_string(Method m) { return name_of(method_names(), m); }
const char* to_string(Extension e) { return name_of(extension_names(), e); }

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

namespace {

// Sizes of one identification: m channels, M+1 samples, N = 2M, and the p, r of 𝒴.
struct Dims {
  int m, M, N, p, r;
};

// The samples' real and imaginary parts as one array (std::complex<double> is
// two doubles, real first): the input checks scan it in vector registers.
Eigen::Map<const Eigen::ArrayXd> sample_parts(const SpectrumData& data) {
  return {reinterpret_cast<const double*>(data.S.data()), 2 * data.S.size()};
}

// Input checks and defaults.
//
// Purpose: validate the samples and the options, and fix p and r.
// Method: p, r from default_pr() where the options leave them 0, then the
// inequalities of step 2 (check_pr) with n = max(order, 1).
// Numerical aspects: the work and memory of steps 1-3 and 8 are estimated
// before anything large is allocated: the SVD of step 3 is O((pm)² rm) and
// holds 𝒴 and its factors (3 (pm)(rm) doubles); steps 1-2 hold N m² complex
// inputs and real outputs; step 8 works on M+1 samples.
// Fails: Error(Input) on a malformed or non-finite sample matrix, Error(Order)
// on a negative order, Error(Dimension) from check_pr, Error(Resource) when
// the SVD or the memory would be beyond what fdsid supports.
Dims check_input(const SpectrumData& data, const SpectrumOptions& opt) {
  Dims d{data.m, data.M, 2 * data.M, opt.p, opt.r};
  const int m = d.m, M = d.M, N = d.N;
  if (m < 1) throw Error(ErrorKind::Input, "spectrum", "need at least one channel");
  if (data.S.rows() != m * m || data.S.cols() != M + 1)
    throw Error(ErrorKind::Input, "spectrum", "sample matrix is not (m*m) x (M+1)");
  // Σ 0·x over the real and imaginary parts is 0 exactly when every part is
  // finite (0·±inf and 0·NaN are NaN, 0·x = ±0 otherwise, never an overflow);
  // Eigen sums it in vector registers, where allFinite on complex entries is
  // a scalar loop with a branch per part (~0.1 ms at M = 32000: perf, issue 16).
  if (!((sample_parts(data) * 0.0).sum() == 0.0))
    throw Error(ErrorKind::Input, "spectrum", "a sample is NaN or infinite");
  if (opt.order < 0) throw Error(ErrorKind::Order, "step 4", "order must be positive");
  int dp, dr;
  default_pr(M, opt.order, dp, dr);
  if (d.p == 0) d.p = dp;
  if (d.r == 0) d.r = dr;
  const int p = d.p, r = d.r;
  check_pr(N, std::max(opt.order, 1), p, r);
  const double pm = double(p) * m, rm = double(r) * m;
  if (pm > kMaxSvdDimension || rm > kMaxSvdDimension)
    throw Error(ErrorKind::Resource, "step 3",
                "the SVD of a " + std::to_string(static_cast<long long>(pm)) + " x " +
                    std::to_string(static_cast<long long>(rm)) + " matrix is beyond the supported " +
                    std::to_string(kMaxSvdDimension) + " (p m and r m; its O((pm)^2 rm) work would not finish)");
  require_memory(8.0 * (3 * pm * rm + 3.0 * N * m * m + 4.0 * (M + 1) * m * m), "identify-spectrum",
                 "Algorithm 1 with M = " + std::to_string(M) + ", m = " + std::to_string(m) + ", p = " +
                     std::to_string(p) + ", r = " + std::to_string(r));
  return d;
}

// Steps 1-2: extension of the M+1 samples to N and inverse DFT (Eq. 20).
//
// Purpose: the Fourier coefficients N ŝ_k, k = 0..N-1, as an (m*m) x N
// column-major array (valid until the next call on this thread).
// Method: unscaled_fourier_coefficients (one FFTW complex-to-real transform
// per entry). ŝ_0 is the zero-lag covariance R_0 = E + aliasing (Eq. 20 at
// k = 0): a power spectrum has a positive definite one. Individual noisy
// samples may dip below zero where S is small (Section 4's data do), so this
// is the check on the data.
// Fails: Error(Positivity) when the symmetric part of ŝ_0 is not positive
// definite; Error(Dimension) or Error(Numerical) from the transform.
// References: Akçay (2011) Algorithm 1 steps 1-2, Eq. (20).
const double* step1_2_fourier_coefficients(const SpectrumData& data, Extension ext) {
  const int m = data.m;
  const double* shat_N = unscaled_fourier_coefficients(data, ext);
  const Eigen::Map<const Eigen::MatrixXd> s0(shat_N, m, m);
  const Eigen::MatrixXd h = 0.5 * (s0 + s0.transpose());
  const double l0 = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(h, Eigen::EigenvaluesOnly).eigenvalues()(0);
  if (!(l0 > 0.0))
    throw Error(ErrorKind::Positivity, "step 2",
                "data are not a power spectrum: the mean of the samples (zero-lag covariance) is not positive "
                "definite (smallest eigenvalue " + fmt(l0, 4) + ")");
  return shat_N;
}

// The range space of step 3: the singular values and the thin left factor.
struct RangeSpace {
  Eigen::VectorXd singular_values;
  Eigen::MatrixXd U;
};

// Step 3: SVD of 𝒴 (Eq. 19) or of Ĝ_p F_r (Eq. 13).
//
// Purpose: the singular values and left singular vectors of the pm x rm matrix.
// Method: 𝒴 is a sum of two block Hankel matrices of the Fourier coefficients
// (Eq. 19); Van Overschee et al. use the first alone (Eq. 13). When 𝒴 is
// symmetric (p = r and symmetric m x m blocks: every SISO spectrum), its SVD
// is its eigen-decomposition, σ_i = |λ_i| and u_i the eigenvector (the sign of
// λ_i goes to v_i, which is not used): Householder tridiagonalisation and
// implicit symmetric QR (Eigen's SelfAdjointEigenSolver), 0.19 ms at 50 x 50
// against 1.3 ms for Jacobi (measured, noisy Section 4 data; Jacobi's sweeps
// were 91 % of identify_spectrum at M = 1000). Otherwise one-sided Jacobi.
// Numerical aspects: both are backward stable: the values are exact for
// 𝒴 + E with ‖E‖₂ ≤ c·size·u·σ₁, so |σ̂_i − σ_i| ≤ c·size·u·σ₁ (Weyl) and the
// span of the first k vectors is accurate to c·size·u·σ₁/(σ_k − σ_{k+1}): the
// accuracy step 4 assumes (its floor √size·u·σ₁). Jacobi's high relative
// accuracy of the smallest σ_i holds for graded matrices only, and the
// Fourier coefficients carry errors of u·|ŝ| already. Not BDCSVD: Eigen
// 3.4.0's divide-and-conquer returned σ_{2n} wrong in the 4th digit on a
// 100 x 100 𝒴 with pairs of equal singular values (a symmetric MIMO case
// found by the property suite), which ruined interpolation.
// References: Akçay (2011) Eqs. (13), (19); Van Overschee et al. (1997);
// Golub & Van Loan (2013), Sections 8.1.2 (Weyl), 8.3 (symmetric QR).
RangeSpace step3_range_space(const double* shat_N, Method method, const Dims& d) {
  const Eigen::MatrixXd Y = (method == Method::Akcay2011 ? akcay_matrix(shat_N, d.N, d.m, d.p, d.r)
                                                         : hankel(shat_N, d.m, d.p, d.r, 0)) /
                            static_cast<double>(d.N);
  if (Y.rows() == Y.cols() && Y == Y.transpose()) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Y);
    if (es.info() == Eigen::Success) {
      const Eigen::Index size = Y.rows();
      std::vector<Eigen::Index> order(static_cast<size_t>(size));
      std::iota(order.begin(), order.end(), Eigen::Index{0});
      const Eigen::VectorXd& lambda = es.eigenvalues();
      std::stable_sort(order.begin(), order.end(),
                       [&](Eigen::Index a, Eigen::Index b) { return std::abs(lambda(a)) > std::abs(lambda(b)); });
      RangeSpace out{Eigen::VectorXd(size), Eigen::MatrixXd(size, size)};
      for (Eigen::Index i = 0; i < size; ++i) {
        out.singular_values(i) = std::abs(lambda(order[static_cast<size_t>(i)]));
        out.U.col(i) = es.eigenvectors().col(order[static_cast<size_t>(i)]);
      }
      return out;
    }
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Y, Eigen::ComputeThinU);
  return {svd.singularValues(), svd.matrixU()};
}

// The order of step 4 and the singular-value gap it was read at.
struct Order {
  int n = 0;
  bool from_data = false;
  int gap_index = 0;
  double gap_ratio = 0.0;
};

// Step 4: the order n.
//
// Purpose: n given by the options, or read from the singular values (𝒴 has
// rank 2n).
// Method: order_from_singular_values (the largest σ_{2n}/σ_{2n+1} for
// n <= min((p-1)/2, r/2)); for a given n, the ratio at 2n is reported
// (infinite when σ_{2n+1} does not exist).
// Fails: Error(Order) when no order can be read; Error(Dimension) when the
// order violates p > 2n, r >= 2n (check_pr).
// References: Akçay (2011) Algorithm 1 step 4.
Order step4_order(const Eigen::VectorXd& sv, int given, const Dims& d) {
  Order o;
  o.n = given;
  if (o.n == 0) {
    const int n_max = std::min((d.p - 1) / 2, d.r / 2);
    o.n = order_from_singular_values(sv, n_max, o.gap_index, o.gap_ratio);
    o.from_data = true;
  } else {
    const int n = o.n;
    o.gap_index = 2 * n;
    o.gap_ratio = 2 * n < sv.size() ? sv(2 * n - 1) / std::max(sv(2 * n), 1e-300)
                                    : std::numeric_limits<double>::infinity();
  }
  check_pr(d.N, o.n, d.p, d.r);
  return o;
}

// Step 5: Ã from the shift equations.
//
// Purpose: the 2n x 2n matrix Ã with J_u U_{2n} = J_d U_{2n} Ã.
// Method: shift_matrix (Householder QR of J_d U_{2n}).
// Fails: Error(Numerical) when Ã is not finite.
// References: Akçay (2011) Algorithm 1 step 5.
Eigen::MatrixXd step5_shift_equations(const Eigen::MatrixXd& U2n, int m) {
  Eigen::MatrixXd Atilde = shift_matrix(U2n, m);
  if (!Atilde.allFinite()) throw Error(ErrorKind::Numerical, "step 5", "shift equations gave a non-finite A");
  return Atilde;
}

// The eigen-decomposition of step 6 and the indices of its stable part.
struct Split {
  Eigen::VectorXcd lambda;
  Eigen::MatrixXcd V;
  std::vector<int> stable;  // i with |λ_i| < 1
  double margin = std::numeric_limits<double>::infinity();  // min | |λ_i| - 1 |
};

// Step 6: eigen-decomposition of Ã and the split |λ| < 1 (causal) / > 1.
//
// Purpose: the n eigenvalues of Ã inside the unit circle and their eigenvectors.
// Method: Eigen::EigenSolver; the left eigenvectors (rows of V^{-1}, with
// y_i^H x_i = 1) give the eigenvalue condition numbers κ_i = ||x_i|| ||y_i||.
// Numerical aspects: |λ_i| can only be trusted to about κ_i u ||Ã||: a split
// closer than 10 times that to the circle is not a split.
// Fails: Error(Split) when the decomposition does not converge, an eigenvalue
// lies within its rounding error of the circle (or is not finite), or not
// exactly n of the 2n eigenvalues lie inside.
// References: Akçay (2011) Algorithm 1 step 6.
Split step6_stable_split(const Eigen::MatrixXd& Atilde, int n) {
  Eigen::EigenSolver<Eigen::MatrixXd> es(Atilde);
  if (es.info() != Eigen::Success) throw Error(ErrorKind::Split, "step 6", "eigen-decomposition of A did not converge");
  Split sp;
  sp.lambda = es.eigenvalues();
  sp.V = es.eigenvectors();
  const Eigen::VectorXcd& lambda = sp.lambda;
  const Eigen::MatrixXcd W = sp.V.inverse();  // rows: left eigenvectors with y_i^H x_i = 1
  const double normA = Atilde.norm();
  std::vector<double> moduli;
  for (int i = 0; i < 2 * n; ++i) {
    const double mod = std::abs(lambda(i));
    const double kappa = sp.V.col(i).norm() * W.row(i).norm();  // eigenvalue condition number
    const double resolution = 10.0 * kappa * kUnitRoundoff * normA;
    sp.margin = std::min(sp.margin, std::abs(mod - 1.0));
    if (std::abs(mod - 1.0) <= resolution || !std::isfinite(mod)) {
      throw Error(ErrorKind::Split, "step 6",
                  "eigenvalue " + fmt(lambda(i).real(), 10) + (lambda(i).imag() < 0 ? "" : "+") +
                      fmt(lambda(i).imag(), 10) + "i of A has modulus " + fmt(mod, 12) +
                      ", within its rounding error " + fmt(resolution, 3) + " of the unit circle");
    }
    moduli.push_back(mod);
    if (mod < 1.0) sp.stable.push_back(i);
  }
  if (static_cast<int>(sp.stable.size()) != n) {
    // At most 12 moduli, those nearest the circle (--order 100 printed 200).
    std::sort(moduli.begin(), moduli.end(),
              [](double a, double b) { return std::abs(std::log(a)) < std::abs(std::log(b)); });
    const size_t shown = std::min<size_t>(moduli.size(), 12);
    std::sort(moduli.begin(), moduli.begin() + static_cast<std::ptrdiff_t>(shown));
    std::ostringstream list;
    // Enough digits to show each modulus's side of the circle: 0.99998 at 4
    // digits read "1" and was called inside (a user review).
    for (size_t i = 0; i < shown; ++i) {
      const double off = std::abs(moduli[i] - 1.0);
      const int digits = off > 0 ? std::clamp(static_cast<int>(std::ceil(-std::log10(off))) + 2, 4, 17) : 17;
      list << (i ? ", " : "") << fmt(moduli[i], digits);
    }
    throw Error(ErrorKind::Split, "step 6",
                "no stable/antistable split: " + std::to_string(sp.stable.size()) + " of the 2n = " +
                    std::to_string(2 * n) + " eigenvalues of A lie inside the unit circle, n = " + std::to_string(n) +
                    " needed (moduli " + list.str() +
                    (shown < moduli.size() ? "; the " + std::to_string(shown) + " nearest the circle" : std::string()) +
                    ")");
  }
  return sp;
}

// Â, Ĉ of step 7 in the real block-diagonal basis, with the blocks of Â.
struct StableRealization {
  Eigen::MatrixXd A, C;
  std::vector<Block> blocks;
};

// Step 7: Â = Σ_c and Ĉ = J_f U_{2n} Π_c.
//
// Purpose: the stable part of Ã as a real pair (Â, Ĉ).
// Method: the real block-diagonal basis T = [x] for real λ, [Re x, Im x] for
// λ = a + ib, b > 0 (Ã x = λ x gives Ã [Re x, Im x] = [Re x, Im x] [[a, b],
// [-b, a]]), columns scaled to unit norm per eigenvector; Ĉ = (first block
// row of U_{2n}) T.
// Fails: Error(Split) when the stable eigenvalues do not form conjugate pairs.
// References: Akçay (2011) Algorithm 1 step 7.
StableRealization step7_A_C(const Split& sp, const Eigen::MatrixXd& U2n, int m, int n) {
  Eigen::MatrixXd T(2 * n, n);
  StableRealization sr;
  sr.A = Eigen::MatrixXd::Zero(n, n);
  int col = 0;
  for (int i : sp.stable) {
    const cplx l = sp.lambda(i);
    if (l.imag() == 0.0) {
      Eigen::VectorXd x = sp.V.col(i).real();
      T.col(col) = x / x.norm();
      sr.A(col, col) = l.real();
      sr.blocks.push_back({col, 1, l.real(), 0.0});
      ++col;
    } else if (l.imag() > 0.0) {
      if (col + 2 > n)
        throw Error(ErrorKind::Split, "step 6", "complex eigenvalue without its conjugate among the stable ones");
      const double s = sp.V.col(i).norm();
      T.col(col) = sp.V.col(i).real() / s;
      T.col(col + 1) = sp.V.col(i).imag() / s;
      sr.A(col, col) = l.real();
      sr.A(col, col + 1) = l.imag();
      sr.A(col + 1, col) = -l.imag();
      sr.A(col + 1, col + 1) = l.real();
      sr.blocks.push_back({col, 2, l.real(), l.imag()});
      col += 2;
    }
  }
  if (col != n) throw Error(ErrorKind::Split, "step 6", "stable eigenvalues do not form conjugate pairs");
  sr.C = U2n.topRows(m) * T;
  return sr;
}

// Step 8: Ê, F̂ by least squares over all M+1 samples.
//
// Purpose: θ = [vec F̂, Ê_ab for a <= b] minimising Σ_k ||Ŝ(z_k) - S_k||_F²,
// Ŝ = Ê + X + X^H, X = Ĉ (zI - Â)^{-1} F̂; writes Ê and F̂ into s.
// Method: the real design of SummandDesign, one group of rows per grid
// sample, reduced to R of the augmented design [Φ | y] by the streamed QR
// (numerics/qr.hpp): 1024 rows per chunk, the fill computing the chunk's grid
// points (UnitGrid) and, for m = 1, the design column by column (scalar_rows);
// blocks by its default work rule (≥ 2^24 flops each, fixed by M and q, so the
// result does not depend on the core count), which splits M = 10⁶ over both
// cores of a 2-core machine; θ by back substitution.
// Numerical aspects: the condition of Φ is not squared (no normal equations).
// The rank test is numerics/rank.hpp's with size factor 10 (floor
// 1e3·u·max|r_ii|, the value this step has always used). The √rows factor of
// the Householder bound would be √((M+1)·rps), larger than 10 whenever
// (M+1)·rps > 100; it is kept at 10 so that no result changes (see the
// numerics layer's report).
// Fails: Error(Dimension) with fewer equations than unknowns,
// Error(Numerical) when the problem is rank deficient.
// References: Akçay (2011) Algorithm 1 step 8.
Eigen::VectorXd step8_least_squares_EF(const SpectrumData& data, const StableRealization& sr, SpectralSummands& s) {
  const int m = data.m, M = data.M, n = static_cast<int>(sr.A.rows());
  SummandDesign shape(sr.C, sr.blocks, m);
  const int q = shape.unknowns(), rps = shape.rows_per_sample();
  if (static_cast<long long>(M + 1) * rps < q)
    throw Error(ErrorKind::Dimension, "step 8", "fewer equations than unknowns in the E, F fit");
  numerics::StreamedQrOptions qr_options;
  qr_options.rows_per_chunk = 1024;
  const UnitGrid grid(M);
  const numerics::ChunkFill fill = [&](int k0, int k1, Eigen::Ref<Eigen::MatrixXd> rows) {
    SummandDesign design(sr.C, sr.blocks, m);  // its own work space: blocks of the QR may run on threads
    Eigen::VectorXd y(rps);
    GridPiece z;
    for (int p0 = k0; p0 < k1; p0 += kGridPiece) {
      const int count = std::min(kGridPiece, k1 - p0);
      grid.points(p0, count, z.re, z.im);
      auto piece = rows.middleRows((p0 - k0) * rps, count * rps);
      if (m == 1) {
        design.scalar_rows(z.re, z.im, count, piece.leftCols(q));
        for (int j = 0; j < count; ++j) piece(j, q) = data.S(0, p0 + j).real();
        continue;
      }
      for (int j = 0; j < count; ++j) {
        auto blk = piece.middleRows(j * rps, rps);
        design.rows(z.z(j), &data, p0 + j, blk.leftCols(q), y);
        blk.col(q) = y;
      }
    }
  };
  const Eigen::MatrixXd R = numerics::streamed_qr_r(M + 1, rps, q + 1, fill, qr_options);
  const Eigen::MatrixXd Rq = R.topLeftCorner(q, q);
  const Eigen::VectorXd rdiag = Rq.diagonal().cwiseAbs();
  const double rmax = rdiag.maxCoeff(), rmin = rdiag.minCoeff();
  if (!numerics::numerically_full_rank(rdiag, 10.0))
    throw Error(ErrorKind::Numerical, "step 8", "E, F least-squares problem is rank deficient (|r_min|/|r_max| = " +
                                                    fmt(rmin / rmax, 3) + ")");
  Eigen::VectorXd theta = Rq.triangularView<Eigen::Upper>().solve(R.col(q).head(q));
  s.A = sr.A;
  s.C = sr.C;
  s.F = Eigen::Map<const Eigen::MatrixXd>(theta.data(), n, m);
  s.E.resize(m, m);
  for (int a = 0; a < m; ++a)
    for (int b = a; b < m; ++b) s.E(a, b) = s.E(b, a) = theta(n * m + shape.e_position(a, b));
  return theta;
}

// Step 8's check: Ŝ must be positive on the grid, or no spectral factor exists.
//
// Purpose: min over k of λ_min(Ŝ(z_k)) for the fitted θ.
// Method: Ŝ(z_k) from the design rows times θ (m = 1: the rows of 1024
// points at a time, one matrix-vector product), the smallest eigenvalue of its Hermitian form.
// Fails: Error(Positivity) when the minimum is not positive, naming ω.
// References: Akçay (2011) Algorithm 1 step 8.
double step8_fitted_spectrum_minimum(const StableRealization& sr, const Eigen::VectorXd& theta, int m, int M) {
  // The smallest value over samples k0 … k1−1, and where (the first k on a tie).
  const UnitGrid grid(M);
  const auto range_minimum = [&](int k0, int k1) {
    SummandDesign design(sr.C, sr.blocks, m);
    const int q = design.unknowns(), rps = design.rows_per_sample();
    Eigen::MatrixXd D(m == 1 ? kGridPiece : rps, q);
    Eigen::VectorXd values(D.rows());
    GridPiece z;
    std::pair<double, int> best{std::numeric_limits<double>::infinity(), k0};
    for (int p0 = k0; p0 < k1; p0 += kGridPiece) {
      const int count = std::min(kGridPiece, k1 - p0);
      grid.points(p0, count, z.re, z.im);
      if (m == 1) {
        design.scalar_rows(z.re, z.im, count, D);
        values.head(count).noalias() = D.topRows(count) * theta;
        for (int j = 0; j < count; ++j)
          if (values(j) < best.first) best = {values(j), p0 + j};
        continue;
      }
      for (int j = 0; j < count; ++j) {
        design.rows(z.z(j), nullptr, p0 + j, D, values);
        values.noalias() = D * theta;
        const double v = min_hermitian_eigenvalue(unpack_hermitian(values, m));
        if (v < best.first) best = {v, p0 + j};
      }
    }
    return best;
  };
  // Two halves on two threads above 2^16 samples. Every z_k (hence every
  // value) depends on k alone (UnitGrid), so the minimum is exact and ties go
  // to the first k: the result does not depend on the split or the core count.
  std::pair<double, int> lo, hi{std::numeric_limits<double>::infinity(), M + 1};
  if (M + 1 >= (1 << 16) && std::thread::hardware_concurrency() > 1) {
    const int mid = (M + 1) / 2;
    std::thread t([&] { hi = range_minimum(mid, M + 1); });
    lo = range_minimum(0, mid);
    t.join();
  } else {
    lo = range_minimum(0, M + 1);
  }
  const auto [worst, worst_k] = hi.first < lo.first ? hi : lo;
  if (!(worst > 0.0))
    throw Error(ErrorKind::Positivity, "step 8",
                "estimated spectrum is not positive on the grid: smallest eigenvalue " + fmt(worst, 4) +
                    " at omega = " + fmt(M_PI * worst_k / M, 6) + " rad/sample (k = " + std::to_string(worst_k + 1) +
                    ")");
  return worst;
}

// For step 8's positivity failure: the data's own diagonal samples with a
// negative real part, or "" (a user review: one negative sample, a sign error
// at file line 11, was reported as the fitted spectrum's minimum at
// ω = 2.9, where nothing is wrong). Noisy estimates may dip below zero where
// the spectrum is small, so they are named, not refused.
std::string negative_samples_note(const SpectrumData& data) {
  int count = 0, first = -1;
  for (int k = 0; k <= data.M; ++k)
    for (int a = 0; a < data.m; ++a)
      if (data.at(a, a, k).real() < 0) {
        if (count++ == 0) first = k;
        break;
      }
  if (count == 0) return "";
  return "; the data's own diagonal samples (S_aa real part) are negative at " + std::to_string(count) + " of " +
         std::to_string(data.M + 1) + " frequencies, the first at omega = " + fmt(M_PI * first / data.M, 6) +
         " rad/sample (k = " + std::to_string(first + 1) + ", file line " + std::to_string(first + 2) +
         "): a power spectrum is >= 0 there, so check those samples' sign (or the noise level)";
}

// What step 9 adds to the summands: the Riccati solution and its report.
struct RiccatiStep {
  std::string method;
  int iterations = 0;
  double residual = 0.0;
  double max_zero_modulus = 0.0;
};

// Step 9: Riccati equation, B̂ and D̂.
//
// Purpose: the stabilising solution P̂ of the spectral Riccati equation of
// (Â, Ĉ, Ê, F̂) (written into s.P) and the minimum-phase factor
// (Â, B̂, Ĉ, D̂) with D̂ D̂ᵀ = Ê - Ĉ P̂ Ĉᵀ, B̂ = (F̂ - Â P̂ Ĉᵀ) D̂^{-1}.
// Method: numerics/riccati.hpp (SDA, else the Riccati difference iteration);
// D̂ the symmetric square root.
// Numerical aspects: the stabilising solution makes Ĝ minimum phase: the
// zeros, eig(Â - B̂ D̂^{-1} Ĉ), lie inside the circle. If they do not, the
// Riccati equation had no stabilising solution -- the fitted spectrum is not
// positive on the whole circle, only on the grid -- and no spectral factor
// exists.
// Fails: Error(Positivity) when Ê or Ê - Ĉ P̂ Ĉᵀ is not positive definite,
// Error(Riccati) when no stabilising solution is found, Error(Numerical) when
// B̂ or D̂ is not finite.
// References: Akçay (2011) Algorithm 1 step 9; Chu, Fan, Lin (2005) (SDA).
RiccatiStep step9_riccati_B_D(SpectralSummands& s, StateSpace& g) {
  {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eE(s.E, Eigen::EigenvaluesOnly);
    if (!(eE.eigenvalues()(0) > 0.0))
      throw Error(ErrorKind::Positivity, "step 9", "E is not positive definite (smallest eigenvalue " +
                                                       fmt(eE.eigenvalues()(0), 4) + ")");
  }
  RiccatiStep rs;
  numerics::RiccatiSolution sol = numerics::solve_spectral_riccati(s, numerics::RiccatiOptions());
  rs.method = sol.method;
  if (!sol.ok) throw Error(ErrorKind::Riccati, "step 9", "no stabilising solution found (SDA and Kalman iteration failed)");
  const Eigen::MatrixXd P = std::move(sol.P);
  s.P = P;
  rs.iterations = sol.iterations;
  rs.residual = numerics::riccati_residual(s, P);
  const Eigen::MatrixXd Rinn = s.E - s.C * P * s.C.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eR(Rinn, Eigen::EigenvaluesOnly);
  if (!(eR.eigenvalues()(0) > 0.0))
    throw Error(ErrorKind::Positivity, "step 9",
                "E - C P C^T is not positive definite (smallest eigenvalue " + fmt(eR.eigenvalues()(0), 4) + ")");
  Eigen::MatrixXd Dhat, Dinv;
  sqrt_spd(Rinn, Dhat, Dinv);
  g.domain = Domain::Discrete;
  g.sample_time = 1.0;
  g.A = s.A;
  g.C = s.C;
  g.B = (s.F - s.A * P * s.C.transpose()) * Dinv;
  g.D = Dhat;
  if (!g.B.allFinite() || !g.D.allFinite()) throw Error(ErrorKind::Numerical, "step 9", "B or D is not finite");
  const Eigen::MatrixXd Z = s.A - g.B * Dinv * s.C;
  rs.max_zero_modulus = s.A.rows() > 0 ? Z.eigenvalues().cwiseAbs().maxCoeff() : 0.0;
  if (!(rs.max_zero_modulus < 1.0))
    throw Error(ErrorKind::Riccati, "step 9",
                "no stabilising solution: the spectral factor has a zero of modulus " + fmt(rs.max_zero_modulus, 12) +
                    " (the estimated spectrum is not positive between the grid points)");
  return rs;
}

// Step 10's companion: where double precision may have lost accuracy.
//
// Purpose: res.error_estimate and res.warnings (m channels).
// Method: double_precision_spectrum_tolerance (fdsid/compare.hpp) at
// σ_1/σ_2n, times κ = 1/(1 - ρ(Â)²): steps 8-9 solve Stein/Riccati-type
// equations in Â, whose operator P ↦ P − Â P Âᵀ has condition ≥ 1/(1 − ρ²)
// (its smallest singular value is at most 1 − ρ²), so near the circle it
// amplifies the error of 𝒴's range. Warnings: estimate above 1e-6, an order
// read from the data with a second gap of >= 10 above it, poles within 1e-3
// of the circle, a Riccati residual above the default accept_residual 1e-8
// (riccati.hpp).
// Fails: never.
void accuracy_warnings(SpectrumResult& res, int m) {
  const int n = res.order;
  const Eigen::VectorXd& sv = res.singular_values;
  const Eigen::Index i2n = std::min<Eigen::Index>(2 * n, sv.size()) - 1;
  const double ratio = i2n >= 0 && sv(i2n) > 0 ? sv(0) / sv(i2n) : std::numeric_limits<double>::infinity();
  double kappa = 1.0;
  if (n > 0) {
    const double rho = res.model.A.eigenvalues().cwiseAbs().maxCoeff();
    kappa = rho < 1.0 ? 1.0 / (1.0 - rho * rho) : std::numeric_limits<double>::infinity();
  }
  res.error_estimate = double_precision_spectrum_tolerance(res.p, res.r, m, res.N, ratio) * kappa;
  if (const std::string w = precision_warning(res.error_estimate, "the spectrum",
                                               "sigma_1/sigma_2n = " + fmt(ratio, 3) + ", 1/(1 - rho^2) = " + fmt(kappa, 3));
      !w.empty())
    res.warnings.push_back(w);
  // A weak mode left out by the largest-gap rule shows as a second gap: a
  // pair σ_{2k-1}, σ_{2k} standing above the tail. The warning needs
  // σ_{2k}/σ_{2k+1} >= 10 (a mode one decade above what follows it, the least
  // a mode must stand out to be identified at all) with σ_{2k} above the
  // rounding estimate. A noise tail alone does not trip it (review finding
  // 20: the README's first command warned on every noisy spectrum; its tail's
  // consecutive ratios are <= 2.3), nor does a rounding-level tail.
  if (res.order_from_data) {
    const int k_max = std::min((res.p - 1) / 2, res.r / 2);
    int k_weak = 0;
    double ratio_weak = 0;
    for (int k = n + 1; k <= k_max && 2 * k < sv.size(); ++k) {
      const double q = sv(2 * k - 1) / std::max(sv(2 * k), sv(0) * kUnitRoundoff);
      if (q >= 10 && sv(2 * k - 1) / sv(0) > res.error_estimate && q > ratio_weak) {
        k_weak = k;
        ratio_weak = q;
      }
    }
    if (k_weak > 0)
      res.warnings.push_back("order read from the data at the largest gap, n = " + std::to_string(n) +
                             "; a second gap at order " + std::to_string(k_weak) + " (sigma_" +
                             std::to_string(2 * k_weak) + "/sigma_" + std::to_string(2 * k_weak + 1) + " = " +
                             fmt(ratio_weak, 3) + ", sigma_" + std::to_string(2 * k_weak) + "/sigma_1 = " +
                             fmt(sv(2 * k_weak - 1) / sv(0), 3) + ") suggests a weak mode left out: try --order " +
                             std::to_string(k_weak));
  }
  if (n > 0 && res.split_margin < 1e-3)
    res.warnings.push_back("poles within " + fmt(res.split_margin, 3) +
                           " of the unit circle: the split of step 6 and the poles are ill-conditioned");
  if (!(res.riccati_residual <= numerics::RiccatiOptions().accept_residual))  // NaN too
    res.warnings.push_back("Riccati residual " + fmt(res.riccati_residual, 3) + " above 1e-8 (step 9)");
}

}  // namespace

// Step 6 for a given order, with the order the singular values support named
// when the split fails (review finding 18: "--order 8" on order-4 data failed
// at step 6 without saying that sigma_9 ... sit at rounding level).
Split step6_with_order_hint(const Eigen::MatrixXd& Atilde, int n, const Order& order, const Eigen::VectorXd& sv,
                            const Dims& d) {
  try {
    return step6_stable_split(Atilde, n);
  } catch (const Error& e) {
    if (order.from_data) throw;
    int gap_index = 0;
    double gap_ratio = 0;
    const int n_data = order_from_singular_values(sv, std::min((d.p - 1) / 2, d.r / 2), gap_index, gap_ratio);
    if (n_data == n || n_data == 0) throw;
    // Facts, not a diagnosis: where the largest gap of the singular values
    // lies, and the gap at the given order.
    throw Error(e.kind(), e.where(),
                e.message() + "; the largest singular-value gap is at order " + std::to_string(n_data) + " (sigma_" +
                    std::to_string(gap_index) + "/sigma_" + std::to_string(gap_index + 1) + " = " +
                    fmt(gap_ratio, 3) + "), the given order " + std::to_string(n) +
                    (2 * n < sv.size() ? " has sigma_" + std::to_string(2 * n) + "/sigma_" + std::to_string(2 * n + 1) +
                                             " = " + fmt(order.gap_ratio, 3)
                                       : " uses all " + std::to_string(sv.size()) + " singular values") +
                    " (--order auto reads the order there)");
  }
}

namespace {
// The algorithm is homogeneous in S: the factor of c S is √c times that of S
// (B̂, D̂ scale by √c; Ê, F̂, P̂, the singular values and the fitted spectrum by
// c; A, C, the order and every ratio not at all). Its quadratic quantities
// (F̂ F̂ᵀ in the Riccati step, the residual's scale) overflow near |S| = 1e154
// and underflow near 1e-154: a spectrum given ×1e200 came back with a NaN
// Riccati residual and a wrong factor (a user review). Samples whose largest
// modulus lies outside [2^-256, 2^256] are scaled by c = 4^-k into [1, 4):
// a power of two, so the scaling itself rounds nothing (the results are those
// of the unscaled samples in exact arithmetic times the powers above); inside
// that range nothing is scaled, so every result there is as before.
// The in-range test runs first on b = max(|Re|, |Im|) <= |s| <= √2 b, which
// needs no hypot (32001 of them were ~10 % of identify_spectrum at
// M = 32000: perf, issue 16); the modulus itself only when b may lie out of range.
int spectrum_scale_exponent(const SpectrumData& data) {
  if (data.S.size() == 0) return 0;  // check_input refuses it
  const double bound = sample_parts(data).abs().maxCoeff();
  if (bound >= std::ldexp(1.0, -256) && bound <= std::ldexp(1.0, 255)) return 0;  // |s| <= √2 b < 2^256
  const double top = data.S.cwiseAbs().maxCoeff();
  if (!(top > 0) || !std::isfinite(top) || (top >= std::ldexp(1.0, -256) && top <= std::ldexp(1.0, 256))) return 0;
  return std::ilogb(top) / 2;  // c = 4^-k brings top into [1, 4)
}
}  // namespace

SpectrumResult identify_spectrum(const SpectrumData& data, const SpectrumOptions& opt) {
  if (const int k = spectrum_scale_exponent(data); k != 0) {
    SpectrumData scaled = data;
    scaled.S *= std::ldexp(1.0, -2 * k);
    if (scaled.variance.size()) scaled.variance *= std::ldexp(1.0, -4 * k);
    SpectrumResult res = identify_spectrum(scaled, opt);
    const double root = std::ldexp(1.0, k), c = std::ldexp(1.0, 2 * k);
    res.model.B *= root;
    res.model.D *= root;
    res.summands.E *= c;
    res.summands.F *= c;
    res.summands.P *= c;
    res.singular_values *= c;
    res.min_spectrum *= c;
    return res;
  }
  const Dims d = check_input(data, opt);
  SpectrumResult res;
  res.method = opt.method;
  res.extension = opt.extension;
  res.N = d.N;
  res.p = d.p;
  res.r = d.r;

  const double* shat_N = step1_2_fourier_coefficients(data, opt.extension);  // N ŝ_k
  RangeSpace range = step3_range_space(shat_N, opt.method, d);
  res.singular_values = range.singular_values;

  const Order order = step4_order(res.singular_values, opt.order, d);
  const int n = order.n;
  res.order = n;
  res.order_from_data = order.from_data;
  res.gap_index = order.gap_index;
  res.gap_ratio = order.gap_ratio;
  const Eigen::MatrixXd U2n = range.U.leftCols(2 * n);

  const Eigen::MatrixXd Atilde = step5_shift_equations(U2n, d.m);
  const Split split = step6_with_order_hint(Atilde, n, order, res.singular_values, d);
  res.split_margin = split.margin;
  const StableRealization sr = step7_A_C(split, U2n, d.m, n);

  const Eigen::VectorXd theta = step8_least_squares_EF(data, sr, res.summands);
  try {
    res.min_spectrum = step8_fitted_spectrum_minimum(sr, theta, d.m, d.M);
  } catch (const Error& e) {
    throw Error(e.kind(), e.where(), e.message() + negative_samples_note(data));
  }

  const RiccatiStep ric = step9_riccati_B_D(res.summands, res.model);
  res.riccati_method = ric.method;
  res.riccati_iterations = ric.iterations;
  res.riccati_residual = ric.residual;
  res.max_zero_modulus = ric.max_zero_modulus;

  accuracy_warnings(res, d.m);
  return res;
}

StateSpace minimum_phase_factor(const StateSpace& factor, double* max_zero_modulus) {
  validate(factor, "factor");
  if (factor.domain != Domain::Discrete || factor.inputs() != factor.outputs())
    throw Error(ErrorKind::Input, "minimum_phase_factor", "needs a square discrete-time factor");
  SpectralSummands s = spectral_summands(factor);
  StateSpace g;
  const RiccatiStep ric = step9_riccati_B_D(s, g);
  g.sample_time = factor.sample_time;
  if (max_zero_modulus) *max_zero_modulus = ric.max_zero_modulus;
  return g;
}

}  // namespace fdsid
