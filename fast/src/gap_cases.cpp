#include "fdsid/gap_cases.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <set>

#include "fdsid/error.hpp"
#include "numerics/fft.hpp"
#include "numerics/optimize.hpp"
#include "numerics/random.hpp"

namespace fdsid {

const char* to_string(Strength s) {
  switch (s) {
    case Strength::None: return "none";
    case Strength::Subtle: return "subtle";
    case Strength::Clear: return "clear";
  }
  return "?";
}

const NameTable<GapFamily>& gap_family_names() {
  static const NameTable<GapFamily> names = {
      {"classic", GapFamily::Classic}, {"structure", GapFamily::Structure}, {"mixed", GapFamily::Mixed}};
  return names;
}

const char* to_string(GapFamily family) { return name_of(gap_family_names(), family); }

std::array<double, 2> gap_ratio_range(Strength s) {
  switch (s) {
    case Strength::Subtle: return {0.5, 3.0};
    case Strength::Clear: return {10.0, 100.0};
    case Strength::None: break;
  }
  return {0.0, 0.0};
}

namespace {

using json = nlohmann::json;
using numerics::splitmix64;
constexpr double kPi = M_PI;
constexpr double kTwoPi = 2 * M_PI;
const char* const kWhere = "gap case";

// ---------------------------------------------------------------------------
// Random draws: platform-independent (raw 64-bit words of mt19937_64 turned
// into doubles and normals here, not by the implementation-defined <random>
// distributions).
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : gen_(seed) {}
  double unit() { return static_cast<double>(gen_() >> 11) * 0x1.0p-53; }            // [0, 1)
  double open_unit() { return (static_cast<double>(gen_() >> 11) + 0.5) * 0x1.0p-53; }  // (0, 1)
  double uniform(double a, double b) { return a + (b - a) * unit(); }
  double log_uniform(double a, double b) { return std::exp(uniform(std::log(a), std::log(b))); }
  bool coin(double p = 0.5) { return unit() < p; }
  double sign() { return coin() ? 1.0 : -1.0; }
  int integer(int a, int b) { return std::min(b, a + static_cast<int>(unit() * (b - a + 1))); }  // a … b
  double normal() {  // Box–Muller
    if (spare_) {
      spare_ = false;
      return spare_value_;
    }
    const double r = std::sqrt(-2 * std::log(open_unit())), t = kTwoPi * unit();
    spare_value_ = r * std::sin(t);
    spare_ = true;
    return r * std::cos(t);
  }

 private:
  std::mt19937_64 gen_;
  bool spare_ = false;
  double spare_value_ = 0;
};

// ---------------------------------------------------------------------------
// Second-order sections in q = z^{-1}: (b0 + b1 q + b2 q²) / (1 + a1 q + a2 q²).
struct Section {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
  cplx at(cplx q) const { return (b0 + q * (b1 + q * b2)) / (1.0 + q * (a1 + q * a2)); }
  // One sample of direct form II transposed: the output for input x from the
  // state w = (w1, w2), which is advanced. With b0 = 0 the output is w1 before
  // the input is known.
  double step(double x, std::array<double, 2>& w) const {
    const double y = b0 * x + w[0];
    w[0] = b1 * x - a1 * y + w[1];
    w[1] = b2 * x - a2 * y;
    return y;
  }
  // y = H x from rest.
  void filter(const std::vector<double>& x, std::vector<double>& y) const {
    std::array<double, 2> w = {0.0, 0.0};
    y.resize(x.size());
    for (std::size_t t = 0; t < x.size(); ++t) y[t] = step(x[t], w);
  }
};

/// Continuous pole of a resonance: ω(−ζ + j√(1−ζ²)), ω in rad/s (rad/sample at sample time 1).
cplx continuous_pole(double omega, double zeta) {
  return cplx(-zeta * omega, omega * std::sqrt(std::max(0.0, 1 - zeta * zeta)));
}

/// Discrete pole of a continuous-like resonance: exp(ω(−ζ + j√(1−ζ²))), ω in rad/sample.
cplx resonance_pole(double omega, double zeta) { return std::exp(continuous_pole(omega, zeta)); }

/// The section of r/(z − P) [+ r̄/(z − P̄) when `pair`]: in q = z⁻¹,
/// (2 Re r q − 2 Re(r P̄) q²)/(1 − 2 Re P q + |P|² q²), or r q/(1 − P q).
Section partial_fraction(cplx P, cplx r, bool pair) {
  Section s;
  s.b0 = 0;
  if (pair) {
    s.b1 = 2 * r.real();
    s.b2 = -2 * (r * std::conj(P)).real();
    s.a1 = -2 * P.real();
    s.a2 = std::norm(P);
  } else {
    s.b1 = r.real();
    s.a1 = -P.real();
  }
  return s;
}

/// A continuous-time part d + r/(s − p) [+ r̄/(s − p̄) when `pair`] (the
/// continuous family of gap_cases.hpp) and its zero-order-hold discretisation
/// at step h (pole e^{ph}, residue r (e^{ph} − 1)/p; exact for an input held
/// over each step), used only for the transient from rest (leakage).
struct CtPart {
  double d = 0;
  cplx p, r;
  bool pair = true;
  cplx at(cplx s) const {
    cplx g = d + r / (s - p);
    if (pair) g += std::conj(r) / (s - std::conj(p));
    return g;
  }
  Section zoh(double h) const {
    const cplx P = std::exp(p * h);
    Section s = partial_fraction(P, r * (P - 1.0) / p, pair);
    s.b0 = d;  // + d (1 + a1 q + a2 q²)/(1 + a1 q + a2 q²)
    s.b1 += d * s.a1;
    s.b2 += d * s.a2;
    return s;
  }
};

struct Mode {
  double omega = 0, zeta = 0;  // natural frequency (rad/sample), damping ratio
  cplx residue;                // c of c/(z − p) + c̄/(z − p̄); continuous family: of c/(s − p) + c̄/(s − p̄)
  cplx pole() const { return resonance_pole(omega, zeta); }
  CtPart ct_part() const { return CtPart{0.0, continuous_pole(omega, zeta), residue, true}; }
  cplx at(double w, bool continuous) const {
    return continuous ? ct_part().at(cplx(0, w)) : section().at(std::polar(1.0, -w));
  }
  Section section() const { return partial_fraction(pole(), residue, true); }
};

/// The simulation model in modal form; continuous: poles and residues in s
/// (real_pole then the continuous pole λ < 0).
struct Base {
  std::vector<Mode> modes;
  bool has_real = false;
  double real_pole = 0, real_residue = 0, D = 0;
  bool continuous = false;
};

/// The continuous family (gap_cases.hpp, step 1): the drawn discrete model's
/// poles mapped by s = ln z (the same ω, ζ) and its residues scaled so that
/// every mode keeps its peak gain |c|/|Re p| = |c|/(1 − |z_p|) and the real
/// pole its DC gain r/(1 − a) = −r_c/λ.
void make_continuous(Base& b) {
  for (Mode& m : b.modes) {
    const double sigma = continuous_pole(m.omega, m.zeta).real();
    m.residue *= -sigma / (1 - std::exp(sigma));
  }
  if (b.has_real) {
    const double lambda = std::log(b.real_pole);
    b.real_residue *= -lambda / (1 - b.real_pole);
    b.real_pole = lambda;
  }
  b.continuous = true;
}

StateSpace realise(const Base& b) {
  const int n = 2 * static_cast<int>(b.modes.size()) + (b.has_real ? 1 : 0);
  StateSpace m;
  m.domain = b.continuous ? Domain::Continuous : Domain::Discrete;
  m.sample_time = 1.0;
  m.A = Eigen::MatrixXd::Zero(n, n);
  m.B = Eigen::MatrixXd::Zero(n, 1);
  m.C = Eigen::MatrixXd::Zero(1, n);
  m.D = Eigen::MatrixXd::Constant(1, 1, b.D);
  int i = 0;
  for (const Mode& md : b.modes) {
    // A = [σ ω'; −ω' σ], B = [0; β], C = [−2 Im c, 2 Re c]/β gives c/(z−p) + c̄/(z−p̄), p = σ + jω'
    // (in s for a continuous model).
    const cplx p = b.continuous ? md.ct_part().p : md.pole();
    m.A(i, i) = m.A(i + 1, i + 1) = p.real();
    m.A(i, i + 1) = p.imag();
    m.A(i + 1, i) = -p.imag();
    const double c1 = -2 * md.residue.imag(), c2 = 2 * md.residue.real();
    const double beta = std::sqrt(std::max(std::hypot(c1, c2), 1e-300));
    m.B(i + 1, 0) = beta;
    m.C(0, i) = c1 / beta;
    m.C(0, i + 1) = c2 / beta;
    i += 2;
  }
  if (b.has_real) {
    const double beta = std::sqrt(std::abs(b.real_residue));
    m.A(i, i) = b.real_pole;
    m.B(i, 0) = beta;
    m.C(0, i) = b.real_residue / beta;
  }
  return m;
}

// ---------------------------------------------------------------------------
// FFT of one period, unitary: X(k) = P^{-1/2} Σ x(t) e^{−j2πkt/P}, k = 0 … P/2
// (numerics/fft.hpp).
using Fft = numerics::UnitaryFft;

// ---------------------------------------------------------------------------
// Effects: parameters drawn at magnitude 1, scaled by `scale` ∈ [0, scale_max]
// (scale 0 is always the identity).
struct Injected {
  Effect effect = Effect::GainError;
  double scale = 1, scale_max = 1, target = 0, ratio = 0;
  double delay_equivalent = 0, ratio_undelayed = 0;    // continuous sensor: the delay taken out of `ratio`, and the ratio with it
  double gain0 = 1;                                    // gain_error: g = 1 + s (g0 − 1)
  double delay0 = 0;                                   // delay: τ = s τ0
  int order = 1;                                       // sensor_dynamics: order, T = s T0, ω_c = 1/T
  double time_constant0 = 0, sensor_zeta = 0.7;
  bool series = false;                                 // unmodelled_mode
  double extra_omega = 0, extra_zeta = 0, kappa0 = 0;  // series: ζ_zero = ζ (1 + s κ0)
  cplx extra_residue0;                                 // parallel: residue s c0
  int mode = 0;                                        // mode_mismatch: ω' = ω (1 + s δ0), ζ' = ζ e^{s λ0}
  double shift0 = 0, damping_log0 = 0;
  bool at_input = false;                               // nonlinearity: x + s (a2 x²/r + a3 x³/r²)
  bool in_loop = false;                                // nonlinearity (structure family): u − s (a2 y²/r + a3 y³/r²)
  double quad0 = 0, cubic0 = 0, reference_rms = 1;
  std::vector<int> lines;                              // the lines the ratio is taken over
  std::vector<double> line_ratio;                      // per line, at the final scale
};

/// A static polynomial x + a₂ x²/r + a₃ x³/r² (r a reference RMS); off: the identity.
struct StaticPolynomial {
  bool on = false;
  double a2 = 0, a3 = 0, r = 1;
  double operator()(double x) const { return x + a2 * x * x / r + a3 * x * x * x / (r * r); }
};

/// The continuous family's fine grid: L samples per sample of the record
/// (gap_cases.hpp).
constexpr int kFineGrid = 8;

/// The true system: u → f_in → plant → f_out → sensor → gain → delay.
/// Discrete: the Sections. Continuous: the CtParts (the Sections empty
/// until `discretised`).
struct Chain {
  std::vector<Section> parallel;  // plant = D + Σ parallel, then × Π series
  std::vector<Section> series;
  double D = 0;
  StaticPolynomial in_nl, out_nl;  // f_in, f_out
  StaticPolynomial loop_nl;        // feedback f(y) − y: the plant's input is x − (loop_nl(y) − y)
  std::vector<Section> sensor;
  double gain = 1, delay = 0, leak = 0;
  bool continuous = false;
  std::vector<CtPart> ct_parallel, ct_series, ct_sensor;

