#include "fdsid/gap.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <cstring>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <numeric>
#include <tuple>
#include <unsupported/Eigen/MatrixFunctions>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/model.hpp"
#include "numerics/autoregression.hpp"
#include "numerics/complex.hpp"
#include "numerics/constants.hpp"
#include "numerics/fft.hpp"
#include "numerics/fisher.hpp"
#include "numerics/optimize.hpp"
#include "numerics/eigen_instances.hpp"

namespace fdsid {

const char* to_string(Effect e) {
  switch (e) {
    case Effect::GainError: return "gain_error";
    case Effect::Delay: return "delay";
    case Effect::SensorDynamics: return "sensor_dynamics";
    case Effect::UnmodelledMode: return "unmodelled_mode";
    case Effect::ModeMismatch: return "mode_mismatch";
    case Effect::Nonlinearity: return "nonlinearity";
    case Effect::Leakage: return "leakage";
  }
  return "?";
}

const char* to_string(GapVerdict v) {
  switch (v) {
    case GapVerdict::NoGap: return "no_gap";
    case GapVerdict::Explained: return "explained";
    case GapVerdict::Unexplained: return "unexplained";
  }
  return "unexplained";
}

Effect effect_from_string(std::string_view name) {
  for (Effect e : kAllEffects)
    if (name == to_string(e)) return e;
  std::string list;
  for (Effect e : kAllEffects) list += (list.empty() ? "" : ", ") + std::string(to_string(e));
  throw Error(ErrorKind::Input, "effect", "unknown effect '" + std::string(name) + "' (known: " + list + ")");
}

std::vector<std::pair<std::string, double>> parameter_list(const EffectParameters& parameters) {
  using List = std::vector<std::pair<std::string, double>>;
  // One overload per effect; flags are listed as 1 or 0, names in sorted order.
  struct Lister {
    static double f(bool b) { return b ? 1.0 : 0.0; }
    List operator()(const GainError& p) const { return {{"gain", p.gain}}; }
    List operator()(const Delay& p) const { return {{"samples", p.samples}, {"seconds", p.seconds}}; }
    List operator()(const SensorDynamics& p) const {
      List l = {{"cutoff_hz", p.cutoff_hz}};
      if (p.order == 2) l.emplace_back("damping", p.damping);
      l.emplace_back("discrete", f(p.discrete));
      l.emplace_back("order", static_cast<double>(p.order));
      return l;
    }
    List operator()(const UnmodelledMode& p) const {
      List l;
      if (p.mode) l = {{"damping", p.mode->damping}, {"frequency_hz", p.mode->frequency_hz}};
      l.emplace_back("series", f(p.series));
      return l;
    }
    List operator()(const ModeMismatch& p) const {
      List l;
      if (p.mode) l = {{"damping", p.mode->damping}, {"frequency_hz", p.mode->frequency_hz}};
      if (p.model_frequency_hz) l.emplace_back("model_frequency_hz", *p.model_frequency_hz);
      return l;
    }
    List operator()(const Nonlinearity& p) const {
      if (!p.fitted) return {};
      List l;
      if (p.in_loop) l.emplace_back("a1", p.a1);
      l.insert(l.end(), {{"a2", p.a2}, {"a3", p.a3}, {"at_input", f(p.at_input)}, {"in_loop", f(p.in_loop)}});
      return l;
    }
    List operator()(const Leakage& p) const {
      return {{"transient_periods", static_cast<double>(p.transient_periods)}};
    }
  };
  return std::visit(Lister{}, parameters);
}

static_assert(std::variant_size_v<EffectParameters> == kAllEffects.size());
static_assert(std::is_same_v<std::variant_alternative_t<static_cast<size_t>(Effect::ModeMismatch), EffectParameters>,
                             ModeMismatch>);
static_assert(std::is_same_v<std::variant_alternative_t<static_cast<size_t>(Effect::Leakage), EffectParameters>,
                             Leakage>);

double f2_survival(double t, int d2) {
  // F(2, d2) has density (1 + 2t/d2)^{−d2/2 − 1}; integrating from t to ∞ gives
  // (1 + 2t/d2)^{−d2/2}.
  return std::exp(-0.5 * d2 * std::log1p(2.0 * t / d2));
}

double gap_null_sd(int periods, int lines) {
  const double d = 2.0 * periods - 2, mean_f = d / (d - 2), var_f = d * d * d / ((d - 2) * (d - 2) * (d - 4));
  return std::sqrt(var_f) / mean_f / std::sqrt(static_cast<double>(lines));
}

namespace {

// The noise bound of the selection's rules (ForwardSelection): how far the gap
// of a right model rises above 1 by chance, one-sided, over `lines` excited
// lines and `periods` periods. From 4 periods on: 3 null sd (gap_null_sd). With
// 3 periods (a 4-period record whose first period is a proven transient) each
// line's t is F(2, 4), whose variance is infinite: the gap is then the mean of
// K variates X = t/2 with P(X > x) = (1 + x)^{−2} (a Pareto II law, mean 1),
// and the bound is the quantile of that mean at 3 sd's one-sided level
// (Φ(3) = 0.99865) minus 1, by Monte Carlo: 20000 means, X = U^{−1/2} − 1,
// fixed seed (≈ 27 draws lie beyond the quantile; measured over three other
// seeds the bound moves by 10–20 %). It is wide: 3.96 at K = 45, 1.49 at
// K = 267, 1.29 at K = 468, against 3 sd = 0.78, 0.32, 0.24 at 4 periods —
// the heavy tail is the law's, one line's t can carry the mean. Cost
// 20000 K draws (≈ 0.1 s at K = 267), only for a 3-period selection.
double gap_noise_bound(int periods, int lines) {
  if (periods >= 4) return 3 * gap_null_sd(periods, lines);
  constexpr int kDraws = 20000;
  std::mt19937_64 gen(0x5eed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> means(kDraws);
  for (double& m : means) {
    double sum = 0;
    for (int i = 0; i < lines; ++i) sum += 1.0 / std::sqrt(1.0 - unit(gen)) - 1.0;
    m = sum / lines;
  }
  const auto q = means.begin() + static_cast<std::ptrdiff_t>(0.99865 * kDraws);
  std::nth_element(means.begin(), q, means.end());
  return *q - 1.0;
}

// The linear effects: the first five of kAllEffects.
constexpr std::array<Effect, 5> kLinearEffects = {Effect::GainError, Effect::Delay, Effect::SensorDynamics,
                                                  Effect::UnmodelledMode, Effect::ModeMismatch};
static_assert(is_linear(Effect::ModeMismatch) && !is_linear(Effect::Nonlinearity));

// Effects ordered by name: the augmented model's factors and terms are
// multiplied and summed in this order (as when they were keyed by name), which
// fixes the rounding of G.
struct ByName {
  bool operator()(Effect a, Effect b) const { return std::strcmp(to_string(a), to_string(b)) < 0; }
};

// The record's DFT per period at every line 0 … P/2 (Eq. 4 scaling).
struct Spectra {
  int P = 0, M = 0;
  double Ts = 1;
  Domain domain = Domain::Discrete;
  Eigen::MatrixXcd U, Y;     // M × (P/2 + 1)
  Eigen::VectorXcd xi;       // the model's variable at each line: e^{jω} or jω
  Eigen::VectorXd hz;        // line frequency in Hz (cycles/sample when Ts = 1)
  Eigen::VectorXd cycles;    // k / P, cycles/sample
  std::vector<int> exc, ne, all;  // excited; unexcited inside the excited band; 1 … P/2
  Eigen::MatrixXd u_time;    // P × M input samples (for the input polynomial)
  Eigen::MatrixXd y_time;    // P × M output samples (for the in-loop polynomial)
};

// The unitary DFT of one period (Eq. 4) and the optimisers: numerics/.
using Fft = numerics::UnitaryFft;
using numerics::minimize_1d;
using numerics::nelder_mead;

// The augmented model: G = Π mult_e · (base + Σ add_e), one factor or term per
// linear effect e (so an effect can be taken out and refitted), plus a
// per-period additive output term `nl` (nonlinear distortion), on periods
// first … M−1.
struct Augment {
  Eigen::VectorXcd base;
  std::map<Effect, Eigen::VectorXcd, ByName> mult, add;
  // M × lines, or none. Shared, never changed once made: the fits copy
  // their states many times, and at P = 8192 the matrix is 0.5 MB, a fresh
  // allocation (and its page faults) per copy when it was held by value.
  std::shared_ptr<const Eigen::MatrixXcd> nl;
  const Eigen::MatrixXcd& distortion() const {
    static const Eigen::MatrixXcd none;
    return nl ? *nl : none;
  }
  int first = 0;
  // A series unmodelled_mode's factor held at unit gain at DC although no
  // gain_error is in the set (ForwardSelection::gain_split's test).
  bool series_at_unit_dc = false;
  Eigen::VectorXcd multiplier() const {
    Eigen::VectorXcd m = Eigen::VectorXcd::Ones(base.size());
    for (const auto& kv : mult) m = m.cwiseProduct(kv.second);
    return m;
  }
  Eigen::VectorXcd inner() const {
    Eigen::VectorXcd g = base;
    for (const auto& kv : add) g += kv.second;
    return g;
  }
  Eigen::VectorXcd G() const { return multiplier().cwiseProduct(inner()); }
  Augment without(Effect e) const {
    Augment a = *this;
    a.mult.erase(e);
    a.add.erase(e);
    return a;
  }
};

struct LineStats {
  Eigen::VectorXd t, var;
  Eigen::VectorXcd mean;
  int M = 0;
  /// Σ M |Ē|² / s̄² with s̄² the mean of s² over the 2h + 1 neighbouring lines of
  /// the list (h = 4): the cost the effect tests use. With s² from 2M − 2
  /// degrees of freedom per line, t(k) is F(2, 2M − 2), heavy-tailed (P(t > 7)
  /// = 1 % at M = 7 against 0.1 % for χ²₂/2); an F-test of a fit that lives on a
  /// few lines (a resonance) then rejects far too often. The noise spectrum is
  /// smooth over a few lines, so the pooled s̄² has ≈ 9 (2M − 2) degrees of
  /// freedom and the tests keep their levels. The gap itself keeps the exact
  /// per-line t.
  double pooled_cost = 0;
};

constexpr int kPoolHalfWidth = 4;

Eigen::VectorXd pooled(const Eigen::VectorXd& v) {
  const Eigen::Index n = v.size();
  Eigen::VectorXd p(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index a = std::max<Eigen::Index>(0, i - kPoolHalfWidth), b = std::min(n - 1, i + kPoolHalfWidth);
    p(i) = v.segment(a, b - a + 1).mean();
  }
  return p;
}

// The periods first … last (inclusive), in order.
std::vector<int> period_range(int first, int last) {
  std::vector<int> p;
  for (int l = first; l <= last; ++l) p.push_back(l);
  return p;
}

// Pintelon (2002) Eq. 25 at one line: the sample mean Ē(k) and the sample
// variance s²(k) (divisor R − 1) over the R periods `periods` of the residual
// E_l(k) = Y_l(k) − G(k) U_l(k) − N_l(k), N the per-period nonlinear term
// (none when `nl` is empty). `e` is scratch of size R. The one place the
// per-period residual statistics are formed (line_stats, the period deviation
// tests).
struct Moments {
  cplx mean;
  double var;
};
Moments residual_moments(const Spectra& s, const Eigen::VectorXcd& G, const Eigen::MatrixXcd& nl, int k,
                         const std::vector<int>& periods, Eigen::VectorXcd& e) {
  const int R = static_cast<int>(periods.size());
  for (int q = 0; q < R; ++q) {
    const int p = periods[q];
    e(q) = s.Y(p, k) - G(k) * s.U(p, k) - (nl.size() ? nl(p, k) : cplx(0));
  }
  const cplx m = e.mean();
  return {m, (e.array() - m).abs2().sum() / (R - 1)};
}

// t(k) over the line indices `idx` for the augmented model.
LineStats line_stats(const Spectra& s, const Augment& a, const std::vector<int>& idx) {
  const int M = s.M - a.first;
  LineStats st;
  st.M = M;
  st.t.resize(idx.size());
  st.var.resize(idx.size());
  st.mean.resize(idx.size());
  const Eigen::VectorXcd G = a.G();
  const std::vector<int> periods = period_range(a.first, s.M - 1);
  Eigen::VectorXcd e(M);
  for (size_t i = 0; i < idx.size(); ++i) {
    const Moments mo = residual_moments(s, G, a.distortion(), idx[i], periods, e);
    st.mean(i) = mo.mean;
    st.var(i) = mo.var;
    st.t(i) = M * std::norm(mo.mean) / mo.var;
  }
  const Eigen::VectorXd pv = pooled(st.var);
  for (size_t i = 0; i < idx.size(); ++i) st.pooled_cost += M * std::norm(st.mean(i)) / pv(i);
  return st;
}

double gap_of(const LineStats& st) { return (st.M - 2.0) / (st.M - 1.0) * st.t.mean(); }

// Fisher's combination of the per-line p-values (numerics/fisher.hpp): the
// lines' t are F(2, 2M − 2), X = 2 (M−1) Σ ln(1 + t/(M−1)) ~ χ²_{2K} under the
// null; fisher_p is its upper tail, fisher_p_below the lower one after a fit.
using numerics::fisher_p;
using numerics::fisher_p_below;

// The leakage test of period l against the mean of periods l+1 … M−1 (see gap.hpp).
double period_deviation_p(const Spectra& s, const Augment& a, int l) {
  const int R = s.M - l - 1;  // periods after l
  const Eigen::VectorXcd G = a.G();
  const std::vector<int> later = period_range(l + 1, s.M - 1);
  Eigen::VectorXd t(s.all.size());
  Eigen::VectorXcd e(R);
  for (size_t i = 0; i < s.all.size(); ++i) {
    const int k = s.all[i];
    const Moments mo = residual_moments(s, G, Eigen::MatrixXcd(), k, later, e);
    const cplx d = s.Y(l, k) - G(k) * s.U(l, k) - mo.mean;
    t(i) = std::norm(d) / (mo.var * (1.0 + 1.0 / R));  // ~ F(2, 2R − 2)
  }
  return fisher_p(t, R);  // the same combination with M − 1 → R − 1
}

// Weighted least-squares view of the excited lines for one state: the target
// T = Ŷ − N̂ and X = Û (means over the used periods), weights w = M/s².
struct Weighted {
  Eigen::VectorXcd T, U;
  Eigen::VectorXd w;
};

Weighted weighted(const Spectra& s, const Augment& a) {
  const LineStats st = line_stats(s, a, s.exc);
  const Eigen::VectorXd pv = pooled(st.var);
  Weighted W;
  const int K = static_cast<int>(s.exc.size());
  W.T.resize(K);
  W.U.resize(K);
  W.w.resize(K);
  for (int i = 0; i < K; ++i) {
    const int k = s.exc[i];
    cplx y = 0, u = 0, n = 0;
    for (int l = a.first; l < s.M; ++l) {
      y += s.Y(l, k);
      u += s.U(l, k);
      if (a.nl) n += (*a.nl)(l, k);
    }
    const double M = s.M - a.first;
    W.T(i) = (y - n) / M;
    W.U(i) = u / M;
    W.w(i) = M / pv(i);
  }
  return W;
}

// V = Σ w |T − G U| over the excited lines for a response G (indexed by line).
double cost(const Spectra& s, const Weighted& W, const Eigen::VectorXcd& G) {
  double V = 0;
  for (size_t i = 0; i < s.exc.size(); ++i) V += W.w(i) * std::norm(W.T(i) - G(s.exc[i]) * W.U(i));
  return V;
}

// V = Σ w |T − m(k) G(k) U|² over the excited lines for a factor m (a
// function of the line k) on the response G: the cost of a multiplicative
// effect (delay, sensor dynamics) as its parameters vary.
template <class Factor>
double factor_cost(const Spectra& s, const Weighted& W, const Eigen::VectorXcd& G, const Factor& m) {
  double v = 0;
  for (size_t i = 0; i < s.exc.size(); ++i) {
    const int k = s.exc[i];
    v += W.w(i) * std::norm(W.T(i) - m(k) * G(k) * W.U(i));
  }
  return v;
}

// An additive term on top of the state's multiplier: X = mult · Û and the
// target R = T − G Û at the excited lines, so that R ≈ X · term.
void additive_target(const Spectra& s, const Weighted& W, const Eigen::VectorXcd& mult, const Eigen::VectorXcd& G,
                     Eigen::VectorXcd& X, Eigen::VectorXcd& R) {
  const Eigen::Index K = static_cast<Eigen::Index>(s.exc.size());
  X.resize(K);
  R.resize(K);
  for (Eigen::Index i = 0; i < K; ++i) {
    const int k = s.exc[i];
    X(i) = mult(k) * W.U(i);
    R(i) = W.T(i) - G(k) * W.U(i);
  }
}

// A candidate effect on top of a state: the new state and its fit.
struct Trial {
  Augment state;
  EffectFit fit;
  double V = 0;
};

// Pole of a mode from s = −σ + jθ (rad/sample for discrete, rad/s for continuous).
cplx mode_pole(Domain d, double theta, double sigma) {
  const cplx s(-sigma, theta);
  return d == Domain::Discrete ? std::exp(s) : s;
}

// Best real linear combination Σ_j c_j Φ_j ≈ R in the weighted norm; returns
// the coefficients and the residual cost V = Σ w |R − Σ c_j Φ_j|².
// Method: normal equations of the q real columns (Re, Im stacked), scaled to
// unit diagonal, solved by a complete orthogonal decomposition of the q × q
// matrix (a rank-deficient set, e.g. a zero column, gets the minimum-norm c);
// V is then summed from the residual itself, not from bᵀb − cᵀAᵀb.
// Numerical aspects: c carries a relative error of order κ² u (κ the condition
// number of the scaled columns), but V is stationary in c at the minimum: the
// fitted values are off by ‖A δc‖ ≲ κ u ‖b‖, so V by (κ u)² ‖b‖² — below
// 1e-10 ‖b‖² for every κ ≤ 10¹⁰, far under the F-tests' and the optimisers'
// resolution. Before, a pivoted Householder QR of the 2K × q matrix formed per
// call (a fifth of a diagnosis at P = 8192).
double weighted_ls(const std::vector<Eigen::VectorXcd>& Phi, const Eigen::VectorXcd& R, const Eigen::VectorXd& w,
                   Eigen::VectorXd& c) {
  const Eigen::Index K = R.size(), q = static_cast<Eigen::Index>(Phi.size());
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(q, q);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(q);
  for (Eigen::Index i = 0; i < K; ++i)
    for (Eigen::Index j = 0; j < q; ++j) {
      const cplx wj = w(i) * std::conj(Phi[j](i));
      rhs(j) += (wj * R(i)).real();
      for (Eigen::Index l = 0; l <= j; ++l) N(j, l) += (wj * Phi[l](i)).real();
    }
  Eigen::VectorXd d(q);
  for (Eigen::Index j = 0; j < q; ++j) d(j) = N(j, j) > 0 ? 1.0 / std::sqrt(N(j, j)) : 1.0;
  N.triangularView<Eigen::StrictlyUpper>() = N.transpose();
  N = d.asDiagonal() * N * d.asDiagonal();
  c = d.cwiseProduct(N.completeOrthogonalDecomposition().solve(d.cwiseProduct(rhs)));
  double V = 0;
  for (Eigen::Index i = 0; i < K; ++i) {
    cplx r = R(i);
    for (Eigen::Index j = 0; j < q; ++j) r -= c(j) * Phi[j](i);
    V += w(i) * std::norm(r);
  }
  return V;
}

// The fits of one diagnosis: the model, the record's spectra, the BIC penalty
// and one FFT plan pair. Each fit_* adds one effect to a state (Augment) and
// returns the new state, its EffectFit and its cost V (gap.hpp's weighted
// residual sum, pooled variances).
// Method: closed form (gain), grid + Brent (delay, first-order low-pass),
// grid + Nelder–Mead (second-order low-pass), variable projection over the
// pole with the residue by weighted least squares (modes), weighted least
// squares on the excited and unexcited lines (nonlinearity).
// Numerical aspects: const and re-entrant but for the FFT buffers: one
// diagnosis runs on one thread.
class Diagnosis {
 public:
  Diagnosis(const StateSpace& model, const Spectra& s) : model_(model), s_(s) {
    penalty_ = 0.5 * std::log(2.0 * s.exc.size());
    if (model.order() > 0) {  // the resonances mode_mismatch may move (one per conjugate pair)
      const Eigen::EigenSolver<Eigen::MatrixXd> es(model.A, false);
      for (Eigen::Index i = 0; i < es.eigenvalues().size(); ++i) resonances_ += es.eigenvalues()(i).imag() > 0;
      free_response_ = free_response(model, s);
    }
  }

  // The unmodelled_mode grid visits every grid_step()-th excited line (at most
  // ~300 frequencies; fit_pole).
  int grid_step() const { return std::max<int>(1, static_cast<int>(s_.exc.size()) / 300); }

  Augment initial() const {
    Augment a;
    const Eigen::Index L = s_.xi.size();
    a.base.resize(L);
    for (Eigen::Index k = 0; k < L; ++k) {
      const cplx g = transfer(model_, s_.xi(k))(0, 0);
      const bool finite = std::isfinite(g.real()) && std::isfinite(g.imag()) && std::abs(g) < 1e150;
      if (!finite && k > 0)
        throw Error(ErrorKind::Input, "model",
                    "has a pole on the frequency axis at DFT line " + std::to_string(k) + " (" +
                        std::to_string(s_.hz(k)) + " Hz): its steady-state response to the record is undefined");
      a.base(k) = finite ? g : cplx(0);  // an integrator at DC: DC is used by no test
    }
    return a;
  }

  // Schwarz (BIC) penalty per real parameter in units of V: V is half the
  // −2 log-likelihood (2 V ≈ χ² over 2K real residuals), so ½ ln(2K).
  double penalty() const { return penalty_; }

  // The F-test p-value of a reduction V0 → V1 by q parameters (q_total in all).
  double f_test(double V0, double V1, int q, int q_total) const {
    const double d2 = 2.0 * s_.exc.size() - q_total;
    if (q <= 0 || d2 <= 0 || !(V1 > 0)) return 1.0;
    const double F = std::max(0.0, (V0 - V1) / q) / (V1 / d2);
    return boost::math::cdf(boost::math::complement(boost::math::fisher_f(q, d2), F));
  }

  // The F-test of an effect found by searching N candidate locations is the
  // smallest of N tests: its p-value is corrected by Šidák, 1 − (1 − p)^N
  // (the look-elsewhere effect; exact for independent locations, conservative
  // otherwise). N: unmodelled_mode, the frequencies of its grid over the band
  // (fit_pole: every step-th excited line, at most ~300); mode_mismatch, the
  // model's resonances it may move; 1 for the effects with one fixed form.
  // Without it, effect-free records of lightly damped structures admitted a
  // mode fitted to the noise of a few lines (gap-validate --family structure:
  // 2 false alarms of 30).
  double searched_p(Effect effect, double p) const {
    const double N = locations(effect);
    return N == 1 ? p : -std::expm1(N * std::log1p(-std::min(p, 1.0 - 1e-16)));
  }

  // The locations an effect's fit searches (searched_p): N for the
  // unmodelled_mode grid and the model's resonances, 1 otherwise.
  double locations(Effect effect) const {
    if (effect == Effect::UnmodelledMode) return std::ceil(static_cast<double>(s_.exc.size()) / grid_step());
    if (effect == Effect::ModeMismatch) return std::max(1, resonances_);
    return 1;
  }

  // The same look-elsewhere in the Schwarz criterion: ln N, in units of V.
  // V is the negative log-likelihood up to a constant and the BIC term
  // approximates the −log marginal likelihood of the effect's continuous
  // parameters; a uniform prior over N searched locations adds −ln(1/N) to
  // it when one location dominates (the location's code length). Without
  // it a mode fitted at the one line where a gain error is largest (a
  // resonance) undercut the 1-parameter gain by less than that (gap-validate
  // classic seed 2: subtle gain errors named unmodelled_mode twice).
  double search_cost(Effect effect) const { return std::log(locations(effect)); }

  // `warm`: the effect's fit of the previous descent round (fit_set): the two
  // mode effects then refine that resonance (mode_mismatch the same model
  // mode; unmodelled_mode in series and in parallel, the better kept) instead
  // of searching the band again.
  Trial fit(Effect effect, const Augment& a, const EffectFit* warm = nullptr) const {
    const Augment b = a.without(effect);
    switch (effect) {
      case Effect::GainError: return fit_gain(b);
      case Effect::Delay: return fit_delay(b);
      case Effect::SensorDynamics: return fit_sensor(b);
      case Effect::UnmodelledMode: return fit_mode(b, warm);
      case Effect::ModeMismatch: return fit_mismatch(b, warm);
      case Effect::Nonlinearity:
      case Effect::Leakage: break;  // leakage is no fit of the response; never asked for
    }
    return fit_nonlinearity(b);
  }

  // Joint fit of a set of linear effects: each fitted in turn on top of the
  // others, then each refitted with the others fixed (coordinate descent)
  // until a round lowers V by less than joint_tol(V), at most kJointRounds.
  // Two effects that trade the same phase lag (a delay and a low-pass's
  // cut-off) make it creep: three fixed rounds left a delay + sensor pair at
  // gap 1.5 where the joint optimum is ≈ 1 (gap-validate classic seed 1,
  // cases 37, 98), so the pair lost to the sensor alone.
  // joint_tol(V) = 0.05 + 1e-4 V in units of V (half a χ²): 0.05 is a
  // thirtieth of the smallest change the selection acts on near a right fit,
  // one parameter's BIC term ½ ln(2K) ≥ 1.5 (K ≥ 10 lines); 1e-4 V bounds
  // the relative error of the F statistics (V0 − V1)/(V1/d) of a fit far from
  // right, whose V is thousands: with 0.05 alone such fits crept on for all
  // kJointRounds (BM_Diagnose, delay + nonlinearity at P = 8192: 2.2 s).
  // Both also bound the linear effects ↔ distortion alternation of
  // ForwardSelection::evaluate.
  static constexpr int kJointRounds = 30;
  static double joint_tol(double V) { return 0.05 + 1e-4 * V; }
  // Several effects: the descent from both ends of the set's order (kAllEffects'
  // order and its reverse), the lower V kept — the effect fitted first on the
  // bare model takes the whole shared phase lag, and from there the descent
  // can stall worse than the other effect alone (a delay first: gap 2.8 for a
  // delay + sensor pair whose sensor alone left 1.6; classic seed 3 case 58).
  // `warm`: the set's fits from an earlier descent (in the set's order), which
  // then continues from them, from one end only.
  std::pair<Augment, std::vector<EffectFit>> fit_set(const std::vector<Effect>& set, const Augment& a, double& V,
                                                     const std::vector<EffectFit>* warm = nullptr) const {
    auto result = descend(set, a, V, warm);
    if (set.size() < 2 || warm) return result;
    std::vector<Effect> reversed(set.rbegin(), set.rend());
    double Vr = 0;
    auto other = descend(reversed, a, Vr);
    if (!(Vr < V)) return result;
    V = Vr;
    std::reverse(other.second.begin(), other.second.end());  // the fits in the set's order
    return other;
  }

  std::pair<Augment, std::vector<EffectFit>> descend(const std::vector<Effect>& set, const Augment& a, double& V,
                                                     const std::vector<EffectFit>* warm = nullptr) const {
    Augment cur = a;
    std::vector<EffectFit> fits = warm ? *warm : std::vector<EffectFit>(set.size());
    double before = std::numeric_limits<double>::infinity();
    for (int round = 0; round < (set.size() > 1 ? kJointRounds : 1); ++round) {
      for (size_t i = 0; i < set.size(); ++i) {
        Trial t = fit(set[i], cur, round > 0 || warm ? &fits[i] : nullptr);
        cur = t.state;
        fits[i] = t.fit;
        V = t.V;
      }
      if (!(before - V > joint_tol(V))) break;
      before = V;
    }
    return {cur, fits};
  }

  // Scale error: G → g G, closed form.
  Trial fit_gain(const Augment& a) const {
    const Weighted W = weighted(s_, a);
    const Eigen::VectorXcd G = a.G();
    double num = 0, den = 0;
    for (size_t i = 0; i < s_.exc.size(); ++i) {
      const cplx x = G(s_.exc[i]) * W.U(i);
      num += W.w(i) * (std::conj(x) * W.T(i)).real();
      den += W.w(i) * std::norm(x);
    }
    const double g = den > 0 ? num / den : 1.0;
    Trial t{a, {0, 0, 1, 1, GainError{g}}, 0};
    t.state.mult[Effect::GainError] = Eigen::VectorXcd::Constant(a.base.size(), g);
    t.V = cost(s_, W, t.state.G());
    return t;
  }

  // Pure delay τ samples: G → e^{−j2πfτ} G, τ ∈ [−10, min(100, P/4)].
  Trial fit_delay(const Augment& a) const {
    const Weighted W = weighted(s_, a);
    const Eigen::VectorXcd G = a.G();
    auto V = [&](double tau) {
      return factor_cost(s_, W, G, [&](int k) { return std::polar(1.0, -2 * M_PI * s_.cycles(k) * tau); });
    };
    const double fmax = s_.cycles(s_.exc.back());
    const double hi = std::min(100.0, s_.P / 4.0), lo = -10.0;
    const int n = static_cast<int>(std::ceil((hi - lo) * 16 * fmax)) + 2;  // ≥ 16 points per cycle at f_max
    const auto best = minimize_1d(V, lo, hi, std::max(n, 50));
    Trial t{a, {0, 0, 1, 1, Delay{best.first, best.first * s_.Ts}}, best.second};
    Eigen::VectorXcd m(a.base.size());
    for (Eigen::Index k = 0; k < m.size(); ++k) m(k) = std::polar(1.0, -2 * M_PI * s_.cycles(k) * best.first);
    t.state.mult[Effect::Delay] = m;
    return t;
  }

  // Unit-DC-gain low-pass in the measurement chain, four standard forms (f in
  // cycles/sample, f_c the cut-off, q = e^{−j2πf}): discrete first order
  // (1−a)/(1−a q), a = e^{−2π f_c}; continuous first order 1/(1 + x),
  // x = j f/f_c; discrete second order with the pole pair e^{2πf_c(−ζ ± j√(1−ζ²))}
  // and a constant numerator; continuous second order 1/(1 + 2ζx + x²).
  static cplx lowpass(int form, double f, double fc, double zeta) {
    const cplx q = std::polar(1.0, -2 * M_PI * f);
    if (form == 0) {
      const double a = std::exp(-2 * M_PI * fc);
      return (1 - a) / (1.0 - a * q);
    }
    if (form == 2) {
      const double w = 2 * M_PI * fc;
      const cplx p = std::exp(cplx(-zeta * w, w * std::sqrt(std::max(0.0, 1 - zeta * zeta))));
      const double a1 = -2 * p.real(), a2 = std::norm(p);
      return (1 + a1 + a2) / (1.0 + q * (a1 + q * a2));
    }
    const cplx x(0, f / fc);
    return form == 1 ? 1.0 / (1.0 + x) : 1.0 / (1.0 + 2 * zeta * x + x * x);
  }

  Trial fit_sensor(const Augment& a) const {
    const Weighted W = weighted(s_, a);
    const Eigen::VectorXcd G = a.G();
    const double fmin = s_.cycles(s_.exc.front()), fmax = s_.cycles(s_.exc.back());
    Trial best{{}, {0, 0, 0, 1, SensorDynamics{}}, 0};
    double best_score = std::numeric_limits<double>::infinity();
    // The forms of the model's domain only: within the band a continuous
    // low-pass differs from the discrete one of the same cut-off by about a
    // fractional delay, so with both forms allowed a sensor and a delay
    // together are one sensor of the other form (measured: 7 of 60 clear
    // delay + sensor_dynamics pairs, gap-validate classic seeds 1-3, named
    // sensor_dynamics alone with gap ≈ 1).
    //
    // Cut-offs from below the band up to f_c = ln(1000)/(2π) ≈ 1.1
    // cycles/sample: for the discrete forms a pole radius e^{−2π f_c} down to
    // 1e-3 — a discrete section with a fast pole (1−a)/(1−a q), a = 0.005, is
    // still a low-pass, its gain falling by 2a/(1+a) towards Nyquist, which a
    // delay is not (measured: such sensors were named delay when the range
    // stopped at 0.45) — the second-order pair's angle 2π f_c √(1−ζ²) below
    // π; for the continuous forms the same range: a continuous sensor has
    // its cut-off wherever its physics puts it, and above Nyquist 1/(1 + x)
    // still loses gain across the band, 1 − x²/2, which a delay does not
    // (measured: gap-validate --continuous, classic seed 1, 3 of 40 cases —
    // first-order sensors at 0.8 … 1.6 cycles/sample — named delay while the
    // range stopped at 0.5).
    const double fc_max = std::log(1000.0) / (2 * M_PI);
    const double lo = std::log(0.3 * fmin), hi = std::log(std::min(fc_max, 30 * fmax));
    const int first_form = model_.domain == Domain::Discrete ? 0 : 1;
    for (int form = first_form; form < 4; form += 2) {
      const bool second = form >= 2;
      auto V = [&](double lfc, double zeta) {
        if (!(lfc >= lo && lfc <= hi && zeta > 0.05 && zeta < (form == 2 ? 0.999 : 5.0)))
          return std::numeric_limits<double>::infinity();
        if (form == 2 && std::exp(lfc) * std::sqrt(1 - zeta * zeta) >= 0.5) return std::numeric_limits<double>::infinity();
        const double fc = std::exp(lfc);
        return factor_cost(s_, W, G, [&](int k) { return lowpass(form, s_.cycles(k), fc, zeta); });
      };
      double lfc = 0, zeta = 0.7, v = 0;
      if (!second) {
        const auto r = minimize_1d([&](double x) { return V(x, 0.7); }, lo, hi, 120);
        lfc = r.first;
        v = r.second;
      } else {
        double vb = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 60; ++i)
          for (double z : {0.3, 0.5, 0.7, 0.9}) {
            const double x = lo + (hi - lo) * i / 59.0, vv = V(x, z);
            if (vv < vb) {
              vb = vv;
              lfc = x;
              zeta = z;
            }
          }
        const Eigen::Vector2d r = nelder_mead([&](const Eigen::Vector2d& x) { return V(x(0), x(1)); },
                                              Eigen::Vector2d(lfc, zeta), Eigen::Vector2d(0.05, 0.05));
        lfc = r(0);
        zeta = r(1);
        v = V(lfc, zeta);
      }
      const int dof = second ? 2 : 1;
      if (v + penalty_ * dof < best_score) {
        best_score = v + penalty_ * dof;
        const double fc = std::exp(lfc);
        best = Trial{a, {0, 0, dof, 1, SensorDynamics{fc / s_.Ts, second ? 2 : 1, form % 2 == 0, second ? zeta : 0.0}},
                     v};
        Eigen::VectorXcd m(a.base.size());
        for (Eigen::Index k = 0; k < m.size(); ++k) m(k) = lowpass(form, s_.cycles(k), fc, zeta);
        best.state.mult[Effect::SensorDynamics] = m;
      }
    }
    return best;
  }

  // The constant beside a mode's two pole terms: none (a moved model mode),
  // free (d: a parallel resonance's feedthrough; a series factor
  // d + c/(ξ−λ) + c̄/(ξ−λ̄)), or the one that makes the factor 1 at DC
  // (1 + c(1/(ξ−λ) − 1/(ξ₀−λ)) + conj, ξ₀ = 1 for z, 0 for s). The free
  // series factor is exactly a real gain (its DC value) times the unit-DC
  // one, so beside a gain_error the series mode is fitted at unit DC (the
  // free d would repeat the gain: one parameter counted twice), and
  // ForwardSelection::gain_split asks whether a series mode's DC gain is a
  // gain error of its own.
  enum class Constant { None, Free, UnitDc };
  static int mode_dof(Constant k) { return k == Constant::Free ? 5 : 4; }
  cplx dc_point() const { return model_.domain == Domain::Discrete ? cplx(1, 0) : cplx(0, 0); }
  // The pole terms 1/(ξ−λ), 1/(ξ−λ̄) at ξ, less their DC values for UnitDc.
  std::pair<cplx, cplx> pole_terms(cplx xi, cplx lambda, Constant k) const {
    cplx p = numerics::reciprocal(xi - lambda), q = numerics::reciprocal(xi - std::conj(lambda));
    if (k == Constant::UnitDc) {
      p -= numerics::reciprocal(dc_point() - lambda);
      q -= numerics::reciprocal(dc_point() - std::conj(lambda));
    }
    return {p, q};
  }
  // A mode c/(ξ−λ) + c̄/(ξ−λ̄) (+ d, or less its DC value) at the excited lines, times X.
  void mode_terms(cplx lambda, const Eigen::VectorXcd& X, Constant k, std::vector<Eigen::VectorXcd>& Phi) const {
    const Eigen::Index K = X.size();
    Phi.assign(k == Constant::Free ? 3 : 2, Eigen::VectorXcd(K));
    for (Eigen::Index i = 0; i < K; ++i) {
      const auto [p, q] = pole_terms(s_.xi(s_.exc[i]), lambda, k);
      Phi[0](i) = X(i) * (p + q);
      Phi[1](i) = X(i) * cplx(0, 1) * (p - q);
      if (k == Constant::Free) Phi[2](i) = X(i);
    }
  }
  // The mode's response at every line: the terms of mode_terms with the
  // fitted c (and d), plus 1 for UnitDc (the series factor itself).
  Eigen::VectorXcd mode_response(cplx lambda, const Eigen::VectorXd& c, Constant k) const {
    const cplx r(c(0), c(1));
    const cplx constant = k == Constant::Free ? cplx(c(2), 0) : k == Constant::UnitDc ? cplx(1, 0) : cplx(0, 0);
    Eigen::VectorXcd m(s_.xi.size());
    for (Eigen::Index i = 0; i < m.size(); ++i) {
      const auto [p, q] = pole_terms(s_.xi(i), lambda, k);
      m(i) = r * p + std::conj(r) * q + constant;
    }
    return m;
  }
  // θ, σ of a pole (inverse of mode_pole).
  void theta_sigma(cplx lambda, double& theta, double& sigma) const {
    const cplx s = model_.domain == Domain::Discrete ? std::log(lambda) : lambda;
    theta = std::abs(s.imag());
    sigma = -s.real();
  }
  Resonance resonance(cplx lambda) const {
    double th, sg;
    theta_sigma(lambda, th, sg);
    const double wn = std::hypot(th, sg);
    return {wn / (2 * M_PI) / (model_.domain == Domain::Discrete ? s_.Ts : 1.0), sg / wn};
  }
  cplx pole_of(const Resonance& r) const {  // inverse of resonance()
    const double wn = 2 * M_PI * r.frequency_hz * (model_.domain == Domain::Discrete ? s_.Ts : 1.0);
    return mode_pole(model_.domain, wn * std::sqrt(std::max(0.0, 1 - r.damping * r.damping)), r.damping * wn);
  }

  // Variable projection over the pole (θ, ln σ): the residue (and d) by weighted
  // least squares for each pole. R ≈ X · mode.
  // The narrowest resonance the unmodelled_mode search admits: half-power
  // width 2ζθ at least kMinWidth line spacings Δ = 2π/P, i.e. ζ ≥ kMinWidth/(2k)
  // at line k. With 1/2, the nearest line to the peak (≤ Δ/2 away, x ≤ 2
  // half-widths) sees at least 1/√(1 + x²) = 1/√5 of the peak: the peak is
  // sampled and the damping identifiable; narrower, a mode is a single-line
  // outlier. (It was a whole line, 1/√2 of the peak: lightly damped modes
  // at low lines — ζ = 0.013 at line 24, gap-validate classic seed 2 case 5 —
  // were then fitted at the bound and left gap 2.8.)
  static constexpr double kMinWidth = 0.5;
  // The least damping ratio of an unmodelled mode, besides the width rule,
  // and the largest (a resonance, not a smooth correction; fit_pole).
  static constexpr double kMinDamping = 1e-3, kMaxDamping = 0.3;
  Trial fit_pole(const Augment& a, Effect effect, const Eigen::VectorXcd& X, const Eigen::VectorXcd& R,
                 Constant constant, const std::vector<cplx>& starts, bool grid, bool search,
                 const std::function<void(Augment&, cplx, const Eigen::VectorXd&)>& apply) const {
    const Weighted W = weighted(s_, a);
    std::vector<Eigen::VectorXcd> Phi;
    Eigen::VectorXd c;
    const double theta_max = model_.domain == Domain::Discrete ? M_PI : M_PI / s_.Ts * 1e3;
    const double scale = model_.domain == Domain::Discrete ? 2 * M_PI : 2 * M_PI / s_.Ts;  // θ per cycle/sample
    // A resonance the model lacks (grid = true) must be one the data can show:
    // its peak inside the excited band, damping ratio at most 0.3 (a resonance,
    // not a smooth correction that would stand in for a gain or a low-pass),
    // and a half-power width 2ζθ of at least kMinWidth line spacings 2π/P.
    const double th_lo = scale * s_.cycles(s_.exc.front()), th_hi = scale * s_.cycles(s_.exc.back());
    auto J = [&](const Eigen::Vector2d& v) {
      if (!(v(0) > 0 && v(0) < theta_max) || v(1) > std::log(v(0)) || v(1) < -30)
        return std::numeric_limits<double>::infinity();
      if (grid) {
        const double zeta = std::exp(v(1)) / std::hypot(v(0), std::exp(v(1)));
        const double k = v(0) / scale * s_.P;
        if (!(v(0) >= th_lo && v(0) <= th_hi && zeta <= kMaxDamping && zeta >= std::max(kMinDamping, kMinWidth / (2 * k))))
          return std::numeric_limits<double>::infinity();
      }
      mode_terms(mode_pole(model_.domain, v(0), std::exp(v(1))), X, constant, Phi);
      return weighted_ls(Phi, R, W.w, c);
    };
    std::vector<Eigen::Vector2d> x0;
    for (cplx l : starts) {
      double th, sg;
      theta_sigma(l, th, sg);
      if (th > 0 && sg > 0) x0.emplace_back(th, std::log(sg));
    }
    if (grid && search) {  // resonances at the excited frequencies, damping ratios 0.003 … 0.3
      const int step = grid_step();
      Eigen::Vector2d gbest(0, 0);
      double jbest = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < s_.exc.size(); i += step)
        for (double zeta : {0.003, 0.01, 0.03, 0.1, 0.3}) {
          const double th = scale * s_.cycles(s_.exc[i]);
          const Eigen::Vector2d v(th, std::log(zeta * th));
          const double j = J(v);
          if (j < jbest) {
            jbest = j;
            gbest = v;
          }
        }
      if (std::isfinite(jbest)) x0.push_back(gbest);
    }
    const int dof = mode_dof(constant);
    // The fitted resonance goes into the effect's parameters (mode_mismatch
    // or unmodelled_mode); absent when no start gives a finite fit.
    const auto parameters = [effect](std::optional<Resonance> r) -> EffectParameters {
      if (effect == Effect::ModeMismatch) return ModeMismatch{r, std::nullopt};
      return UnmodelledMode{r, false};
    };
    Trial best{a, {0, 0, dof, 1, parameters(std::nullopt)}, std::numeric_limits<double>::infinity()};
    for (const Eigen::Vector2d& st : x0) {
      const Eigen::Vector2d v = nelder_mead(J, st, Eigen::Vector2d(0.02 * st(0), 0.3));
      const double j = J(v);
      if (!(j < best.V)) continue;
      const cplx lambda = mode_pole(model_.domain, v(0), std::exp(v(1)));
      best.V = j;
      best.state = a;
      best.fit = EffectFit{0, 0, dof, 1, parameters(resonance(lambda))};
      apply(best.state, lambda, c);
    }
    if (!std::isfinite(best.V)) best.V = cost(s_, W, a.G());  // nothing to refine: the state unchanged
    return best;
  }

