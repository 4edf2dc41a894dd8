// fast/'s gap statistic (FFTW DFTs, LU transfer, double) against the 50-digit
// reference (direct DFT sums; reference/src/gap.cpp): t(k) on every excited
// line and the gap, for the model as given and for the effects the diagnosis
// fitted, rebuilt in 50 digits from their reported parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <numeric>
#include <random>

#include "fdsid/gap.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/gap.hpp"
#include "fdsid/simulate.hpp"
#include "gap_systems.hpp"
#include "reference_bridge.hpp"

namespace fdsid {
namespace {

using reference::Complex;
using reference::Real;
using testing::to_reference;

constexpr double kU = 0x1p-53;

struct Case {
  StateSpace truth;
  std::vector<Real> u, y;
  RecordMeta meta;
  Eigen::MatrixXd rec;
};

Case make(const StateSpace& truth, std::uint64_t seed) {
  Case c;
  c.truth = truth;
  RecordOptions o;
  o.period = 256;
  o.periods = 6;
  for (int k = 1; k < 60; k += 2) o.lines.push_back(k);
  o.output_noise_std = 0.02;
  o.seed = seed;
  c.rec = simulate_periodic_record(truth, o, c.meta);
  for (Eigen::Index i = 0; i < c.rec.rows(); ++i) {
    c.u.emplace_back(c.rec(i, 0));
    c.y.emplace_back(c.rec(i, 1));
  }
  return c;
}

// Tolerance on t(k): t = M|Ē|²/s², so δt/t ≤ 2 δĒ/|Ē| + δs²/s². Ē and the
// deviations E_l − Ē are sums of O(log2 P) rounded DFT terms and one product
// G U, each off by at most c u S with c = 4 (log2 P + n + 4) (FFT depth, the
// LU solve of order n for G, the subtraction) and S the size of the period's
// data: an FFT's rounding error is bounded norm-wise, |δY_l(k)| ≤ ‖δY_l‖₂ ≤
// c u ‖y_l‖₂ (unitary DFT), so S = (1 + max|G|) max_l ‖x_l‖₂ ≤ 10 √P max|x|
// (|G| ≤ 9 on these plants); hence δt/t ≤ c u S (2/|Ē| + 2/s), s = √s².
// Measured: the worst line at 6e-5 of this bound — the norm-wise FFT bound
// against a typical per-line error ≈ u √(log2 P) ‖x‖/√P, and c against ≈ 1.
// The reference is exact to 1e-45 in comparison.
double t_tolerance(const reference::LineStatistics& ref, std::size_t i, const Case& c, int n) {
  const double E = std::abs(ref.mean_residual[i]).convert_to<double>();
  const double s = sqrt(ref.variance[i]).convert_to<double>();
  const double t = ref.t[i].convert_to<double>();
  const double S = 10 * std::sqrt(c.meta.period) * c.rec.cwiseAbs().maxCoeff();  // |DFT| ≤ √P max|x|, × (1 + |G|≤9)
  const double cu = 4 * (std::log2(c.meta.period) + n + 4) * kU;
  return t * cu * S * (2 / E + 2 / s);
}

TEST(GapVsReference, ModelAsGivenSameTAtEveryExcitedLine) {
  const StateSpace g = pintelon_plant();
  StateSpace truth = g;
  truth.B *= 1.1;  // a gain error: t ranges from O(1) to O(10⁴) over the lines
  truth.D *= 1.1;
  const Case c = make(truth, 3);
  const GapReport fast = diagnose_gap(g, c.rec, 1, c.meta);
  const reference::GapStatistic ref =
      reference::gap_statistic(c.u, c.y, c.meta.period, c.meta.periods, c.meta.excited_lines, {}, to_reference(g),
                               Real(1));
  ASSERT_EQ(static_cast<std::size_t>(fast.t_before.size()), ref.excited.t.size());
  double worst = 0;
  for (std::size_t i = 0; i < ref.excited.t.size(); ++i) {
    const double tol = t_tolerance(ref.excited, i, c, g.order());
    const double err = std::abs(fast.t_before(i) - ref.excited.t[i].convert_to<double>());
    worst = std::max(worst, err / tol);
    EXPECT_LE(err, tol) << "line " << c.meta.excited_lines[i];
  }
  std::printf("  worst |t_fast - t_ref| / tolerance = %.3g\n", worst);
  // gap: a mean of the t's, so within the largest of their tolerances relative.
  double tol = 0;
  for (std::size_t i = 0; i < ref.excited.t.size(); ++i)
    tol = std::max(tol, t_tolerance(ref.excited, i, c, g.order()) / ref.excited.t[i].convert_to<double>());
  EXPECT_NEAR(fast.gap_before, ref.gap.convert_to<double>(), tol * ref.gap.convert_to<double>());
}

TEST(GapVsReference, FittedGainAndDelayGiveTheReportedGapAfter) {
  // The diagnosis reports the fitted parameter and the gap after it; the
  // reference, given the same parameter (rounded to double, as printed in the
  // JSON), must find the same gap: G'(k) = g G(k) and G'(k) = e^{−j2πkτ/P} G(k).
  const StateSpace g = pintelon_plant();
  for (int which = 0; which < 2; ++which) {
    StateSpace truth = g;
    if (which == 0) {
      truth.B *= 0.9;
      truth.D *= 0.9;
    } else {  // y(t) = y0(t - 1)
      truth = testing::one_sample_delay(g);
    }
    const Case c = make(truth, 4 + which);
    const GapReport fast = diagnose_gap(g, c.rec, 1, c.meta);
    const std::string effect = which == 0 ? "gain_error" : "delay";
    const EffectFit* fit = nullptr;
    for (const EffectFit& f : fast.candidates)
      if (to_string(f.effect()) == effect) fit = &f;
    ASSERT_NE(fit, nullptr);
    const reference::Model rm = to_reference(g);
    const Real par(which == 0 ? std::get<GainError>(fit->parameters).gain : std::get<Delay>(fit->parameters).samples);
    const int P = c.meta.period;
    auto response = [&](int k) {
      const Real w = 2 * boost::math::constants::pi<Real>() * k / P;
      const Complex G = reference::frequency_response(rm, w)(0, 0);
      if (which == 0) return Complex(par * G.real(), par * G.imag());
      return G * Complex(cos(w * par), -sin(w * par));
    };
    const reference::GapStatistic ref =
        reference::gap_statistic(c.u, c.y, P, c.meta.periods, c.meta.excited_lines, {}, response);
    // After the fit t(k) = O(1) and |Ē| is noise-sized: the same first-order
    // bound with |Ē| ≥ s/√M · 1e-3 would be loose; use the per-line bound.
    double tol = 0;
    for (std::size_t i = 0; i < ref.excited.t.size(); ++i)
      tol += t_tolerance(ref.excited, i, c, g.order() + 1);
    tol *= (c.meta.periods - 2.0) / (c.meta.periods - 1.0) / ref.excited.t.size();
    EXPECT_NEAR(fit->gap_after, ref.gap.convert_to<double>(), tol) << effect;
    EXPECT_LT(fit->gap_after, 2.0) << effect;
  }
}

// ---------------------------------------------------------------------------
// The period tests (gap.hpp: period_power_test, period_independence_test)
// against their 50-digit transcription (reference/gap.hpp), on residual
// matrices R × K built here: a periodic model error a(k) (the same in every
// period), noise of relative power ρ_m per period with a smooth shape, a
// smooth leakage term per period L_m/(1 − 0.9 e^{−j2πk/P}), and optionally
// noise correlated between adjacent periods (a drifting disturbance).
Eigen::MatrixXcd period_residuals(int R, int K, const std::vector<double>& power, double carry, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, std::sqrt(0.5));
  Eigen::MatrixXcd r(R, K);
  Eigen::VectorXcd prev = Eigen::VectorXcd::Zero(K);
  for (int m = 0; m < R; ++m) {
    const cplx L(n(rng), n(rng));
    Eigen::VectorXcd cur(K);
    for (int i = 0; i < K; ++i) {
      const double w = 2 * M_PI * (i + 5) / 1024.0;
      const cplx fresh = std::sqrt(power[static_cast<std::size_t>(m)]) * (1 + 0.5 * std::cos(3 * w)) * cplx(n(rng), n(rng));
      cur(i) = carry * prev(i) + std::sqrt(1 - carry * carry) * fresh;
      r(m, i) = 3.0 * std::polar(1.0, 0.1 * i) + cur(i) + 0.7 * L / (1.0 - 0.9 * std::polar(1.0, -w));
    }
    prev = cur;
  }
  return r;
}

std::vector<std::vector<Complex>> in_fifty_digits(const Eigen::MatrixXcd& r) {
  std::vector<std::vector<Complex>> out(static_cast<std::size_t>(r.rows()));
  for (Eigen::Index m = 0; m < r.rows(); ++m)
    for (Eigen::Index i = 0; i < r.cols(); ++i) out[static_cast<std::size_t>(m)].emplace_back(Real(r(m, i).real()), Real(r(m, i).imag()));
  return out;
}

// First-order rounding bounds of fast/'s double computation, per pair j of
// lines (the inputs are the same doubles, exact in 50 digits):
//  - e_m = r_m(2j) − r_m(2j+1), the mean over R and d_m = e_m − ē: each d_m off
//    by at most (R + 2) u E_j, E_j = max_m |e_m| (a subtraction, R additions, a
//    division, a subtraction); relative to ‖d‖: η_j = (R + 2) u E_j / ‖d‖, so
//    ‖δd‖ ≤ √R η_j ‖d‖ and Σ|d|² is off by ≤ 2√R η_j ‖d‖² + R u ‖d‖²;
//  - q_m = |d_m|²/Σ|d|² ≤ 1 off by a_j = (2 + 2√R) η_j + (2R + 4) u;
//  - c = Σ Re(d_m d̄_{m+1})/Σ|d|² (|c| ≤ 1) off by b_j = 4√R η_j + (3R + 4) u.
// The sums over the J' pairs add J' u (recursive summation of terms ≤ 1).
struct PairBounds {
  std::vector<double> a, b, q;  // a_j, b_j; q_m(j) (pair-major) to weigh them
};

PairBounds pair_bounds(const Eigen::MatrixXcd& r) {
  const Eigen::Index R = r.rows(), J = r.cols() / 2;
  const double Rd = static_cast<double>(R);
  PairBounds pb;
  for (Eigen::Index j = 0; j < J; ++j) {
    const Eigen::VectorXcd e = r.col(2 * j) - r.col(2 * j + 1);
    const Eigen::VectorXcd d = e.array() - e.mean();
    const double eta = (Rd + 2) * kU * e.cwiseAbs().maxCoeff() / d.norm();
    pb.a.push_back((2 + 2 * std::sqrt(Rd)) * eta + (2 * Rd + 4) * kU);
    pb.b.push_back(4 * std::sqrt(Rd) * eta + (3 * Rd + 4) * kU);
    for (Eigen::Index m = 0; m < R; ++m) pb.q.push_back(std::norm(d(m)) / d.squaredNorm());
  }
  return pb;
}

// S = J'(R − 1)/(vR) Σ_m (Q_m − 1/R)², from Q_m (each off by ΔQ = mean a_j + J' u)
// and v (relatively off by Δv/v = Σ_j Σ_m 2|q − 1/R| a_j / Σ (q − 1/R)² + (J'R + 2) u):
//   ΔS/S ≤ Δv/v + (Σ_m 2|Q_m − 1/R| ΔQ + R ΔQ²)/Σ_m (Q_m − 1/R)² + (R + 6) u,
// and p = P[χ²_{R−1} > S] off by pdf(S) ΔS plus Boost's own error of the
// double chi-squared complement, at most 100 u relative (its accuracy tables
// for gamma_q in double report peak errors of tens of u).
TEST(GapVsReference, PeriodTestsAgreeWithTheirFiftyDigitTranscription) {
  struct Setup {
    int R, K;
    std::vector<double> power;
    double carry;
  };
  const std::vector<Setup> setups = {
      {8, 400, std::vector<double>(8, 1.0), 0.0},                       // the null: p not small
      {4, 4096, {0.78, 1.41, 0.9, 1.1}, 0.0},                           // the F-16's R and J, unequal power
      {12, 100, {1, 1.2, 0.8, 1, 1, 1, 1.3, 0.7, 1, 1, 1, 1}, 0.0},      // many periods, few pairs
      {6, 1000, std::vector<double>(6, 1.0), 0.5},                      // adjacent periods alike
  };
  std::uint64_t seed = 11;
  for (const Setup& su : setups) {
    SCOPED_TRACE("R = " + std::to_string(su.R) + ", K = " + std::to_string(su.K));
    const Eigen::MatrixXcd r = period_residuals(su.R, su.K, su.power, su.carry, seed++);
    const auto rr = in_fifty_digits(r);
    const PairBounds pb = pair_bounds(r);
    const double Rd = su.R, J = static_cast<double>(pb.a.size());

    const PeriodPowerTest fast = period_power_test(r);
    const reference::PeriodPowerStatistic ref = reference::period_power_statistic(rr);
    ASSERT_TRUE(ref.tested);
    ASSERT_EQ(fast.relative.size(), ref.relative.size());
    const double dQ = std::accumulate(pb.a.begin(), pb.a.end(), 0.0) / J + J * kU;
    double num = 0, den = 0;
    for (std::size_t i = 0; i < pb.q.size(); ++i) {
      num += 2 * std::abs(pb.q[i] - 1 / Rd) * pb.a[i / static_cast<std::size_t>(su.R)];
      den += (pb.q[i] - 1 / Rd) * (pb.q[i] - 1 / Rd);
    }
    const double dv = num / den + (J * Rd + 2) * kU;
    double spread_err = 0, spread = 0;
    for (std::size_t m = 0; m < ref.relative.size(); ++m) {
      const double Qm = ref.relative[m].convert_to<double>() / Rd;
      EXPECT_NEAR(fast.relative[m], ref.relative[m].convert_to<double>(), Rd * dQ + 2 * kU) << "period " << m;
      spread_err += 2 * std::abs(Qm - 1 / Rd) * dQ + dQ * dQ;
      spread += (Qm - 1 / Rd) * (Qm - 1 / Rd);
    }
    const double S = ref.S.convert_to<double>(), dS = S * (dv + spread_err / spread + (Rd + 6) * kU);
    const double p = ref.p.convert_to<double>();
    const double tol_p = boost::math::pdf(boost::math::chi_squared(Rd - 1), S) * dS + 100 * kU * p;
    EXPECT_NEAR(fast.p, p, tol_p) << "S = " << S;
    std::printf("  R %d, J %.0f: S %.6g, p %.3g; |p_fast - p_ref| = %.2g of tolerance %.2g\n", su.R, J, S, p,
                std::abs(fast.p - p), tol_p);

    const PeriodIndependenceTest fi = period_independence_test(r, fast.relative);
    const reference::PeriodCorrelation rc = reference::period_lag_correlation(rr);
    ASSERT_TRUE(rc.tested);
    const double db = std::accumulate(pb.b.begin(), pb.b.end(), 0.0) / J + (J + 1) * kU;
    EXPECT_NEAR(fi.correlation, rc.mean.convert_to<double>(), db);
    // With equal powers fast/'s Monte Carlo null mean (4000 draws, a fixed
    // seed) is −1/(R − 1) (reference/gap.hpp derives it) within 4.5 of its
    // standard error √(Var c / 4000) (two-sided 4.5 σ: 7e-6); the pairs here,
    // independent periods of equal power, estimate the same Var c.
    if (su.carry == 0 && std::all_of(su.power.begin(), su.power.end(), [](double x) { return x == 1.0; })) {
      EXPECT_NEAR(fi.expected, -1 / (Rd - 1), 4.5 * std::sqrt(rc.variance.convert_to<double>() / 4000));
    }
    if (su.carry > 0) {
      EXPECT_LT(fi.p, 1e-6);  // alike periods are what the test is for
    }
  }
}

}  // namespace
}  // namespace fdsid