  // At the line of angular frequency ω (rad per record sample) and q = e^{−jω h},
  // h the grid's step in record samples (1, or 1/kFineGrid on the fine grid).
  cplx plant_at(double omega, cplx q) const {
    cplx g = D;
    if (continuous) {
      const cplx s(0, omega);
      for (const CtPart& p : ct_parallel) g += p.at(s);
      for (const CtPart& p : ct_series) g *= p.at(s);
      return g;
    }
    for (const Section& s : parallel) g += s.at(q);
    for (const Section& s : series) g *= s.at(q);
    return g;
  }
  cplx meas_at(double omega, cplx q, bool with_delay = true) const {
    cplx g = gain;
    if (continuous) {
      for (const CtPart& p : ct_sensor) g *= p.at(cplx(0, omega));
    } else {
      for (const Section& s : sensor) g *= s.at(q);
    }
    if (with_delay && delay != 0) g *= std::polar(1.0, -omega * delay);
    return g;
  }
  // A continuous chain's zero-order-hold discretisation on the fine grid (step 1/kFineGrid).
  Chain discretised() const {
    Chain d = *this;
    d.continuous = false;
    const double h = 1.0 / kFineGrid;
    for (const CtPart& p : ct_parallel) d.parallel.push_back(p.zoh(h));
    for (const CtPart& p : ct_series) d.series.push_back(p.zoh(h));
    for (const CtPart& p : ct_sensor) d.sensor.push_back(p.zoh(h));
    return d;
  }
  // The plant with the loop closed, y = plant(x − f(y)), f(y) = loop_nl(y) − y,
  // simulated sample by sample over x from the section states `w` (zero: from
  // rest; carried on between calls). D = 0 and every parallel section strictly
  // proper, so y(t) depends on the input before t only. Returns false when y
  // leaves [−1e6 r, 1e6 r] (the loop is unstable).
  using LoopState = std::vector<std::array<double, 2>>;  // parallel sections, then series
  bool loop_filter(const std::vector<double>& x, std::vector<double>& y, LoopState& w) const {
    w.resize(parallel.size() + series.size(), {0.0, 0.0});
    y.resize(x.size());
    const double bound = 1e6 * loop_nl.r;
    const std::size_t np = parallel.size();
    for (std::size_t t = 0; t < x.size(); ++t) {
      double yt = 0;
      for (std::size_t i = 0; i < np; ++i) yt += w[i][0];  // b0 = 0: the output is w1
      for (std::size_t i = 0; i < series.size(); ++i) yt = series[i].step(yt, w[np + i]);
      if (!(std::abs(yt) <= bound)) return false;
      y[t] = yt;
      const double v = x[t] - (loop_nl(yt) - yt);
      for (std::size_t i = 0; i < np; ++i) parallel[i].step(v, w[i]);  // advances the state; its output was w1
    }
    return true;
  }
  void plant_filter(const std::vector<double>& x, std::vector<double>& y) const {
    y.assign(x.size(), 0.0);
    for (std::size_t t = 0; t < x.size(); ++t) y[t] = D * x[t];
    std::vector<double> tmp;
    for (const Section& s : parallel) {
      s.filter(x, tmp);
      for (std::size_t t = 0; t < x.size(); ++t) y[t] += tmp[t];
    }
    for (const Section& s : series) {
      s.filter(y, tmp);
      y.swap(tmp);
    }
  }
};

Chain make_chain(const Base& base, const std::vector<const Injected*>& effects) {
  std::vector<Mode> modes = base.modes;
  Chain c;
  c.D = base.D;
  c.continuous = base.continuous;
  for (const Injected* e : effects) {
    const double s = e->scale;
    switch (e->effect) {
      case Effect::GainError: c.gain *= 1 + s * (e->gain0 - 1); break;
      case Effect::Delay: c.delay += s * e->delay0; break;
      case Effect::SensorDynamics: {
        const double T = s * e->time_constant0;
        if (T <= 0) break;
        const double wc = 1 / T;
        if (c.continuous) {  // ω_c/(s + ω_c), or ω_c²/(s² + 2ζω_c s + ω_c²)
          const cplx p = continuous_pole(wc, e->sensor_zeta);
          c.ct_sensor.push_back(e->order == 1 ? CtPart{0.0, cplx(-wc, 0), cplx(wc, 0), false}
                                              : CtPart{0.0, p, wc * wc / (p - std::conj(p)), true});
          break;
        }
        Section sec;
        if (e->order == 1) {
          const double a = std::exp(-wc);
          sec.b0 = 1 - a;
          sec.a1 = -a;
        } else {
          const cplx p = resonance_pole(wc, e->sensor_zeta);
          sec.a1 = -2 * p.real();
          sec.a2 = std::norm(p);
          sec.b0 = 1 + sec.a1 + sec.a2;
        }
        c.sensor.push_back(sec);
        break;
      }
      case Effect::UnmodelledMode:
        if (e->series && c.continuous) {
          // (s² + 2ζ_z ω s + ω²)/(s² + 2ζ ω s + ω²) = 1 + 2(ζ_z − ζ) ω s/((s − p)(s − p̄)): unit DC gain
          const cplx p = continuous_pole(e->extra_omega, e->extra_zeta);
          const double dz = e->extra_zeta * s * e->kappa0;
          c.ct_series.push_back(CtPart{1.0, p, 2 * dz * e->extra_omega * p / (p - std::conj(p)), true});
        } else if (e->series) {
          const cplx p = resonance_pole(e->extra_omega, e->extra_zeta);
          const cplx z = resonance_pole(e->extra_omega, e->extra_zeta * (1 + s * e->kappa0));
          Section sec;
          sec.b1 = -2 * z.real();
          sec.b2 = std::norm(z);
          sec.a1 = -2 * p.real();
          sec.a2 = std::norm(p);
          const double k = (1 + sec.a1 + sec.a2) / (1 + sec.b1 + sec.b2);  // unit DC gain
          sec.b0 = k;
          sec.b1 *= k;
          sec.b2 *= k;
          c.series.push_back(sec);
        } else {
          Mode m{e->extra_omega, e->extra_zeta, s * e->extra_residue0};
          if (c.continuous) {
            c.ct_parallel.push_back(m.ct_part());
          } else {
            c.parallel.push_back(m.section());
          }
        }
        break;
      case Effect::ModeMismatch:
        modes[static_cast<std::size_t>(e->mode)].omega *= 1 + s * e->shift0;
        modes[static_cast<std::size_t>(e->mode)].zeta *= std::exp(s * e->damping_log0);
        break;
      case Effect::Nonlinearity:
        (e->in_loop ? c.loop_nl : e->at_input ? c.in_nl : c.out_nl) =
            StaticPolynomial{true, s * e->quad0, s * e->cubic0, e->reference_rms};
        break;
      case Effect::Leakage: c.leak = s; break;
    }
  }
  if (c.continuous) {
    for (const Mode& m : modes) c.ct_parallel.push_back(m.ct_part());
    if (base.has_real)
      c.ct_parallel.push_back(CtPart{0.0, cplx(base.real_pole, 0), cplx(base.real_residue, 0), false});
    return c;
  }
  for (const Mode& m : modes) c.parallel.push_back(m.section());
  if (base.has_real) c.parallel.push_back(partial_fraction(base.real_pole, base.real_residue, false));
  return c;
}

// ---------------------------------------------------------------------------
struct FineGrid;

/// Everything fixed before the effects are calibrated.
struct Setting {
  int P = 0, M = 0, K = 0;
  std::vector<double> omega;      // bins 0 … P/2
  std::vector<cplx> q;            // e^{−jω}
  std::vector<int> excited, unexcited_band, band;  // excited; non-excited 1 … K; all 1 … K
  std::vector<double> u;          // one period of the input
  std::vector<cplx> U;            // its spectrum, bins 0 … P/2
  std::vector<cplx> Hsim;         // simulation model at every bin
  std::vector<double> y_sim;      // one period of its steady-state output
  std::vector<double> w;          // noise shape |H_v|² at every bin (mean 1 over the excited lines)
  std::shared_ptr<FineGrid> fine;  // the continuous family's fine grid; null for discrete cases
};

/// The continuous family's grid of kFineGrid · P samples per period: the
/// band-limited input interpolated exactly (U zero-padded, scaled by √L for
/// the unitary DFT of L·P samples), ω in rad per record sample (up to L π),
/// q = e^{−jω/L}.
struct FineGrid {
  Setting st;
  Fft fft;
  explicit FineGrid(const Setting& coarse) : fft(kFineGrid * coarse.P, kWhere) {
    const int L = kFineGrid;
    st.P = L * coarse.P;
    st.M = coarse.M;
    st.K = coarse.K;
    const std::size_t bins = static_cast<std::size_t>(st.P / 2 + 1);
    st.U.assign(bins, 0.0);
    for (std::size_t k = 0; k + 1 < coarse.U.size(); ++k) st.U[k] = std::sqrt(static_cast<double>(L)) * coarse.U[k];
    st.u = fft.inverse(st.U);
    st.omega.resize(bins);
    st.q.resize(bins);
    for (std::size_t k = 0; k < bins; ++k) {
      st.omega[k] = kTwoPi * static_cast<double>(k) / coarse.P;
      st.q[k] = std::polar(1.0, -kTwoPi * static_cast<double>(k) / st.P);
    }
  }
};

/// One period of the loop's periodic steady state for the periodic plant
/// input x (one period): simulated from rest, period by period (the state
/// carried on), until a period repeats the previous one to 1e-11 of its peak;
/// at most 4000 periods. False when the loop does not settle.
bool loop_steady(const Chain& c, const std::vector<double>& x, std::vector<double>& y) {
  Chain::LoopState w;
  std::vector<double> prev, cur;
  if (!c.loop_filter(x, prev, w)) return false;
  for (int period = 1; period < 4000; ++period) {
    if (!c.loop_filter(x, cur, w)) return false;
    double peak = 0, diff = 0;
    for (std::size_t t = 0; t < cur.size(); ++t) {
      peak = std::max(peak, std::abs(cur[t]));
      diff = std::max(diff, std::abs(cur[t] - prev[t]));
    }
    if (diff <= 1e-11 * peak) {
      y = std::move(cur);
      return true;
    }
    prev.swap(cur);
  }
  return false;
}

/// The continuous loop's periodic steady state by harmonic balance on the
/// grid of `st` (the fine grid): Y = G(jω) (X − F[f(y)]), iterated from the
/// linear response Y = G X. The spring's magnitude bound (draw_nonlinearity:
/// |f'| max|G| ≤ 1/2 over the lines, for |y| ≤ 3 r) is meant to make the map a
/// contraction of factor ≤ 1/2 — then it converges geometrically and, once a
/// step changes y by ≤ 1e-12 of its peak, the remaining steps sum to no more
/// than that step; at most 200 steps. X: the plant input's spectrum on entry, the plant
/// output's on return. False when it does not converge.
bool harmonic_balance(const Chain& c, const Setting& st, Fft& fft, std::vector<cplx>& X) {
  const std::size_t bins = X.size();
  std::vector<cplx> G(bins), Y(bins);
  for (std::size_t k = 0; k < bins; ++k) Y[k] = (G[k] = c.plant_at(st.omega[k], st.q[k])) * X[k];
  std::vector<double> y = fft.inverse(Y);
  for (int it = 0; it < 200; ++it) {
    std::vector<double> f(y.size());
    for (std::size_t t = 0; t < y.size(); ++t) f[t] = c.loop_nl(y[t]) - y[t];
    const std::vector<cplx> F = fft.forward(f.data());
    for (std::size_t k = 0; k < bins; ++k) Y[k] = G[k] * (X[k] - F[k]);
    std::vector<double> next = fft.inverse(Y);
    double peak = 0, step = 0;
    for (std::size_t t = 0; t < y.size(); ++t) {
      peak = std::max(peak, std::abs(next[t]));
      step = std::max(step, std::abs(next[t] - y[t]));
    }
    if (!std::isfinite(step) || peak > 1e6 * c.loop_nl.r) return false;
    y.swap(next);
    if (step <= 1e-12 * peak) {
      X = Y;
      return true;
    }
  }
  return false;
}

/// Steady-state output spectrum (bins 0 … P/2) of one period; empty when the
/// chain's loop does not settle.
std::vector<cplx> steady(const Chain& c, const Setting& st, Fft& fft, bool with_delay) {
  const std::size_t bins = st.U.size();
  std::vector<cplx> X = st.U;
  if (c.in_nl.on) {
    std::vector<double> x = st.u;
    for (double& v : x) v = c.in_nl(v);
    X = fft.forward(x.data());
  }
  if (c.loop_nl.on && c.continuous) {
    if (!harmonic_balance(c, st, fft, X)) return {};
  } else if (c.loop_nl.on) {
    std::vector<double> y;
    if (!loop_steady(c, fft.inverse(X), y)) return {};
    X = fft.forward(y.data());
  } else {
    for (std::size_t k = 0; k < bins; ++k) X[k] *= c.plant_at(st.omega[k], st.q[k]);
  }
  if (c.out_nl.on) {
    std::vector<double> x = fft.inverse(X);
    for (double& v : x) v = c.out_nl(v);
    X = fft.forward(x.data());
  }
  for (std::size_t k = 0; k < bins; ++k) X[k] *= c.meas_at(st.omega[k], st.q[k], with_delay);
  X.back() = X.back().real();  // P/2: a real signal's line (a fractional delay there has no real meaning)
  return X;
}

/// Every kFineGrid-th sample of a fine-grid signal: the first n (an ideal sampler).
std::vector<double> sampled(const std::vector<double>& fine, std::size_t n) {
  std::vector<double> x(n);
  for (std::size_t t = 0; t < n; ++t) x[t] = fine[t * kFineGrid];
  return x;
}

/// The steady state of the record's samples (bins 0 … P/2 of one period),
/// either family: a continuous chain with a nonlinear stage is computed on
/// the fine grid (harmonics of the polynomials up to kFineGrid/2 times the
/// sample rate kept at their own frequencies) and then sampled every
/// kFineGrid-th point, as an ideal sampler does; a linear one per line (the
/// input is band-limited, so sampling changes nothing). Empty when the loop
/// does not settle.
std::vector<cplx> response(const Chain& c, const Setting& st, Fft& fft, bool with_delay) {
  if (!c.continuous || !(c.in_nl.on || c.out_nl.on || c.loop_nl.on)) return steady(c, st, fft, with_delay);
  FineGrid& fine = *st.fine;
  const std::vector<cplx> Yf = steady(c, fine.st, fine.fft, with_delay);
  if (Yf.empty()) return {};
  const std::vector<double> y = sampled(fine.fft.inverse(Yf), static_cast<std::size_t>(st.P));
  return fft.forward(y.data());
}

/// The transient of the chain started from rest (delay left out): y_rest(t) − y_ss(t), over `periods` periods.
std::vector<double> transient(const Chain& c, const Setting& st, const std::vector<double>& y_ss_nodelay, int periods) {
  const std::size_t P = static_cast<std::size_t>(st.P), N = P * static_cast<std::size_t>(periods);
  std::vector<double> x(N), y, tmp;
  for (std::size_t t = 0; t < N; ++t) x[t] = st.u[t % P];
  if (c.in_nl.on)
    for (double& v : x) v = c.in_nl(v);
  if (c.loop_nl.on) {
    Chain::LoopState w;
    if (!c.loop_filter(x, y, w)) return std::vector<double>(N, 0.0);  // never: the loop settled in steady()
  } else {
    c.plant_filter(x, y);
  }
  if (c.out_nl.on)
    for (double& v : y) v = c.out_nl(v);
  for (const Section& s : c.sensor) {
    s.filter(y, tmp);
    y.swap(tmp);
  }
  for (std::size_t t = 0; t < N; ++t) y[t] = c.gain * y[t] - y_ss_nodelay[t % P];
  return y;
}

/// transient() for either family: a continuous chain's from its
/// zero-order-hold discretisation on the fine grid (Chain::discretised), its
/// steady state and its start from rest both of that discretisation, sampled
/// every kFineGrid-th point. Its poles, and so the shape of its free
/// response, are the continuous chain's exactly; its initial state is
/// the discretisation's (the hold delays the input by half a fine step).
std::vector<double> transient_of(const Chain& c, const Setting& st, const std::vector<double>& y_ss_nodelay, int periods) {
  if (!c.continuous) return transient(c, st, y_ss_nodelay, periods);
  FineGrid& fine = *st.fine;
  const Chain d = c.discretised();
  const std::vector<cplx> Yf = steady(d, fine.st, fine.fft, false);
  if (Yf.empty()) return std::vector<double>(static_cast<std::size_t>(st.P) * static_cast<std::size_t>(periods), 0.0);
  return sampled(transient(d, fine.st, fine.fft.inverse(Yf), periods),
                 static_cast<std::size_t>(st.P) * static_cast<std::size_t>(periods));
}

/// tr delayed by τ ≥ 0 samples with an ideal (band-limited) delay, truncated
/// to a Hann-windowed sinc of half-width 32 (taps normalised to unit DC gain;
/// exact for integer τ); before the start the from-rest output is 0, so the
/// transient there is −y_ss. `tr` must run at least 32 samples past the record.
std::vector<double> delay_transient(const std::vector<double>& tr, const std::vector<double>& y_ss_nodelay, double tau,
                                    std::size_t N) {
  if (tau == 0) return std::vector<double>(tr.begin(), tr.begin() + static_cast<long>(N));
  constexpr int L = 32;
  const long P = static_cast<long>(y_ss_nodelay.size()), n = static_cast<long>(std::floor(tau));
  const double f = tau - static_cast<double>(n);
  auto ext = [&](long i) {
    if (i >= 0) return tr[static_cast<std::size_t>(i)];
    return -y_ss_nodelay[static_cast<std::size_t>(((i % P) + P) % P)];
  };
  std::vector<double> h;
  long m0 = 0;
  if (f == 0) {
    h = {1.0};
  } else {
    m0 = -L + 1;
    double sum = 0;
    for (long m = m0; m <= L; ++m) {
      const double x = static_cast<double>(m) - f;
      h.push_back(std::sin(kPi * x) / (kPi * x) * 0.5 * (1 + std::cos(kPi * x / L)));
      sum += h.back();
    }
    for (double& v : h) v /= sum;
  }
  std::vector<double> out(N);
  for (std::size_t t = 0; t < N; ++t) {
    double acc = 0;
    for (std::size_t j = 0; j < h.size(); ++j) acc += h[j] * ext(static_cast<long>(t) - n - (m0 + static_cast<long>(j)));
    out[t] = acc;
  }
  return out;
}

/// Σ-normalised deviation of one effect alone (magnitude s): returns
/// A = mean over its lines of |ΔY(k)|² / (|H_v(k)|²/M) — the ratio is A/ν —
/// and, when asked, the per-line terms.
class Calibrator {
 public:
  Calibrator(const Base& base, const Setting& st, Fft& fft) : base_(base), st_(st), fft_(fft) {}