  // A resonance the model lacks, in parallel (G + d + c/(ξ−λ) + c̄/(ξ−λ̄), 5
  // parameters) or in series (G · (d + c/(ξ−λ) + c̄/(ξ−λ̄)), 5 parameters; at
  // unit DC gain, 4, beside a gain_error: Constant), the better of the two by
  // the Schwarz criterion. Starts: the project's own FRF subspace
  // identification (Pintelon 2002, order 2) of the residual FRF, and a grid
  // over the band.
  Trial fit_mode(const Augment& a, const EffectFit* warm = nullptr) const {
    const Weighted W = weighted(s_, a);
    const Eigen::VectorXcd G = a.G(), mult = a.multiplier();
    const int K = static_cast<int>(s_.exc.size());
    Eigen::VectorXcd Xp, Rp, Xs(K), Rs(K);
    additive_target(s_, W, mult, G, Xp, Rp);  // parallel: R ≈ mult · Û · mode
    const Constant series = a.series_at_unit_dc || a.mult.count(Effect::GainError) ? Constant::UnitDc : Constant::Free;
    for (int i = 0; i < K; ++i) {  // series: T ≈ G Û · mode, or T − G Û ≈ G Û · (mode − 1) at unit DC
      Xs(i) = G(s_.exc[i]) * W.U(i);
      Rs(i) = series == Constant::UnitDc ? W.T(i) - Xs(i) : W.T(i);
    }
    const auto in_parallel = [this](Augment& s, cplx l, const Eigen::VectorXd& c) {
      s.add[Effect::UnmodelledMode] = mode_response(l, c, Constant::Free);
    };
    const auto in_series = [this, series](Augment& s, cplx l, const Eigen::VectorXd& c) {
      s.mult[Effect::UnmodelledMode] = mode_response(l, c, series);
    };
    std::vector<cplx> starts;
    const UnmodelledMode* prev = warm ? std::get_if<UnmodelledMode>(&warm->parameters) : nullptr;
    const auto better = [this](Trial par, Trial ser) {
      std::get<UnmodelledMode>(par.fit.parameters).series = false;
      std::get<UnmodelledMode>(ser.fit.parameters).series = true;
      return ser.V + penalty_ * ser.fit.dof < par.V + penalty_ * par.fit.dof ? ser : par;
    };
    if (prev && prev->mode) {  // a descent round: the previous resonance refined in both connections
      starts.push_back(pole_of(*prev->mode));
      return better(fit_pole(a, Effect::UnmodelledMode, Xp, Rp, Constant::Free, starts, true, false, in_parallel),
                    fit_pole(a, Effect::UnmodelledMode, Xs, Rs, series, starts, true, false, in_series));
    }
    try {
      Eigen::VectorXd omega(K);
      std::vector<Eigen::MatrixXcd> Gr(K);
      std::vector<Eigen::MatrixXd> var(K);
      for (int i = 0; i < K; ++i) {
        const int k = s_.exc[i];
        omega(i) = model_.domain == Domain::Discrete ? 2 * M_PI * s_.cycles(k) : 2 * M_PI * s_.hz(k);
        Gr[i] = Eigen::MatrixXcd::Constant(1, 1, Rp(i) / Xp(i));
        var[i] = Eigen::MatrixXd::Constant(1, 1, 1.0 / (W.w(i) * std::norm(Xp(i))));
      }
      const FrfResult r = identify_frf_fixed(frf_data(model_.domain, omega, Gr, var), 2, 4, ContinuousMethod::Bilinear, 0,
                                                 DiscreteMethod::Monomial, false);
      for (Eigen::Index i = 0; i < r.poles.size(); ++i)
        if (r.poles(i).imag() > 0) starts.push_back(r.poles(i));
    } catch (const Error&) {
      // the subspace start is optional; the grid still runs
    }
    return better(fit_pole(a, Effect::UnmodelledMode, Xp, Rp, Constant::Free, starts, true, true, in_parallel),
                  fit_pole(a, Effect::UnmodelledMode, Xs, Rs, series, starts, true, true, in_series));
  }

