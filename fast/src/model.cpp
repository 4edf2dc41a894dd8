#include "fdsid/model.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "numerics/lyapunov.hpp"
#include "numerics/eigen_instances.hpp"

namespace fdsid {

const NameTable<Domain>& domain_names() {
  static const NameTable<Domain> names = {{"discrete", Domain::Discrete}, {"continuous", Domain::Continuous}};
  return names;
}

const char* to_string(Domain d) { return name_of(domain_names(), d); }

void validate(const StateSpace& m, const std::string& where) {
  const auto n = m.A.rows();
  auto fail = [&](const std::string& what) { throw Error(ErrorKind::Input, where, what); };
  if (m.A.cols() != n) fail("A must be square, got " + std::to_string(n) + "x" + std::to_string(m.A.cols()));
  if (m.B.rows() != n) fail("B must have " + std::to_string(n) + " rows (the order of A), got " + std::to_string(m.B.rows()));
  if (m.C.cols() != n) fail("C must have " + std::to_string(n) + " columns (the order of A), got " + std::to_string(m.C.cols()));
  if (m.D.rows() != m.C.rows() || m.D.cols() != m.B.cols())
    fail("D must be " + std::to_string(m.C.rows()) + "x" + std::to_string(m.B.cols()) + ", got " +
         std::to_string(m.D.rows()) + "x" + std::to_string(m.D.cols()));
  if (m.D.size() == 0) fail("D is empty: a model needs at least one input and one output");
  const std::pair<const char*, const Eigen::MatrixXd*> mats[] = {{"A", &m.A}, {"B", &m.B}, {"C", &m.C}, {"D", &m.D}};
  for (const auto& [name, mat] : mats)
    if (!mat->allFinite()) fail(std::string(name) + " has a NaN or infinite entry");
  // A continuous-time model may say sample_time 0 (the reference writes it so);
  // a discrete-time one needs its sample period.
  if (!std::isfinite(m.sample_time) || m.sample_time < 0 || (m.domain == Domain::Discrete && !(m.sample_time > 0)))
    fail(m.domain == Domain::Discrete ? "sample_time must be positive and finite"
                                      : "sample_time must be finite and not negative (0 for a continuous-time model)");
}

Eigen::MatrixXcd transfer(const StateSpace& m, cplx z) {
  const auto n = m.A.rows();
  if (n == 0) return m.D.cast<cplx>();
  Eigen::MatrixXcd zIA = -m.A.cast<cplx>();
  zIA.diagonal().array() += z;
  return m.D.cast<cplx>() + m.C.cast<cplx>() * zIA.partialPivLu().solve(m.B.cast<cplx>());
}

Eigen::MatrixXcd power_spectrum(const StateSpace& m, cplx z) {
  return transfer(m, z) * transfer(m, 1.0 / z).transpose();
}

namespace {

// Sorted by modulus, then argument (the order poles() and zeros() promise).
Eigen::VectorXcd sorted_by_modulus(std::vector<cplx> v) {
  std::sort(v.begin(), v.end(), [](cplx a, cplx b) {
    if (std::abs(a) != std::abs(b)) return std::abs(a) < std::abs(b);
    return std::arg(a) < std::arg(b);
  });
  return Eigen::Map<Eigen::VectorXcd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

Eigen::VectorXcd poles(const StateSpace& m) {
  if (m.A.rows() == 0) return {};
  Eigen::VectorXcd ev = m.A.eigenvalues();
  std::vector<cplx> v(ev.data(), ev.data() + ev.size());
  return sorted_by_modulus(std::move(v));
}

bool unstable_pole(Domain domain, cplx pole) {
  return domain == Domain::Discrete ? std::abs(pole) >= 1 : pole.real() >= 0;
}

std::string unstable_poles_text(Domain domain, const Eigen::VectorXcd& poles) {
  const bool discrete = domain == Domain::Discrete;
  const auto margin = [&](Eigen::Index i) { return discrete ? std::abs(poles(i)) - 1 : poles(i).real(); };
  std::vector<Eigen::Index> unstable;  // |λ| − 1 or Re λ >= 0
  for (Eigen::Index i = 0; i < poles.size(); ++i)
    if (unstable_pole(domain, poles(i))) unstable.push_back(i);
  if (unstable.empty()) return "";
  std::stable_sort(unstable.begin(), unstable.end(), [&](Eigen::Index a, Eigen::Index b) { return margin(a) > margin(b); });
  const auto text = [&](Eigen::Index i) {
    return pole_text(poles(i)) + (discrete ? " of modulus " + fmt(std::abs(poles(i)), 6) : std::string());
  };
  std::string all;
  if (unstable.size() > 1) {
    all = " (" + std::to_string(unstable.size()) + " unstable poles:";
    for (size_t k = 0; k < unstable.size(); ++k) all += (k ? ", " : " ") + text(unstable[k]);
    all += ")";
  }
  return "pole " + text(unstable[0]) + (discrete ? " >= 1" : " with real part >= 0") + all;
}

void require_stable(const StateSpace& m, const std::string& use) {
  const std::string unstable = unstable_poles_text(m.domain, poles(m));
  if (!unstable.empty())
    throw Error(ErrorKind::Input, "model",
                "has an unstable " + unstable + ": an unstable model has no periodic steady state " + use +
                    " (identify with the default reflection of unstable poles, not --allow-unstable)");
}

double spectral_radius(const StateSpace& m) {
  const Eigen::VectorXcd p = poles(m);
  return p.size() ? p.cwiseAbs().maxCoeff() : 0.0;
}

Eigen::VectorXcd zeros(const StateSpace& m) {
  const Eigen::Index n = m.A.rows(), k = m.B.cols();
  if (n == 0 || k != m.C.rows()) return {};
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n + k, n + k), Q = Eigen::MatrixXd::Zero(n + k, n + k);
  P << m.A, m.B, m.C, m.D;
  Q.topLeftCorner(n, n).setIdentity();
  Eigen::GeneralizedEigenSolver<Eigen::MatrixXd> qz(P, Q);
  if (qz.info() != Eigen::Success) throw Error(ErrorKind::Numerical, "zeros", "QZ of the Rosenbrock pencil did not converge");
  const double scale = std::max(1.0, P.norm());
  std::vector<cplx> v;
  for (Eigen::Index i = 0; i < n + k; ++i) {
    const cplx a = qz.alphas()(i);
    const double b = qz.betas()(i);
    if (b != 0 && std::abs(a / b) < 1e10 * scale)
      v.push_back(a / b);
  }
  return sorted_by_modulus(std::move(v));
}

// Smith doubling, in numerics/lyapunov.hpp.
Eigen::MatrixXd lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q) { return numerics::stein_smith(A, Q); }

SpectralSummands spectral_summands(const StateSpace& m) {
  SpectralSummands s;
  s.A = m.A;
  s.C = m.C;
  s.P = lyapunov(m.A, m.B * m.B.transpose());
  s.E = m.C * s.P * m.C.transpose() + m.D * m.D.transpose();
  s.F = m.A * s.P * m.C.transpose() + m.B * m.D.transpose();
  return s;
}

Eigen::MatrixXcd summand_spectrum(const SpectralSummands& s, cplx z) {
  const auto n = s.A.rows();
  Eigen::MatrixXcd zIA = -s.A.cast<cplx>();
  zIA.diagonal().array() += z;
  Eigen::MatrixXcd X = s.C.cast<cplx>() * zIA.partialPivLu().solve(s.F.cast<cplx>());
  Eigen::MatrixXcd zinvIA = -s.A.transpose().cast<cplx>();
  zinvIA.diagonal().array() += 1.0 / z;
  Eigen::MatrixXcd Y = s.F.transpose().cast<cplx>() * zinvIA.partialPivLu().solve(s.C.transpose().cast<cplx>());
  (void)n;
  return s.E.cast<cplx>() + X + Y;
}

Eigen::MatrixXcd sample_spectrum(const StateSpace& m, int M) {
  const auto p = m.outputs();
  Eigen::MatrixXcd out(p * p, M + 1);
  for (int k = 0; k <= M; ++k) {
    const double w = M_PI * k / M;
    const Eigen::MatrixXcd S = power_spectrum(m, std::polar(1.0, w));
    out.col(k) = Eigen::Map<const Eigen::VectorXcd>(S.data(), S.size());
  }
  return out;
}

Eigen::MatrixXd observability(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, int r) {
  const auto p = C.rows();
  Eigen::MatrixXd O(p * r, A.rows());
  Eigen::MatrixXd block = C;
  for (int k = 0; k < r; ++k) {
    O.middleRows(k * p, p) = block;
    block = (block * A).eval();
  }
  return O;
}

StateSpace refer_realization(const StateSpace& est, const StateSpace& ref, int r) {
  if (est.order() != ref.order() || est.outputs() != ref.outputs())
    throw Error(ErrorKind::Dimension, "Eq. (14)", "estimate and reference differ in order or outputs");
  const Eigen::MatrixXd T = observability(est.A, est.C, r).householderQr().solve(observability(ref.A, ref.C, r));
  const Eigen::PartialPivLU<Eigen::MatrixXd> Tlu(T);
  StateSpace out = est;
  out.A = Tlu.solve(est.A * T);
  out.B = Tlu.solve(est.B);
  out.C = est.C * T;
  return out;
}

std::vector<OutOfBandResonance> resonances_outside_band(const Eigen::VectorXcd& poles, Domain domain, double lo,
                                                        double hi) {
  std::vector<OutOfBandResonance> found;
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    const cplx p = poles(i);
    if (!(p.imag() > 0)) continue;  // one pole per pair; real poles have no resonance
    const cplx s = domain == Domain::Discrete ? std::log(p) : p;
    const double sigma = std::abs(s.real()), wd = s.imag();
    if (!(sigma < wd)) continue;  // ζ ≥ 1/√2: no resonance peak
    const bool above = wd - sigma > hi, below = wd + sigma < lo;
    if (above || below) found.push_back({p, wd, -s.real() / std::abs(s), above});
  }
  return found;
}

std::string pole_text(cplx z) {
  return fmt(z.real(), 6) + (z.imag() < 0 ? "-" : "+") + fmt(std::abs(z.imag()), 6) + "j";
}

std::string out_of_band_warning(const std::vector<OutOfBandResonance>& found, Domain domain, double lo, double hi,
                                const std::string& excited) {
  if (found.empty()) return "";
  const std::string unit = domain == Domain::Discrete ? " rad/sample" : " rad/s";
  std::string list;
  for (const OutOfBandResonance& r : found)
    list += std::string(list.empty() ? "" : "; ") + "pole pair " + fmt(r.pole.real(), 6) + "±" +
            fmt(r.pole.imag(), 6) + "j (resonance at " + fmt(r.frequency, 4) + unit + ", damping ratio " +
            fmt(r.damping, 2) + ", " + (r.above ? "above" : "below") + " the band)";
  return list + ": outside " + excited + " (" + fmt(lo, 4) + " to " + fmt(hi, 4) + unit +
         ") by more than its half-power width, so only its tail is in the data and its frequency and damping are "
         "poorly determined; excite the band where it lies, or read it as a fitting term, not a mode";
}

}  // namespace fdsid