  /// For a continuous sensor, *delay (when asked) is the delay τ removed
  /// from its deviation (delay_equivalent); 0 for every other effect.
  double deviation(const Injected& e, double s, std::vector<double>* per_line = nullptr, double* delay = nullptr) {
    if (delay) *delay = 0;
    Injected es = e;
    es.scale = s;
    std::vector<double> r;
    switch (e.effect) {
      case Effect::Nonlinearity: {
        if (e.in_loop || base_.continuous) {  // the distortion of the chain (none when its loop does not settle)
          const std::vector<cplx> Y = response(make_chain(base_, {&es}), st_, fft_, true);
          for (int k : st_.unexcited_band)
            r.push_back(Y.empty() ? 0.0 : std::norm(Y[static_cast<std::size_t>(k)]) * st_.M / st_.w[static_cast<std::size_t>(k)]);
          break;
        }
        std::vector<double> x = e.at_input ? st_.u : st_.y_sim;
        const StaticPolynomial f{true, s * e.quad0, s * e.cubic0, e.reference_rms};
        for (double& v : x) v = f(v);
        const std::vector<cplx> X = fft_.forward(x.data());
        for (int k : st_.unexcited_band) {
          const cplx y = e.at_input ? st_.Hsim[static_cast<std::size_t>(k)] * X[static_cast<std::size_t>(k)]
                                    : X[static_cast<std::size_t>(k)];
          r.push_back(std::norm(y) * st_.M / st_.w[static_cast<std::size_t>(k)]);
        }
        break;
      }
      case Effect::Leakage: {
        if (T1_.empty()) {
          const Chain c = make_chain(base_, {});
          const std::vector<double> tr = transient_of(c, st_, st_.y_sim, 1);
          T1_ = fft_.forward(tr.data());
        }
        for (int k : st_.band)
          r.push_back(s * s * std::norm(T1_[static_cast<std::size_t>(k)]) / st_.w[static_cast<std::size_t>(k)]);
        break;
      }
      default: {
        const std::vector<cplx> G = frf(es);
        const double tau = base_.continuous && e.effect == Effect::SensorDynamics ? delay_equivalent(G) : 0.0;
        if (delay) *delay = tau;
        r = weighted_deviation(G, tau);
      }
    }
    const double A = r.empty() ? 0.0 : std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
    if (per_line) *per_line = std::move(r);
    return A;
  }