  // A fitted resonance (unmodelled_mode, mode_mismatch) held by a bound of
  // its search (fit_pole): the bounds it touches, or nothing when the fit
  // has no resonance. The bounds of an unmodelled mode: damping ratio at
  // most 0.3 and at least the floor (kMinDamping and the half-power width of
  // kMinWidth lines), its peak inside the excited band. "At" a damping
  // bound: within 1 % of it (Nelder–Mead stops on the cost's change, not on
  // the bound; the F-16's fit held at 0.3 landed within 1e-14 of it); at the
  // band's edge: the damped frequency within half a line spacing of the
  // first or last excited line, the resolution of a peak on the grid. A
  // moved model mode (no bounds) is marked when its peak lies outside the
  // band, beyond half a line from it: no line resolves it.
  struct Bounds {
    bool upper = false, floor = false, edge = false, outside = false;
    double floor_value = 0;
  };
  std::optional<Bounds> bounds(const EffectFit& f) const {
    const Resonance* r = nullptr;
    if (const auto* m = std::get_if<UnmodelledMode>(&f.parameters)) r = m->mode ? &*m->mode : nullptr;
    if (const auto* m = std::get_if<ModeMismatch>(&f.parameters)) r = m->mode ? &*m->mode : nullptr;
    if (!r) return std::nullopt;
    const bool unmodelled = f.effect() == Effect::UnmodelledMode;
    const double line = s_.hz(1), fd = r->frequency_hz * std::sqrt(std::max(0.0, 1 - r->damping * r->damping));
    const double lo = s_.hz(s_.exc.front()), hi = s_.hz(s_.exc.back());
    Bounds b;
    b.floor_value = std::max(kMinDamping, kMinWidth / (2 * fd / line));
    b.upper = unmodelled && r->damping >= kMaxDamping * (1 - 0.01);
    b.floor = unmodelled && r->damping <= b.floor_value * (1 + 0.01);
    b.edge = unmodelled && (std::abs(fd - lo) <= line / 2 || std::abs(fd - hi) <= line / 2);
    b.outside = !unmodelled && (fd < lo - line / 2 || fd > hi + line / 2);
    return b;
  }

  // One of the model's resonances moved: its modal term r/(ξ−λ) + r̄/(ξ−λ̄)
  // replaced by a refitted pole and residue (4 parameters). No bounds: a
  // model mode may move anywhere. Moved out of the band, where no line
  // resolves it, it can run to ζ ≈ 1e-15 (the F-16's order-16 model on its
  // own Level-1 record: 15.8 → 19.5 Hz, above the 15 Hz band), a stand-in
  // the report names (note_bounds). A floor ζ ≥ min(1e-3, the model mode's)
  // was tried (stop 46) and dropped: the fit it leaves is a stand-in all the
  // same, and it can be a worse one (AModeAboveTheBandIsNamedAStandIn: gap
  // 24.6 with the floor against 3.6 without; gap-validate's 1500 cases and
  // the real records unchanged beyond ±0.03 of gap).
  Trial fit_mismatch(const Augment& a, const EffectFit* warm = nullptr) const {
    const Weighted W = weighted(s_, a);
    Trial best{a, {0, 0, 4, 1, ModeMismatch{}}, cost(s_, W, a.G())};
    if (model_.order() == 0) return best;
    Eigen::EigenSolver<Eigen::MatrixXd> es(model_.A);
    const Eigen::MatrixXcd V = es.eigenvectors();
    const Eigen::MatrixXcd Wi = V.inverse();
    if (!Wi.allFinite()) return best;
    const Eigen::VectorXcd CV = (model_.C.cast<cplx>() * V).row(0).transpose();
    const Eigen::VectorXcd WB = Wi * model_.B.cast<cplx>();
    const Eigen::VectorXcd mult = a.multiplier();
    bool any = false;
    // A descent round: only the model mode moved before, from where it went.
    const ModeMismatch* prev = warm ? std::get_if<ModeMismatch>(&warm->parameters) : nullptr;
    if (prev && !(prev->mode && prev->model_frequency_hz)) prev = nullptr;
    for (Eigen::Index i = 0; i < model_.A.rows(); ++i) {
      const cplx l = es.eigenvalues()(i);
      if (!(l.imag() > 0)) continue;
      if (prev && resonance(l).frequency_hz != *prev->model_frequency_hz) continue;
      const cplx r = CV(i) * WB(i, 0);
      Eigen::VectorXcd old(s_.xi.size());
      for (Eigen::Index k = 0; k < old.size(); ++k)
        old(k) = r / (s_.xi(k) - l) + std::conj(r) / (s_.xi(k) - std::conj(l));
      Augment w = a;
      w.add[Effect::ModeMismatch] = -old;
      const Eigen::VectorXcd G = w.G();
      Eigen::VectorXcd X, R;
      additive_target(s_, W, mult, G, X, R);
      Trial t = fit_pole(w, Effect::ModeMismatch, X, R, Constant::None, {prev ? pole_of(*prev->mode) : l}, false, false,
                         [this, old](Augment& s, cplx lambda, const Eigen::VectorXd& c) {
                           s.add[Effect::ModeMismatch] = mode_response(lambda, c, Constant::None) - old;
                         });
      if (!any || t.V < best.V) {
        any = true;
        std::get<ModeMismatch>(t.fit.parameters).model_frequency_hz = resonance(l).frequency_hz;
        best = t;
      }
    }
    return best;
  }

  // The nonlinearity's three forms (fit_nonlinearity): a static polynomial
  // of the model's output G U (degrees 2, 3), of the input u (2, 3), or of
  // the measured output y fed back through the model (in the loop, 1 … 3).
  enum class NlForm { Output, Input, InLoop };
  static std::vector<int> nl_degrees(NlForm form) {
    return form == NlForm::InLoop ? std::vector<int>{1, 2, 3} : std::vector<int>{2, 3};
  }
  // The form's terms for a period's signal x (G U, u or y in time): the
  // spectra of x^degree, one per degree of nl_degrees — the output form's as
  // they are, the input form's through G, the in-loop form's through −G (fed
  // back). Unscaled; powers by products (std::pow was a tenth of a diagnosis).
  static std::vector<Eigen::VectorXcd> nl_terms(NlForm form, const Eigen::VectorXd& x, const Eigen::VectorXcd& G,
                                                Fft& fft) {
    const std::vector<int> degrees = nl_degrees(form);
    std::vector<Eigen::VectorXcd> terms;
    for (int degree : degrees) {
      Eigen::VectorXd xd = x;
      for (int e = 1; e < degree; ++e) xd.array() *= x.array();
      Eigen::VectorXcd F = fft.forward(xd);
      if (form == NlForm::Input) F = F.cwiseProduct(G);
      if (form == NlForm::InLoop) F = -F.cwiseProduct(G);
      terms.push_back(std::move(F));
    }
    return terms;
  }

  // Nonlinear distortion, three forms, fitted on the excited and the
  // unexcited lines by weighted least squares; the one with the lowest
  // Schwarz score V + penalty · dof wins:
  //  - a static polynomial a₂ x² + a₃ x³ at the output (x the linear
  //    prediction G ū of the mean period), 2 parameters;
  //  - the same at the input (G · DFT(ū², ū³)), 2 parameters;
  //  - in the loop: the measured output fed back through the model,
  //    y = G (u − a₁ y − a₂ y² − a₃ y³) (a Duffing-type stiffness, the
  //    Silverbox's and the cubic-feedback circuit's structure), so that
  //    Y − G U = −G · DFT(a₁ y + a₂ y² + a₃ y³), 3 parameters. a₁ carries the
  //    level dependence of a model that is itself a linearisation (a best
  //    linear approximation at another level: the cubic's linear share).
  // ū, ȳ are the mean periods of the used periods (time domain), so each
  // form's term is the same in every period and the noise floor s² is
  // untouched: the term moves the lines' mean residual only. Computed from
  // each period's own input (until stop 56) it carried that period's input
  // noise into the scatter, which a joint fit could inflate — a new user's
  // F-16 order-10 model on Level 7 read "explained" at gap 1.4e-3 after
  // mode_mismatch (the 7.35 Hz mode moved to 2e-6 Hz) and an output
  // polynomial, the lines' scatter raised 1e7–1e8 times, their mean
  // residual left at 0.3 of the model's (test
  // GapDiagnosis.ANonlinearityTermIsTheSameInEveryPeriod). The mean period
  // still carries noise (errors in the regressor) that the scatter does not
  // count: it biases the coefficients by O(noise variance / signal power)
  // and leaves a gap after above 1 where the recorded input is noisy
  // (the Pintelon plant with an output cubic 0.02 y³ and 2 % input noise:
  // 1.59; with 0.1 y³: 12, against 0.70–0.80 per period — see README).
  Trial fit_nonlinearity(const Augment& a0) const {
    Augment a = a0;
    a.nl.reset();
    const Eigen::VectorXcd G = a.G();
    const int L = static_cast<int>(s_.xi.size());
    Fft& fft = this_thread_fft();
    std::vector<int> lines = s_.exc;
    lines.insert(lines.end(), s_.ne.begin(), s_.ne.end());
    const LineStats st = line_stats(s_, a, lines);
    Trial best{a, {0, 0, 2, 1, Nonlinearity{}}, std::numeric_limits<double>::infinity()};
    double best_score = std::numeric_limits<double>::infinity();
    const double used = static_cast<double>(s_.M - a.first);
    const Eigen::VectorXd u_mean = s_.u_time.rightCols(s_.M - a.first).rowwise().sum() / used;
    const Eigen::VectorXd y_mean = s_.y_time.rightCols(s_.M - a.first).rowwise().sum() / used;
    const Eigen::VectorXcd U_mean = s_.U.bottomRows(s_.M - a.first).colwise().sum().transpose() / used;
    // Q[d], per form: the term of degree degrees[d] per period and line. Its
    // storage is kept per thread (q M × L matrices, 1.5 MB at P = 8192: made
    // fresh per call they were 80 % of a diagnosis's page faults, a third of
    // its time on this VM; setZero on a matrix of the same size reallocates
    // nothing).
    thread_local std::vector<Eigen::MatrixXcd> Q;
    for (NlForm form : {NlForm::Output, NlForm::Input, NlForm::InLoop}) {
      const std::vector<int> degrees = nl_degrees(form);
      const int q = static_cast<int>(degrees.size());
      if (Q.size() < static_cast<size_t>(q)) Q.resize(static_cast<size_t>(q));
      for (int d = 0; d < q; ++d) Q[d].setZero(s_.M, L);
      double scale = 0;
      for (int l = a.first; l < s_.M; ++l) {
        if (l > a.first) {  // the same term in every period
          for (int d = 0; d < q; ++d) Q[d].row(l) = Q[d].row(a.first);
          continue;
        }
        const Eigen::VectorXd x = form == NlForm::Output ? fft.inverse(G.cwiseProduct(U_mean))
                                  : form == NlForm::Input ? u_mean
                                                          : y_mean;
        scale = std::max(scale, x.cwiseAbs().maxCoeff());
        const std::vector<Eigen::VectorXcd> F = nl_terms(form, x, G, fft);
        for (int d = 0; d < q; ++d) Q[d].row(l) = F[d].transpose();
      }
      if (!(scale > 0)) continue;
      const int K = static_cast<int>(lines.size());
      std::vector<Eigen::VectorXcd> Phi(q, Eigen::VectorXcd(K));
      Eigen::VectorXd w(K);
      for (int i = 0; i < K; ++i) {
        for (int d = 0; d < q; ++d)
          Phi[d](i) = Q[d].col(lines[i]).segment(a.first, s_.M - a.first).mean() / std::pow(scale, degrees[d]);
        w(i) = st.var(i);
      }
      w = pooled(w).cwiseInverse() * st.M;  // excited then unexcited lines: pooled within each run
      Eigen::VectorXd c;
      weighted_ls(Phi, st.mean, w, c);
      Nonlinearity p{true, 0, 0, form == NlForm::Input, form == NlForm::InLoop, 0};
      Trial t{a, {0, 0, q, 1, p}, 0};
      Eigen::MatrixXcd nl = Eigen::MatrixXcd::Zero(s_.M, L);
      for (int d = 0; d < q; ++d) {
        const double coef = c(d) / std::pow(scale, degrees[d]);
        (degrees[d] == 1 ? p.a1 : degrees[d] == 2 ? p.a2 : p.a3) = coef;
        nl += coef * Q[d];
      }
      t.state.nl = std::make_shared<const Eigen::MatrixXcd>(std::move(nl));
      t.fit.parameters = p;
      t.V = line_stats(s_, t.state, s_.exc).pooled_cost;
      if (t.V + penalty_ * q < best_score) {
        best_score = t.V + penalty_ * q;
        best = std::move(t);
      }
    }
    if (!std::isfinite(best.V)) best.V = line_stats(s_, a, s_.exc).pooled_cost;
    return best;
  }

