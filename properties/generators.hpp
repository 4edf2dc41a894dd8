#pragma once
/// Random systems that meet Akçay (2011) Assumption 2.1: stable, strictly
/// minimum phase, minimal, with distinct nonzero eigenvalues.
///
/// A system is built from a SystemSpec, a plain list of numbers that a
/// RapidCheck generator draws and shrinks (smaller order, fewer channels,
/// moduli and couplings towards simple values); the spec prints as the
/// reproducer of a failing case.
#include <algorithm>
#include <cmath>
#include <ostream>
#include <vector>

#include <Eigen/Dense>

#include "linalg.hpp"
#include "fdsid/model.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid::testing {

struct Mode {
  double modulus;  ///< eigenvalue modulus in [0.1, 0.9]
  double angle;    ///< 0 for a real eigenvalue (sign from `negative`), else in (0.15, 3.0) rad: a conjugate pair
  bool negative;   ///< real eigenvalue at -modulus
};

struct SystemSpec {
  int channels = 1;             ///< m (square system, m inputs and m outputs)
  std::vector<Mode> modes;      ///< real modes add 1 to the order, pairs add 2
  std::vector<double> mixing;   ///< entries of the similarity T = I + 0.3 * mixing (n x n, row-major, in [-1, 1])
  std::vector<double> b, c;     ///< entries of B (n x m) and C (m x n) in [-1, 1]
  double gain = 0.3;            ///< scale of B relative to D = I: small gain keeps A - B D^{-1} C stable
};

inline std::ostream& operator<<(std::ostream& os, const SystemSpec& s) {
  os << "SystemSpec{channels=" << s.channels << ", gain=" << s.gain << ", modes=[";
  for (const Mode& m : s.modes) os << "{" << m.modulus << ", " << m.angle << ", " << m.negative << "} ";
  os << "], mixing=[";
  for (double x : s.mixing) os << x << " ";
  os << "], b=[";
  for (double x : s.b) os << x << " ";
  os << "], c=[";
  for (double x : s.c) os << x << " ";
  return os << "]}";
}

inline int spec_order(const SystemSpec& s) {
  int n = 0;
  for (const Mode& m : s.modes) n += m.angle == 0.0 ? 1 : 2;
  return n;
}

/// The model of a spec: A = T blockdiag(modes) T^{-1}, B = gain * b, C = c, D = I.
inline StateSpace make_system(const SystemSpec& s) {
  const int n = spec_order(s), m = s.channels;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  int i = 0;
  for (const Mode& md : s.modes) {
    if (md.angle == 0.0) {
      J(i, i) = md.negative ? -md.modulus : md.modulus;
      ++i;
    } else {
      const double a = md.modulus * std::cos(md.angle), b = md.modulus * std::sin(md.angle);
      J(i, i) = a;
      J(i, i + 1) = b;
      J(i + 1, i) = -b;
      J(i + 1, i + 1) = a;
      i += 2;
    }
  }
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const size_t k = static_cast<size_t>(r * n + c);
      if (k < s.mixing.size()) T(r, c) += 0.3 * s.mixing[k];
    }
  StateSpace sys;
  sys.A = T * J * fdsid::testing::inverse(T);
  sys.B.resize(n, m);
  sys.C.resize(m, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < m; ++c) sys.B(r, c) = s.gain * s.b[static_cast<size_t>(r * m + c)];
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < n; ++c) sys.C(r, c) = s.c[static_cast<size_t>(r * n + c)];
  sys.D = Eigen::MatrixXd::Identity(m, m);
  return sys;
}

/// Checks Assumption 2.1 with margins: eigenvalues of A and of A - B D^{-1} C
/// inside |z| <= rho_max, eigenvalues pairwise at least min_gap apart, and
/// minimality through the controllability and observability Gramians, whose
/// smallest eigenvalues must exceed gramian_min times their largest.
inline bool meets_assumption_2_1(const StateSpace& sys, double rho_max = 0.95, double min_gap = 1e-2,
                                 double gramian_min = 1e-8) {
  const Eigen::VectorXcd ev = fdsid::testing::eigenvalues(sys.A);
  for (Eigen::Index i = 0; i < ev.size(); ++i) {
    if (std::abs(ev(i)) > rho_max || std::abs(ev(i)) < 1e-2) return false;
    for (Eigen::Index j = 0; j < i; ++j)
      if (std::abs(ev(i) - ev(j)) < min_gap) return false;
  }
  const Eigen::MatrixXd Z = sys.A - sys.B * fdsid::testing::inverse(sys.D) * sys.C;
  if (fdsid::testing::eigenvalues(Z).cwiseAbs().maxCoeff() > rho_max) return false;
  const Eigen::MatrixXd Wc = lyapunov(sys.A, sys.B * sys.B.transpose());
  const Eigen::MatrixXd Wo = lyapunov(sys.A.transpose(), sys.C.transpose() * sys.C);
  for (const Eigen::MatrixXd* W : {&Wc, &Wo}) {
    const Eigen::VectorXd l = fdsid::testing::symmetric_eigenvalues(*W);
    if (!(l(0) > gramian_min * l(l.size() - 1))) return false;
  }
  return true;
}

/// The M+1 noise-free samples of sys's spectrum on the uniform grid (Eq. 7, s̃ = 0).
inline SpectrumData noise_free(const StateSpace& sys, int M) {
  SpectrumData d;
  d.m = sys.outputs();
  d.M = M;
  d.S = sample_spectrum(sys, M);
  return d;
}

/// A fixed 2 × 2 factor of order 3 meeting Assumption 2.1 (a complex pair and
/// a real pole): the unit tests' MIMO case (the property suite draws random ones).
inline SystemSpec mimo_2x2_spec() {
  SystemSpec a;
  a.channels = 2;
  a.modes = {{0.7, 0.9, false}, {0.5, 0.0, true}};
  a.mixing = {0.2, -0.5, 0.1, 0.4, 0.3, -0.2, 0.6, -0.1, 0.5};
  a.b = {0.9, -0.2, 0.4, 0.8, -0.6, 0.3};
  a.c = {0.5, -0.7, 0.2, 0.3, 0.6, -0.9};
  return a;
}

/// Largest distance from a pole of `truth` to the nearest pole of `estimate`.
inline double pole_error(const StateSpace& truth, const StateSpace& estimate) {
  const Eigen::VectorXcd a = poles(truth), b = poles(estimate);
  double worst = 0;
  for (Eigen::Index i = 0; i < a.size(); ++i) worst = std::max(worst, (b.array() - a(i)).abs().minCoeff());
  return worst;
}

}  // namespace fdsid::testing