  const std::vector<int>& lines(const Injected& e) const {
    return e.effect == Effect::Nonlinearity ? st_.unexcited_band : e.effect == Effect::Leakage ? st_.band : st_.excited;
  }

  /// A linear effect's Σ-normalised deviation with no delay removed (the
  /// same as deviation() for every effect but the continuous sensor).
  double undelayed_deviation(const Injected& e, double s) const {
    Injected es = e;
    es.scale = s;
    const std::vector<double> r = weighted_deviation(frf(es), 0.0);
    return std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
  }

 private:
  // The true FRF at the excited lines with the linear effect es alone.
  std::vector<cplx> frf(const Injected& es) const {
    const Chain c = make_chain(base_, {&es});
    std::vector<cplx> G;
    for (int k : st_.excited) {
      const std::size_t i = static_cast<std::size_t>(k);
      G.push_back(c.plant_at(st_.omega[i], st_.q[i]) * c.meas_at(st_.omega[i], st_.q[i]));
    }
    return G;
  }

  // Per excited line, |(G(k) − G_sim(k) e^{−jω_k τ}) U(k)|² M / w(k), w = σ²/ν
  // the noise shape: ν times the line's ratio.
  std::vector<double> weighted_deviation(const std::vector<cplx>& G, double tau) const {
    std::vector<double> r;
    for (std::size_t j = 0; j < G.size(); ++j) {
      const std::size_t i = static_cast<std::size_t>(st_.excited[j]);
      const cplx dY = (G[j] - st_.Hsim[i] * std::polar(1.0, -st_.omega[i] * tau)) * st_.U[i];
      r.push_back(std::norm(dY) * st_.M / st_.w[i]);
    }
    return r;
  }

  // The continuous sensor's calibration (gap_cases.hpp, "Strength
  // calibration"): the delay τ ≥ 0 that explains most of G − G_sim, i.e.
  // minimises Σ_k |(G − G_sim e^{−jωτ}) U|² M/σ² over [0, 2π/ω_edge] (ω_edge
  // the highest excited line; a full turn of phase there: a sensor whose phase
  // lag at the band edge exceeds it is nowhere near a delay). The sum is
  // Re Σ c_k e^{jω_k τ} plus a constant, a trigonometric sum whose fastest
  // term turns once over that interval: a grid of 64 points (1/64 turn)
  // resolves its basins, Brent's method refines (numerics::minimize_1d).
  double delay_equivalent(const std::vector<cplx>& G) const {
    const double edge = st_.omega[static_cast<std::size_t>(st_.excited.back())];
    const auto total = [&](double tau) {
      const std::vector<double> r = weighted_deviation(G, tau);
      return std::accumulate(r.begin(), r.end(), 0.0);
    };
    return numerics::minimize_1d(total, 0.0, kTwoPi / edge, 64).first;
  }

  const Base& base_;
  const Setting& st_;
  Fft& fft_;
  std::vector<cplx> T1_;
};

/// Bands (cycles/sample) holding the lines that make up half the total ratio.
std::vector<std::array<double, 2>> bands_of(const std::vector<int>& lines, const std::vector<double>& r, int P) {
  std::vector<std::array<double, 2>> out;
  const double total = std::accumulate(r.begin(), r.end(), 0.0);
  if (!(total > 0)) return out;
  std::vector<std::size_t> idx(r.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return r[a] > r[b]; });
  std::vector<std::size_t> chosen;
  double cum = 0;
  for (std::size_t i : idx) {
    chosen.push_back(i);
    cum += r[i];
    if (cum >= 0.5 * total) break;
  }
  std::sort(chosen.begin(), chosen.end());
  struct Group {
    int lo, hi;
    double mass;
  };
  std::vector<Group> groups;
  for (std::size_t i : chosen) {
    const int k = lines[i];
    if (!groups.empty() && k - groups.back().hi <= 4) {
      groups.back().hi = k;
      groups.back().mass += r[i];
    } else {
      groups.push_back({k, k, r[i]});
    }
  }
  std::stable_sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) { return a.mass > b.mass; });
  if (groups.size() > 4) groups.resize(4);
  for (const Group& g : groups)
    out.push_back({std::max(0.0, (g.lo - 1.0) / P), std::min(0.5, (g.hi + 1.0) / P)});
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::array<double, 2>> merge_bands(std::vector<std::array<double, 2>> b) {
  std::sort(b.begin(), b.end());
  std::vector<std::array<double, 2>> out;
  for (const auto& x : b) {
    if (!out.empty() && x[0] <= out.back()[1])
      out.back()[1] = std::max(out.back()[1], x[1]);
    else
      out.push_back(x);
  }
  return out;
}

json bands_json(const std::vector<std::array<double, 2>>& b) {
  json j = json::array();
  for (const auto& x : b) j.push_back({x[0], x[1]});
  return j;
}