  // The nonlinearity's second test, by prediction. Issue 17: a cubic fed
  // back through a lightly damped structure (Duffing type) spreads its
  // distortion thinly over the unexcited lines, and the Fisher combination
  // over them misses it (p 0.059 and 0.0115 on gap-validate structure seed 1
  // case 34 and seed 2 case 154, where the in-loop cubic alone leaves gap
  // 1.09 and 1.13 and the modes chosen instead 4.25 and 4.78). The test asks
  // instead whether the polynomial that explains the excited lines predicts
  // the unexcited ones:
  //  1. each form of fit_nonlinearity fitted on the excited lines alone, its
  //     regressor x built from the excited lines alone (G ū, ū or ȳ with
  //     every other line zeroed before the powers are taken, so the
  //     regressors at an unexcited line hold none of that line's noise);
  //  2. the form of least Schwarz score V + penalty · q predicts the
  //     distortion d at the unexcited lines;
  //  3. its agreement with their mean residual r̄, in the weights of the
  //     fits (w = M / s̄², s̄² the pooled variance):
  //       z = Σ w Re(d̄ r̄) / √(Σ w |d|² / 2),
  //     one-sided (a distortion the fit predicts has its sign). Without a
  //     distortion r̄ is the period mean of the noise, circular with
  //     variance s²/M at each line, independent of the excited lines' data,
  //     so z ~ N(0, 1) (up to the pooled variances' ≈ 9 (2M − 2) degrees of
  //     freedom) and p = Φ(−z).
  // Measured on the 155 nonlinearity-free cases of gap-validate structure
  // seed 2: p < 0.01, < 0.05 in 3, 10 (null 1.6, 7.8), the three smallest
  // an unmodelled_mode (5e-4), a leakage (9e-4: its transient is on the
  // unexcited lines too) and a mode_mismatch (2e-3). A t-test on the
  // periods' Helmert contrasts in place of the pooled variance (robust to
  // noise correlated between lines) gave those three 3e-3, 9e-4, 2e-2 and
  // cost power (case 154: p 1.1e-4 → 8.7e-3 with M − 1 = 7 degrees of
  // freedom). How the selection uses it: ForwardSelection::admit.
  // Returns 1 with fewer than 4 unexcited lines.
  double nonlinearity_prediction_p(const Augment& a0) const {
    if (s_.ne.size() < 4) return 1.0;
    Augment a = a0;
    a.nl.reset();
    const Eigen::VectorXcd G = a.G();
    Fft& fft = this_thread_fft();
    const LineStats se = line_stats(s_, a, s_.exc), sn = line_stats(s_, a, s_.ne);
    const Eigen::VectorXd we = pooled(se.var).cwiseInverse() * se.M, wn = pooled(sn.var).cwiseInverse() * sn.M;
    const double used = static_cast<double>(s_.M - a.first);
    const Eigen::VectorXcd U_mean = s_.U.bottomRows(s_.M - a.first).colwise().sum().transpose() / used;
    const Eigen::VectorXcd Y_mean = s_.Y.bottomRows(s_.M - a.first).colwise().sum().transpose() / used;
    auto excited_only = [&](const Eigen::VectorXcd& X) {
      Eigen::VectorXcd Z = Eigen::VectorXcd::Zero(X.size());
      for (int k : s_.exc) Z(k) = X(k);
      return Z;
    };
    double best_score = std::numeric_limits<double>::infinity(), p = 1.0;
    for (NlForm form : {NlForm::Output, NlForm::Input, NlForm::InLoop}) {
      const std::vector<int> degrees = nl_degrees(form);
      const int q = static_cast<int>(degrees.size());
      const Eigen::VectorXcd X = form == NlForm::Output ? Eigen::VectorXcd(G.cwiseProduct(U_mean))
                                 : form == NlForm::Input ? U_mean
                                                         : Y_mean;
      const Eigen::VectorXd x = fft.inverse(excited_only(X));
      const double scale = x.cwiseAbs().maxCoeff();
      if (!(scale > 0)) continue;
      const std::vector<Eigen::VectorXcd> F = nl_terms(form, x, G, fft);
      std::vector<Eigen::VectorXcd> Pe(q, Eigen::VectorXcd(s_.exc.size())), Pn(q, Eigen::VectorXcd(s_.ne.size()));
      for (int d = 0; d < q; ++d) {
        const double s = std::pow(scale, degrees[d]);
        for (size_t i = 0; i < s_.exc.size(); ++i) Pe[d](i) = F[d](s_.exc[i]) / s;
        for (size_t i = 0; i < s_.ne.size(); ++i) Pn[d](i) = F[d](s_.ne[i]) / s;
      }
      Eigen::VectorXd c;
      const double score = weighted_ls(Pe, se.mean, we, c) + penalty_ * q;
      if (!(score < best_score)) continue;
      best_score = score;
      Eigen::VectorXcd dn = Eigen::VectorXcd::Zero(s_.ne.size());
      for (int d = 0; d < q; ++d) dn += c(d) * Pn[d];
      double num = 0, den = 0;
      for (size_t i = 0; i < s_.ne.size(); ++i) {
        num += wn(i) * (std::conj(dn(i)) * sn.mean(i)).real();
        den += wn(i) * std::norm(dn(i)) / 2;
      }
      p = den > 0 ? 0.5 * std::erfc(num / std::sqrt(2 * den)) : 1.0;
    }
    return p;
  }

  // Leakage: is period l's residual off the mean of the later periods by a
  // transient? A transient is a free response of the model over the period,
  // y(t) = C A_dᵗ x₀, t = 0 … P−1, for some real x₀ ∈ Rⁿ (A_d = A for a
  // discrete model, e^{A Ts} for a continuous one: its free response sampled,
  // exact, no hold involved; the columns of free_response_). The test, in the
  // time domain of one period:
  //  1. the residual of each period l … M−1, e_q = IDFT(Y_q − G U_q) with the
  //     DC line left out (an offset is no transient; the basis's period means
  //     are removed alike); the deviation d = e_l − the mean of the J = M−l−1
  //     later periods;
  //  2. the noise is coloured, so it is whitened: the later periods' Helmert
  //     contrasts h_i = (e_{l+1} + … + e_{l+i} − i e_{l+i+1}) / √(i(i+1)),
  //     i = 1 … J−1 — noise only, independent of d and of each other — give
  //     the autocovariance, and so the prediction-error filter of an
  //     autoregression (order ≤ min(40, P/8) by Schwarz;
  //     numerics/autoregression.hpp); d, the h_i and the basis are filtered,
  //     the first p samples dropped (conditional least squares);
  //  3. each whitened series' F ratio of the basis fit,
  //     F = (ΔV/q)/(V₁/(P − p − q)), q the basis's rank: a test of the
  //     deviation's shape, not of its size, so periods whose noise power
  //     differs (real noise varies 30–50 % from period to period) do not look
  //     like a transient;
  //  4. d's F against the mean F of the J − 1 contrasts: each is
  //     ~ χ²_q/q when the whitening is right, so the ratio is
  //     ~ F(q, q(J−1)) under the null; dividing by their mean also absorbs a
  //     whitening that is not quite right, as long as it errs alike on d and
  //     on the contrasts, which have the same noise law.
  // Why the time domain: a period's DFT of coloured noise carries the noise
  // filter's own leakage term (its free response from the state at the
  // period's start and end), smooth in frequency, which the model's transient
  // basis partly fits; in the frequency domain the F of transient-free periods
  // came out 0.4–14 times its null mean (gap-validate seed 2), and judging
  // log F_l against the later periods' spread of log F (Student's t, J − 1
  // degrees of freedom; until stop 42) lost subtle transients: p 0.012 and
  // 0.37 on that seed's cases 15 and 75, 3.1e-11 and 2.8e-12 now. On the
  // 253 transient-free cases of gap-validate seeds 1, 3, 4 this p-value
  // falls below 0.01, 0.05, 0.1 in 2, 10, 23 of them (null: 2.5, 12.7, 25.3),
  // never below 1e-3; their 47 transient cases all at p < 1e-8.
  // A static model (n = 0) has no transient: the Fisher combination of the
  // per-line period deviations instead.
  double leakage_p(const Augment& a, int l) const {
    const int P = s_.P, J = s_.M - l - 1;
    if (free_response_.size() == 0 || J < 2) return period_deviation_p(s_, a, l);
    const Eigen::VectorXcd G = a.G();
    Fft& fft = this_thread_fft();
    Eigen::MatrixXd e(P, J + 1);
    for (int q = 0; q <= J; ++q) {
      Eigen::VectorXcd E = s_.Y.row(l + q).transpose() - G.cwiseProduct(s_.U.row(l + q).transpose());
      E(0) = 0;
      e.col(q) = fft.inverse(E);
    }
    const Eigen::VectorXd d = e.col(0) - e.rightCols(J).rowwise().mean();
    Eigen::MatrixXd h(P, J - 1);
    for (int i = 1; i < J; ++i)
      h.col(i - 1) = (e.middleCols(1, i).rowwise().sum() - i * e.col(i + 1)) / std::sqrt(i * (i + 1.0));
    // The contrasts' autocovariance (biased: positive definite) and the filter.
    const int p_max = std::min(40, P / 8);
    Eigen::VectorXd r(p_max + 1);
    for (int tau = 0; tau <= p_max; ++tau)
      r(tau) = (h.topRows(P - tau).array() * h.bottomRows(P - tau).array()).sum();
    const Eigen::VectorXd f = numerics::whitening_filter(r, p_max, static_cast<double>(h.size()));
    const int p = static_cast<int>(f.size()) - 1, rows = P - p;
    auto whiten = [&](const Eigen::MatrixXd& x) {
      Eigen::MatrixXd w = Eigen::MatrixXd::Zero(rows, x.cols());
      for (int i = 0; i <= p; ++i) w += f(i) * x.middleRows(p - i, rows);
      return w;
    };
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(whiten(free_response_));
    const int q = static_cast<int>(qr.rank());
    if (q == 0 || rows - q < 1) return 1.0;
    auto F_of = [&](const Eigen::MatrixXd& x) {
      const Eigen::MatrixXd w = whiten(x);
      const Eigen::MatrixXd Qtw = qr.householderQ().transpose() * w;  // the reflectors applied, Q never formed
      Eigen::VectorXd F(w.cols());
      for (Eigen::Index c = 0; c < w.cols(); ++c) {
        const double V0 = w.col(c).squaredNorm(), fit = Qtw.col(c).head(q).squaredNorm(), V1 = V0 - fit;
        F(c) = V1 > 0 ? (fit / q) / (V1 / (rows - q)) : 0.0;
      }
      return F;
    };
    const double F = F_of(d)(0), Fc = F_of(h).mean();
    if (!(Fc > 0) || !std::isfinite(F)) return 1.0;
    return boost::math::cdf(boost::math::complement(boost::math::fisher_f(q, q * (J - 1.0)), F / Fc));
  }

  // FFTW plans of length P for the calling thread, made once per thread and
  // length (fit_nonlinearity runs for every candidate set, and the forward
  // selection tries candidates on two threads; FFTW's planner is serialised
  // in numerics/fft.cpp, executing plans is thread-safe, the buffers are not
  // shared).
  Fft& this_thread_fft() const {
    thread_local std::unique_ptr<Fft> fft;
    if (!fft || fft->size() != s_.P) fft = std::make_unique<Fft>(s_.P);
    return *fft;
  }

  // The model's free responses over one period, column i = C A_dᵗ e_i,
  // t = 0 … P−1 (the extended observability matrix O_P of (A_d, C)), each
  // column's mean removed (leakage_p); empty for a static model or when they
  // overflow (an unstable model over a long period).
  static Eigen::MatrixXd free_response(const StateSpace& model, const Spectra& s) {
    const bool discrete = model.domain == Domain::Discrete;
    const Eigen::MatrixXd Ad = discrete ? model.A : Eigen::MatrixXd((model.A * s.Ts).exp());
    const Eigen::MatrixXd X = observability(Ad, model.C.topRows(1), s.P);
    if (!X.allFinite()) return {};
    return X.rowwise() - X.colwise().mean();
  }

  const StateSpace& model_;
  const Spectra& s_;
  double penalty_ = 0;
  int resonances_ = 0;        // complex-conjugate pole pairs of the model
  Eigen::MatrixXd free_response_;  // P × n (free_response)
};

Spectra spectra_of(const Eigen::MatrixXd& record, const RecordMeta& meta, Domain domain) {
  Spectra s;
  s.P = meta.period;
  s.M = meta.periods;
  s.Ts = meta.sample_time;
  s.domain = domain;
  std::vector<int> lines(s.P / 2 + 1);
  std::iota(lines.begin(), lines.end(), 0);
  std::vector<int> nonzero(lines.begin() + 1, lines.end());
  const auto sp = period_spectra(record, s.P, s.M, nonzero);
  const int L = s.P / 2 + 1;
  s.U = Eigen::MatrixXcd::Zero(s.M, L);
  s.Y = Eigen::MatrixXcd::Zero(s.M, L);
  for (int l = 0; l < s.M; ++l) {
    double mu = 0, my = 0;
    for (int t = 0; t < s.P; ++t) {
      mu += record(static_cast<Eigen::Index>(l) * s.P + t, 0);
      my += record(static_cast<Eigen::Index>(l) * s.P + t, 1);
    }
    s.U(l, 0) = mu / std::sqrt(static_cast<double>(s.P));
    s.Y(l, 0) = my / std::sqrt(static_cast<double>(s.P));
    for (int k = 1; k < L; ++k) {
      s.U(l, k) = sp[l][k - 1](0);
      s.Y(l, k) = sp[l][k - 1](1);
    }
  }
  s.u_time.resize(s.P, s.M);
  s.y_time.resize(s.P, s.M);
  for (int l = 0; l < s.M; ++l) {
    s.u_time.col(l) = record.col(0).segment(static_cast<Eigen::Index>(l) * s.P, s.P);
    s.y_time.col(l) = record.col(1).segment(static_cast<Eigen::Index>(l) * s.P, s.P);
  }
  s.xi.resize(L);
  s.hz.resize(L);
  s.cycles.resize(L);
  for (int k = 0; k < L; ++k) {
    s.cycles(k) = static_cast<double>(k) / s.P;
    s.hz(k) = s.cycles(k) / s.Ts;
    s.xi(k) = domain == Domain::Discrete ? std::polar(1.0, 2 * M_PI * s.cycles(k)) : cplx(0, 2 * M_PI * s.hz(k));
  }
  std::vector<bool> excited(L, false);
  for (int k : meta.excited_lines) {
    if (k < 1 || k > s.P / 2)
      throw Error(ErrorKind::Input, "meta field \"excited_lines\"",
                  "line " + std::to_string(k) + " is outside 1 ... P/2 = " + std::to_string(s.P / 2));
    excited[k] = true;
  }
  const int kmax = *std::max_element(meta.excited_lines.begin(), meta.excited_lines.end());
  // Line P/2 (even P) is real in every period: there t ~ F(1, M−1), not
  // F(2, 2M−2), so it is left out of every test.
  const int top = s.P % 2 == 0 ? L - 1 : L;
  for (int k = 1; k < top; ++k) {
    if (excited[k]) s.exc.push_back(k);
    else if (k < kmax) s.ne.push_back(k);
    s.all.push_back(k);
  }
  return s;
}

// Benjamini–Hochberg over the per-line p-values: which lines are discoveries.
std::vector<bool> benjamini_hochberg(const std::vector<double>& p, double q) {
  std::vector<size_t> o(p.size());
  std::iota(o.begin(), o.end(), 0);
  std::sort(o.begin(), o.end(), [&](size_t a, size_t b) { return p[a] < p[b]; });
  size_t cut = 0;
  for (size_t i = 0; i < o.size(); ++i)
    if (p[o[i]] <= q * (i + 1) / o.size()) cut = i + 1;
  std::vector<bool> f(p.size(), false);
  for (size_t i = 0; i < cut; ++i) f[o[i]] = true;
  return f;
}

// Input checks of diagnose_gap (see gap.hpp for the conditions).
// Fails: Error(Input) naming the model, the data, the meta field or the options.
void check_inputs(const StateSpace& model, const Eigen::MatrixXd& record, int inputs, const RecordMeta& meta,
                  const GapOptions& options) {
  validate(model);
  if (model.inputs() != 1)
    throw Error(ErrorKind::Input, "model",
                "the gap diagnosis takes a model with one input, got " + std::to_string(model.inputs()) +
                    " (the residual of several inputs needs each one's path: not supported)");
  if (inputs != 1 || record.cols() != 2)
    throw Error(ErrorKind::Input, "data", "the single-output diagnosis needs one input and one output column (u,y)");
  if (model.outputs() != 1)
    throw Error(ErrorKind::Input, "model",
                "has " + std::to_string(model.outputs()) + " outputs, the record 1: give a SISO model for a u,y "
                "record, or the record's outputs (u,y1,...,yp, or --output NAME ...) for a model with p outputs");
  if (meta.periods < 4)
    throw Error(ErrorKind::Input, "meta field \"periods\"",
                "the gap needs at least 4 periods (the noise floor's F(2, 2M-2) law has a finite variance only for "
                "M >= 4), got " + std::to_string(meta.periods));
  if (meta.excited_lines.size() < 4)
    throw Error(ErrorKind::Input, "meta field \"excited_lines\"", "needs at least 4 excited lines");
  // A discrete model is evaluated at e^{j 2 pi k / P}: that is the record's
  // line k only when both count time in the same sample period (review
  // finding 10: a model with Ts 0.5 against a record with Ts 1 gave the same
  // answer as the matching one). Equal up to the rounding of a writer that
  // prints >= 6 significant digits (<= 0.5e-5 relative each, so <= 1e-5 apart).
  if (model.domain == Domain::Discrete &&
      std::abs(model.sample_time - meta.sample_time) > 1e-5 * std::max(model.sample_time, meta.sample_time))
    throw Error(ErrorKind::Input, "model field \"sample_time\"",
                fmt(model.sample_time, 10) + " s differs from the record's " + fmt(meta.sample_time, 10) +
                    " s (meta \"sample_time\"): a discrete-time model holds for one sample period; resample or "
                    "re-identify it at the record's");
  // The diagnosis compares the model's periodic steady state, G U line by
  // line, with the record's: an unstable model has none (fdsid validate
  // refuses it alike).
  require_stable(model, "to compare with the record");
  if (!(options.alpha > 0 && options.alpha < 1 && options.effect_alpha > 0 && options.effect_alpha < 1 &&
        options.fdr > 0 && options.fdr < 1 && options.min_share >= 0 && options.min_share < 1))
    throw Error(ErrorKind::Input, "options", "levels must lie in (0, 1)");
  // Review finding 1: a 0-based meta gave "no gap" (the lines held no input).
  require_input_power(record, inputs, meta);
}

// A noise floor must exist: periods identical to rounding give s² ≈ 0.
// Method: the median over the excited lines of s²(k) against that of |Ȳ(k)|²
// (relative threshold numerics::kNegligibleVarianceRatio = 1e-24, far below any
// measured record: periods that agree to 1e-12 in amplitude).
// Fails: Error(Input) on "data" when s² vanishes or t(k) is not finite.
void require_noise_floor(const Spectra& s, const LineStats& st0) {
  std::vector<double> v(st0.var.data(), st0.var.data() + st0.var.size()), y;
  for (int k : s.exc) y.push_back(std::norm(s.Y.col(k).mean()));
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  std::nth_element(y.begin(), y.begin() + y.size() / 2, y.end());
  if (!(v[v.size() / 2] > numerics::kNegligibleVarianceRatio * y[y.size() / 2]) || !st0.t.allFinite())
    throw Error(ErrorKind::Input, "data",
                "the periods do not vary (sample variance " + std::to_string(v[v.size() / 2]) +
                    " at the median excited line): no noise floor to measure the gap against; the gap diagnosis "
                    "needs measured (noisy) periods");
}

// The detection tests on the model as given (gap.hpp): the gap and its Fisher
// combination over the excited lines, the leakage test of the first period,
// and the nonlinearity test on the unexcited lines inside the band (not
// testable with fewer than 4 of them: p = 1 and a note).
void detection_tests(const Diagnosis& dg, const Spectra& s, const Augment& a0, const LineStats& st0, GapReport& rep) {
  rep.gap_before = gap_of(st0);
  rep.p_gap = fisher_p(st0.t, st0.M);
  rep.p_leakage = dg.leakage_p(a0, 0);
  rep.p_nonlinearity = s.ne.size() >= 4 ? fisher_p(line_stats(s, a0, s.ne).t, s.M) : 1.0;
  if (s.ne.size() < 4) rep.notes.push_back("fewer than 4 unexcited lines inside the band: nonlinearity not testable");
}

// Equal noise power per period (gap.hpp: period_power_test) on the consecutive
// lines 1 … P/2, periods first … M−1: after the first period (which may hold the
// transient the leakage test looks for) and after any further periods the
// transient still reaches (transient_periods), so that a slow transient is
// not read as noise of unequal power. A note when p < effect_alpha, saying
// what unequal power does to the tests here. Per line, t = M|Ē|²/s² over
// periods whose noise variances ρ_l σ² differ is the complex analogue of
// Student's one-sample t under unequal variances, whose level is at most
// nominal at the usual levels (Bakirov & Székely 2005, "Student's t-test for
// Gaussian scale mixtures"): the loudest period raises |Ē|² and s² together.
// Measured (2·10⁶ lines each, M = 4 and 8, relative powers 0.4 … 1.6 and
// 0.25, 0.25, 0.25, 3.25): P(t > its F(2, 2M − 2) α-point) = 0.26 … 0.96 α at
// α = 0.1 … 1e-4, and the same for the several-output Hotelling T² (p = 2, 3);
// GapDiagnosis.UnequalNoisePowerLeavesTheTestsValid checks the diagnosis.
// So the gap, its bands and Fisher combinations are conservative; the effect
// F-tests are ratios of costs in which a period's power enters numerator and
// denominator alike; the transient test of a dynamic model compares the
// shape of a period's deviation, not its size (Diagnosis::leakage_p). Only a
// static model's transient test (period_deviation_p, a test of size) comes
// out too small: `static_model` says so in the note.
void period_power(const Spectra& s, const Augment& a0, int first, bool static_model, GapReport& rep) {
  const Eigen::VectorXcd G = a0.G();
  Eigen::MatrixXcd res(s.M - first, static_cast<Eigen::Index>(s.all.size()));
  for (Eigen::Index i = 0; i < res.cols(); ++i) {
    const int k = s.all[static_cast<size_t>(i)];
    for (int m = first; m < s.M; ++m) res(m - first, i) = s.Y(m, k) - G(k) * s.U(m, k);
  }
  const PeriodPowerTest pp = period_power_test(res);
  rep.p_period_power = pp.p;
  rep.period_power = pp.relative;
  const PeriodIndependenceTest pi = period_independence_test(res, pp.relative);
  rep.p_period_independence = pi.p;
  rep.period_correlation = pi.correlation;
  rep.period_correlation_expected = pi.expected;
  if (rep.periods_dependent())
    rep.notes.push_back(
        "adjacent periods' noise is alike (mean lag-1 correlation of their deviations from the mean period " +
        fmt(pi.correlation, 3) + ", " + fmt(pi.expected, 3) + " for independent periods, p " +
        p_text(pi.p, 2) +
        "): something varies slowly from period to period that is neither periodic nor independent noise (a "
        "disturbance drifting in phase, a non-periodic response), so the periods' scatter underestimates the noise "
        "of their mean and the p-values here come out too small — a gap, band or effect near its threshold may be "
        "that disturbance, not the model");
  if (rep.period_power_unequal()) {
    const auto [lo, hi] = std::minmax_element(pp.relative.begin(), pp.relative.end());
    rep.notes.push_back("the noise power differs between periods " + std::to_string(first + 1) + "-" +
                        std::to_string(s.M) + " of the " + std::to_string(s.M) + " analysed (relative power " +
                        fmt(*lo, 3) + " to " + fmt(*hi, 3) + ", p " +
                        p_text(pp.p, 2) +
                        "): the noise is not stationary. Unequal power by itself leaves the gap, band and effect "
                        "tests valid, if anything conservative (each line's t is Student's t under unequal "
                        "variances: the loudest period raises the mean and the variance together), so a gap or "
                        "effect near its threshold may be missed, not invented; " +
                        (static_model ? std::string("the transient test of this static model compares the periods' "
                                                    "deviation sizes, so its leakage p-value comes out too small")
                                      : std::string("the transient test compares the shape of a period's deviation, "
                                                    "not its size")));
  }
}

// The best-linear-approximation view of the model as given (GapDistortion in
// gap.hpp): the gap on the detection lines, its level and share, and whether
// the excited lines show more than it.
// Method: the prediction for excited line k is the mean t of the 4 detection
// lines nearest in frequency; Z = (Σ t_k − Σ pred_k) / √(Σ pred_k² +
// Σ_j c_j² t̄_j²) with c_j the times detection line j enters the predictions
// / 4 and t̄_j the prediction level there. Under the BLA view the t's are
// independent scaled F(2, d) variates, d = 2M − 2 (circular Gaussian
// distortion plus noise, a level that changes slowly with frequency), and Z
// is scale-free, so its null law depends only on d and the lines' layout:
// p_beyond is its Monte Carlo tail, kBlaDraws draws of every line's t as
// F(2, d) at level 1 (fixed seed: the same record, the same p), (1 + #{Z_b ≥
// Z}) / (kBlaDraws + 1). A normal approximation of Z was liberal: 26 of 300
// right BLAs rejected at alpha 0.01 (12 detection lines, M = 8: the F(2, 14)
// tails are heavy); this null, 10 of 300 (GapDiagnosis.DistortionAround…'s
// comment says why not 3). kBlaDraws = 2000: p resolution 5e-4, Monte Carlo
// standard error at p = 0.01 of √(0.01 · 0.99 / 2000) = 0.0022.
// With more than kBlaLines lines in all the draws would cost more than the
// rest of a diagnosis (≈ 30 ns per line and draw), and the normal law is then
// close: the sums' skewness is that of one F(2, d) over √(lines), 3.4/√1000 ≈
// 0.11 at d = 14 (the Cornish–Fisher shift of the 1 % point, (γ/6)(z² − 1),
// 0.08 in Z, p 0.010 → 0.012); there p_beyond is the normal tail of Z/cv,
// cv² = d/(d − 4) the F(2, d) variance over its squared mean.
constexpr int kBlaDraws = 2000;
constexpr size_t kBlaLines = 1000;
// p_gap, gap_before: the report's (detection_tests).
GapDistortion distortion_view(const Spectra& s, const Augment& a0, const LineStats& st0, double p_gap,
                              double gap_before, double alpha) {
  GapDistortion d;
  d.odd_only = std::all_of(s.exc.begin(), s.exc.end(), [](int k) { return k % 2 == 1; });
  std::vector<int> det;
  for (int k : s.ne)
    if (!d.odd_only || k % 2 == 1) det.push_back(k);
  d.lines = static_cast<int>(det.size());
  d.estimable = det.size() >= 4;
  if (!d.estimable) return d;
  const LineStats sd = line_stats(s, a0, det);
  d.gap = gap_of(sd);
  if (d.gap > 1) d.level_db = 10 * std::log10(d.gap - 1);
  d.share = gap_before > 1 ? std::max(0.0, d.gap - 1) / (gap_before - 1) : 0.0;
  d.p_detected = fisher_p(sd.t, s.M);
  constexpr int kNearest = 4;
  const size_t J = det.size(), K = s.exc.size();
  std::vector<std::array<size_t, kNearest>> nearest(K);  // each excited line's detection lines
  std::vector<size_t> order(J);
  for (size_t i = 0; i < K; ++i) {
    const int k = s.exc[i];
    std::iota(order.begin(), order.end(), size_t{0});
    std::partial_sort(order.begin(), order.begin() + kNearest, order.end(),
                      [&](size_t x, size_t y) { return std::abs(det[x] - k) < std::abs(det[y] - k); });
    std::copy(order.begin(), order.begin() + kNearest, nearest[i].begin());
  }
  std::vector<double> c(J, 0.0), level(J, 0.0);
  const auto Z_of = [&](const auto& t_exc, const auto& t_det) {
    std::fill(c.begin(), c.end(), 0.0);
    double sum_t = 0, sum_pred = 0, var = 0;
    for (size_t i = 0; i < K; ++i) {
      double pred = 0;
      for (size_t j : nearest[i]) pred += t_det(j) / kNearest;
      for (size_t j : nearest[i]) {
        c[j] += 1.0 / kNearest;
        level[j] = pred;
      }
      sum_t += t_exc(i);
      sum_pred += pred;
      var += pred * pred;
    }
    for (size_t j = 0; j < J; ++j) var += c[j] * c[j] * level[j] * level[j];
    return (sum_t - sum_pred) / std::sqrt(var);
  };
  const double Z = Z_of([&](size_t i) { return st0.t(static_cast<Eigen::Index>(i)); },
                        [&](size_t j) { return sd.t(static_cast<Eigen::Index>(j)); });
  d.p_beyond = 1;
  if (std::isfinite(Z) && K + J > kBlaLines) {
    d.p_beyond = 0.5 * std::erfc(Z / gap_null_sd(s.M, 1) / std::sqrt(2.0));
  } else if (std::isfinite(Z)) {
    // F(2, d) by inversion: P(F > x) = (1 + 2x/d)^(−d/2), so x = (d/2)(U^(−2/d) − 1).
    const double dof = 2.0 * s.M - 2;
    std::mt19937_64 rng(0x5eed0b1aULL);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const auto draw = [&] { return 0.5 * dof * (std::pow(1.0 - unit(rng), -2.0 / dof) - 1.0); };  // 1 − U ∈ (0, 1]
    std::vector<double> te(K), td(J);
    int beyond = 0;
    for (int b = 0; b < kBlaDraws; ++b) {
      for (double& v : te) v = draw();
      for (double& v : td) v = draw();
      beyond += Z_of([&](size_t i) { return te[i]; }, [&](size_t j) { return td[j]; }) >= Z;
    }
    d.p_beyond = (1.0 + beyond) / (kBlaDraws + 1.0);
    d.p_beyond_min = 1.0 / (kBlaDraws + 1.0);
  }
  d.bla_right = p_gap < alpha && d.p_detected < alpha && d.p_beyond >= alpha;
  return d;
}

// The runs of set lines in `in` (indices of the excited lines) within two
// excited lines of each other, as {first, last}: the bands and the peaks
// (gap.hpp) are merged alike.
std::vector<std::array<size_t, 2>> runs_within_two(const std::vector<bool>& in) {
  std::vector<std::array<size_t, 2>> out;
  for (size_t i = 0; i < in.size();) {
    if (!in[i]) {
      ++i;
      continue;
    }
    size_t j = i, last = i;
    while (j < in.size() && j <= last + 2) {
      if (in[j]) last = j;
      ++j;
    }
    out.push_back({i, last});
    i = last + 1;
  }
  return out;
}

// GapReport::peaks, from the flagged lines (gap_bands).
void gap_peaks(const Spectra& s, const LineStats& st0, GapReport& rep) {
  const Eigen::Index K = st0.t.size();
  const double excess = (st0.t.array() - 1).sum();
  if (!(excess > 0)) return;
  std::vector<Eigen::Index> order;
  for (Eigen::Index i = 0; i < K; ++i)
    if (rep.flagged[static_cast<size_t>(i)] && st0.t(i) > 1) order.push_back(i);
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return st0.t(a) > st0.t(b); });
  std::vector<bool> in(static_cast<size_t>(K), false);
  double held = 0;
  for (size_t n = 0; n < order.size() && held < excess / 2; ++n) {
    in[static_cast<size_t>(order[n])] = true;
    held += st0.t(order[n]) - 1;
  }
  for (const auto& [first, last] : runs_within_two(in)) {
    double sum = 0;
    for (size_t j = first; j <= last; ++j)
      if (in[j]) sum += st0.t(static_cast<Eigen::Index>(j)) - 1;
    rep.peaks.push_back({{s.hz(s.exc[first]), s.hz(s.exc[last])}, sum / excess});
  }
  std::stable_sort(rep.peaks.begin(), rep.peaks.end(),
                   [](const GapReport::Peak& a, const GapReport::Peak& b) { return a.share > b.share; });
}

// Bands of the model as given: the flags and the bands of rep (gap.hpp).
// Method: Benjamini–Hochberg at `fdr` over p(k) = P(F(2, 2M−2) > t(k)); when
// no line is flagged, over windows of 8 excited lines (Fisher-combined)
// instead. Flagged lines within two excited lines of each other form a band.
void gap_bands(const Spectra& s, const LineStats& st0, double fdr, GapReport& rep) {
  std::vector<double> p(s.exc.size());
  for (size_t i = 0; i < p.size(); ++i) p[i] = f2_survival(st0.t(i), 2 * st0.M - 2);
  std::vector<bool> flag = benjamini_hochberg(p, fdr);
  if (std::none_of(flag.begin(), flag.end(), [](bool b) { return b; })) {
    const size_t w = 8;
    std::vector<double> pw;
    for (size_t i = 0; i < p.size(); i += w) {
      const size_t n = std::min(w, p.size() - i);
      pw.push_back(fisher_p(st0.t.segment(i, n), st0.M));
    }
    const std::vector<bool> fw = benjamini_hochberg(pw, fdr);
    for (size_t i = 0; i < p.size(); ++i) flag[i] = fw[i / w];
  }
  rep.flagged = flag;
  for (const auto& [first, last] : runs_within_two(flag)) rep.bands.push_back({s.hz(s.exc[first]), s.hz(s.exc[last])});
  gap_peaks(s, st0, rep);
}

// Runs task(0) … task(n − 1) on two workers, each taking the next untried
// index; the tasks must be independent (each writes its own result). Used
// where a diagnosis fits independent candidates: the results, and so the
// report, do not depend on which worker ran which.
void on_two_workers(size_t n, const std::function<void(size_t)>& task) {
  std::atomic<size_t> next{0};
  const auto worker = [&] {
    for (size_t i; (i = next++) < n;) task(i);
  };
  auto second = std::async(std::launch::async, worker);
  worker();
  second.get();
}

// Every linear effect and the nonlinearity, each alone on the model as given:
// gap after, and p-value (the F-test against the pooled cost V0 for a linear
// effect; the nonlinearity test for the nonlinearity).
std::vector<EffectFit> fits_alone(const Diagnosis& dg, const Spectra& s, const Augment& a0, double V0,
                                  double p_nonlinearity) {
  // kLinearEffects' fits, then the nonlinearity's; independent of each other.
  std::vector<EffectFit> fits(kLinearEffects.size() + 1);
  on_two_workers(fits.size(), [&](size_t i) {
    const bool linear = i < kLinearEffects.size();
    const Trial t = linear ? dg.fit(kLinearEffects[i], a0) : dg.fit_nonlinearity(a0);
    const LineStats ls = line_stats(s, t.state, s.exc);
    fits[i] = t.fit;
    fits[i].gap_after = gap_of(ls);
    fits[i].p_value =
        linear ? dg.searched_p(kLinearEffects[i], dg.f_test(V0, ls.pooled_cost, t.fit.dof, t.fit.dof)) : p_nonlinearity;
  });
  return fits;
}

// Leakage: how many leading periods carry a transient. Method: drop periods
// while the period-deviation test (Diagnosis::leakage_p) of the first kept
// one rejects at `alpha` and at least `keep` periods remain after the drop;
// the transient decays geometrically, so the first period that passes still
// carries some of it: one more goes when at least `keep` remain after it.
int transient_periods(const Diagnosis& dg, const Spectra& s, const Augment& a0, double p_leakage, double alpha) {
  // Periods kept: at least 4, or 3 of a 4-period record (its one transient
  // period dropped; the selection's noise bound then comes from the F(2, 4)
  // law by Monte Carlo, gap_noise_bound).
  const int keep = std::min(4, s.M - 1);
  int drop = 0;
  for (double p = p_leakage; s.M - drop - 1 >= keep && p < alpha;)  // p = leakage_p(a0, drop)
    if (s.M - ++drop - 1 >= keep) p = dg.leakage_p(a0, drop);
  if (drop > 0 && s.M - drop - 1 >= keep) ++drop;
  return drop;
}

// The leakage candidate: the gap with the transient periods (at least one) left out.
EffectFit leakage_alone(const Spectra& s, const Augment& a0, int drop, double p_leakage) {
  Augment a = a0;
  a.first = std::max(drop, 1);
  return {gap_of(line_stats(s, a, s.exc)), 0, 0, p_leakage, Leakage{a.first}};
}

// The level at which an effect's own test admits it (ForwardSelection::admit):
// alpha for the nonlinearity's test on the unexcited lines as the first effect
// (beside an effect found it is an addition, at effect_alpha: admit),
// effect_alpha for the leakage test and the linear effects' F-tests.
double admission_level(Effect e, const GapOptions& o) { return e == Effect::Nonlinearity ? o.alpha : o.effect_alpha; }

// One stage of the forward selection: a set of effects fitted jointly on the
// model as given — linear effects (Diagnosis::fit_set, in kAllEffects' order),
// the transient periods dropped (leakage), the nonlinear distortion refitted
// on top (nonlinearity) — and its pooled cost.
struct Stage {
  std::vector<Effect> linear;
  int first = 0;
  bool nonlinear = false;
  double p_nonlinear = 1;           // the nonlinearity test that admitted it
  bool distortion_fitted = true;    // the static polynomial is part of the fit (see ForwardSelection::admit)
  bool by_prediction = false;       // the nonlinearity admitted by its prediction test (ForwardSelection::admit)
  bool admitted = true;             // the last addition passed its tests
  Augment state;
  std::vector<EffectFit> fits;      // every effect of the set, in the order added
  double V = std::numeric_limits<double>::infinity();  // pooled cost on the excited lines
  double gap = std::numeric_limits<double>::infinity();
  int q = 0;                        // real parameters of the set
};

// The selection of the chosen set (gap.hpp, "Selection"): forward, every stage
// refitted jointly from the model as given and admitted by a test on that
// joint fit.
// Method: at each stage every effect not yet in the set is added and the
// whole set refitted. The addition is admissible when
//  - a linear effect: the F-test of the joint fit against the current one
//    rejects at effect_alpha and the relevance rule holds (it removes
//    min_share of the current excess gap, or of 3 null sd of the gap);
//  - nonlinearity: the Fisher test on the unexcited lines inside the band of
//    the current fit (its periods) rejects at alpha; when its static
//    polynomial raises the gap by more than the noise it enters without that
//    term (present, not fitted); or, at the first stage only, when that test
//    does not reject, its prediction test (Diagnosis::
//    nonlinearity_prediction_p) rejects at alpha, the polynomial is fitted
//    and the joint fit beats every linear candidate on the criterion
//    (hold_prediction_to_the_criterion);
//  - leakage: the transient test (Diagnosis::leakage_p) of the current fit
//    rejects at effect_alpha, like a linear effect's F-test (at alpha, with
//    its full power since stop 42, it added a leakage beside 5 clear or
//    subtle effects in 600 blind cases, p 2.5e-3 … 9.6e-3; the transients of
//    gap-validate seeds 1, 3, 4 all test at p < 1e-8); when it rejects on the
//    model as given, leakage leads instead (leakage_stage);
// and, for every effect, the joint gap does not rise by more than the noise
// (gap_noise_bound of the periods the joint fit uses: 3 null sd from 4
// periods on): an effect that makes the fit worse never enters. Of the linear
// effects only the one with the lowest criterion is tested. Among the
// admissible additions the one with the lowest Schwarz criterion
// (V + ½ ln(2K) q + Σ ln N_e) / K (N_e: the locations effect e searched,
// Diagnosis::search_cost) — in units of the gap, the pooled cost per excited line
// being ≈ 1 under a right model whatever the periods used — is taken; the
// selection stops when none is admissible (at most 4 stages).
class ForwardSelection {
 public:
  // At most two linear effects, as the pair search before it allowed: the
  // blind cases hold at most pairs, and a third linear effect admitted on them
  // fitted the noise's structure (measured: 1 of 20 pairs on seed 1).
  static constexpr size_t kMaxLinear = 2;

  // `p_leakage`: the transient test on the model as given; when it rejects at
  // effect_alpha (and `drop` > 0) the selection starts from the steady-state
  // periods (leakage_stage).
  ForwardSelection(const Diagnosis& dg, const Spectra& s, const Augment& a0, int drop, double p_leakage,
                   const GapOptions& o)
      : dg_(dg), s_(s), a0_(a0), drop_(drop), p_leakage_(p_leakage),
        leakage_first_(drop > 0 && p_leakage < o.effect_alpha), o_(o) {
    const int K = static_cast<int>(s.exc.size());
    floor_all_ = gap_noise_bound(s.M, K);
    floor_kept_ = drop > 0 ? gap_noise_bound(s.M - drop, K) : floor_all_;
    Augment start = a0;
    start.first = leakage_first_ ? drop : 0;
    p_prediction_ = dg.nonlinearity_prediction_p(start);
  }