// ---------------------------------------------------------------------------
// n resonances spread one per log-spaced slot of [w_lo, w_hi], ζ log-uniform
// on [zeta_lo, zeta_hi], peak gains within a factor 10 of `overall`,
// near-quadrature residues (step 1 of gap_cases.hpp). Draws per mode: slot
// position, ζ, peak, sign, phase.
void draw_modes(Draw& d, Base& b, int n, double w_lo, double w_hi, double overall, double zeta_lo, double zeta_hi) {
  const double l0 = std::log(w_lo), l1 = std::log(w_hi);
  for (int i = 0; i < n; ++i) {
    Mode m;
    m.omega = std::exp(l0 + (l1 - l0) * (i + d.uniform(0.15, 0.85)) / n);
    m.zeta = d.log_uniform(zeta_lo, zeta_hi);
    const double peak = overall * d.log_uniform(0.3, 3.0);
    const cplx p = m.pole();
    m.residue = d.sign() * peak * (1 - std::abs(p)) * std::polar(1.0, -kPi / 2 + d.uniform(-0.4, 0.4));
    b.modes.push_back(m);
  }
}

Base draw_system(Draw& d, double w_lo, double w_hi) {
  Base b;
  const int n = d.integer(2, 4);
  const double overall = std::pow(10.0, d.uniform(-1, 1));
  draw_modes(d, b, n, w_lo, w_hi, overall, 0.01, 0.2);
  if (d.coin()) {
    b.has_real = true;
    b.real_pole = std::exp(-d.log_uniform(0.5 * w_lo, 2 * w_hi));
    b.real_residue = d.sign() * overall * d.log_uniform(0.3, 3.0) * (1 - b.real_pole);
  }
  if (d.coin()) b.D = d.sign() * overall * d.log_uniform(0.05, 0.5);
  return b;
}

// The structure family's model (gap_cases.hpp): 5 … 8 resonances spread as in
// draw_system, ζ log-uniform on [0.005, 0.05], no real pole, D = 0.
Base draw_structure(Draw& d, double w_lo, double w_hi) {
  Base b;
  const int n = d.integer(5, 8);
  draw_modes(d, b, n, w_lo, w_hi, std::pow(10.0, d.uniform(-1, 1)), 0.005, 0.05);
  return b;
}

// unmodelled_mode: the frequency log-uniform over the band, at least 12 %
// away from every model mode (the best of 200 tries), ζ log-uniform on
// [0.01, 0.1], then series (a unit-DC-gain bump of peak ratio 1 + s κ0) or
// parallel (a residue of size ρ relative to the model at that frequency).
void draw_unmodelled_mode(Injected& e, Draw& d, bool clear, const Base& base, const Setting& st, double w_lo,
                          double w_band) {
  const double l0 = std::log(std::max(w_lo, kTwoPi * 2 / st.P)), l1 = std::log(0.95 * w_band);
  double best = 0, best_sep = -1;
  for (int tries = 0; tries < 200; ++tries) {
    const double w = std::exp(d.uniform(l0, l1));
    double sep = 1e300;
    for (const Mode& m : base.modes) sep = std::min(sep, std::abs(std::log(w / m.omega)));
    if (sep > best_sep) {
      best_sep = sep;
      best = w;
    }
    if (sep >= std::log(1.12)) break;
  }
  e.extra_omega = best;
  e.extra_zeta = d.log_uniform(0.01, 0.1);
  e.series = d.coin();
  if (e.series) {
    e.kappa0 = clear ? d.log_uniform(0.5, 3.0) : d.log_uniform(0.02, 0.1);
    e.scale_max = std::min(20.0, 0.95 / e.extra_zeta - 1) / e.kappa0;
  } else {
    const double rho = clear ? d.log_uniform(0.2, 1.0) : d.log_uniform(0.01, 0.05);
    const cplx unit = d.sign() * std::polar(1.0, -kPi / 2 + d.uniform(-0.4, 0.4));
    const double unit_peak = std::abs(Mode{best, e.extra_zeta, unit}.at(best, base.continuous));
    Chain sim = make_chain(base, {});
    e.extra_residue0 = unit * rho * std::abs(sim.plant_at(best, std::polar(1.0, -best))) / unit_peak;
    e.scale_max = 5.0 / rho;
  }
}

// mode_mismatch: a random model mode; its frequency, damping or both moved
// (ω' = ω (1 + s δ0), ζ' = ζ e^{s λ0}); scale_max keeps ω' below 0.95 π and
// ζ' within [0.002, 0.7].
void draw_mode_mismatch(Injected& e, Draw& d, bool clear, const Base& base) {
  e.mode = d.integer(0, static_cast<int>(base.modes.size()) - 1);
  const Mode& m = base.modes[static_cast<std::size_t>(e.mode)];
  const double u = d.unit();
  const int type = u < 0.4 ? 0 : u < 0.6 ? 1 : 2;  // frequency, damping, both
  if (type != 1) e.shift0 = d.sign() * (clear ? d.uniform(0.02, 0.08) : d.uniform(0.002, 0.01));
  if (type != 0)
    e.damping_log0 = d.sign() * (clear ? d.uniform(std::log(1.4), std::log(2.5)) : d.uniform(std::log(1.03), std::log(1.1)));
  double smax = 1e300;
  if (e.shift0 != 0) smax = std::min(smax, 0.25 / std::abs(e.shift0));
  if (e.shift0 > 0) smax = std::min(smax, (0.95 * kPi / m.omega - 1) / e.shift0);
  if (e.damping_log0 > 0) smax = std::min(smax, std::log(0.7 / m.zeta) / e.damping_log0);
  if (e.damping_log0 < 0) smax = std::min(smax, std::log(0.002 / m.zeta) / e.damping_log0);
  e.scale_max = std::max(1.0, smax);
}

// nonlinearity: at the input or the output, quadratic, cubic or both, each
// coefficient of random sign and log-uniform size, relative to the RMS of
// the signal it acts on.
void draw_nonlinearity(Injected& e, Draw& d, bool clear, const Setting& st, bool in_loop) {
  e.in_loop = in_loop;
  e.at_input = !in_loop && d.coin();
  const double u = d.unit();
  const int type = u < 1.0 / 3 ? 0 : u < 2.0 / 3 ? 1 : 2;  // quadratic, cubic, both
  auto coef = [&] { return d.sign() * (clear ? d.log_uniform(0.02, 0.1) : d.log_uniform(0.002, 0.01)); };
  if (type != 1) e.quad0 = coef();
  if (type != 0) e.cubic0 = coef();
  double ss = 0;
  const std::vector<double>& x = e.at_input ? st.u : st.y_sim;
  for (double v : x) ss += v * v;
  e.reference_rms = std::sqrt(ss / static_cast<double>(x.size()));
  e.scale_max = 0.5 / std::max(std::abs(e.quad0), std::abs(e.cubic0));
  if (in_loop) {
    // In the loop the spring's incremental gain f'(y) = s (2 a2 y/r + 3 a3 y²/r²)/r
    // meets the plant's peak gain: at |y| ≤ 3r, |f'| ≤ s (6|a2| + 27|a3|)/r; keep
    // |f'| · max|G| ≤ 0.5 (small-gain: the loop stays a contraction around the
    // linear response) or the static bound, whichever is smaller.
    double gmax = 0;
    for (int k : st.band) gmax = std::max(gmax, std::abs(st.Hsim[static_cast<std::size_t>(k)]));
    const double slope = (6 * std::abs(e.quad0) + 27 * std::abs(e.cubic0)) / e.reference_rms;
    e.scale_max = std::min(e.scale_max, 0.5 / (slope * gmax));
  }
}

// One effect's physical parameters at magnitude 1 for the strength, and the
// largest magnitude scale_max its physical bounds allow (see each draw).
void draw_effect(Injected& e, Draw& d, Strength strength, const Base& base, const Setting& st, double w_lo,
                 double w_band, bool structure) {
  const bool clear = strength == Strength::Clear;
  switch (e.effect) {
    case Effect::GainError: {
      const bool up = d.coin();
      const double dev = clear ? (up ? d.uniform(0.05, 0.4) : d.uniform(0.05, 0.3)) : d.uniform(0.005, 0.03);
      e.gain0 = up ? 1 + dev : 1 - dev;
      e.scale_max = up ? 2.0 / dev : 0.8 / dev;  // g ∈ [0.2, 3]
      break;
    }
    case Effect::Delay: {
      const double phase = clear ? d.uniform(0.15, 1.0) : d.uniform(0.02, 0.15);  // at the band edge
      e.delay0 = phase / w_band;
      if (clear && d.coin() && std::round(e.delay0) >= 1 && std::round(e.delay0) * w_band <= 3.0)
        e.delay0 = std::round(e.delay0);
      e.scale_max = (3.0 / w_band) / e.delay0;
      break;
    }
    case Effect::SensorDynamics: {
      const double fc_rel = clear ? d.log_uniform(0.5, 2.0) : d.log_uniform(3.0, 8.0);
      e.order = d.coin() ? 1 : 2;
      e.sensor_zeta = d.uniform(0.5, 0.9);
      e.time_constant0 = 1.0 / (fc_rel * w_band);
      e.scale_max = (4.0 / w_band) / e.time_constant0;  // cut-off down to a quarter of the band edge
      break;
    }
    case Effect::UnmodelledMode: draw_unmodelled_mode(e, d, clear, base, st, w_lo, w_band); break;
    case Effect::ModeMismatch: draw_mode_mismatch(e, d, clear, base); break;
    case Effect::Nonlinearity: draw_nonlinearity(e, d, clear, st, structure); break;
    case Effect::Leakage:
      e.scale_max = 1.0;  // 1: from rest
      break;
  }
}