  // The nonlinearity's prediction test (Diagnosis::nonlinearity_prediction_p)
  // on the periods the selection starts from.
  double p_prediction() const { return p_prediction_; }

  // The noise bound of a stage's gap (gap_noise_bound) for the periods it
  // uses: all, or those after the transient's (a leading leakage, or one
  // admitted later).
  double floor(const Stage& st) const { return st.first > 0 ? floor_kept_ : floor_all_; }

  // The stages taken, from the model as given (stage 0) to the chosen set;
  // `best_single`: of the effects admitted alone (stage 1), the one leaving
  // the least gap.
  // `alternatives`, `additions`, `pair_ties`: see GapReport::alternatives,
  // ::possible_additions and ::alternative_pairs, for the stage-1 linear
  // effect, from the fits the selection made anyway (each effect alone at
  // stage 1, each added to it at stage 2, the pairs of pair_beats_single).
  // `base`: the stage the free selection starts from (0, or 1 after a
  // leading leakage); best_single, alternatives and additions are taken
  // relative to it.
  std::vector<Stage> run(std::optional<Stage>& best_single, std::vector<std::pair<Effect, double>>& alternatives,
                         std::vector<std::pair<Effect, double>>& additions,
                         std::vector<std::array<Effect, 2>>& pair_ties, size_t& base) const {
    std::vector<Stage> path{evaluate(Stage{})};
    if (leakage_first_) path.push_back(leakage_stage(path.front()));
    base = path.size() - 1;
    std::array<std::optional<Stage>, kAllEffects.size()> alone;
    for (size_t stage = base; stage < 4; ++stage) {
      const Stage& cur = path.back();
      // Of the linear effects only the best by the criterion is put to the
      // test (as a best-subset search would: an effect that merely passes
      // its test while another explains the data better is not taken);
      // leakage and nonlinearity by their own tests.
      std::optional<Stage> best, best_linear;
      // Every candidate refitted on `cur` (independent of each other) by two
      // workers taking the next untried one; the choice below runs in
      // kAllEffects' order, so the result does not depend on who did which.
      std::array<std::optional<Stage>, kAllEffects.size()> tried;
      on_two_workers(tried.size(), [&](size_t i) { tried[i] = admit(cur, kAllEffects[i]); });
      hold_prediction_to_the_criterion(tried);
      if (stage == base) alone = tried;
      const bool single = stage == base + 1 && cur.linear.size() == 1 && cur.first == path[base].first && !cur.nonlinear;
      if (single) {
        alternatives = equivalents(cur.linear[0], alone, tried);
        additions = possible_additions(cur, tried);
      }
      const bool to_delay = single && lagging_delay_suffices(cur.linear[0], alone, tried);
      for (size_t i = 0; i < kAllEffects.size(); ++i) {
        const Effect e = kAllEffects[i];
        std::optional<Stage> next = std::move(tried[i]);
        if (!next) continue;
        if (stage == base && next->admitted && (!best_single || next->gap < best_single->gap)) best_single = next;
        if (is_linear(e)) {
          if (!best_linear || score(*next) < score(*best_linear)) best_linear = next;
        } else if (next->admitted && (!best || score(*next) < score(*best))) {
          best = std::move(next);
        }
      }
      if (best_linear && best_linear->admitted && (!best || score(*best_linear) < score(*best)))
        best = std::move(best_linear);
      if (!best && to_delay) {  // the low-pass alone would be the verdict: the delay instead, and its stage redone
        path.back() = *alone[index_of(Effect::Delay)];
        --stage;
        continue;
      }
      if (!best && single) {
        if (std::optional<std::pair<size_t, Stage>> pair = pair_beats_single(cur, alone, pair_ties)) {
          path.back() = *alone[pair->first];  // the pair's first member, then the pair
          path.push_back(std::move(pair->second));
          continue;
        }
      }
      if (!best) break;
      path.push_back(exchanged(cur, std::move(*best)));
    }
    if (std::optional<Stage> split = gain_split(path.back())) path.push_back(std::move(*split));
    return path;
  }

 private:
  // The leading stage when a transient is proven (leakage_first): the
  // transient periods dropped, before any other effect is tried. Dropping is
  // no fitted effect — the periods' data are not in steady state, whatever
  // the model — so it is not held to the gap rule: the transient's period-to-
  // period scatter inflates the noise floor, and once it is gone the gap can
  // rise (the circuit's record: 7.6 on all 8 periods, 1.7e3 on the steady
  // ones), the model's misfit that the other effects must then explain.
  Stage leakage_stage(const Stage& model) const {
    Stage st = model;
    st.first = drop_;
    st = evaluate(std::move(st));
    set_p(st, Effect::Leakage, p_leakage_);
    return st;
  }

  // `cur` with e added and refitted jointly, `admitted` when e's test admits
  // it (see the class comment); nothing when e cannot be added (in the set,
  // two linear effects already, no transient or no unexcited lines, or
  // leakage's or nonlinearity's test does not reject).
  std::optional<Stage> admit(const Stage& cur, Effect e) const {
    if (holds(cur, e) || (e == Effect::Leakage && cur.first > 0) || (e == Effect::Nonlinearity && cur.nonlinear)) return {};
    Stage next = cur;
    double p = 1;
    if (e == Effect::Leakage) {
      if (drop_ == 0) return {};
      p = dg_.leakage_p(cur.state, 0);
      if (!(p < admission_level(e, o_))) return {};
      next.first = drop_;
    } else if (e == Effect::Nonlinearity) {
      if (s_.ne.size() < 4) return {};
      // The detection test at alpha where the nonlinearity is the first
      // effect; beside an effect already found it is an addition, held to
      // an addition's level, effect_alpha, as the linear effects and leakage
      // are. Why: the clear-single target (>= 99 % right) leaves under 1 %
      // per case for every false addition together; the five linear
      // candidates and leakage at effect_alpha take at most 0.6 % of it
      // (Bonferroni), a nonlinearity test at alpha = 1 % alone would take
      // it all. Measured on gap-validate seeds 1-6 x {classic, structure} x
      // {discrete, continuous} at 300 cases and classic at 100 (7800) against
      // stop 72's binary: 18 verdicts changed, 17 fixed, none broken — each a
      // nonlinearity at p 1e-3 ... 1e-2 dropped from beside a right set
      // (classic seed 3 case 26 in every family: mode_mismatch +
      // nonlinearity at p 6.1e-3, the polynomial leaving the gap at 0.930
      // from 0.931; seed 6 case 232, seed 5 cases 258 and 299, ...), the
      // 18th a wrong set that kept its wrong low-pass; no true nonlinearity
      // was lost. The F-16's model on its own Level-1 record loses one (p
      // 9.8e-3, README "Real data").
      const bool first_stage = cur.linear.empty() && cur.first == (leakage_first_ ? drop_ : 0);
      p = fisher_p(line_stats(s_, cur.state, s_.ne).t, s_.M - cur.first);
      if (!(p < (first_stage ? admission_level(e, o_) : o_.effect_alpha))) {
        if (!(first_stage && p_prediction_ < admission_level(e, o_)))
          return {};
        p = p_prediction_;
        next.by_prediction = true;
      }
      next.nonlinear = true;
      next.p_nonlinear = p;
    } else {
      if (cur.linear.size() >= kMaxLinear) return {};
      next.linear.push_back(e);
    }
    next = evaluate(std::move(next));
    if (e == Effect::Nonlinearity && !(next.gap <= cur.gap + floor(next))) {
      // Detected on the unexcited lines, but the static polynomial on the
      // linear prediction is not the record's nonlinearity (one inside the
      // loop or behind another element): present, without a fitted term.
      next.distortion_fitted = false;
      next = evaluate(std::move(next));
    }
    next.admitted = next.gap <= cur.gap + floor(next) && !(next.by_prediction && !next.distortion_fitted);
    if (is_linear(e)) {
      p = addition_p(e, cur, next);
      next.admitted = next.admitted && p < admission_level(e, o_) && relevant(cur.gap, next.gap, floor(cur));
    }
    set_p(next, e, p);
    return next;
  }

  // A nonlinearity admitted by its prediction test alone (admit, at the
  // first stage only) stays admitted only where its joint fit beats every
  // linear candidate of the stage on the criterion (score), admitted or not:
  // it is to explain the excited lines better than any linear effect does,
  // as the in-loop cubics it is for do (gap 1.1 against 4–5 for the modes
  // taken instead). Why the first stage only: as a plain second test at
  // every stage (both tests at alpha/2, Bonferroni) it added a nonlinearity
  // beside a right linear effect in ~13 of the ~1240 nonlinearity-free cases
  // of gap-validate seeds 2–4 × classic, structure × discrete, continuous
  // (p 5e-4 … 1e-2: the test at its level, 1 % of them; a linear effect's
  // misfit also leaves the excited lines for the polynomial to fit), against
  // ~9 nonlinearities found. Its level here: at most alpha beside the Fisher
  // test's alpha, once per diagnosis. Measured with both rules (README,
  // stop 68): 15 verdicts of seeds 1–4 changed and 8 of seeds 5–6 (held
  // out), each a subtle nonlinearity read as linear effects before and named
  // alone now; no other verdict changed.
  void hold_prediction_to_the_criterion(std::array<std::optional<Stage>, kAllEffects.size()>& tried) const {
    auto nl = std::find_if(tried.begin(), tried.end(), [](const std::optional<Stage>& t) { return t && t->by_prediction; });
    if (nl == tried.end()) return;
    for (size_t i = 0; i < kAllEffects.size(); ++i)
      if (is_linear(kAllEffects[i]) && tried[i] && !(score(**nl) < score(*tried[i]))) (*nl)->admitted = false;
  }

  // e's index in kAllEffects (the order of the stage arrays `alone`, `tried`).
  static size_t index_of(Effect e) {
    return static_cast<size_t>(std::find(kAllEffects.begin(), kAllEffects.end(), e) - kAllEffects.begin());
  }

  // Parsimony between the two lags: whether the low-pass e = sensor_dynamics
  // the criterion chose is to give way to a delay admitted alone, with fewer
  // parameters, that lags too (τ > 0) and beside which the low-pass is not
  // significant (the pair fitted at stage 2 against the delay alone: the
  // F-test every addition passes, at effect_alpha). The Schwarz criterion
  // charges ½ ln(2K) per parameter (2.3 for K = 48), less than that F-test's
  // critical value (effect_alpha 1e-3: χ²₁ 10.8 in units of 2V, 5.4 of V),
  // so it took the low-pass's extra parameter where the selection's own test,
  // asked whether the record demands it beyond the delay, says no (a delay of
  // 0.58 samples named an order-2 low-pass, cut-off 0.34 Hz, damping 0.60:
  // nearly linear phase, flat magnitude in a band to 0.12 Hz; the low-pass
  // beside the delay at p 0.022: gap-validate --continuous seed 1 case 63).
  // Only a lagging delay: the low-pass always lags, so only there are the two
  // stand-ins for one another; where the best delay leads (τ < 0), the
  // low-pass explains the magnitude, not a lag. And only where the low-pass
  // alone would be the verdict (run): a pair the selection goes on to build
  // from the low-pass is not rebuilt from the delay. Measured on 1200 blind
  // cases (gap-validate seeds 1–4 × classic, continuous, structure): 4
  // delays named a low-pass are named right, 1 clear low-pass (cut-off 0.13
  // Hz at a band edge of 0.10 Hz) is named a delay, with the low-pass as its
  // alternative; nothing else changes. Taken on seeds 1, 2 over a first form
  // (any simpler effect, τ of either sign, applied at stage 2 whatever
  // followed), which turned 3 misses right and 7 right verdicts wrong — 5
  // low-passes with a leading best delay, a pair rebuilt from the delay;
  // seeds 3, 4 then held out: 1 right, none wrong.
  bool lagging_delay_suffices(Effect e, const std::array<std::optional<Stage>, kAllEffects.size()>& alone,
                              const std::array<std::optional<Stage>, kAllEffects.size()>& pairs) const {
    const size_t is = index_of(e), id = index_of(Effect::Delay);
    if (e != Effect::SensorDynamics || !alone[is] || !alone[id] || !pairs[id]) return false;
    const Stage& delay = *alone[id];
    if (!delay.admitted || delay.q >= alone[is]->q) return false;
    const EffectFit* lag = fit_of(delay, Effect::Delay);
    if (!lag || !(std::get<Delay>(lag->parameters).samples > 0)) return false;
    const Stage& pair = *pairs[id];
    return dg_.f_test(delay.V, pair.V, std::max(1, pair.q - delay.q), pair.q) >= o_.effect_alpha;
  }

  // The linear effects g that explain the data as well as e: g admitted
  // alone, its Schwarz criterion within 1 of e's (in units of V, a log Bayes
  // factor: 2 ln B ≤ 2, "not worth more than a bare mention" on Kass and
  // Raftery's scale — so a richer effect that merely nests e, a mode whose
  // constant term is a gain, is no alternative to it), and e added to g (the
  // pair fitted at stage 2) not significant.
  std::vector<std::pair<Effect, double>> equivalents(Effect e, const std::array<std::optional<Stage>, kAllEffects.size()>& alone,
                                                     const std::array<std::optional<Stage>, kAllEffects.size()>& pairs) const {
    std::vector<std::pair<Effect, double>> out;
    const size_t ie = index_of(e);
    if (ie >= kAllEffects.size() || !alone[ie]) return out;
    const double K = static_cast<double>(s_.exc.size());
    for (size_t i = 0; i < kAllEffects.size(); ++i) {
      const Effect g = kAllEffects[i];
      if (g == e || !is_linear(g) || !alone[i] || !alone[i]->admitted || !pairs[i]) continue;
      if ((score(*alone[i]) - score(*alone[ie])) * K > 1) continue;
      const Stage& pair = *pairs[i];
      const double p = dg_.f_test(alone[i]->V, pair.V, std::max(1, pair.q - alone[i]->q), pair.q);
      if (p >= o_.effect_alpha) out.emplace_back(g, p);
    }
    return out;
  }

  // The linear effects g whose joint fit beside the one linear effect of
  // `cur` (stage 1) explains the record as well as it alone: Schwarz
  // criterion within 1 of cur's (2 ln B ≤ 2, as equivalents) and g's F-test
  // not significant at effect_alpha (the record does not demand g; one that
  // does but fails the relevance rule is no "as well"). With that p-value.
  std::vector<std::pair<Effect, double>> possible_additions(
      const Stage& cur, const std::array<std::optional<Stage>, kAllEffects.size()>& pairs) const {
    std::vector<std::pair<Effect, double>> out;
    const double K = static_cast<double>(s_.exc.size());
    for (size_t i = 0; i < kAllEffects.size(); ++i) {
      const Effect g = kAllEffects[i];
      if (!is_linear(g) || !pairs[i] || pairs[i]->admitted) continue;
      if ((score(*pairs[i]) - score(cur)) * K > 1) continue;
      for (const EffectFit& f : pairs[i]->fits)
        if (f.effect() == g && f.p_value >= o_.effect_alpha) out.emplace_back(g, f.p_value);
    }
    return out;
  }

  // Stepwise exchange after an addition `next` to `cur`: each earlier linear
  // effect of the set may be exchanged for another linear effect g when the
  // joint fit's Schwarz criterion falls and the exchanged set passes the
  // addition's tests (F-test at effect_alpha, relevance, gap rule) — against
  // `cur`, or, member by member, against the set without that member (each
  // member must pay for itself beside the others, as an addition does). A
  // greedy first choice fixed for good would miss pairs whose members are
  // weak alone (a delay beside a mode whose fit first took the phase lag).
  // Why the second form: the exchanged set no longer contains `cur`, so the
  // test against it compares sets that are not nested; a richer first effect
  // that explains most of the record alone makes it fail for a better pair
  // (a 0.80 gain with a 0.26-sample delay read as a series unmodelled_mode,
  // gap 0.97, then the delay: the gain + delay pair was rejected since it
  // lowers V little below the mode's, gap-validate seed 3 case 98).
  Stage exchanged(const Stage& cur, Stage next) const {
    if (next.linear.size() < 2 || next.linear.size() == cur.linear.size()) return next;
    const Effect added = next.linear.back();
    for (size_t i = 0; i + 1 < next.linear.size(); ++i)
      for (Effect g : kLinearEffects) {
        if (holds(next, g)) continue;
        Stage alt = without(next, next.linear[i]);
        alt.linear.insert(alt.linear.begin() + static_cast<std::ptrdiff_t>(i), g);
        alt = evaluate(std::move(alt));
        if (!(score(alt) < score(next))) continue;
        const double p = addition_p(g, cur, alt);
        if (p < o_.effect_alpha && passes(cur, alt)) {
          set_p(alt, g, p);
          set_p(alt, added, p);
          next = std::move(alt);
          continue;
        }
        std::vector<double> ps;
        bool each_pays = true;
        for (size_t k = 0; k < alt.linear.size() && each_pays; ++k) {
          const Effect m = alt.linear[k];
          const Stage other = evaluate(without(alt, m));
          ps.push_back(addition_p(m, other, alt));
          each_pays = ps.back() < admission_level(m, o_) && passes(other, alt);
        }
        if (!each_pays) continue;
        for (size_t k = 0; k < alt.linear.size(); ++k) set_p(alt, alt.linear[k], ps[k]);
        next = std::move(alt);
      }
    return next;
  }

  // Whether the stage's linear set holds e.
  static bool holds(const Stage& st, Effect e) {
    return std::find(st.linear.begin(), st.linear.end(), e) != st.linear.end();
  }

  // The stage's fit of the effect e; null when e is not in the stage.
  static const EffectFit* fit_of(const Stage& st, Effect e) {
    const auto f = std::find_if(st.fits.begin(), st.fits.end(), [&](const EffectFit& x) { return x.effect() == e; });
    return f == st.fits.end() ? nullptr : &*f;
  }

  // The p-value that admitted e into the stage, set on e's fit.
  static void set_p(Stage& st, Effect e, double p) {
    for (EffectFit& f : st.fits)
      if (f.effect() == e) f.p_value = p;
  }

  // `st` without the linear effect m (its fit dropped; not refitted).
  static Stage without(const Stage& st, Effect m) {
    Stage out = st;
    out.linear.erase(std::remove(out.linear.begin(), out.linear.end(), m), out.linear.end());
    out.fits.erase(std::remove_if(out.fits.begin(), out.fits.end(), [&](const EffectFit& f) { return f.effect() == m; }),
                   out.fits.end());
    return out;
  }

  // The addition's F-test of the linear effect m on the step from `from` to
  // `to` (which holds m), with m's search accounted for (searched_p). At
  // least one parameter: the joint refit can lower another effect's order (a
  // second-order sensor becomes first order beside a delay), and q ≤ 0 would
  // make the test say p = 1 for any decrease.
  double addition_p(Effect m, const Stage& from, const Stage& to) const {
    return dg_.searched_p(m, dg_.f_test(from.V, to.V, std::max(1, to.q - from.q), to.q));
  }

  // A series unmodelled_mode's DC gain as a gain_error of its own. The free
  // series factor d + c/(ξ−λ) + c̄/(ξ−λ̄) is exactly its DC value times a
  // unit-DC resonance (Diagnosis::Constant), so a series mode fitted without
  // a gain_error takes any gain error beside it for nothing: gain_error +
  // unmodelled_mode was read as the mode alone in 27 of the 7200 stop-70
  // gap-validate cases (seeds 1–6 × 4 families × 300), a gain_error +
  // mode_mismatch so in 2 more. The set with a gain_error and the mode at
  // unit DC fits as the free mode does (the same function class, q the same);
  // it is taken when the gain passes an addition's test against the set with
  // the mode held at unit DC and no gain (F-test at effect_alpha on one
  // degree of freedom, relevance, gap rule): the gain pays for itself as any
  // addition does. Appended as a stage of its own: the path shows the mode
  // found, then its DC gain named, at the same gap. Not beside a
  // nonlinearity: an odd polynomial changes the best linear approximation's
  // gain by its describing function (y = u + a₃u³ driven by a Gaussian-like
  // multisine of power σ²: gain 1 + 3a₃σ²), so a gain change there is not
  // the linear chain's own (measured: the split named a gain beside 2 true
  // nonlinearity + unmodelled_mode pairs and fixed none with a
  // nonlinearity).
  std::optional<Stage> gain_split(const Stage& last) const {
    if (last.linear.size() >= kMaxLinear || last.nonlinear || holds(last, Effect::GainError)) return std::nullopt;
    const EffectFit* mode = fit_of(last, Effect::UnmodelledMode);
    if (!mode || !std::get<UnmodelledMode>(mode->parameters).series) return std::nullopt;
    const Stage unit = evaluate(last, /*series_at_unit_dc=*/true);
    Stage split = last;
    split.linear.push_back(Effect::GainError);
    split = evaluate(std::move(split));
    const double p = addition_p(Effect::GainError, unit, split);
    if (!(p < admission_level(Effect::GainError, o_) && passes(unit, split))) return std::nullopt;
    set_p(split, Effect::GainError, p);
    return split;
  }