json effect_json(const Injected& e, const Base& base) {
  const double s = e.scale;
  json j;
  switch (e.effect) {
    case Effect::GainError: j["gain"] = 1 + s * (e.gain0 - 1); break;
    case Effect::Delay: j["samples"] = s * e.delay0; break;
    case Effect::SensorDynamics:
      j["order"] = e.order;
      j["cutoff"] = 1.0 / (kTwoPi * s * e.time_constant0);  // cycles/sample
      if (e.order == 2) j["damping"] = e.sensor_zeta;
      if (base.continuous) {  // the calibration's delay (gap_cases.hpp, "Strength calibration")
        j["delay_equivalent"] = e.delay_equivalent;
        j["ratio_undelayed"] = e.ratio_undelayed;
      }
      break;
    case Effect::UnmodelledMode:
      j["connection"] = e.series ? "series" : "parallel";
      j["frequency"] = e.extra_omega / kTwoPi;
      j["damping"] = e.extra_zeta;
      if (e.series) {
        j["peak_ratio"] = 1 + s * e.kappa0;  // ζ_zero/ζ_pole: the bump's peak gain
      } else {
        j["residue"] = {(s * e.extra_residue0).real(), (s * e.extra_residue0).imag()};
      }
      break;
    case Effect::ModeMismatch: {
      const Mode& m = base.modes[static_cast<std::size_t>(e.mode)];
      j["mode"] = e.mode;
      j["frequency_sim"] = m.omega / kTwoPi;
      j["frequency_true"] = m.omega * (1 + s * e.shift0) / kTwoPi;
      j["frequency_shift"] = s * e.shift0;
      j["damping_sim"] = m.zeta;
      j["damping_true"] = m.zeta * std::exp(s * e.damping_log0);
      j["damping_ratio"] = std::exp(s * e.damping_log0);
      break;
    }
    case Effect::Nonlinearity:
      j["location"] = e.in_loop ? "loop" : e.at_input ? "input" : "output";
      j["quadratic"] = s * e.quad0;
      j["cubic"] = s * e.cubic0;
      j["reference_rms"] = e.reference_rms;
      j["form"] = e.in_loop ? "plant input u - (quadratic y^2/r + cubic y^3/r^2), y the plant output"
                            : "x + quadratic x^2/r + cubic x^3/r^2";
      break;
    case Effect::Leakage:
      j["initial_state"] = s == 1.0 ? "rest" : "partly settled";
      j["transient_fraction"] = s;  // x(0) = (1 − s) x_ss(0)
      break;
  }
  j["ratio"] = e.ratio;
  j["target_ratio"] = e.target;
  j["scale"] = s;
  j["scale_max"] = e.scale_max;
  j["lines"] = e.effect == Effect::Nonlinearity ? "unexcited" : e.effect == Effect::Leakage ? "band (first period)" : "excited";
  return j;
}

void validate_options(const GapCaseOptions& o) {
  auto fail = [](const std::string& m) { throw Error(ErrorKind::Input, kWhere, m); };
  if (o.period < 32 || o.period % 2 != 0 || o.period > (1 << 22))
    fail("period P must be even and within 32 ... 2^22, got " + std::to_string(o.period));
  if (o.periods < 2) fail("needs at least 2 periods, got " + std::to_string(o.periods));
  if (static_cast<double>(o.period) * o.periods > static_cast<double>(1 << 26))
    fail("P*M = " + std::to_string(static_cast<double>(o.period) * o.periods) + " samples exceeds 2^26");
  if (o.effects.size() > 2) fail("at most 2 effects, got " + std::to_string(o.effects.size()));
  std::set<Effect> seen;
  for (Effect e : o.effects)
    if (!seen.insert(e).second) fail("effect '" + std::string(to_string(e)) + "' given twice");
  if (!o.effects.empty() && o.strength == Strength::None) fail("effects need strength subtle or clear, not none");
  if (o.measured_noise) {
    const MeasuredNoise& mn = *o.measured_noise;
    if (mn.period != o.period)
      fail("the measured noise has period " + std::to_string(mn.period) + ", the case " + std::to_string(o.period) +
           ": use the noise record's period");
    if (static_cast<std::size_t>(o.periods) > mn.periods.size())
      fail("the measured noise holds " + std::to_string(mn.periods.size()) +
           " noise periods, the case needs " + std::to_string(o.periods) +
           ": use fewer periods or add noise records");
  }
}

// Step 2 of gap_cases.hpp: the random-odd multisine (Schoukens) over the odd
// lines 1 … K, K a random fraction 0.15 … 0.4 of P/2; one random line of each
// full group of 4 consecutive odd lines left out; random phases, flat
// amplitude, RMS 1 exactly (Σ u² = 2 Σ |U(k)|² = P). Also the line grid ω, q.
// Draws: K, then one skip per full group, then one phase per excited line.
Setting draw_excitation(Draw& d, int P, int M, Fft& fft) {
  const std::size_t bins = static_cast<std::size_t>(P / 2 + 1);
  Setting st;
  st.P = P;
  st.M = M;
  st.K = std::clamp(static_cast<int>(std::floor(d.uniform(0.15, 0.4) * P / 2)), 7, P / 2 - 1);
  std::vector<int> odd;
  for (int k = 1; k <= st.K; k += 2) odd.push_back(k);
  std::vector<bool> excited(bins, false);
  for (std::size_t g = 0; g < odd.size(); g += 4) {
    const std::size_t size = std::min<std::size_t>(4, odd.size() - g);
    const std::size_t skip = size == 4 ? static_cast<std::size_t>(d.integer(0, 3)) : size;
    for (std::size_t i = 0; i < size; ++i)
      if (i != skip) excited[static_cast<std::size_t>(odd[g + i])] = true;
  }
  for (int k = 1; k <= st.K; ++k) {
    st.band.push_back(k);
    (excited[static_cast<std::size_t>(k)] ? st.excited : st.unexcited_band).push_back(k);
  }
  const double amplitude = std::sqrt(P / (2 * static_cast<double>(st.excited.size())));
  st.U.assign(bins, 0.0);
  for (int k : st.excited) st.U[static_cast<std::size_t>(k)] = std::polar(amplitude, kTwoPi * d.unit());
  st.u = fft.inverse(st.U);
  st.omega.resize(bins);
  st.q.resize(bins);
  for (std::size_t k = 0; k < bins; ++k) {
    st.omega[k] = kTwoPi * static_cast<double>(k) / P;
    st.q[k] = std::polar(1.0, -st.omega[k]);
  }
  return st;
}

// The simulation model's response at every line and its steady-state output
// over one period (Y(k) = G(e^{jω_k}) U(k), inverse FFT).
void simulate_model(const Base& base, Fft& fft, Setting& st) {
  const Chain sim = make_chain(base, {});
  const std::size_t bins = st.U.size();
  st.Hsim.resize(bins);
  std::vector<cplx> Y(bins);
  for (std::size_t k = 0; k < bins; ++k) {
    st.Hsim[k] = sim.plant_at(st.omega[k], st.q[k]);
    Y[k] = st.Hsim[k] * st.U[k];
  }
  st.y_sim = fft.inverse(Y);
}

// Step 4 of gap_cases.hpp, the shape: H_v a random stable first- or
// second-order filter (coin, then its coefficients), normalised to mean
// |H_v|² = 1 over the excited lines; st.w = |H_v|² at every line.
Section draw_noise_filter(Draw& d, Setting& st, bool rising) {
  Section hv;
  if (rising) {  // the structure family: 1 − a q⁻¹, rising with frequency
    hv.b1 = -d.uniform(0.5, 0.95);
  } else if (d.coin()) {
    hv.b1 = d.uniform(-0.6, 0.6);
    hv.a1 = -d.uniform(-0.3, 0.9);
  } else {
    const double r = d.uniform(0.3, 0.9), th = d.uniform(0, kPi);
    hv.a1 = -2 * r * std::cos(th);
    hv.a2 = r * r;
    hv.b1 = d.uniform(-0.8, 0.8);
  }
  double mean = 0;
  for (int k : st.excited) mean += std::norm(hv.at(st.q[static_cast<std::size_t>(k)]));
  const double c = 1 / std::sqrt(mean / static_cast<double>(st.excited.size()));
  hv.b0 *= c;
  hv.b1 *= c;
  hv.b2 *= c;
  st.w.resize(st.q.size());
  for (std::size_t k = 0; k < st.q.size(); ++k) st.w[k] = std::norm(hv.at(st.q[k]));
  return hv;
}

// The measured noise's shape (gap_cases.hpp, "Measured noise"): st.w = the
// pool's per-line variance averaged over lines k−4 … k+4 (fewer at the ends),
// normalised to mean 1 over the excited lines. Returns that normalisation, s0:
// the pool's samples have per-line variance s0 · st.w(k), so the factor
// √(ν / s0) gives them ν · st.w(k). A line where the pool has no power at all
// (a zero band of a filtered measurement) is floored at 1e-12 of the mean, so
// the calibration's divisions stay finite; the effects there are then huge
// against the noise, as they would be in that measurement.
double measured_shape(const MeasuredNoise& mn, Fft& fft, Setting& st) {
  const std::size_t bins = st.q.size();
  std::vector<double> raw(bins, 0.0);
  for (const std::vector<double>& n : mn.periods) {
    const std::vector<cplx> N = fft.forward(n.data());
    for (std::size_t k = 0; k < bins; ++k) raw[k] += std::norm(N[k]);
  }
  const int half = 4;
  st.w.assign(bins, 0.0);
  for (std::size_t k = 0; k < bins; ++k) {
    const std::size_t lo = k >= static_cast<std::size_t>(half) ? k - half : 0, hi = std::min(bins - 1, k + half);
    double sum = 0;
    for (std::size_t i = lo; i <= hi; ++i) sum += raw[i];
    st.w[k] = sum / static_cast<double>((hi - lo + 1) * mn.periods.size());
  }
  double mean = 0;
  for (int k : st.excited) mean += st.w[static_cast<std::size_t>(k)];
  mean /= static_cast<double>(st.excited.size());
  if (!(mean > 0)) throw Error(ErrorKind::Input, kWhere, "the measured noise has no power on the excited lines");
  for (double& w : st.w) w = std::max(w / mean, 1e-12);
  return mean;
}