  // The gap rule and the relevance rule of a step from `from` to `to`.
  bool passes(const Stage& from, const Stage& to) const {
    return to.gap <= from.gap + floor(to) && relevant(from.gap, to.gap, floor(from));
  }

  // The stage's state, fits and cost: the linear set fitted jointly on the
  // model as given with the stage's periods, then the nonlinear distortion.
  // series_at_unit_dc: a series unmodelled_mode held at unit DC gain without
  // a gain_error beside it (gain_split's reference fit; Augment).
  Stage evaluate(Stage st, bool series_at_unit_dc = false) const {
    Augment a = a0_;
    a.first = st.first;
    a.series_at_unit_dc = series_at_unit_dc;
    // With nonlinear distortion in the set: the distortion fitted on the bare
    // model first, the linear effects fitted on the target without it, then
    // the distortion refitted on top (fitting the linear effects to a target
    // that still holds the distortion biases them: a moved mode absorbed a
    // cubic's harmonics, gap 47 where 1.6 was reachable).
    const bool distortion = st.nonlinear && st.distortion_fitted;
    if (distortion) a.nl = dg_.fit_nonlinearity(a).state.nl;
    double V = 0;
    std::vector<EffectFit> linear_fits;
    // The joint fit is coordinate descent, so its optimum can depend on the
    // order: the set is fitted in kAllEffects' order, whatever order the
    // selection added it in (the same set, the same fit).
    std::vector<Effect> ordered = st.linear;
    std::sort(ordered.begin(), ordered.end());
    std::tie(a, linear_fits) = dg_.fit_set(ordered, a, V);
    // With both: linear effects and distortion refitted in turn until a round
    // lowers V by less than Diagnosis::joint_tol (at most kJointRounds). One
    // pass left strong distortions beside a linear effect at gap 2.5-8 (the
    // linear fit saw the first, biased polynomial; gap-validate classic seeds
    // 2, 3: input/output cubics with a delay, a moved mode or a low-pass).
    std::optional<Trial> nl_trial;
    if (distortion) {
      nl_trial = dg_.fit_nonlinearity(a);
      for (int round = 1; round < Diagnosis::kJointRounds && !ordered.empty(); ++round) {
        Augment b = nl_trial->state;
        double Vb = 0;
        auto refit = dg_.fit_set(ordered, b, Vb, &linear_fits);
        Trial t = dg_.fit_nonlinearity(refit.first);
        if (!(nl_trial->V - t.V > Diagnosis::joint_tol(t.V))) break;
        linear_fits = std::move(refit.second);
        nl_trial = std::move(t);
      }
      a = nl_trial->state;
    }
    std::vector<EffectFit> fits;
    for (const EffectFit& old : st.fits) {  // keep the order added and each admitting p-value
      EffectFit f = old;
      for (const EffectFit& lf : linear_fits)
        if (lf.effect() == old.effect()) f = {0, 0, lf.dof, old.p_value, lf.parameters};
      if (old.effect() == Effect::Leakage) f = {0, 0, 0, old.p_value, Leakage{st.first}};
      fits.push_back(f);
    }
    EffectFit nl_fit{0, 0, 0, st.p_nonlinear, Nonlinearity{}};  // detected, no distortion fitted
    if (distortion) {
      nl_fit = nl_trial->fit;
      nl_fit.p_value = st.p_nonlinear;
    }
    if (st.nonlinear) {
      for (EffectFit& f : fits)
        if (f.effect() == Effect::Nonlinearity) f = nl_fit;
    }
    // The effect just added (not yet in st.fits).
    const auto listed = [&](Effect e) {
      return std::any_of(fits.begin(), fits.end(), [&](const EffectFit& f) { return f.effect() == e; });
    };
    for (const EffectFit& lf : linear_fits)
      if (!listed(lf.effect())) fits.push_back({0, 0, lf.dof, 1, lf.parameters});
    if (st.first > 0 && !listed(Effect::Leakage)) fits.push_back({0, 0, 0, 1, Leakage{st.first}});
    if (st.nonlinear && !listed(Effect::Nonlinearity)) fits.push_back(nl_fit);
    st.fits = fits;
    st.state = a;
    const LineStats ls = line_stats(s_, a, s_.exc);
    st.V = ls.pooled_cost;
    st.gap = gap_of(ls);
    st.q = 0;
    for (const EffectFit& f : st.fits) st.q += f.dof;
    return st;
  }

  // A pair the greedy order cannot reach: the single linear effect e of
  // `cur` (stage 1) would be the verdict, no addition to it admitted, while
  // two other linear effects g, h — each admitted alone, neither the best
  // alone — explain the record better jointly. A parallel mode's constant
  // term is a gain, so a series mode fitted alone can take a mode_mismatch
  // plus a gain_error (gap-validate seed 1 case 18: the mode alone 0.82,
  // mode_mismatch alone 2.0; the pair, never tried, since the greedy builds
  // on the best single). The pair is taken when each member passes, on the
  // joint fit, the test an addition passes (F-test at effect_alpha against
  // the other alone, relevance, the gap rule — h by admit, g here) and its
  // Schwarz criterion (the rule that orders the stages, so a richer pair pays
  // for its parameters) is below e's by more than 1 in units of V (2 ln B >
  // 2, past "not worth more than a bare mention" on Kass and Raftery's scale,
  // the width equivalents() gives a tie): the greedy order chose e, and only
  // positive evidence overturns it for a set it never built. With the
  // criterion merely lower, two subtle unmodelled modes became delay +
  // mode_mismatch (gap-validate --continuous seed 1 case 192, structure
  // seed 5 case 252). Returns the index of the member to stand as stage 1
  // (the lower criterion alone) and the pair's stage; `ties` gets the pairs
  // that pass the same tests with a criterion within 1 of e's either way
  // (2 ln B ≤ 2): sets the record cannot tell from e (GapReport::
  // alternative_pairs), read only where e stays the verdict.
  std::optional<std::pair<size_t, Stage>> pair_beats_single(
      const Stage& cur, const std::array<std::optional<Stage>, kAllEffects.size()>& alone,
      std::vector<std::array<Effect, 2>>& ties) const {
    std::vector<std::pair<size_t, size_t>> pairs;
    auto candidate = [&](size_t i) {
      return is_linear(kAllEffects[i]) && kAllEffects[i] != cur.linear[0] && alone[i] && alone[i]->admitted;
    };
    for (size_t i = 0; i < kAllEffects.size(); ++i)
      for (size_t j = 0; j < kAllEffects.size(); ++j)
        if (candidate(i) && candidate(j) && score(*alone[i]) < score(*alone[j])) pairs.emplace_back(i, j);
    const double K = static_cast<double>(s_.exc.size());
    std::vector<std::optional<Stage>> fitted(pairs.size());
    on_two_workers(pairs.size(), [&](size_t k) { fitted[k] = admit(*alone[pairs[k].first], kAllEffects[pairs[k].second]); });
    std::optional<std::pair<size_t, Stage>> out;
    ties.clear();
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (!fitted[k] || !fitted[k]->admitted) continue;
      const double lower_by = (score(cur) - score(*fitted[k])) * K;
      if (!(lower_by >= -1) || (out && !(score(*fitted[k]) < score(out->second)))) continue;
      const Effect g = kAllEffects[pairs[k].first];
      const Stage& h = *alone[pairs[k].second];
      const Stage& both = *fitted[k];
      const double p = addition_p(g, h, both);
      if (!(p < admission_level(g, o_) && passes(h, both))) continue;
      if (lower_by > 1)
        out.emplace(pairs[k].first, both);
      else
        ties.push_back({g, kAllEffects[pairs[k].second]});
    }
    return out;
  }

  // The relevance rule: a step from gap g_from to g_to must remove min_share
  // of the excess gap g_from − 1 (or of the noise bound `floor` of the
  // stage's periods, when the excess is below it).
  bool relevant(double g_from, double g_to, double floor) const {
    return g_from - g_to >= o_.min_share * std::max(g_from - 1, floor);
  }

  double score(const Stage& st) const {
    double search = 0;
    for (const EffectFit& f : st.fits) search += dg_.search_cost(f.effect());
    return (st.V + dg_.penalty() * st.q + search) / static_cast<double>(s_.exc.size());
  }

  const Diagnosis& dg_;
  const Spectra& s_;
  const Augment& a0_;
  int drop_;
  double p_leakage_;
  bool leakage_first_;
  const GapOptions& o_;
  double floor_all_ = 0, floor_kept_ = 0;
  double p_prediction_ = 1;
};

// The chosen set (gap.hpp): the forward selection's last stage, unless an
// effect admitted alone leaves less than it by more than the noise (3 null sd
// of the gap) — a later stage admitted by its own test can cost more than it
// gains — then that single. Fills rep.chosen, rep.steps (t per stage, for the
// figure) and rep.path; returns the final state.
Augment choose_effects(const Diagnosis& dg, const Spectra& s, const Augment& a0, int drop, const GapOptions& options,
                       GapReport& rep) {
  const ForwardSelection sel(dg, s, a0, drop, rep.p_leakage, options);
  rep.p_nonlinearity_prediction = sel.p_prediction();
  std::optional<Stage> best_single;
  std::vector<std::pair<Effect, double>> alternatives, additions;
  std::vector<std::array<Effect, 2>> pair_ties;
  size_t base = 0;
  std::vector<Stage> path = sel.run(best_single, alternatives, additions, pair_ties, base);
  if (base > 0)
    rep.notes.push_back("leakage: the first " + std::to_string(path[base].first) +
                        " period(s) carry a transient (p " + sci(rep.p_leakage, 2) +
                        "); the other effects are selected on the remaining steady-state periods, on which the model "
                        "as given leaves gap " + sci(path[base].gap, 4) + " (" + sci(rep.gap_before, 4) +
                        " on all periods)");
  if (best_single && best_single->gap < path.back().gap - sel.floor(path.back())) {
    rep.notes.push_back("the forward selection left gap " +
                        sci(path.back().gap, 4) + ", more than " + std::string(to_string(best_single->fits.back().effect())) +
                        " alone (" + sci(best_single->gap, 4) + "): the single is reported");
    path.resize(base + 1);
    path.push_back(*best_single);
  }
  if (path.back().nonlinear && !path.back().distortion_fitted)
    rep.notes.push_back(
        "nonlinearity: detected on the unexcited lines, but no polynomial form (static at the input or output, or "
        "fed back from the output through the model) improves the fit on the excited lines, so gap_after leaves it "
        "out: the nonlinearity is elsewhere (behind another element, or of higher degree or with memory)");
  if (path.back().nonlinear && path.back().by_prediction)
    rep.notes.push_back("nonlinearity: the polynomial fitted on the excited lines predicts the residual on the " +
                        std::to_string(s.ne.size()) + " unexcited lines (p " + sci(rep.p_nonlinearity_prediction, 3) +
                        "), where their own test does not reject (p " + sci(rep.p_nonlinearity, 3) +
                        "): a distortion spread thinly over them, as a cubic fed back through a lightly damped "
                        "structure gives");
  for (size_t i = 0; i < path.size(); ++i) {
    const Stage& st = path[i];
    std::string label = "model";
    SelectionStep step;
    for (const EffectFit& f : st.fits) {
      label = (label == "model" ? "+ " : label + " + ") + to_string(f.effect());
      step.set.push_back(f.effect());
      const bool before = i > 0 && std::any_of(path[i - 1].fits.begin(), path[i - 1].fits.end(),
                                               [&](const EffectFit& g) { return g.effect() == f.effect(); });
      if (!before) {  // new at this stage (an exchange can bring in an earlier stage's replacement too)
        step.added = f.effect();
        step.p_value = f.p_value;
      }
    }
    rep.steps.emplace_back(label, line_stats(s, st.state, s.exc).t);
    step.gap_after = st.gap;
    if (i > 0) rep.path.push_back(step);
  }
  rep.chosen = path.back().fits;
  // Alternatives only when the final set's one linear effect is stage 1's.
  const Stage& last = path.back();
  if (path.size() >= base + 2 && last.linear.size() == 1 && path[base + 1].linear.size() == 1 &&
      path[base + 1].linear[0] == last.linear[0]) {
    rep.alternatives = alternatives;
    rep.possible_additions = additions;
    rep.alternative_pairs = pair_ties;
  }
  return path.back().state;
}

// The report's conclusion from the final state `cur`: gap after, each chosen
// effect's shrink, "present" (largest shrink alone first; ties by name), the
// bands cleared when nothing is present and the gap test passes, and the
// plot table.
void conclude(const Spectra& s, const LineStats& st0, const Augment& a0, const Augment& cur, const GapOptions& options,
              GapReport& rep) {
  rep.periods_used = s.M - cur.first;
  const LineStats st1 = line_stats(s, cur, s.exc);
  rep.gap_after = gap_of(st1);
  rep.gap_model_used = rep.gap_before;
  if (cur.first > 0) {
    Augment steady = a0;
    steady.first = cur.first;
    rep.gap_model_used = gap_of(line_stats(s, steady, s.exc));
  }
  for (EffectFit& f : rep.chosen) {
    if (f.gap_after == 0) f.gap_after = rep.gap_after;
    f.shrink = 1.0 - f.gap_after / rep.gap_before;
  }
  std::vector<std::pair<double, Effect>> order;
  for (const EffectFit& f : rep.chosen)
    for (const EffectFit& c : rep.candidates)
      if (c.effect() == f.effect()) order.emplace_back(-c.shrink, f.effect());
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
    return a.first < b.first || (!(b.first < a.first) && ByName()(a.second, b.second));
  });
  for (const auto& o : order) rep.present.push_back(o.second);
  if (rep.present.empty()) {
    rep.gap_after = rep.gap_before;
    if (rep.p_gap >= options.alpha) rep.bands.clear();
  }
  // The verdict: the gap test again on what remains. The fitted parameters
  // (q of them against 2K residuals) absorb a little noise, so under a right
  // augmented model this p-value is, if anything, conservative.
  rep.p_after = rep.present.empty() ? rep.p_gap : fisher_p(st1.t, st1.M);
  int fitted = 0;
  for (const EffectFit& f : rep.chosen) fitted += f.dof;
  rep.p_below = rep.present.empty() ? 1.0 : fisher_p_below(st1.t, st1.M, fitted);
  // The excess gap the present effects are asked to remove: gap_before, or
  // the model's gap on the steady-state periods when dropping a transient
  // revealed more misfit than the transient's scatter let gap_before show.
  const double excess = std::max(rep.gap_before, rep.gap_model_used);
  rep.explained_share = rep.present.empty() || !(excess > 1) ? 0 : (excess - rep.gap_after) / (excess - 1);
  if (rep.present.empty())
    rep.verdict = rep.p_gap < options.alpha ? GapVerdict::Unexplained : GapVerdict::NoGap;
  else
    rep.verdict = rep.p_after < options.alpha ? GapVerdict::Unexplained : GapVerdict::Explained;
  // A possible addition says the explained record cannot tell whether it is
  // there too; where the effects found leave a gap, nothing explains it "as
  // well", and the misfit, not the noise, sets the Schwarz criterion.
  if (rep.verdict != GapVerdict::Explained) rep.possible_additions.clear();
  const Eigen::Index K = static_cast<Eigen::Index>(s.exc.size());
  // An unexplained gap that a candidate alone would leave lower by more than
  // the noise (gap_noise_bound: 3 null sd of the gap), had its own test
  // admitted it: named, with that test, so that the best partial explanation
  // is not read as the best fit the catalogue has (gap-validate --family
  // structure seed 1, case 34 until stop 68: an in-loop cubic alone leaves
  // gap 1.09, the chosen unmodelled_mode + mode_mismatch 4.25; the cubic's
  // distortion on the unexcited lines tests p 0.059 by the Fisher test; its
  // prediction test, p 1.9e-29, now admits it).
  if (rep.verdict == GapVerdict::Unexplained) {
    // The bound only for a candidate that could be named: with fewer than 4
    // periods it is a Monte Carlo of 20000 K draws.
    std::optional<double> bound;
    for (const EffectFit& c : rep.candidates) {
      const double level = admission_level(c.effect(), options);
      const bool chosen = std::find(rep.present.begin(), rep.present.end(), c.effect()) != rep.present.end();
      if (chosen || !(c.p_value >= level) || !(c.gap_after < rep.gap_after)) continue;
      if (!bound) bound = gap_noise_bound(st1.M, static_cast<int>(K));
      if (!(c.gap_after < rep.gap_after - *bound)) continue;
      // The nonlinearity has a second test (ForwardSelection::admit): its
      // p-value too, and, where it rejects, why it still was not taken (a
      // linear effect or leakage scored better at the first stage, or the
      // polynomial did not improve the excited lines).
      const bool nl = c.effect() == Effect::Nonlinearity;
      const bool predicted = nl && rep.p_nonlinearity_prediction < level;
      rep.notes.push_back(
          std::string(to_string(c.effect())) + " alone would leave gap " + sci(c.gap_after, 4) + ", less than the " +
          sci(rep.gap_after, 4) + (rep.present.empty() ? " of the model as given" : " the effects found leave") +
          (predicted ? ", and the polynomial fitted on the excited lines predicts the unexcited ones (p " +
                           sci(rep.p_nonlinearity_prediction, 3) + " at level " + fmt(level, 3) +
                           "), but the selection's first stage preferred another effect on the excited lines"
                     : ", but its own test does not admit it (p " + sci(c.p_value, 3) +
                           (nl ? "; predicted from the excited lines " + sci(rep.p_nonlinearity_prediction, 3) : "") +
                           " at level " + fmt(level, 3) + ")") +
          (nl ? "; a record at another excitation level would tell" : ""));
    }
  }
  rep.frequency.resize(K);
  for (Eigen::Index i = 0; i < K; ++i) rep.frequency(i) = s.hz(s.exc[i]);
  rep.t_before = st0.t;
  rep.t_after = rep.present.empty() ? st0.t : st1.t;
}

// The R deviations from their mean of a set of R period residuals.
Eigen::VectorXcd deviations(const Eigen::VectorXcd& e) { return e.array() - e.mean(); }

// Line pair j's period deviations: of the difference of lines 2j and 2j + 1,
// in which the leakage term (smooth across adjacent lines) cancels.
Eigen::VectorXcd pair_deviations(const Eigen::MatrixXcd& residuals, Eigen::Index j) {
  return deviations(residuals.col(2 * j) - residuals.col(2 * j + 1));
}

}  // namespace

PeriodPowerTest period_power_test(const Eigen::MatrixXcd& residuals) {
  const Eigen::Index R = residuals.rows(), J = residuals.cols() / 2;
  PeriodPowerTest out;
  if (R < 3 || J < 30) return out;
  Eigen::VectorXd Q = Eigen::VectorXd::Zero(R);
  double v = 0;
  Eigen::Index used = 0;
  for (Eigen::Index j = 0; j < J; ++j) {
    const Eigen::VectorXcd d = pair_deviations(residuals, j);
    const double total = d.squaredNorm();
    if (!(total > 0)) continue;  // a pair without noise (exactly periodic) says nothing
    const Eigen::VectorXd q = d.cwiseAbs2() / total;
    Q += q;
    v += (q.array() - 1.0 / static_cast<double>(R)).square().sum();
    ++used;
  }
  if (used < 30 || !(v > 0)) return out;
  Q /= static_cast<double>(used);
  v /= static_cast<double>(used * R);
  const double Rd = static_cast<double>(R);
  const double S = static_cast<double>(used) * (Rd - 1) / (v * Rd) * (Q.array() - 1 / Rd).square().sum();
  out.p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(Rd - 1), S));
  out.relative.resize(static_cast<size_t>(R));
  for (Eigen::Index m = 0; m < R; ++m) out.relative[static_cast<size_t>(m)] = Rd * Q(m);
  return out;
}