// Output signal power per excited line of one period's DFT (the SNR's numerator).
double signal_power(const Setting& st) {
  double signal = 0;
  for (int k : st.excited) signal += std::norm(st.Hsim[static_cast<std::size_t>(k)] * st.U[static_cast<std::size_t>(k)]);
  return signal / static_cast<double>(st.excited.size());
}

// The withheld effects at magnitude 1: per effect, in the order given, its
// physical parameters (draw_effect) and then its target ratio.
std::vector<Injected> draw_effects(Draw& d, const GapCaseOptions& o, const Base& base, const Setting& st, double w_lo,
                                   double w_band) {
  std::vector<Injected> effects;
  for (Effect effect : o.effects) {
    Injected e;
    e.effect = effect;
    draw_effect(e, d, o.strength, base, st, w_lo, w_band, o.structure);
    const auto range = gap_ratio_range(o.strength);
    e.target = d.log_uniform(range[0], range[1]);
    effects.push_back(e);
  }
  return effects;
}

// The upper end of the bisection bracket [0, hi] of each effect's magnitude,
// lowering ν where an effect cannot reach its target: hi = 1 (the draw) when
// it reaches the target, else the first point of a grid of 32 over
// (1, scale_max] that does (the deviation need not grow monotonically, e.g. a
// mode moving across the lines); when none does, the best one, and ν lowered
// so that it hits the target (past 60 dB: snr_clamped).
// Fails: Error(Numerical) when an effect makes no deviation at all.
std::vector<double> magnitude_brackets(std::vector<Injected>& effects, Calibrator& cal, double& nu) {
  std::vector<double> hi_of;
  for (Injected& e : effects) {
    double hi = std::min(1.0, e.scale_max), best = hi, Abest = cal.deviation(e, hi);
    if (Abest < e.target * nu) {
      for (int i = 1; i <= 32; ++i) {
        const double s = hi + (e.scale_max - hi) * i / 32.0, A = cal.deviation(e, s);
        if (A > Abest) {
          Abest = A;
          best = s;
        }
        if (A >= e.target * nu) break;
      }
      if (!(Abest > 0))
        throw Error(ErrorKind::Numerical, kWhere, "effect " + std::string(to_string(e.effect)) + " makes no deviation");
      if (Abest < e.target * nu * (1 - 1e-9)) {
        nu = Abest / e.target;
      }
      hi = best;
    }
    hi_of.push_back(hi);
  }
  return hi_of;
}

// Each effect's magnitude by bisection on [0, hi] to its target ratio at the
// noise level ν (relative 1e-7; the draw itself when it already hits it), then
// its achieved ratio, per-line ratios and lines.
void hit_targets(std::vector<Injected>& effects, const std::vector<double>& hi_of, Calibrator& cal, double nu) {
  for (std::size_t j = 0; j < effects.size(); ++j) {
    Injected& e = effects[j];
    double s = 1.0;
    double A = cal.deviation(e, s);
    if (!(e.scale_max >= 1.0 && std::abs(A / nu / e.target - 1) <= 1e-9)) {
      double lo = 0, hi = hi_of[j];
      for (int it = 0; it < 200; ++it) {
        s = 0.5 * (lo + hi);
        A = cal.deviation(e, s);
        const double rel = A / nu / e.target - 1;
        if (std::abs(rel) <= 1e-7 || hi - lo <= 1e-15 * hi_of[j]) break;
        (rel < 0 ? lo : hi) = s;
      }
    }
    e.scale = s;
    e.ratio = cal.deviation(e, s, &e.line_ratio, &e.delay_equivalent) / nu;
    if (e.effect == Effect::SensorDynamics) e.ratio_undelayed = cal.undelayed_deviation(e, s) / nu;
    for (double& r : e.line_ratio) r /= nu;
    e.lines = cal.lines(e);
  }
}

// The strength calibration of gap_cases.hpp: returns the noise level ν and
// sets each effect's magnitude. Without effects ν gives a random SNR of
// 20 … 60 dB (one draw); with effects it is the geometric mean of the levels
// at which each draw hits its target, clamped to that SNR range, then lowered
// where an effect cannot reach its target (magnitude_brackets).
double calibrate(Draw& d, std::vector<Injected>& effects, Calibrator& cal, double signal) {
  if (effects.empty()) return signal / std::pow(10.0, d.uniform(2, 6));
  const double nu_lo = signal * 1e-6, nu_hi = signal * 1e-2;  // SNR 60 … 20 dB
  double lsum = 0;
  for (Injected& e : effects) lsum += std::log(cal.deviation(e, 1.0) / e.target);
  double nu = std::clamp(std::exp(lsum / static_cast<double>(effects.size())), nu_lo, nu_hi);
  const std::vector<double> hi_of = magnitude_brackets(effects, cal, nu);
  hit_targets(effects, hi_of, cal, nu);
  return nu;
}

// The noise-free record of the true system (step 3 of gap_cases.hpp).
struct TrueOutput {
  std::vector<cplx> Y;           // steady-state output spectrum of one period
  std::vector<double> y;         // P·M samples
  double transient_energy = 0;   // of the first period (leakage)
};

// Exact periodic steady state per line; with leakage, the transient of the
// start from rest (scaled by its magnitude) added, delayed by the chain's
// delay (delay_transient).
TrueOutput true_output(const Base& base, const std::vector<Injected>& effects, const Setting& st, Fft& fft) {
  const int P = st.P, M = st.M;
  std::vector<const Injected*> ptrs;
  for (const Injected& e : effects) ptrs.push_back(&e);
  const Chain truth_chain = make_chain(base, ptrs);
  TrueOutput out;
  out.Y = response(truth_chain, st, fft, true);
  if (out.Y.empty())
    throw Error(ErrorKind::Numerical, kWhere, "the nonlinearity's loop does not settle at the calibrated magnitude");
  const std::vector<double> y_ss = fft.inverse(out.Y);
  const std::size_t N = static_cast<std::size_t>(P) * static_cast<std::size_t>(M);
  out.y.resize(N);
  for (std::size_t t = 0; t < N; ++t) out.y[t] = y_ss[t % static_cast<std::size_t>(P)];
  if (truth_chain.leak > 0) {
    const std::vector<double> y_nd = fft.inverse(response(truth_chain, st, fft, false));
    const std::vector<double> tr = delay_transient(transient_of(truth_chain, st, y_nd, M + 1), y_nd, truth_chain.delay, N);
    for (std::size_t t = 0; t < N; ++t) out.y[t] += truth_chain.leak * tr[t];
    for (int t = 0; t < P; ++t) out.transient_energy += std::pow(truth_chain.leak * tr[static_cast<std::size_t>(t)], 2);
  }
  return out;
}

// All effects together: mean over the excited lines of |Y − G_sim U|² M / σ²(k).
double combined_ratio(const Setting& st, const std::vector<cplx>& Y, double nu) {
  double ratio = 0;
  for (int k : st.excited) {
    const std::size_t i = static_cast<std::size_t>(k);
    ratio += std::norm(Y[i] - st.Hsim[i] * st.U[i]) * st.M / (nu * st.w[i]);
  }
  return ratio / static_cast<double>(st.excited.size());
}

// Step 4 of gap_cases.hpp, the input noise: with probability 1/2 (one coin) a
// white noise whose effect on Y/U is 0.1 … 1 % of the output noise's at the
// worst excited line (one more draw); else none. Returns its variance.
double draw_input_noise(Draw& d, const Setting& st, double nu) {
  if (!d.coin()) return 0;
  double m = 1e300;
  for (int k : st.excited) {
    const std::size_t i = static_cast<std::size_t>(k);
    m = std::min(m, nu * st.w[i] / std::max(std::norm(st.Hsim[i]), 1e-300));
  }
  return d.log_uniform(1e-3, 1e-2) * m;
}