// kIndependenceDraws: the Monte Carlo error of the null mean, sd ≈ 0.24/√N =
// 0.0038, enters Z's variance; against the pairs' standard error 0.24/√J
// (0.0053 at J = 2048, the F-16's P = 8192) it costs ~20 % of Z's scale
// there, and 4000 draws of R normals are ~0.1 ms.
constexpr int kIndependenceDraws = 4000;

PeriodIndependenceTest period_independence_test(const Eigen::MatrixXcd& residuals,
                                                const std::vector<double>& relative) {
  const Eigen::Index R = residuals.rows(), J = residuals.cols() / 2;
  PeriodIndependenceTest out;
  if (R < 4 || J < 30) return out;
  // c of one set of R period deviations d.
  const auto lag_correlation = [R](const Eigen::VectorXcd& d) {
    const double total = d.squaredNorm();
    double c = 0;
    for (Eigen::Index m = 0; m < R; ++m) c += (d(m) * std::conj(d((m + 1) % R))).real();
    return total > 0 ? std::optional<double>(c / total) : std::nullopt;
  };
  double sum = 0, sum2 = 0;
  Eigen::Index used = 0;
  for (Eigen::Index j = 0; j < J; ++j) {
    const std::optional<double> c = lag_correlation(pair_deviations(residuals, j));
    if (!c) continue;  // a pair without noise says nothing
    sum += *c;
    sum2 += *c * *c;
    ++used;
  }
  if (used < 30) return out;
  const double n = static_cast<double>(used);
  out.correlation = sum / n;
  const double var = std::max(0.0, (sum2 - n * out.correlation * out.correlation) / (n - 1));
  // The null mean under the periods' own powers: relative[m] = R Q_m, Q_m ≈
  // (ρ_m (1 − 2/R) + 1/R)/(R − 1) for Σρ = R (the expected share of a
  // deviation from the mean), so ρ_m = ((R − 1) relative[m] − 1)/(R − 2).
  const double Rd = static_cast<double>(R);
  Eigen::VectorXd sd = Eigen::VectorXd::Ones(R);
  if (relative.size() == static_cast<size_t>(R))
    for (Eigen::Index m = 0; m < R; ++m)
      sd(m) = std::sqrt(std::max(1e-3, ((Rd - 1) * relative[static_cast<size_t>(m)] - 1) / (Rd - 2)));
  std::mt19937_64 rng(0x1d3b9e5aULL);
  std::normal_distribution<double> normal(0.0, std::sqrt(0.5));
  double msum = 0, msum2 = 0;
  Eigen::VectorXcd e(R);
  for (int b = 0; b < kIndependenceDraws; ++b) {
    for (Eigen::Index m = 0; m < R; ++m) e(m) = sd(m) * cplx(normal(rng), normal(rng));
    const double c = lag_correlation(deviations(e)).value_or(-1 / (Rd - 1));
    msum += c;
    msum2 += c * c;
  }
  const double N = kIndependenceDraws;
  out.expected = msum / N;
  const double var_mc = std::max(0.0, (msum2 - N * out.expected * out.expected) / (N - 1));
  const double se = std::sqrt(var / n + var_mc / N);
  if (!(se > 0)) return out;
  out.p = 0.5 * std::erfc((out.correlation - out.expected) / se / std::sqrt(2.0));
  return out;
}

// The chosen resonances that a bound of their search holds (Diagnosis::
// bounds), in the notes. A stand-in — damping at the upper bound 0.3, an
// unmodelled peak at the excited band's edge, a moved mode outside the band
// — is a smooth correction for something the catalogue lacks, not a
// resonance the data resolve (the F-16's order-16 model on Level 7: an
// unmodelled_mode with ζ = 0.3; on Level 1 a mode moved from 15.8 to 19.5
// Hz, above the band, ζ 1e-15): GapReport::stand_ins. An unmodelled mode's
// damping ratio at the floor alone is a resonance narrower than the search
// admits (gap-validate's lightly damped unmodelled modes at low lines): its
// peak is placed, its damping is an upper bound.
void note_bounds(const Diagnosis& dg, const Spectra& s, GapReport& rep) {
  for (const EffectFit& f : rep.chosen) {
    const auto b = dg.bounds(f);
    if (!b) continue;
    const std::string name = to_string(f.effect());
    std::vector<std::string> why;
    if (b->upper) why.push_back("its damping ratio at the search's upper bound " + fmt(Diagnosis::kMaxDamping, 2));
    if (b->edge) why.push_back("its peak at the excited band's edge");
    if (b->outside)
      why.push_back("its peak outside the excited band (" + sci(s.hz(s.exc.front()), 4) + " to " +
                    sci(s.hz(s.exc.back()), 4) + " Hz), where no line resolves it");
    if (!why.empty()) {
      if (b->floor) why.push_back("its damping ratio at the search's floor " + sci(b->floor_value, 2));
      std::string text;
      for (const std::string& w : why) text += (text.empty() ? "" : "; ") + w;
      rep.stand_ins.push_back(f.effect());
      rep.notes.push_back(name + " is a stand-in, not a resonance the data resolve: " + text +
                          "; read its shrink, not its parameters");
    } else if (b->floor) {
      rep.notes.push_back(name + ": its damping ratio sits at the search's floor " + sci(b->floor_value, 2) +
                          " (a half-power width of half a line, or 1e-3): the data place its peak but do not resolve "
                          "its width, so read the damping as an upper bound");
    }
  }
}

/// Sim-to-real gap diagnosis (gap.hpp; CONTRACTS.md `fdsid gap`).
///
/// Method: the per-period DFT of the record; t(k) and the gap of the model as
/// given (Pintelon 2002, Eq. 25); the detection tests and the bands; every
/// effect fitted alone (the candidates); the chosen set by the tests and the
/// relevance rule; the report.
/// Numerical aspects: cost dominated by the joint fits of the 15 linear pairs,
/// each O(K) per cost evaluation over a few hundred Nelder–Mead/Brent steps.
/// Fails: Error(Input) as stated in gap.hpp.
/// References: Pintelon, Guillaume, Schoukens et al. (2002); Benjamini &
/// Hochberg (1995); Fisher (1932).
GapReport diagnose_gap(const StateSpace& model, const Eigen::MatrixXd& record, int inputs, const RecordMeta& meta,
                       const GapOptions& options) {
  check_inputs(model, record, inputs, meta, options);
  const Spectra s = spectra_of(record, meta, model.domain);
  if (s.exc.size() < 4)
    throw Error(ErrorKind::Input, "meta field \"excited_lines\"", "needs at least 4 excited lines below P/2");
  const Diagnosis dg(model, s);
  GapReport rep;
  rep.options = options;
  rep.excited = static_cast<int>(s.exc.size());
  rep.unexcited = static_cast<int>(s.ne.size());
  const Augment a0 = dg.initial();
  const LineStats st0 = line_stats(s, a0, s.exc);
  require_noise_floor(s, st0);
  detection_tests(dg, s, a0, st0, rep);
  rep.distortion = distortion_view(s, a0, st0, rep.p_gap, rep.gap_before, options.alpha);
  gap_bands(s, st0, options.fdr, rep);

  rep.candidates = fits_alone(dg, s, a0, st0.pooled_cost, rep.p_nonlinearity);
  const int drop = transient_periods(dg, s, a0, rep.p_leakage, options.alpha);
  period_power(s, a0, std::max(1, drop), model.order() == 0, rep);
  rep.candidates.push_back(leakage_alone(s, a0, drop, rep.p_leakage));
  for (EffectFit& f : rep.candidates) f.shrink = 1.0 - f.gap_after / rep.gap_before;
  std::stable_sort(rep.candidates.begin(), rep.candidates.end(),
                   [](const EffectFit& a, const EffectFit& b) { return a.gap_after < b.gap_after; });

  const Augment cur = choose_effects(dg, s, a0, drop, options, rep);
  note_bounds(dg, s, rep);
  conclude(s, st0, a0, cur, options, rep);
  return rep;
}

nlohmann::json gap_report_to_json(const GapReport& r) {
  auto fit_json = [](const EffectFit& f) {
    nlohmann::json p = nlohmann::json::object();
    for (const auto& kv : parameter_list(f.parameters)) p[kv.first] = kv.second;
    return nlohmann::json{{"effect", to_string(f.effect())}, {"gap_after", f.gap_after}, {"shrink", f.shrink},
                          {"parameters", p},     {"dof", f.dof},            {"p_value", f.p_value}};
  };
  nlohmann::json j;
  j["gap_before"] = r.gap_before;
  j["gap_after"] = r.gap_after;
  j["present"] = nlohmann::json::array();
  for (Effect e : r.present) j["present"].push_back(to_string(e));
  j["bands"] = nlohmann::json::array();
  for (const auto& b : r.bands) j["bands"].push_back({b[0], b[1]});
  j["peaks"] = nlohmann::json::array();
  for (const auto& p : r.peaks) j["peaks"].push_back({{"band", {p.band[0], p.band[1]}}, {"share", p.share}});
  j["verdict"] = to_string(r.verdict);
  j["p_after"] = r.p_after;
  j["p_below"] = r.p_below;
  j["explained_share"] = r.explained_share;
  j["steps"] = nlohmann::json::array();
  for (const SelectionStep& st : r.path) {
    nlohmann::json set = nlohmann::json::array();
    for (Effect e : st.set) set.push_back(to_string(e));
    j["steps"].push_back(
        {{"added", to_string(st.added)}, {"set", set}, {"gap_after", st.gap_after}, {"p_value", st.p_value}});
  }
  j["alternatives"] = nlohmann::json::array();
  for (const auto& [e, p] : r.alternatives) j["alternatives"].push_back({{"effect", to_string(e)}, {"p_value", p}});
  j["stand_ins"] = nlohmann::json::array();
  for (Effect e : r.stand_ins) j["stand_ins"].push_back(to_string(e));
  j["alternative_pairs"] = nlohmann::json::array();
  for (const auto& [g, h] : r.alternative_pairs) j["alternative_pairs"].push_back({to_string(g), to_string(h)});
  j["possible_additions"] = nlohmann::json::array();
  for (const auto& [e, p] : r.possible_additions)
    j["possible_additions"].push_back({{"effect", to_string(e)}, {"p_value", p}});
  j["candidates"] = nlohmann::json::array();
  for (const EffectFit& f : r.candidates) j["candidates"].push_back(fit_json(f));
  j["chosen"] = nlohmann::json::array();
  for (const EffectFit& f : r.chosen) j["chosen"].push_back(fit_json(f));
  j["tests"] = {{"p_gap", r.p_gap},
                {"p_nonlinearity", r.p_nonlinearity},
                {"p_nonlinearity_prediction", r.p_nonlinearity_prediction},
                {"p_leakage", r.p_leakage},
                {"p_period_power", r.p_period_power},
                {"period_power", r.period_power},
                {"period_power_unequal", r.period_power_unequal()},
                {"p_period_independence", r.p_period_independence},
                {"period_correlation", {{"observed", r.period_correlation}, {"independent", r.period_correlation_expected}}},
                {"periods_dependent", r.periods_dependent()},
                {"alpha", r.options.alpha},
                {"effect_alpha", r.options.effect_alpha},
                {"min_share", r.options.min_share},
                {"fdr", r.options.fdr}};
  const GapDistortion& d = r.distortion;
  j["distortion"] = {{"estimable", d.estimable}, {"odd_only", d.odd_only},
                     {"lines", d.lines},         {"gap", d.gap},
                     {"share", d.share},         {"p_detected", d.p_detected},
                     {"p_beyond", d.p_beyond},   {"p_beyond_min", d.p_beyond_min},
                     {"bla_right", d.bla_right}};
  j["distortion"]["level_db"] = d.level_db ? nlohmann::json(*d.level_db) : nlohmann::json(nullptr);
  j["periods_used"] = r.periods_used;
  j["gap_model_used"] = r.gap_model_used;
  j["excited_lines"] = r.excited;
  j["unexcited_lines"] = r.unexcited;
  j["notes"] = r.notes;
  return j;
}

// ---- several output channels (gap.hpp, MultiGapReport) ----

namespace {

// The model's output row o as a SISO model.
StateSpace output_row(const StateSpace& model, int o) {
  StateSpace r = model;
  r.C = model.C.row(o);
  r.D = model.D.row(o);
  return r;
}

// The joint test over the excited lines (gap.hpp): complex Hotelling per line.
void joint_test(const StateSpace& model, const Eigen::MatrixXd& record, const RecordMeta& meta, MultiGapReport& rep) {
  const int p = model.outputs(), M = meta.periods;
  if (M < p + 3) {
    rep.notes.push_back("joint test of the " + std::to_string(p) + " outputs not computed: it needs M >= p + 3 = " +
                        std::to_string(p + 3) + " periods, got " + std::to_string(M));
    return;
  }
  std::vector<Spectra> sp;
  std::vector<Eigen::VectorXcd> G;
  for (int o = 0; o < p; ++o) {
    Eigen::MatrixXd rec(record.rows(), 2);
    rec << record.col(0), record.col(1 + o);
    sp.push_back(spectra_of(rec, meta, model.domain));
    const StateSpace row = output_row(model, o);
    G.emplace_back(sp.back().xi.size());
    for (Eigen::Index k = 0; k < G.back().size(); ++k) G.back()(k) = transfer(row, sp.back().xi(k))(0, 0);
  }
  const std::vector<int>& exc = sp[0].exc;
  const boost::math::fisher_f law(2.0 * p, 2.0 * (M - p));
  double chi = 0, sumF = 0;
  const auto dependent = [&](int k) {
    rep.notes.push_back("joint test of the " + std::to_string(p) + " outputs not computed: their residuals are "
                        "linearly dependent at line " + std::to_string(k) + " (an output given twice, or one "
                        "a combination of the others)");
  };
  for (int k : exc) {
    Eigen::MatrixXcd E(M, p);
    for (int o = 0; o < p; ++o)
      for (int l = 0; l < M; ++l) E(l, o) = sp[o].Y(l, k) - G[o](k) * sp[o].U(l, k);
    const Eigen::RowVectorXcd mean = E.colwise().mean();
    const Eigen::MatrixXcd D = E.rowwise() - mean;
    const Eigen::MatrixXcd S = D.adjoint() * D / static_cast<double>(M - 1);
    // S positive definite unless the residuals are dependent: a pivot below
    // numerics::kNegligibleRelative of the largest (rounding of a copied
    // column) means no usable covariance.
    const Eigen::LDLT<Eigen::MatrixXcd> ldlt(S);
    const Eigen::VectorXd piv = ldlt.vectorD().real();
    if (ldlt.info() != Eigen::Success || !(piv.minCoeff() > numerics::kNegligibleRelative * piv.maxCoeff()))
      return dependent(k);
    const double T2 = M * (mean * ldlt.solve(mean.adjoint()))(0, 0).real();
    const double F = (M - p) / (p * (M - 1.0)) * T2;
    sumF += F;
    const double pk = boost::math::cdf(boost::math::complement(law, std::max(0.0, F)));
    chi += -2 * std::log(std::max(pk, std::numeric_limits<double>::min()));
  }
  rep.joint_tested = true;
  rep.gap_joint = sumF / exc.size() * (M - p - 1.0) / (M - p);
  rep.p_joint = boost::math::cdf(boost::math::complement(boost::math::chi_squared(2.0 * exc.size()), chi));
}

}  // namespace

MultiGapReport diagnose_gap_outputs(const StateSpace& model, const Eigen::MatrixXd& record, int inputs,
                                    const RecordMeta& meta, const GapOptions& options) {
  validate(model);
  require_stable(model, "to compare with the record");
  if (inputs != 1 || model.inputs() != 1)
    throw Error(ErrorKind::Input, inputs != 1 ? "data" : "model",
                "the gap diagnosis takes one input (several outputs are diagnosed channel by channel); got " +
                    std::to_string(inputs != 1 ? inputs : model.inputs()) +
                    " inputs: the residual of several inputs needs each one's path, not supported; choose a "
                    "single-input experiment (--input NAME)");
  const int p = static_cast<int>(record.cols()) - inputs;
  if (p < 2) throw Error(ErrorKind::Input, "data", "one output: use the single-output diagnosis");
  if (model.outputs() != p)
    throw Error(ErrorKind::Input, "model",
                "has " + std::to_string(model.outputs()) + " outputs, the record " + std::to_string(p) +
                    " (give the model's outputs in the record's order, e.g. --output A B C)");
  MultiGapReport rep;
  for (int o = 0; o < p; ++o) {
    Eigen::MatrixXd rec(record.rows(), 2);
    rec << record.col(0), record.col(1 + o);
    try {
      rep.channels.push_back(diagnose_gap(output_row(model, o), rec, 1, meta, options));
    } catch (const Error& e) {
      throw Error(e.kind(), e.where() + " (output " + std::to_string(o + 1) + ")", e.message());
    }
  }
  joint_test(model, record, meta, rep);
  bool any_effect = false, all_explained_or_none = true, some_explained = false;
  for (const GapReport& r : rep.channels) {
    rep.gap_before += r.gap_before / p;
    rep.gap_after += r.gap_after / p;
    for (Effect e : r.present)
      if (std::find(rep.present.begin(), rep.present.end(), e) == rep.present.end()) rep.present.push_back(e);
    any_effect = any_effect || !r.present.empty();
    all_explained_or_none = all_explained_or_none && r.verdict != GapVerdict::Unexplained;
    some_explained = some_explained || r.verdict == GapVerdict::Explained;
  }
  const bool joint_passes = !rep.joint_tested || rep.p_joint >= options.alpha;
  if (!any_effect && joint_passes && all_explained_or_none)
    rep.verdict = GapVerdict::NoGap;
  else if (all_explained_or_none && some_explained && (joint_passes || any_effect))
    rep.verdict = GapVerdict::Explained;
  else
    rep.verdict = GapVerdict::Unexplained;
  return rep;
}

nlohmann::json gap_report_to_json(const MultiGapReport& r) {
  nlohmann::json j;
  j["gap_before"] = r.gap_before;
  j["gap_after"] = r.gap_after;
  j["verdict"] = to_string(r.verdict);
  j["present"] = nlohmann::json::array();
  for (Effect e : r.present) j["present"].push_back(to_string(e));
  std::vector<std::array<double, 2>> bands;
  for (const GapReport& c : r.channels) bands.insert(bands.end(), c.bands.begin(), c.bands.end());
  std::sort(bands.begin(), bands.end());
  std::vector<std::array<double, 2>> merged;
  for (const auto& b : bands)
    if (!merged.empty() && b[0] <= merged.back()[1])
      merged.back()[1] = std::max(merged.back()[1], b[1]);
    else
      merged.push_back(b);
  j["bands"] = nlohmann::json::array();
  for (const auto& b : merged) j["bands"].push_back({b[0], b[1]});
  std::vector<std::pair<double, Effect>> cand;
  for (Effect e : kAllEffects) {
    double g = 0;
    for (const GapReport& c : r.channels)
      for (const EffectFit& f : c.candidates)
        if (f.effect() == e) g += f.gap_after / static_cast<double>(r.channels.size());
    cand.emplace_back(g, e);
  }
  std::stable_sort(cand.begin(), cand.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  j["candidates"] = nlohmann::json::array();
  for (const auto& [g, e] : cand)
    j["candidates"].push_back({{"effect", to_string(e)},
                               {"gap_after", g},
                               {"shrink", 1.0 - g / r.gap_before},
                               {"parameters", nlohmann::json::object()},
                               {"note", "mean over the channels; each channel's parameters under channels"}});
  j["joint"] = {{"tested", r.joint_tested}, {"gap", r.gap_joint}, {"p", r.p_joint}};
  j["channels"] = nlohmann::json::array();
  for (size_t o = 0; o < r.channels.size(); ++o) {
    nlohmann::json c = gap_report_to_json(r.channels[o]);
    c["output"] = static_cast<int>(o) + 1;
    j["channels"].push_back(c);
  }
  j["notes"] = r.notes;
  return j;
}

}  // namespace fdsid