// The u, y record: the input period repeated and the true output, plus (when
// `noise`) the coloured output noise v = H_v e, one stationary sequence over
// the record after a burn-in of 400 samples (noise-filter poles have modulus
// ≤ 0.9), and the white input noise. All from the noise stream `dn`: first
// the N + 400 output-noise normals, then one input-noise normal per sample.
// With measured noise (`chosen` not null) the output noise is instead the
// pool's periods, M of them drawn without replacement (a partial
// Fisher–Yates shuffle by the noise stream, one draw per period; their pool
// indices into *chosen), times `factor`; then the input noise as above.
Eigen::MatrixXd noisy_record(Draw& dn, const Section& hv, double nu, double input_var, const Setting& st,
                             const std::vector<double>& y, bool noise, const MeasuredNoise* measured = nullptr,
                             double factor = 0, std::vector<int>* chosen = nullptr) {
  const std::size_t P = static_cast<std::size_t>(st.P), N = y.size(), burn = 400;
  Eigen::MatrixXd record(static_cast<Eigen::Index>(N), 2);
  std::vector<double> v;
  if (measured) {
    std::vector<int> pool(measured->periods.size());
    for (std::size_t i = 0; i < pool.size(); ++i) pool[i] = static_cast<int>(i);
    for (int m = 0; m < st.M; ++m) {
      const int j = dn.integer(m, static_cast<int>(pool.size()) - 1);
      std::swap(pool[static_cast<std::size_t>(m)], pool[static_cast<std::size_t>(j)]);
      chosen->push_back(pool[static_cast<std::size_t>(m)]);
      for (double x : measured->periods[static_cast<std::size_t>(pool[static_cast<std::size_t>(m)])])
        v.push_back(factor * x);
    }
  } else {
    std::vector<double> e(N + burn);
    for (double& x : e) x = std::sqrt(nu) * dn.normal();
    hv.filter(e, v);
    v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(burn));
  }
  const double su = std::sqrt(input_var);
  for (std::size_t t = 0; t < N; ++t) {
    const Eigen::Index i = static_cast<Eigen::Index>(t);
    const double nu_t = su * dn.normal();
    record(i, 0) = st.u[t % P] + (noise ? nu_t : 0.0);
    record(i, 1) = y[t] + (noise ? v[t] : 0.0);
  }
  return record;
}

// The scalar results of the case that the truth reports.
struct CaseNumbers {
  double signal = 0, nu = 0, input_var = 0, ratio_combined = 0, transient_energy = 0;
  bool clamped = false;
  double measured_scale = 0;       // s0 of measured_shape (measured noise only)
  std::vector<int> measured_chosen;  // the pool periods used, in record order
};

// The truth JSON of gap_cases.hpp, and the truth bands (each effect's
// bands_of, merged) into out.bands.
void write_truth(const GapCaseOptions& o, const Base& base, const Setting& st, const Section& hv,
                 const std::vector<Injected>& effects, const CaseNumbers& n, GapCase& out) {
  json details = json::object();
  std::vector<std::array<double, 2>> all_bands;
  for (const Injected& e : effects) {
    json j = effect_json(e, base);
    const auto b = bands_of(e.lines, e.line_ratio, st.P);
    j["bands"] = bands_json(b);
    all_bands.insert(all_bands.end(), b.begin(), b.end());
    details[to_string(e.effect)] = j;
  }
  out.bands = merge_bands(all_bands);

  json modes = json::array();
  for (const Mode& m : base.modes)
    modes.push_back({{"frequency", m.omega / kTwoPi},
                     {"damping", m.zeta},
                     {"damped_frequency", (o.continuous ? m.ct_part().p.imag() : std::arg(m.pole())) / kTwoPi},
                     {"residue", {m.residue.real(), m.residue.imag()}}});
  json& t = out.truth;
  t["effects"] = json::array();
  for (Effect e : o.effects) t["effects"].push_back(to_string(e));
  t["strength"] = effects.empty() ? "none" : to_string(o.strength);
  t["family"] = to_string(o.structure ? GapFamily::Structure : GapFamily::Classic);
  t["domain"] = to_string(o.continuous ? Domain::Continuous : Domain::Discrete);
  t["seed"] = o.seed;
  t["period"] = st.P;
  t["periods"] = st.M;
  t["bands"] = bands_json(out.bands);
  t["snr_db"] = 10 * std::log10(n.signal / n.nu);
  t["snr_clamped"] = n.clamped;
  t["noise"] = {{"scale", n.nu},
                {"filter", {{"b", {hv.b0, hv.b1, hv.b2}}, {"a", {1.0, hv.a1, hv.a2}}}},
                {"input_std", std::sqrt(n.input_var)},
                {"enabled", o.noise},
                {"definition", "per-line variance of one period's unitary DFT = scale |H_v|^2; of the M-period mean: /M"}};
  if (o.measured_noise) {
    t["noise"]["filter"] = nullptr;
    t["noise"]["definition"] =
        "per-line variance of one period's unitary DFT = scale w(k), w the measured pool's own shape (gap_cases.hpp); "
        "of the M-period mean: /M";
    t["noise"]["measured"] = {{"sources", o.measured_noise->sources},
                              {"pool", o.measured_noise->periods.size()},
                              {"chosen", n.measured_chosen},
                              {"factor", std::sqrt(n.nu / n.measured_scale)}};
  }
  t["system"] = {{"modes", modes},
                 {"real_pole", base.has_real ? json(base.real_pole) : json(nullptr)},
                 {"real_residue", base.has_real ? json(base.real_residue) : json(nullptr)},
                 {"D", base.D}};
  t["excitation"] = {{"band_line", st.K}, {"lines", st.excited.size()}, {"rms", 1.0}};
  t["ratio_combined"] = n.ratio_combined;
  t["transient_energy_first_period"] = n.transient_energy;
  t["details"] = details;
}

}  // namespace

void add_measured_noise(MeasuredNoise& pool, const Eigen::VectorXd& column, const std::string& source) {
  const Eigen::Index P = pool.period;
  if (P < 2 || column.size() % P != 0 || column.size() / P < 3)
    throw Error(ErrorKind::Input, source,
                "a measured noise record needs at least 3 whole periods of " + std::to_string(P) + " samples, got " +
                    std::to_string(column.size()) + " samples");
  if (!column.allFinite()) throw Error(ErrorKind::Input, source, "the noise column holds a value that is not finite");
  // The orthonormal contrasts of gap_cases.hpp (MeasuredNoise): per four
  // consecutive periods the quadratic and cubic orthogonal polynomials, per
  // three left over the quadratic.
  static const std::vector<std::vector<double>> four = {{0.5, -0.5, -0.5, 0.5},
                                                        {-1 / std::sqrt(20.0), 3 / std::sqrt(20.0),
                                                         -3 / std::sqrt(20.0), 1 / std::sqrt(20.0)}};
  static const std::vector<std::vector<double>> three = {{1 / std::sqrt(6.0), -2 / std::sqrt(6.0), 1 / std::sqrt(6.0)}};
  const Eigen::Index R = column.size() / P;
  for (Eigen::Index m = 0; m + 2 < R;) {
    const auto& contrasts = m + 4 <= R ? four : three;
    for (const auto& c : contrasts) {
      std::vector<double> n(static_cast<std::size_t>(P), 0.0);
      Eigen::Map<Eigen::VectorXd> sum(n.data(), P);
      for (std::size_t i = 0; i < c.size(); ++i) sum += c[i] * column.segment((m + static_cast<Eigen::Index>(i)) * P, P);
      pool.periods.push_back(std::move(n));
    }
    m += static_cast<Eigen::Index>(contrasts.front().size());
  }
  pool.sources.push_back(source);
}

/// One blind case of the gap validation (gap_cases.hpp, steps 1-4 and the
/// strength calibration).
///
/// Method: excitation; simulation model; noise shape; the withheld effects and
/// their calibration against the noise level; the true record; the noise; the
/// truth. Every draw comes from one mt19937_64 stream in that order (the
/// output and input noise from a second one), so a case is a function of the
/// seed alone.
/// Numerical aspects: O(P log P) per calibration evaluation, up to ~250 of them
/// per effect (grid and bisection); O(P M) for the record (O(P M · 64) with a
/// fractional delay and leakage: the windowed-sinc delay of the transient).
/// Fails: Error(Input) for bad options (validate_options), Error(Numerical)
/// when an effect makes no deviation.
GapCase make_gap_case(const GapCaseOptions& o) {
  validate_options(o);
  Draw d(o.seed);
  Draw dn(splitmix64(o.seed));  // the noise stream
  Fft fft(o.period, kWhere);
  Setting st = draw_excitation(d, o.period, o.periods, fft);
  // Resonances inside the excited band.
  const double w_band = kTwoPi * st.K / st.P;
  const double w_lo = std::max(0.08 * w_band, kTwoPi * 2 / st.P), w_hi = 0.9 * w_band;
  Base base = o.structure ? draw_structure(d, w_lo, w_hi) : draw_system(d, w_lo, w_hi);
  if (o.continuous) {
    make_continuous(base);
    st.fine = std::make_shared<FineGrid>(st);
  }
  simulate_model(base, fft, st);
  const Section hv = draw_noise_filter(d, st, o.structure);  // drawn either way: the same draws follow
  CaseNumbers n;
  if (o.measured_noise) n.measured_scale = measured_shape(*o.measured_noise, fft, st);

  n.signal = signal_power(st);
  std::vector<Injected> effects = draw_effects(d, o, base, st, w_lo, w_band);
  Calibrator cal(base, st, fft);
  n.nu = calibrate(d, effects, cal, n.signal);
  n.clamped = n.nu < n.signal * 1e-6 * (1 - 1e-9);  // the SNR had to exceed 60 dB

  const TrueOutput y = true_output(base, effects, st, fft);
  n.transient_energy = y.transient_energy;
  n.ratio_combined = combined_ratio(st, y.Y, n.nu);
  n.input_var = draw_input_noise(d, st, n.nu);

  GapCase out;
  out.record = o.measured_noise ? noisy_record(dn, hv, n.nu, n.input_var, st, y.y, o.noise, o.measured_noise.get(),
                                               std::sqrt(n.nu / n.measured_scale), &n.measured_chosen)
                                : noisy_record(dn, hv, n.nu, n.input_var, st, y.y, o.noise);
  out.sim_model = realise(base);
  out.meta.period = st.P;
  out.meta.periods = st.M;
  out.meta.sample_time = 1.0;
  out.meta.excited_lines = st.excited;
  out.effects = o.effects;
  write_truth(o, base, st, hv, effects, n, out);
  return out;
}

}  // namespace fdsid
