// Sim-to-real gap diagnosis (fdsid/gap.hpp) on records whose truth is built
// here, one effect at a time, from the Eq. (36) plant of Pintelon (2002):
// the noise floor's law (the gap is 1 in expectation for a right model and
// false alarms stay near the stated levels), each effect found and its
// parameter recovered, and the failure paths. Monte Carlo limits are stated
// beside each check.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <functional>
#include <random>

#include "fdsid/error.hpp"
#include "fdsid/gap.hpp"
#include "fdsid/format.hpp"
#include "fdsid/gap_cases.hpp"
#include "fdsid/model.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/simulate.hpp"
#include "gap_systems.hpp"
#include "numerics/fft.hpp"

namespace fdsid {
namespace {

constexpr int kP = 512, kM = 8;

std::vector<std::string> names(const std::vector<Effect>& effects) {
  std::vector<std::string> n;
  for (Effect e : effects) n.emplace_back(to_string(e));
  return n;
}
bool has(const GapReport& r, const std::string& e) { return std::find(r.present.begin(), r.present.end(), effect_from_string(e)) != r.present.end(); }
double param(const GapReport& r, const std::string& e, const std::string& name) {
  for (const EffectFit& f : r.chosen)
    if (f.effect() == effect_from_string(e))
      for (const auto& kv : parameter_list(f.parameters))
        if (kv.first == name) return kv.second;
  return NAN;
}
std::string verdict(const GapReport& r) {
  std::string s = "gap " + std::to_string(r.gap_before) + " -> " + std::to_string(r.gap_after) + ", present [";
  for (Effect e : r.present) s += std::string(to_string(e)) + " ";
  s += "], p_gap " + std::to_string(r.p_gap) + ", p_nl " + std::to_string(r.p_nonlinearity) + ", p_leak " +
       std::to_string(r.p_leakage) + "; candidates:";
  for (const auto& c : r.candidates) s += " " + std::string(to_string(c.effect())) + "=" + std::to_string(c.gap_after);
  return s;
}

// Odd lines 1 … 99 except every fourth (random-odd-like, fixed), P = 512.
std::vector<int> lines() {
  std::vector<int> l;
  for (int k = 1; k < 100; k += 2)
    if (k % 8 != 7) l.push_back(k);
  return l;
}

RecordOptions options(std::uint64_t seed, double noise = 0.01) {
  RecordOptions o;
  o.period = kP;
  o.periods = kM;
  o.lines = lines();
  o.rms = 1.0;
  o.output_noise_std = noise;
  o.seed = seed;
  return o;
}

// The record with y(t) replaced by f(u(t), y(t)) plus white noise of std 0.01
// (sample by sample, in time order).
Eigen::MatrixXd with_output(Eigen::MatrixXd rec, std::uint64_t seed, const std::function<double(double, double)>& f) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (Eigen::Index i = 0; i < rec.rows(); ++i) rec(i, 1) = f(rec(i, 0), rec(i, 1)) + noise(gen);
  return rec;
}

// The plant plus a parallel resonance at `f` cycles/sample, damping ratio 0.02.
StateSpace with_mode(const StateSpace& g, double f, double gain) {
  const double th = 2 * M_PI * f, rho = std::exp(-0.02 * th);
  const int n = g.order();
  StateSpace d = g;
  d.A = Eigen::MatrixXd::Zero(n + 2, n + 2);
  d.A.topLeftCorner(n, n) = g.A;
  d.A.block(n, n, 2, 2) << rho * std::cos(th), rho * std::sin(th), -rho * std::sin(th), rho * std::cos(th);
  d.B.resize(n + 2, 1);
  d.B << g.B, gain, 0;
  d.C.resize(1, n + 2);
  d.C << g.C, 0, 1;
  return d;
}

TEST(GapStatistic, F2SurvivalIsBoostsFisherF) {
  // Closed form (1 + 2t/d2)^(-d2/2) against Boost's incomplete-beta evaluation;
  // both are accurate to a few ulps times |ln p| (the exp of a log), so 1e-12
  // relative is ≥ 100× their combined rounding at these arguments.
  for (int d2 : {6, 14, 30, 200})
    for (double t : {0.01, 0.5, 1.0, 3.0, 20.0}) {
      const double b = boost::math::cdf(boost::math::complement(boost::math::fisher_f(2, d2), t));
      EXPECT_NEAR(f2_survival(t, d2), b, 1e-12 * b) << "d2 = " << d2 << ", t = " << t;
    }
}

// The null moments behind the relevance rule (issue 17: a mutant d/(d+2) of the
// F mean passed the quick suite). Boost's F(2, d) mean and variance are an
// independent statement of the formulas; a Monte Carlo of the gap itself
// (mean of K variates t = (chi2_2 / 2) / (chi2_d / d), times (M-2)/(M-1), the
// gap's definition in gap.hpp) checks mean 1 and the standard deviation:
// R = 20000 replicates, M >= 6 so that F(2, d) has a finite fourth moment
// (d > 8) and the sample standard deviation its usual error ~ sd / sqrt(2R)
// (0.5 %, the mean of K = 50 lines being close to Gaussian); 5 % is 10 of those.
TEST(GapStatistic, NullMomentsOfTheGap) {
  constexpr int K = 50, R = 20000;
  for (int M : {4, 6, 10}) {
    const int d = 2 * M - 2;
    const boost::math::fisher_f f(2, d);
    EXPECT_NEAR(gap_null_sd(M, K),
                std::sqrt(boost::math::variance(f)) / boost::math::mean(f) / std::sqrt(double(K)),
                1e-12 * gap_null_sd(M, K))
        << "M = " << M;
    if (M < 6) continue;
    std::mt19937_64 rng(M);
    std::exponential_distribution<double> e(1.0);
    std::chi_squared_distribution<double> chi(d);
    double sum = 0, sum2 = 0;
    for (int rep = 0; rep < R; ++rep) {
      double t = 0;
      for (int k = 0; k < K; ++k) t += e(rng) / (chi(rng) / d);
      const double gap = (M - 2.0) / (M - 1.0) * t / K;
      sum += gap;
      sum2 += gap * gap;
    }
    const double mean = sum / R, sd = std::sqrt((sum2 - R * mean * mean) / (R - 1));
    EXPECT_NEAR(mean, 1.0, 5 * gap_null_sd(M, K) / std::sqrt(double(R))) << "M = " << M;
    EXPECT_NEAR(sd / gap_null_sd(M, K), 1.0, 0.05) << "M = " << M;
  }
}

TEST(GapStatistic, RightModelGivesGapOneAndFewFalseAlarms) {
  // H0: the plant itself, white output noise, exact steady state. Per record
  // gap = mean of K = 38 lines of F(2, 14)/μ: sd = sqrt(var F / μ² / K) with
  // var F(2,14) = 14³/(12²·10) = 1.906, μ = 14/12, so sd = 0.19 and the mean
  // of 60 records has sd 0.024: |mean − 1| < 0.1 is a 4-sd limit. Verdicts:
  // three tests at α = 0.01 give P(false alarm) ≤ 0.03; P(Bin(60, 0.03) ≥ 8)
  // = 4e-4, so at most 7 false alarms.
  const StateSpace g = pintelon_plant();
  double sum = 0;
  int alarms = 0;
  const int runs = 60;
  for (int i = 0; i < runs; ++i) {
    RecordMeta meta;
    const Eigen::MatrixXd rec = simulate_periodic_record(g, options(1000 + i), meta);
    const GapReport r = diagnose_gap(g, rec, 1, meta);
    sum += r.gap_before;
    if (!r.present.empty()) {
      ++alarms;
      std::printf("  false alarm: %s\n", verdict(r).c_str());
    }
    EXPECT_EQ(r.periods_used, kM);
  }
  EXPECT_NEAR(sum / runs, 1.0, 0.1);
  EXPECT_LE(alarms, 7);
}

TEST(GapDiagnosis, GainError) {
  const StateSpace g = pintelon_plant();
  StateSpace t = g;
  t.B *= 1.2;
  t.D *= 1.2;
  RecordMeta meta;
  const Eigen::MatrixXd rec = simulate_periodic_record(t, options(7), meta);
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"gain_error"});
  // The stages the figure draws: the model as given, then the gain added.
  ASSERT_EQ(r.steps.size(), 2u);
  EXPECT_EQ(r.steps[0].first, "model");
  EXPECT_EQ(r.steps[1].first, "+ gain_error");
  EXPECT_EQ(r.steps[0].second, r.t_before);
  EXPECT_EQ(r.steps[1].second, r.t_after);
  // Noise 0.01 against |Y| ≈ 0.1 … 5 on 38 lines, 8 periods: the weighted LS
  // gain has relative sd below 1e-3; 0.01 is ≥ 10 sd.
  EXPECT_NEAR(param(r, "gain_error", "gain"), 1.2, 0.01);
  EXPECT_LT(r.gap_after, 2.0);
  EXPECT_GT(r.gap_before, 100.0);
}

TEST(GapDiagnosis, OneSampleDelay) {
  const StateSpace g = pintelon_plant();
  RecordMeta meta;
  const Eigen::MatrixXd rec = simulate_periodic_record(testing::one_sample_delay(g), options(8), meta);
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"delay"});
  EXPECT_NEAR(param(r, "delay", "samples"), 1.0, 0.01);  // same sd argument as the gain: phase sd < 1e-3 rad
  EXPECT_LT(r.gap_after, 2.0);
}

TEST(GapDiagnosis, UnmodelledModeAndItsBand) {
  const StateSpace g = pintelon_plant();
  const double f = 61.0 / kP;  // between the excited lines 59 and 61's neighbourhood
  RecordMeta meta;
  const Eigen::MatrixXd rec = simulate_periodic_record(with_mode(g, f, 0.05), options(9), meta);
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"unmodelled_mode"});
  // The mode's frequency to within one line spacing 1/P.
  EXPECT_NEAR(param(r, "unmodelled_mode", "frequency_hz"), f, 1.0 / kP);
  ASSERT_FALSE(r.bands.empty());
  bool hit = false;
  for (const auto& b : r.bands) hit = hit || (b[0] <= f + 2.0 / kP && b[1] >= f - 2.0 / kP);
  EXPECT_TRUE(hit);
  EXPECT_LT(r.gap_after, 2.0);
}

TEST(GapDiagnosis, CubicOutputNonlinearitySeenOnUnexcitedLines) {
  const StateSpace g = pintelon_plant();
  RecordMeta meta;
  const Eigen::MatrixXd rec = with_output(simulate_periodic_record(g, options(10, 0.0), meta), 10,
                                          [](double, double y) { return y + 0.02 * y * y * y; });
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_TRUE(has(r, "nonlinearity"));
  EXPECT_LT(r.p_nonlinearity, 1e-6);
  EXPECT_NEAR(param(r, "nonlinearity", "a3"), 0.02, 0.002);
  EXPECT_LT(r.gap_after, 2.0);
}

// Issue 17, item 3(b): the best-linear-approximation view. A static cubic at
// the output, y = x + a₃x³ with x the plant's response to the random-odd
// multisine (38 lines, close to Gaussian), and as the model the plant's best
// linear approximation G_BLA = (1 + 3a₃σ_x²) G (Bussgang's theorem for a
// Gaussian x): the gap is the stochastic distortion alone, the odd detection
// lines (7, 15, …: 12 of them) see it at the same level, and the report says
// the model is right as a BLA. The plant itself (G) as the model: the excited
// lines carry more than the distortion (the BLA's gain change), so it does not.
TEST(GapDiagnosis, DistortionAroundTheBestLinearApproximation) {
  const StateSpace g = pintelon_plant();
  const std::uint64_t seed = 13;
  RecordMeta meta;
  const Eigen::MatrixXd lin = simulate_periodic_record(g, options(seed, 0.0), meta);
  const double a3 = 0.05;
  const Eigen::VectorXd x = lin.col(1).head(kP);
  const double var_x = (x.array() - x.mean()).square().mean();
  const Eigen::MatrixXd rec = with_output(lin, seed, [&](double, double y) { return y + a3 * y * y * y; });
  StateSpace bla = g;
  bla.C *= 1 + 3 * a3 * var_x;
  bla.D *= 1 + 3 * a3 * var_x;
  const GapReport r = diagnose_gap(bla, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  const GapDistortion& d = r.distortion;
  EXPECT_TRUE(d.estimable);
  EXPECT_TRUE(d.odd_only);
  EXPECT_EQ(d.lines, 12);
  EXPECT_LT(r.p_gap, r.options.alpha);
  EXPECT_LT(d.p_detected, r.options.alpha);
  EXPECT_TRUE(d.bla_right);
  // A Monte Carlo over 40 seeds (100 … 139) of this case: share median 1.00,
  // range 0.25 … 2.01 (12 detection lines predict the level of 38 excited
  // ones). Limits: the share within 0.2 … 2.5, beyond every value seen;
  // level_db = 10 log10(gap − 1) exactly. p_beyond over 300 seeds (100 …
  // 399): the BLA rejected at alpha = 0.01 in 10 (3.3 %, Monte Carlo null of
  // the statistic; the normal approximation it replaced rejected 26, 8.7 %),
  // the plant in 223 (74 %; 276 before). Still above 1 %: the Bussgang gain
  // of a Gaussian is not this 38-line realisation's best linear fit, and the
  // distortion level is not the same at every line.
  EXPECT_GT(d.share, 0.2);
  EXPECT_LT(d.share, 2.5);
  ASSERT_TRUE(d.level_db.has_value());
  EXPECT_NEAR(*d.level_db, 10 * std::log10(d.gap - 1), 1e-12 * std::abs(*d.level_db));
  const GapReport r2 = diagnose_gap(g, rec, 1, meta);
  EXPECT_LT(r2.distortion.p_beyond, r2.options.alpha);
  EXPECT_FALSE(r2.distortion.bla_right);
  // 50 lines: the Monte Carlo null (2000 draws), whose p is never below 1/2001.
  EXPECT_DOUBLE_EQ(r2.distortion.p_beyond_min, 1.0 / 2001);
  EXPECT_GE(r2.distortion.p_beyond, r2.distortion.p_beyond_min);
  // The detection lines do not see the gain: no input power there (the
  // multisine's DFT at an unexcited line is rounding, ≲ P u ≈ 1e-13 of an
  // excited line's), so the same gap there up to that rounding; 1e-9 relative.
  EXPECT_NEAR(r2.distortion.gap, d.gap, 1e-9 * d.gap);
}

// Issue 17, item 3(a): a cubic spring fed back through a lightly damped
// structure (Duffing type): x(t+1) = A x + B (u − k₃ y³), y = C x, D = 0, in
// periodic steady state, the measured y with white noise of std 0.01 (about
// 3 % of its rms, 0.33). The model is the linear structure itself. The level-
// dependent resonance shift and the distortion on the unexcited lines are
// one effect: the in-loop polynomial, alone — no mode_mismatch or
// unmodelled_mode beside it — and what remains is noise.
TEST(GapDiagnosis, CubicFeedbackThroughTheStructureIsOneInLoopNonlinearity) {
  StateSpace g;
  g.domain = Domain::Discrete;
  g.sample_time = 1;
  const double th = 2 * M_PI * 0.05, rho = std::exp(-0.05 * th);  // 0.05 cycles/sample, damping ratio 0.05
  g.A.resize(2, 2);
  g.A << rho * std::cos(th), rho * std::sin(th), -rho * std::sin(th), rho * std::cos(th);
  g.B = Eigen::Vector2d(0.05, 0);
  g.C = Eigen::RowVector2d(0, 1);
  g.D = Eigen::MatrixXd::Zero(1, 1);
  const double k3 = 0.5;
  RecordMeta meta;
  const Eigen::MatrixXd lin = simulate_periodic_record(g, options(12, 0.0), meta);
  // Steady state: 40 periods of the (periodic) input first; the slowest decay
  // of the linear part is rho^P = e^{-0.05·2π·0.05·512} ≈ 3e-4 per period.
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  auto step = [&](double u) {
    const double y = (g.C * x)(0);
    x = g.A * x + g.B * (u - k3 * y * y * y);
    return y;
  };
  for (int rep = 0; rep < 40; ++rep)
    for (int t = 0; t < kP; ++t) step(lin(t, 0));
  const Eigen::MatrixXd rec = with_output(lin, 12, [&](double u, double) { return step(u); });
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"nonlinearity"});
  EXPECT_EQ(param(r, "nonlinearity", "in_loop"), 1.0);
  EXPECT_LT(r.p_nonlinearity, r.options.alpha);
  EXPECT_EQ(to_string(r.verdict), std::string("explained"));
  EXPECT_LT(r.gap_after, 2.0);
  // The coefficients against the truth (a₁ = a₂ = 0, a₃ = k₃): a Monte Carlo
  // over 30 seeds (100 … 129) of this very case gave a₃ mean 0.5005, sd
  // 0.0084 and a₁ mean −0.0002, sd 0.0021 (no visible bias from the noise in
  // the fed-back output); limits 5 sd (0.042, 0.011): a false failure below
  // 1e-6 for a normal estimate, leaving room for the sd's own ~13 % sampling
  // error. The same runs: every one chose the in-loop nonlinearity alone,
  // gap_after ≤ 1.66; one of 30 read "unexplained" (what remained failed the
  // gap test at 0.01: the test's level).
  EXPECT_NEAR(param(r, "nonlinearity", "a3"), k3, 0.042);
  EXPECT_NEAR(param(r, "nonlinearity", "a1"), 0.0, 0.011);
}

// The plant g driven from rest by the record of `o` (seed 11, output noise
// 0.01), its output scaled by `gain`: the first period carries the transient
// (the Eq. (36) plant's poles have modulus ≤ 0.954: 0.954^512 ≈ 4e-11 of it
// is left after one period).
GapReport diagnose_from_rest(const StateSpace& g, const RecordOptions& o, double gain = 1.0) {
  RecordMeta meta;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(g.order());
  const Eigen::MatrixXd rec = with_output(simulate_periodic_record(g, o, meta), 11, [&](double u, double) {
    const double y = (g.C * x)(0) + g.D(0, 0) * u;
    x = g.A * x + g.B.col(0) * u;
    return gain * y;
  });
  return diagnose_gap(g, rec, 1, meta);
}

TEST(GapDiagnosis, TransientFromRestIsLeakage) {
  const GapReport r = diagnose_from_rest(pintelon_plant(), options(11, 0.0));
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"leakage"});
  EXPECT_LT(r.p_leakage, 1e-6);
  EXPECT_LT(r.periods_used, kM);
  EXPECT_LT(r.gap_after, 2.0);
}

// The same transient in a 4-period record (the F-16's measured-noise cases
// have M = 4): its one transient period is dropped and 3 are kept, the
// selection's noise bound then from the F(2, 4) law by Monte Carlo
// (gap_noise_bound in gap.cpp). Until stop 43 no period of a 4-period record
// could go (at least 4 were kept) and leakage was never admitted there.
TEST(GapDiagnosis, TransientInAFourPeriodRecordIsLeakage) {
  RecordOptions o = options(11, 0.0);
  o.periods = 4;
  const GapReport r = diagnose_from_rest(pintelon_plant(), o);
  SCOPED_TRACE(verdict(r));
  EXPECT_LT(r.p_leakage, r.options.effect_alpha);
  EXPECT_EQ(names(r.present), std::vector<std::string>{"leakage"});
  EXPECT_EQ(r.periods_used, 3);
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
}

// A proven transient leads the selection (issue 17; the circuit's record,
// README "Real data"): the plant driven from rest (as TransientFromRestIsLeakage)
// with a 0.1 % gain error at the sensor. On all 8 periods the transient's
// period-to-period scatter is most of the noise floor and hides the gain: the
// gap test does not reject there (measured: gap 1.06, p 0.26). On the steady-
// state periods the model as given leaves gap 2.45 (gap_model_used). The
// report drops the transient first (step 1: leakage, admitted by its test
// alone: the gap rises), then finds the gain there, and says so in a note;
// the share it explains is judged against the larger, steady-state gap.
// Before (leakage tried like any effect) it was refused at stage 1: its gap
// rose beyond the 3 null sd bound (0.53 here).
TEST(GapDiagnosis, AProvenTransientLeadsAndUncoversTheGainItHid) {
  const GapReport r = diagnose_from_rest(pintelon_plant(), options(11, 0.0), 1.001);
  SCOPED_TRACE(verdict(r));
  ASSERT_FALSE(r.path.empty());
  EXPECT_EQ(r.path.front().added, Effect::Leakage);
  EXPECT_LT(r.p_leakage, r.options.effect_alpha);
  EXPECT_EQ(names(r.present), (std::vector<std::string>{"gain_error", "leakage"}));
  // The gain's sd: its excess gap 2.45 − 1 on K = 44 lines is a noncentrality
  // of ≈ 1.45 · 2K ≈ 128 for one parameter, z ≈ 11, sd ≈ 1e-3 / 11 ≈ 9e-5;
  // allowed 3.3 sd.
  EXPECT_NEAR(param(r, "gain_error", "gain"), 1.001, 3e-4);
  EXPECT_LT(r.periods_used, kM);
  // What the transient hid: the steady-state gap is above the all-period one
  // by more than 3 null sd of either.
  EXPECT_GT(r.gap_model_used, r.gap_before + 3 * gap_null_sd(r.periods_used, r.excited));
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
  EXPECT_GT(r.explained_share, 0.0);
  EXPECT_LE(r.explained_share, 1.0 + 3 * gap_null_sd(r.periods_used, r.excited) / (r.gap_model_used - 1));
  EXPECT_TRUE(std::any_of(r.notes.begin(), r.notes.end(),
                          [](const std::string& n) { return n.rfind("leakage: the first", 0) == 0; }));
}

// A continuous-time record (Ts = 0.01 s) of a two-mode structure
// (1/(s² + 2ζω s + ω²) at 3 and 11 Hz, ζ = 0.03 and 0.05), in steady state
// (the multisine's exact response, no hold), plus white output noise whose
// power changes from period to period by the factors `power` (real measured
// noise, e.g. the F-16's, varies so by 30–50 %), plus `transient(t)`.
struct ContinuousRecord {
  StateSpace model;
  RecordMeta meta;
  Eigen::MatrixXd record;
};
ContinuousRecord continuous_record(std::uint64_t seed, const std::vector<double>& power,
                                   const std::function<double(double)>& transient) {
  ContinuousRecord c;
  StateSpace& g = c.model;
  g.domain = Domain::Continuous;
  g.sample_time = 0;
  g.A = Eigen::MatrixXd::Zero(4, 4);
  const double w1 = 2 * M_PI * 3, w2 = 2 * M_PI * 11;
  g.A.block(0, 0, 2, 2) << 0, 1, -w1 * w1, -2 * 0.03 * w1;
  g.A.block(2, 2, 2, 2) << 0, 1, -w2 * w2, -2 * 0.05 * w2;
  g.B = Eigen::Vector4d(0, w1 * w1, 0, w2 * w2);
  g.C = Eigen::RowVector4d(1, 0, 1, 0);
  g.D = Eigen::MatrixXd::Zero(1, 1);
  const int M = static_cast<int>(power.size());
  c.meta = {kP, M, 0.01, lines()};
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> phase(0, 2 * M_PI);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(kP), y = Eigen::VectorXd::Zero(kP);
  for (int k : c.meta.excited_lines) {
    const double ph = phase(gen), wt = 2 * M_PI * k / kP;
    const cplx G = transfer(g, cplx(0, 2 * M_PI * k / (kP * c.meta.sample_time)))(0, 0);
    for (int t = 0; t < kP; ++t) {
      u(t) += 0.2 * std::cos(wt * t + ph);
      y(t) += 0.2 * std::abs(G) * std::cos(wt * t + ph + std::arg(G));
    }
  }
  c.record.resize(static_cast<Eigen::Index>(kP) * M, 2);
  for (int l = 0; l < M; ++l)
    for (int t = 0; t < kP; ++t) {
      const Eigen::Index i = static_cast<Eigen::Index>(l) * kP + t;
      c.record(i, 0) = u(t);
      c.record(i, 1) = y(t) + std::sqrt(power[l]) * noise(gen) + transient(i * c.meta.sample_time);
    }
  return c;
}

// Issue 17: real noise is not stationary. With no effect at all and the
// noise power of the periods varying by up to 60 % (the first period the
// loudest, as a transient would make it), the leakage test must hold its
// level: it asks whether period 1's deviation has the shape of a free response
// of the model (the continuous model's free response sampled, e^{A Ts} per
// sample), not whether it is large. 40 records at alpha = 0.01: under the null
// the false alarms are Binomial(40, ≤ 0.01), P(≥ 3) = 0.0075; the test allows
// 2 (measured: 0 until stop 42; since, 1 — seed 38 at p 2.9e-3, not admitted,
// leakage enters at effect_alpha). Before, a continuous model's leakage test combined the
// per-line period deviations (a test of their size) and reported leakage on
// every one of the first 12 at p < 1e-6.
// The positive control: a decaying free response of the 3 Hz mode in the
// first period (from amplitude 0.3, 1/e after 0.9 s) is found.
TEST(GapDiagnosis, NonStationaryNoiseIsNoLeakageButATransientIs) {
  const std::vector<double> power = {1.6, 0.8, 1.0, 0.9, 1.2, 0.85, 1.1, 0.95};
  int alarms = 0;
  std::string list;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const ContinuousRecord c = continuous_record(seed, power, [](double) { return 0.0; });
    const GapReport r = diagnose_gap(c.model, c.record, 1, c.meta);
    if (r.p_leakage < r.options.alpha || has(r, "leakage")) {
      ++alarms;
      list += "\nseed " + std::to_string(seed) + ": " + verdict(r);
    }
  }
  EXPECT_LE(alarms, 2) << list;
  const double sigma = 2 * M_PI * 3 * 0.03 * 6, wd = 2 * M_PI * 3;  // ζω stretched 6×: a visibly decaying term
  const ContinuousRecord c =
      continuous_record(99, power, [&](double t) { return 0.3 * std::exp(-sigma * t) * std::cos(wd * t); });
  const GapReport r = diagnose_gap(c.model, c.record, 1, c.meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_LT(r.p_leakage, r.options.alpha);
  EXPECT_TRUE(has(r, "leakage"));
}

// Issue 17: periods that drift. A disturbance shaped like the structure's
// response (amplitude ∝ 1 + |G| on every line 1 … P/2, rms 0.03, three times
// the white noise's) at frequencies 0.02–0.06 of a line above the grid: its
// phase turns by 0.13–0.38 rad per period, so adjacent periods are alike (the
// F-16's records: lag-1 correlation of the period deviations 0.21 against
// −0.16 for independent periods; every record here gets the report's note)
// and, across 8 periods, it is close to a trend, whose extreme is the first
// period. The transient test (Diagnosis::leakage_p) assumes independent
// reference periods, but it tests the shape of the first period's deviation
// (a free response of the model after whitening), not its size, so the drift
// must not read as a transient: 20 records at alpha = 0.01, false alarms
// Binomial(20, ≤ 0.01), P(≥ 3) = 0.001; allowed 2. Measured: none; a size
// test in its place (period_deviation_p, as a continuous model had until
// stop 42) alarms on all 20. The positive control: the same drift plus a
// decaying 3 Hz free response (NonStationaryNoiseIsNoLeakageButATransientIs',
// amplitude 1 instead of 0.3: the drift's power at the 3 Hz mode, 1/(2ζ) =
// 17 times its floor, enters the references too and hides the weaker one,
// p 0.017) is found at effect_alpha.
TEST(GapDiagnosis, DriftingPeriodsAreNoLeakageButATransientIs) {
  const std::vector<double> power(kM, 1.0);
  const auto drift = [](std::uint64_t seed, const StateSpace& g) {
    std::mt19937_64 gen(seed);
    std::uniform_real_distribution<double> phase(0, 2 * M_PI), offset(0.02, 0.06);
    const double Ts = 0.01;
    std::vector<std::array<double, 3>> terms;  // amplitude, frequency (Hz), phase
    double power_sum = 0;
    for (int k = 1; k < kP / 2; ++k) {
      const double a = 1 + std::abs(transfer(g, cplx(0, 2 * M_PI * k / (kP * Ts)))(0, 0));
      terms.push_back({a, (k + offset(gen)) / (kP * Ts), phase(gen)});
      power_sum += a * a / 2;
    }
    for (auto& t : terms) t[0] *= 0.03 / std::sqrt(power_sum);
    return [terms](double t) {
      double v = 0;
      for (const auto& x : terms) v += x[0] * std::cos(2 * M_PI * x[1] * t + x[2]);
      return v;
    };
  };
  const StateSpace g = continuous_record(1, power, [](double) { return 0.0; }).model;
  int alarms = 0, dependent = 0;
  std::string list;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ContinuousRecord c = continuous_record(seed, power, drift(seed, g));
    const GapReport r = diagnose_gap(c.model, c.record, 1, c.meta);
    dependent += r.periods_dependent();
    if (r.p_leakage < r.options.alpha || has(r, "leakage")) {
      ++alarms;
      list += "\nseed " + std::to_string(seed) + ": p(leakage) " + std::to_string(r.p_leakage) + "; " + verdict(r);
    }
  }
  EXPECT_EQ(dependent, 20);  // the drift is there: the reports say the periods are alike
  EXPECT_LE(alarms, 2) << list;
  const double sigma = 2 * M_PI * 3 * 0.03 * 6, wd = 2 * M_PI * 3;
  const auto d = drift(99, g);
  const ContinuousRecord c =
      continuous_record(99, power, [&](double t) { return d(t) + 1.0 * std::exp(-sigma * t) * std::cos(wd * t); });
  const GapReport r = diagnose_gap(c.model, c.record, 1, c.meta);
  SCOPED_TRACE(verdict(r));
  EXPECT_LT(r.p_leakage, r.options.effect_alpha);
  EXPECT_TRUE(has(r, "leakage"));
}

// Issue 17: the verdict follows the numbers, and the chosen set never leaves
// more than an effect admitted alone. Cases from the blind generator
// (gap_cases.hpp): subtle and clear gain errors at M = 4 (the issue's
// counterexample: a 1.9 % gain error, M = 4, answered with a pair whose joint
// gap was 10.7 where the gain alone left 0.87), subtle pairs, effect-free
// records. Checked on every case, whatever its truth:
//  - "explained" only with effects present and what remains passing the gap
//    test at alpha; "no_gap" only with nothing present and the gap test
//    passing; otherwise "unexplained";
//  - gap_after <= the gap left by any linear effect that its own tests admit
//    alone (F-test at effect_alpha and the relevance rule, read off the
//    candidates) + 3 null sd of the gap (gap_null_sd): the selection's stated
//    slack for a cheaper effect chosen on a near-tie (gap.hpp);
//  - the path ends at gap_after, one stage per present effect.
TEST(GapDiagnosis, VerdictFollowsTheNumbersAndNeverWorseThanTheBestSingle) {
  struct Spec {
    std::vector<Effect> effects;
    Strength strength;
    int periods;
  };
  const std::vector<Spec> specs = {
      {{Effect::GainError}, Strength::Subtle, 4},     {{Effect::GainError}, Strength::Clear, 4},
      {{Effect::GainError, Effect::Delay}, Strength::Subtle, 8},
      {{Effect::SensorDynamics, Effect::ModeMismatch}, Strength::Subtle, 8},
      {{Effect::UnmodelledMode, Effect::Nonlinearity}, Strength::Clear, 8}, {{}, Strength::None, 4},
      {{}, Strength::None, 8}};
  int explained = 0;
  for (size_t i = 0; i < specs.size(); ++i)
    for (std::uint64_t seed : {1u, 2u}) {
      GapCaseOptions o;
      o.effects = specs[i].effects;
      o.strength = specs[i].strength;
      o.periods = specs[i].periods;
      o.period = 512;
      o.seed = 100 * i + seed;
      const GapCase c = make_gap_case(o);
      const GapReport r = diagnose_gap(c.sim_model, c.record, 1, c.meta);
      SCOPED_TRACE("spec " + std::to_string(i) + ", seed " + std::to_string(o.seed) + ": " + verdict(r));
      const double alpha = r.options.alpha;
      switch (r.verdict) {
        case GapVerdict::NoGap:
          EXPECT_TRUE(r.present.empty());
          EXPECT_GE(r.p_gap, alpha);
          break;
        case GapVerdict::Explained:
          ++explained;
          EXPECT_FALSE(r.present.empty());
          EXPECT_GE(r.p_after, alpha);
          break;
        case GapVerdict::Unexplained:
          EXPECT_LT(r.present.empty() ? r.p_gap : r.p_after, alpha);
          break;
      }
      const double floor = 3 * gap_null_sd(r.periods_used, r.excited);
      for (const EffectFit& f : r.candidates) {
        const bool admitted = is_linear(f.effect()) && f.p_value < r.options.effect_alpha &&
                              r.gap_before - f.gap_after >= r.options.min_share * std::max(r.gap_before - 1, floor);
        if (admitted) {
          EXPECT_LE(r.gap_after, f.gap_after + floor) << to_string(f.effect());
        }
      }
      ASSERT_EQ(r.path.size(), r.present.size());
      if (!r.path.empty()) {
        EXPECT_DOUBLE_EQ(r.path.back().gap_after, r.gap_after);
      }
    }
  EXPECT_GT(explained, 0);  // the checks above met the "explained" branch at least once
}

// Blind cases of gap-validate's classic schedule, or with `structure` of its
// structure family (P = 1024, M = 8; the seeds
// are the cases' own, `gap-validate --seed S` case i has seed S·1000003 + i)
// that were named wrongly before the changes each names; every one is
// identifiable at its noise level (the truth's own fit reaches gap ≈ 1 and the
// confusion's does not, or costs more parameters than it saves).
GapReport diagnose_case(std::vector<Effect> effects, Strength strength, std::uint64_t seed, bool structure = false) {
  GapCaseOptions o;
  o.effects = std::move(effects);
  o.strength = strength;
  o.seed = seed;
  o.structure = structure;
  const GapCase c = make_gap_case(o);
  return diagnose_gap(c.sim_model, c.record, 1, c.meta);
}

// Issue 17: subtle transients in coloured noise. gap-validate classic seed 2,
// cases 15 and 75 (subtle leakage, ratios 0.52 and 0.95 of the noise floor;
// noise filters with poles of modulus 0.87 and 0.88): the frequency-domain
// test (until stop 42) gave p 0.012 and 0.37 — the noise filter's own leakage
// term, fitted by the model's transient basis, inflated the later periods' F
// 3 and 14 times — and both were read as no effect. Whitened in time
// (Diagnosis::leakage_p) they are found at p < 1e-10; the test here asks for
// effect_alpha, the level that admits leakage.
// The level: 20 effect-free generated cases (M = 8, P = 512, coloured noise
// of the generator's random filters, SNR 20–60 dB): under the null the count
// below alpha = 0.01 is Binomial(20, ≤ 0.01), P(≥ 3) = 0.001; allowed 2.
// p_below, the lower tail of the gap test on what remains: Fisher's X over
// the excited lines (each −2 ln p of t ~ F(2, 2M−2), M the periods used)
// against χ² with 2K − q degrees, q the chosen effects' parameters. Computed
// here from the report's own t_after: the tail's direction and the q
// subtracted are what a mutant would get wrong. Two correct verdicts: a clear
// gain error (what remains is noise: p_below not small) and classic seed 2
// case 75, subtle leakage, whose remaining gap 0.30 is below the noise
// (flagged at p ≈ 5e-10 in the validation runs; leakage cases hold the
// smallest p_below there, why is not established).
TEST(GapDiagnosis, AGapBelowTheNoiseIsTheLowerTailOfTheGapTest) {
  for (const auto& [effect, strength, seed] :
       {std::tuple{Effect::GainError, Strength::Clear, std::uint64_t{3}},
        std::tuple{Effect::Leakage, Strength::Subtle, std::uint64_t{2000081}}}) {
    const GapReport r = diagnose_case({effect}, strength, seed);
    SCOPED_TRACE(verdict(r));
    ASSERT_EQ(r.verdict, GapVerdict::Explained);
    int q = 0;
    for (const EffectFit& f : r.chosen) q += f.dof;
    const int M = r.periods_used, K = static_cast<int>(r.t_after.size());
    double X = 0;
    for (double t : r.t_after) X += 2.0 * (M - 1) * std::log1p(t / (M - 1));
    const double expected = boost::math::cdf(boost::math::chi_squared(2.0 * K - q), X);
    EXPECT_NEAR(r.p_below, expected, 1e-12 + 1e-9 * expected);
    if (effect == Effect::GainError) {
      EXPECT_GT(r.p_below, r.options.alpha) << r.gap_after;
    } else {
      EXPECT_LT(r.p_below, 1e-6) << r.gap_after;
    }
  }
}

// The report's candidate e (fitted alone), or nullptr when it has none.
const EffectFit* candidate(const GapReport& r, Effect e) {
  const auto it =
      std::find_if(r.candidates.begin(), r.candidates.end(), [&](const EffectFit& f) { return f.effect() == e; });
  return it == r.candidates.end() ? nullptr : &*it;
}

// Issue 17, item 3(a): a Duffing-type distortion too thin for the Fisher test.
// gap-validate --family structure seed 1, case 34 (seed 1000037): a subtle
// cubic fed back from the output through a lightly damped structure. Its
// distortion on the 87 unexcited lines tests p 0.059 (Fisher), so until stop
// 68 the selection did not admit it and chose unmodelled_mode +
// mode_mismatch, gap 4.25, where the in-loop cubic alone leaves 1.09. The
// polynomial fitted on the excited lines predicts the unexcited lines' mean
// residual (Diagnosis::nonlinearity_prediction_p), and at the first stage,
// where its fit beats every linear effect's, that test admits it.
TEST(GapDiagnosis, AThinInLoopDistortionIsAdmittedByItsPrediction) {
  const GapReport r = diagnose_case({Effect::Nonlinearity}, Strength::Subtle, 1000037, true);
  SCOPED_TRACE(verdict(r) + ", p_pred " + std::to_string(r.p_nonlinearity_prediction));
  ASSERT_GE(r.p_nonlinearity, r.options.alpha);  // the case is one the Fisher test misses
  EXPECT_LT(r.p_nonlinearity_prediction, r.options.alpha);
  EXPECT_EQ(names(r.present), std::vector<std::string>{"nonlinearity"});
  EXPECT_EQ(param(r, "nonlinearity", "in_loop"), 1.0);
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
  EXPECT_LT(r.gap_after, 2.0);
  EXPECT_EQ(std::count_if(r.notes.begin(), r.notes.end(),
                          [](const std::string& n) {
                            return n.find("nonlinearity: the polynomial fitted on the excited lines predicts") == 0;
                          }),
            1);
}

// Issue 17: every addition pays for itself at an addition's level, the
// nonlinearity too. gap-validate classic seed 3, case 26 (seed 3000035): a
// clear mode_mismatch and no nonlinearity; the Fisher test on the 111
// unexcited lines gives p 6.1e-3, below alpha (0.01) and above effect_alpha
// (1e-3), and its polynomial leaves the gap beside the moved mode where it
// was (0.930 against 0.931). Until stop 73 the nonlinearity was admitted
// beside the mode at alpha, its detection level, and the verdict read
// mode_mismatch + nonlinearity in all four families; beside an effect found
// it is now held to effect_alpha (ForwardSelection::admit).
TEST(GapDiagnosis, ANonlinearityBesideAFoundEffectIsAnAdditionAtEffectAlpha) {
  const GapReport r = diagnose_case({Effect::ModeMismatch}, Strength::Clear, 3000035);
  SCOPED_TRACE(verdict(r));
  ASSERT_LT(r.p_nonlinearity, r.options.alpha);  // the case is one the detection level would admit
  ASSERT_GE(r.p_nonlinearity, r.options.effect_alpha);
  EXPECT_EQ(names(r.present), std::vector<std::string>{"mode_mismatch"});
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
  EXPECT_LT(r.gap_after, 2.0);
}

// The prediction test is consulted once, at the first stage: gap-validate
// --family structure seed 2, case 105 (seed 2000111), a clear unmodelled mode
// and no nonlinearity, where it rejects (p 5e-4: the mode's misfit on the
// excited lines gives the polynomial something to fit, and 1 % of null cases
// fall below alpha anyway). The mode explains the excited lines far better
// (gap 0.98 against the polynomial's 46), so it is chosen, and no
// nonlinearity beside it (stop 67's prototype, which tested the prediction
// at every stage, added one here).
TEST(GapDiagnosis, APredictedDistortionBesideABetterLinearEffectIsNotAdded) {
  const GapReport r = diagnose_case({Effect::UnmodelledMode}, Strength::Clear, 2000111, true);
  SCOPED_TRACE(verdict(r) + ", p_pred " + std::to_string(r.p_nonlinearity_prediction));
  ASSERT_LT(r.p_nonlinearity_prediction, r.options.alpha);  // the case is one where the test rejects
  EXPECT_GE(r.p_nonlinearity, r.options.alpha);
  EXPECT_EQ(names(r.present), std::vector<std::string>{"unmodelled_mode"});
}

// Issue 17: a pair the greedy order never builds. gap-validate seed 1, case
// 18 (seed 1000021): a clear mode_mismatch (the 0.089 Hz mode moved by
// 0.17 %) and a gain error of 0.89. Alone, a series unmodelled_mode near that
// mode takes both (gap 0.82: its factor's constant term is a gain), the
// mode_mismatch leaves 2.0, the gain 19; nothing added to the series mode
// passes its test, so until stop 69 the verdict was unmodelled_mode, 5
// parameters. The pair, 3 parameters, leaves 0.82 too and its Schwarz
// criterion is lower by more than 1 (ForwardSelection::pair_beats_single):
// the pair is named, its path first the mode_mismatch then the gain.
// The verdict of a pair case: exactly the (sorted) pair, explained within
// issue 17's gap_after ≤ 2, reached in two steps, the first `first_step`.
void expect_pair_explained(const GapReport& r, const std::vector<std::string>& pair, const char* first_step) {
  std::vector<std::string> present = names(r.present);
  std::sort(present.begin(), present.end());
  EXPECT_EQ(present, pair);
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
  EXPECT_LT(r.gap_after, 2.0);
  ASSERT_EQ(r.path.size(), 2u);
  EXPECT_STREQ(to_string(r.path[0].added), first_step);  // a C string: STREQ, not pointer equality
}

TEST(GapDiagnosis, APairTheGreedyOrderMissesIsFound) {
  const GapReport r = diagnose_case({Effect::ModeMismatch, Effect::GainError}, Strength::Clear, 1000021);
  SCOPED_TRACE(verdict(r));
  expect_pair_explained(r, {"gain_error", "mode_mismatch"}, "mode_mismatch");
  EXPECT_TRUE(r.alternatives.empty());
}

// Issue 17: a pair the record cannot tell from the single verdict is named.
// gap-validate seed 1, case 192 (seed 1000195): a subtle series unmodelled
// mode (gap 2.3). The mode alone leaves 0.92 with 5 parameters; delay +
// mode_mismatch, 3 parameters, each significant beside the other alone,
// leaves about as little — Schwarz criteria within 1 (2 ln B ≤ 2), too close
// for pair_beats_single to overturn the mode, too close to leave unsaid: the
// report lists the pair under alternative_pairs.
TEST(GapDiagnosis, APairAsGoodAsTheSingleVerdictIsNamed) {
  const GapReport r = diagnose_case({Effect::UnmodelledMode}, Strength::Subtle, 1000195);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"unmodelled_mode"});
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
  ASSERT_EQ(r.alternative_pairs.size(), 1u);
  std::vector<std::string> pair{to_string(r.alternative_pairs[0][0]), to_string(r.alternative_pairs[0][1])};
  std::sort(pair.begin(), pair.end());
  EXPECT_EQ(pair, (std::vector<std::string>{"delay", "mode_mismatch"}));
  for (Effect e : r.alternative_pairs[0]) {  // each member admitted alone
    const EffectFit* alone = candidate(r, e);
    ASSERT_NE(alone, nullptr);
    EXPECT_LT(alone->p_value, r.options.effect_alpha) << to_string(e);
  }
  const nlohmann::json j = gap_report_to_json(r);
  ASSERT_EQ(j.at("alternative_pairs").size(), 1u);
  EXPECT_EQ(j["alternative_pairs"][0].size(), 2u);
}

// Issue 17: an exchange whose set no longer holds the first effect is tested
// member by member. gap-validate seed 3, case 98 (seed 3000107): a clear gain
// of 0.80 and a 0.26-sample delay. Alone a series unmodelled_mode takes most
// of both (gap 0.97: its factor's constant term is a gain; the gain alone
// leaves 6.2, the delay 28), then the delay is added (0.86). Exchanging the
// mode for the gain lowers the Schwarz criterion (4 parameters fewer), but
// until stop 70 the exchanged pair was tested against the mode alone — sets
// that are not nested, and the pair lowers V little below the mode's — and
// was refused: the verdict was delay + unmodelled_mode. Now each member is
// tested beside the other alone (the gain against the delay alone, the
// delay against the gain alone), as an addition is.
TEST(GapDiagnosis, AnExchangedPairIsTestedMemberByMember) {
  const GapReport r = diagnose_case({Effect::Delay, Effect::GainError}, Strength::Clear, 3000107);
  SCOPED_TRACE(verdict(r));
  expect_pair_explained(r, {"delay", "gain_error"}, "unmodelled_mode");  // the greedy's first step, then exchanged
  for (const EffectFit& f : r.chosen) EXPECT_LT(f.p_value, r.options.effect_alpha) << to_string(f.effect());
}

// Issue 17: a series mode's DC gain is named as a gain error. gap-validate
// classic seed 4, case 18 (seed 4000030): a clear gain error beside a series
// unmodelled mode. The free series factor d + c/(ξ−λ) + c̄/(ξ−λ̄) is exactly
// its DC value times a unit-DC resonance, so the mode alone took the gain
// too (verdict unmodelled_mode, gap 0.69, until stop 71; 27 such pairs in
// 7200 gap-validate cases). ForwardSelection::gain_split tests the gain, on
// one degree of freedom at effect_alpha, against the set with the mode held
// at unit DC: the path shows the mode (gap 0.69), then its gain (0.71: the
// same function class refitted jointly, within the gap rule's noise bound).
// Checked to fail with gain_split's call removed (verdict unmodelled_mode).
TEST(GapDiagnosis, ASeriesModesDcGainIsAGainErrorOfItsOwn) {
  const GapReport r = diagnose_case({Effect::UnmodelledMode, Effect::GainError}, Strength::Clear, 4000030);
  SCOPED_TRACE(verdict(r));
  expect_pair_explained(r, {"gain_error", "unmodelled_mode"}, "unmodelled_mode");
  EXPECT_EQ(r.path[1].added, Effect::GainError);
  EXPECT_LT(r.path[1].p_value, r.options.effect_alpha);
}

// Issue 17: an unexplained gap must not hide a candidate that explains it
// better. gap-validate --family structure seed 2, case 102 (seed 2000108): a
// clear gain error, every candidate's test at p ≥ 1e-80, diagnosed at an
// effect level (1e-300) no linear effect can meet: nothing is admitted, the
// verdict is "unexplained", and each candidate that alone would leave the gap
// lower by more than the noise bound (3 null sd, gap_noise_bound) while its
// test keeps it out is named in a note with that test's p and level — the
// gain error first among them; the nonlinearity's note carries both its
// tests. (Until stop 68 the case was structure seed 1 case 34 at the default
// levels, an in-loop cubic its Fisher test missed; its prediction test now
// admits it: AThinInLoopDistortionIsAdmittedByItsPrediction.)
TEST(GapDiagnosis, AnUnexplainedGapNamesABetterCandidateItsTestKeptOut) {
  GapCaseOptions o;
  o.effects = {Effect::GainError};
  o.structure = true;
  o.seed = 2000108;
  const GapCase c = make_gap_case(o);
  GapOptions strict;
  strict.effect_alpha = 1e-300;
  const GapReport r = diagnose_gap(c.sim_model, c.record, 1, c.meta, strict);
  SCOPED_TRACE(verdict(r));
  ASSERT_EQ(r.verdict, GapVerdict::Unexplained);
  ASSERT_TRUE(r.present.empty());
  const double bound = 3 * gap_null_sd(c.meta.periods, r.excited);
  const EffectFit* gain = candidate(r, Effect::GainError);
  ASSERT_NE(gain, nullptr);
  ASSERT_LT(gain->gap_after, r.gap_after - bound);
  ASSERT_GE(gain->p_value, strict.effect_alpha);
  const std::string expected = "gain_error alone would leave gap " + sci(gain->gap_after, 4) + ", less than the " +
                               sci(r.gap_after, 4) + " of the model as given, but its own test does not admit it (p " +
                               sci(gain->p_value, 3) + " at level 1e-300)";
  EXPECT_EQ(std::count_if(r.notes.begin(), r.notes.end(), [&](const std::string& n) { return n == expected; }), 1);
  // The nonlinearity's note names both its tests.
  const EffectFit* nl = candidate(r, Effect::Nonlinearity);
  ASSERT_NE(nl, nullptr);
  ASSERT_LT(nl->gap_after, r.gap_after - bound);
  ASSERT_GE(r.p_nonlinearity_prediction, r.options.alpha);
  const std::string nl_note = "nonlinearity alone would leave gap " + sci(nl->gap_after, 4) + ", less than the " +
                              sci(r.gap_after, 4) + " of the model as given, but its own test does not admit it (p " +
                              sci(nl->p_value, 3) + "; predicted from the excited lines " +
                              sci(r.p_nonlinearity_prediction, 3) + " at level 0.01)";
  EXPECT_EQ(std::count_if(r.notes.begin(), r.notes.end(),
                          [&](const std::string& n) { return n.find(nl_note) == 0; }),
            1);
  // Every candidate named is one the rule names, and every one it names is named.
  for (const EffectFit& f : r.candidates) {
    const bool named = std::any_of(r.notes.begin(), r.notes.end(), [&](const std::string& n) {
      return n.find(std::string(to_string(f.effect())) + " alone would leave gap ") == 0;
    });
    EXPECT_EQ(named, f.gap_after < r.gap_after - bound) << to_string(f.effect());
  }
}

// Issue 17, parsimony between the two lags. gap-validate --continuous seed 1,
// case 63 (seed 1000066): a clear delay of 0.58 samples. An order-2 low-pass
// (cut-off 0.34 Hz, damping 0.60: nearly linear phase, flat magnitude in the
// band) leaves gap 0.93, the delay 1.03, and the Schwarz criterion (½ ln 96 =
// 2.3 per parameter) took the low-pass; beside the delay the low-pass tests p
// 0.022, not significant at effect_alpha, so the selection's own F-test does
// not demand it: the verdict is the delay, the low-pass named as explaining
// the record as well. The case must show what the rule is for: the low-pass
// leaves less gap alone and the delay lags.
TEST(GapDiagnosis, ALowPassALaggingDelayMakesRedundantGivesWayToIt) {
  GapCaseOptions o;
  o.effects = {Effect::Delay};
  o.continuous = true;
  o.seed = 1000066;
  const GapCase c = make_gap_case(o);
  const GapReport r = diagnose_gap(c.sim_model, c.record, 1, c.meta);
  SCOPED_TRACE(verdict(r));
  const EffectFit* sensor = candidate(r, Effect::SensorDynamics);
  const EffectFit* delay = candidate(r, Effect::Delay);
  ASSERT_NE(sensor, nullptr);
  ASSERT_NE(delay, nullptr);
  ASSERT_LT(sensor->gap_after, delay->gap_after);
  ASSERT_GT(std::get<Delay>(delay->parameters).samples, 0);
  EXPECT_EQ(r.verdict, GapVerdict::Explained);
  EXPECT_EQ(names(r.present), std::vector<std::string>{"delay"});
  ASSERT_EQ(r.alternatives.size(), 1u);
  EXPECT_EQ(r.alternatives[0].first, Effect::SensorDynamics);
  EXPECT_GE(r.alternatives[0].second, r.options.effect_alpha);
}

TEST(GapDiagnosis, ASubtleTransientInColouredNoiseIsLeakage) {
  for (std::uint64_t seed : {2000021u, 2000081u}) {
    const GapReport r = diagnose_case({Effect::Leakage}, Strength::Subtle, seed);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + verdict(r));
    EXPECT_LT(r.p_leakage, r.options.effect_alpha);
    EXPECT_EQ(names(r.present), std::vector<std::string>{"leakage"});
  }
  int below = 0;
  std::string list;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    GapCaseOptions o;
    o.strength = Strength::None;
    o.period = 512;
    o.seed = 7000000 + seed;
    const GapCase c = make_gap_case(o);
    const GapReport r = diagnose_gap(c.sim_model, c.record, 1, c.meta);
    if (r.p_leakage < r.options.alpha) {
      ++below;
      list += " seed " + std::to_string(o.seed) + ": p(leakage) " + std::to_string(r.p_leakage) + ";";
    }
  }
  EXPECT_LE(below, 2) << list;
}

// A delay and a low-pass together: before, the joint refit turned the second-
// order sensor into a first-order one beside the delay, q = 0 new parameters
// made the F-test p = 1 (now at least one), and a delay fitted first on the
// bare model stalled the coordinate descent above the sensor alone (now from
// both ends). Classic seed 1 case 37 (the first) and seed 3 case 58 (the
// second): both named sensor_dynamics alone.
TEST(GapDiagnosis, ADelayBesideALowPassIsAPair) {
  for (std::uint64_t seed : {1000040u, 3000067u}) {
    const GapReport r = diagnose_case({Effect::Delay, Effect::SensorDynamics}, Strength::Clear, seed);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + verdict(r));
    std::vector<std::string> present = names(r.present);  // ordered by shrink
    std::sort(present.begin(), present.end());
    EXPECT_EQ(present, (std::vector<std::string>{"delay", "sensor_dynamics"}));
    EXPECT_LT(r.gap_after, 2.0);  // issue 17's target on a right verdict
  }
}

// A continuous delay beside a low-pass can be, on the record, one low-pass of
// another shape (gap_after at the noise level), so the selection takes the
// sensor alone and cannot admit the delay beside it; the report must say that
// the delay may be there too (GapReport::possible_additions). Continuous
// seed 2, case 59. (Not every such pair gets it: on seed 1's case 38, a delay
// of 0.52 samples beside a first-order low-pass, fitted by one overdamped
// second-order low-pass, the pair's Schwarz criterion is more than 1 above
// the sensor's alone.)
TEST(GapDiagnosis, ADelayTheRecordCannotDemandIsNamedAsPossible) {
  GapCaseOptions o;
  o.effects = {Effect::Delay, Effect::SensorDynamics};
  o.strength = Strength::Clear;
  o.seed = 2000065;
  o.continuous = true;
  const GapCase c = make_gap_case(o);
  const GapReport r = diagnose_gap(c.sim_model, c.record, 1, c.meta);
  SCOPED_TRACE(verdict(r));
  ASSERT_EQ(names(r.present), std::vector<std::string>{"sensor_dynamics"});
  EXPECT_LT(r.gap_after, 2.0);
  bool delay = false;
  for (const auto& [e, p] : r.possible_additions) delay = delay || (e == Effect::Delay && p >= GapOptions{}.effect_alpha);
  EXPECT_TRUE(delay);
}

// A discrete sensor whose pole is fast (a = e^{−2π f_c} ≈ 0.005 and a pole
// pair at f_c = 0.65 cycles/sample): before, the discrete forms' cut-off
// stopped at 0.45 cycles/sample and both were named delay (classic seed 2,
// cases 71 and 51).
TEST(GapDiagnosis, AFastDiscreteLowPassIsNoDelay) {
  for (std::uint64_t seed : {2000077u, 2000057u}) {
    const GapReport r = diagnose_case({Effect::SensorDynamics}, Strength::Subtle, seed);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + verdict(r));
    EXPECT_EQ(names(r.present), std::vector<std::string>{"sensor_dynamics"});
  }
}

// A 1-parameter gain error whose deviation is largest at a resonance: a
// 5-parameter mode fitted at that line undercut it by less than the ln N
// the mode's search over N frequencies costs in the Schwarz criterion
// (classic seed 2, cases 9 and 89: named unmodelled_mode before).
TEST(GapDiagnosis, ASearchedModePaysForItsSearch) {
  for (std::uint64_t seed : {2000015u, 2000095u}) {
    const GapReport r = diagnose_case({Effect::GainError}, Strength::Subtle, seed);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + verdict(r));
    EXPECT_EQ(names(r.present), std::vector<std::string>{"gain_error"});
  }
}

// A mode narrower than a line spacing (ζ = 0.013 at line 24: half-power width
// 0.6 lines) is fitted, not held at the old one-line bound (gap 2.8 left;
// classic seed 2, case 5).
// Where the gap concentrates (GapReport::peaks): for a resonance the model
// lacks, the interval with the largest share holds the resonance (within two
// lines), and the intervals hold at least half the excess gap, at most all.
TEST(GapDiagnosis, TheGapsPeaksHoldHalfItsExcessAtTheResonance) {
  const StateSpace g = pintelon_plant();
  const double f = 61.0 / kP;
  RecordMeta meta;
  const Eigen::MatrixXd rec = simulate_periodic_record(with_mode(g, f, 0.05), options(9), meta);
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  ASSERT_FALSE(r.peaks.empty());
  EXPECT_LE(r.peaks[0].band[0], f + 2.0 / kP);
  EXPECT_GE(r.peaks[0].band[1], f - 2.0 / kP);
  double held = 0;
  for (size_t i = 0; i < r.peaks.size(); ++i) {
    held += r.peaks[i].share;
    if (i > 0) {
      EXPECT_LE(r.peaks[i].share, r.peaks[i - 1].share);
    }
  }
  EXPECT_GE(held, 0.5);
  EXPECT_LE(held, 1.0);
}

TEST(GapDiagnosis, ALightlyDampedModeAtALowLineIsFittedThrough) {
  const GapReport r = diagnose_case({Effect::UnmodelledMode}, Strength::Clear, 2000011);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"unmodelled_mode"});
  EXPECT_LT(r.gap_after, 2.0);
}

// A resonance above the excited band (line 120 of P = 512, ζ = 0.02; the
// band ends at line 99) bends the band's upper lines. The catalogue has no
// such effect: an unmodelled mode must peak inside the band, so the best it
// offers is one of the model's modes moved out of the band (as the F-16's
// order-16 model on its own Level-1 record, 15.8 → 16.4 Hz; beside a cubic,
// until stop 73, to 19.5 Hz) and an unmodelled mode at the band's edge. The
// report names both stand-ins and does not call the gap explained.
TEST(GapDiagnosis, AModeAboveTheBandIsNamedAStandIn) {
  const StateSpace g = pintelon_plant();
  RecordMeta meta;
  const Eigen::MatrixXd rec = simulate_periodic_record(with_mode(g, 120.0 / kP, 0.05), options(9), meta);
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  std::vector<std::string> stand_ins = names(r.stand_ins);
  std::sort(stand_ins.begin(), stand_ins.end());
  EXPECT_EQ(stand_ins, (std::vector<std::string>{"mode_mismatch", "unmodelled_mode"}));
  EXPECT_GT(param(r, "mode_mismatch", "frequency_hz"), 99.5 / kP);
  EXPECT_NE(r.verdict, GapVerdict::Explained);
  int noted = 0;
  for (const auto& n : r.notes) noted += n.find(" is a stand-in, not a resonance the data resolve") != std::string::npos;
  EXPECT_EQ(noted, 2);
}

// A clear unmodelled mode narrower than the search admits (gap-validate
// classic seed 2 case 45: ζ 0.011 at 0.0106 cycles/sample, half a line wide
// at ζ 0.023 there): its peak is found, its damping sits at the floor, and
// the report says to read that damping as an upper bound — no stand-in.
TEST(GapDiagnosis, AModeNarrowerThanTheSearchHasItsDampingAsABound) {
  const GapReport r = diagnose_case({Effect::UnmodelledMode}, Strength::Clear, 2000051);
  SCOPED_TRACE(verdict(r));
  EXPECT_EQ(names(r.present), std::vector<std::string>{"unmodelled_mode"});
  EXPECT_TRUE(r.stand_ins.empty());
  EXPECT_GE(param(r, "unmodelled_mode", "damping"), 0.011);
  bool noted = false;
  for (const auto& n : r.notes) noted = noted || n.find("read the damping as an upper bound") != std::string::npos;
  EXPECT_TRUE(noted);
}

// A resonance added in parallel beside a sensor is refitted in both
// connections in every descent round (classic seed 6 case 78: a clear
// first-order sensor and a parallel mode at 0.0535 cycles/sample, ζ 0.015).
// Fitted beside the sensor as first found, the mode came out in series; with
// the connection kept through the joint descent the pair left gap 2.06 (above
// issue 17's bound 2 on a correct verdict); decided again as the sensor
// settles, the parallel mode leaves 0.91.
TEST(GapDiagnosis, AModesConnectionIsDecidedOnTheJointFit) {
  const GapReport r = diagnose_case({Effect::SensorDynamics, Effect::UnmodelledMode}, Strength::Clear, 6000096);
  SCOPED_TRACE(verdict(r));
  std::vector<std::string> present = names(r.present);  // ordered by shrink
  std::sort(present.begin(), present.end());
  EXPECT_EQ(present, (std::vector<std::string>{"sensor_dynamics", "unmodelled_mode"}));
  EXPECT_LT(r.gap_after, 2.0);  // issue 17's target on a right verdict
  for (const EffectFit& f : r.chosen)
    if (const auto* m = std::get_if<UnmodelledMode>(&f.parameters)) {
      EXPECT_FALSE(m->series);
    }
}

// A subtle first-order low-pass the data cannot tell from a delay (classic
// seed 2 case 91: 20 dB SNR; the delay alone leaves 0.760, the low-pass 0.761,
// each with one parameter): the verdict names the delay, and the report says
// the low-pass explains the record as well (adding the delay to it is not
// significant) — never the richer effects that merely nest the chosen one
// (a mode's constant term is a gain: 0 of the 35 clear singles of classic
// seed 1 get an alternative).
TEST(GapDiagnosis, IndistinguishableEffectsAreNamed) {
  const GapReport r = diagnose_case({Effect::SensorDynamics}, Strength::Subtle, 2000097);
  SCOPED_TRACE(verdict(r));
  ASSERT_EQ(r.present.size(), 1u);
  const Effect named = r.present[0];
  const Effect other = named == Effect::Delay ? Effect::SensorDynamics : Effect::Delay;
  EXPECT_TRUE(named == Effect::Delay || named == Effect::SensorDynamics);
  ASSERT_FALSE(r.alternatives.empty());
  EXPECT_EQ(r.alternatives[0].first, other);
  EXPECT_GE(r.alternatives[0].second, r.options.effect_alpha);
  const GapReport clear = diagnose_case({Effect::GainError}, Strength::Clear, 1000002);
  EXPECT_EQ(names(clear.present), std::vector<std::string>{"gain_error"});
  EXPECT_TRUE(clear.alternatives.empty()) << verdict(clear);
}

// Issue 17, item 4: two sensors on the same structure (a model with two
// outputs, C = [c; c]), the second one sample late; independent white noise
// of std 0.01 on each. Channel 1 has no gap, channel 2 a delay of one sample
// (a channel-local effect, found in that channel's report); the joint test
// sees the gap of the model as given, and the verdict is "explained". With
// both sensors right, no channel and the joint test find nothing (a fixed
// seed: each test's false-alarm probability is its level, 0.01).
TEST(GapDiagnosis, TwoOutputsASensorDelayOnOne) {
  const StateSpace g = pintelon_plant();
  StateSpace two = g;
  two.C.resize(2, g.order());
  two.C << g.C, g.C;
  two.D.resize(2, 1);
  two.D << g.D, g.D;
  RecordMeta meta;
  const Eigen::MatrixXd r1 = with_output(simulate_periodic_record(g, options(21, 0.0), meta), 21,
                                         [](double, double y) { return y; });
  const Eigen::MatrixXd late = simulate_periodic_record(testing::one_sample_delay(g), options(21, 0.0), meta);
  const Eigen::MatrixXd right = simulate_periodic_record(g, options(21, 0.0), meta);
  ASSERT_EQ(late.col(0), r1.col(0));  // the same multisine: options(21) fixes it
  const auto record = [&](const Eigen::MatrixXd& second) {
    const Eigen::MatrixXd r2 = with_output(second, 22, [](double, double y) { return y; });
    Eigen::MatrixXd rec(r1.rows(), 3);
    rec << r1.col(0), r1.col(1), r2.col(1);
    return rec;
  };
  const MultiGapReport m = diagnose_gap_outputs(two, record(late), 1, meta);
  ASSERT_EQ(m.channels.size(), 2u);
  SCOPED_TRACE(verdict(m.channels[0]) + " | " + verdict(m.channels[1]));
  EXPECT_EQ(m.channels[0].verdict, GapVerdict::NoGap);
  EXPECT_EQ(names(m.channels[1].present), std::vector<std::string>{"delay"});
  EXPECT_NEAR(param(m.channels[1], "delay", "samples"), 1.0, 0.01);  // as in OneSampleDelay
  EXPECT_EQ(names(m.present), std::vector<std::string>{"delay"});
  EXPECT_EQ(m.verdict, GapVerdict::Explained);
  EXPECT_TRUE(m.joint_tested);
  EXPECT_LT(m.p_joint, 1e-6);
  EXPECT_NEAR(m.gap_before, (m.channels[0].gap_before + m.channels[1].gap_before) / 2, 1e-12 * m.gap_before);
  const MultiGapReport n = diagnose_gap_outputs(two, record(right), 1, meta);
  EXPECT_EQ(n.verdict, GapVerdict::NoGap);
  EXPECT_GE(n.p_joint, 0.01);
  EXPECT_TRUE(n.present.empty());
  // The same output twice: no joint test (a singular covariance), said in a note.
  Eigen::MatrixXd twice(r1.rows(), 3);
  twice << r1.col(0), r1.col(1), r1.col(1);
  const MultiGapReport t = diagnose_gap_outputs(two, twice, 1, meta);
  EXPECT_FALSE(t.joint_tested);
  ASSERT_FALSE(t.notes.empty());
  EXPECT_NE(t.notes.back().find("linearly dependent"), std::string::npos);
  // Refused: a model with another number of outputs, several inputs, one output.
  EXPECT_THROW(diagnose_gap_outputs(g, record(right), 1, meta), Error);
  EXPECT_THROW(diagnose_gap_outputs(two, record(right), 2, meta), Error);
  EXPECT_THROW(diagnose_gap_outputs(two, r1, 1, meta), Error);
}

TEST(GapDiagnosis, RefusesWhatItCannotUse) {
  const StateSpace g = pintelon_plant();
  RecordMeta meta;
  const Eigen::MatrixXd clean = simulate_periodic_record(g, options(12, 0.0), meta);
  EXPECT_THROW(diagnose_gap(g, clean, 1, meta), Error);  // no noise floor
  const Eigen::MatrixXd rec = simulate_periodic_record(g, options(12), meta);
  RecordMeta few = meta;
  few.periods = 3;
  few.period = kP * kM / 3;  // not whole periods either way; the period count is named first
  EXPECT_THROW(diagnose_gap(g, rec, 1, few), Error);
  RecordMeta bad = meta;
  bad.excited_lines.push_back(kP);  // above P/2
  EXPECT_THROW(diagnose_gap(g, rec, 1, bad), Error);
  StateSpace mimo = g;
  mimo.C = Eigen::MatrixXd::Ones(2, g.order());
  mimo.D = Eigen::MatrixXd::Zero(2, 1);
  EXPECT_THROW(diagnose_gap(mimo, rec, 1, meta), Error);
  // a pole on the unit circle at excited line 1: e^{±j2π/P}
  StateSpace osc;
  osc.A.resize(2, 2);
  osc.A << std::cos(2 * M_PI / kP), std::sin(2 * M_PI / kP), -std::sin(2 * M_PI / kP), std::cos(2 * M_PI / kP);
  osc.B = Eigen::MatrixXd::Ones(2, 1);
  osc.C = Eigen::MatrixXd::Ones(1, 2);
  osc.D = Eigen::MatrixXd::Zero(1, 1);
  EXPECT_THROW(diagnose_gap(osc, rec, 1, meta), Error);
  // A model with a pole outside the circle has no periodic steady state to
  // compare (new-user review: gap diagnosed an --allow-unstable model where
  // validate refused it); refused before any work, as validate does.
  StateSpace unstable = g;
  unstable.A *= 1.1 / spectral_radius(g);
  try {
    diagnose_gap(unstable, rec, 1, meta);
    ADD_FAILURE() << "an unstable model was diagnosed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("unstable pole"), std::string::npos) << e.what();
    // Every pole pushed out is named (a user review: the refusal named one of
    // the Silverbox's six): those of g with |λ| >= ρ / 1.1.
    const Eigen::VectorXcd lambda = poles(g);
    const long out = (lambda.cwiseAbs().array() >= spectral_radius(g) / 1.1).count();
    ASSERT_GE(out, 2);  // a complex pair at least
    EXPECT_NE(std::string(e.what()).find("(" + std::to_string(out) + " unstable poles: "), std::string::npos) << e.what();
  }
  GapOptions o;
  o.alpha = 0;
  EXPECT_THROW(diagnose_gap(g, rec, 1, meta, o), Error);
}

// Equal noise power per period (period_power_test, gap.hpp; issue 17: real
// noise is not stationary). Level: 2000 null draws (R = 3 … 7 periods, K =
// 400 consecutive lines; a fixed model error per line, which the test must
// ignore; a noise level smooth in k, exp(1.5 sin(2πk/K + φ)), 26 dB from
// lowest to highest power; and per period a leakage term c_m T(k), T(k) =
// 1 / (1 − 0.68 e^{−iπk/K}) — the DFT of a period of noise through a
// first-order filter with pole 0.68 — c_m ~ 3 × complex normal: power 18 ×
// 9.8 = 176 at the lowest lines against a line noise power of 0.05 … 20,
// which the pairwise differencing must cancel). The count of p < 0.01 is
// Bin(2000, 0.01) if the test holds its level — mean 20, sd 4.4 — and
// [5, 38] is ± 3.4 sd (the normal limit over 200 pairs adds little); p < 0.1:
// mean 200, sd 13.4, [150, 250]. The same statistic on the lines one by one
// (each line paired with a zero column: no differencing) must reject nearly
// always on these draws — else they would not test the cancellation; more
// than half is asked.
// Power: one period at 1.5 × and one at 0.7 × the noise power of the rest,
// 200 pairs, R = 5: the shares move by ~0.05 against a standard error of
// ~0.012, so S is near 70 (p ≪ 1e-6); its relative powers order so.
TEST(GapDiagnosis, EqualNoisePowerPerPeriodTestHoldsItsLevel) {
  std::mt19937_64 g(2024);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> phase(0, 2 * M_PI);
  auto draw = [&](int R, int K, const std::vector<double>& power) {
    Eigen::MatrixXcd res(R, K);
    std::vector<cplx> leak;
    for (int m = 0; m < R; ++m) leak.push_back(3.0 * cplx(normal(g), normal(g)));
    const double phi = phase(g);
    for (int k = 0; k < K; ++k) {
      const double level = std::exp(1.5 * std::sin(2 * M_PI * k / K + phi));
      const cplx error(3 * normal(g), 3 * normal(g));
      const cplx T = 1.0 / (1.0 - 0.68 * std::polar(1.0, -M_PI * k / K));
      for (int m = 0; m < R; ++m)
        res(m, k) = error + leak[static_cast<size_t>(m)] * T +
                    level * std::sqrt(power[static_cast<size_t>(m)] / 2) * cplx(normal(g), normal(g));
    }
    return res;
  };
  int below_001 = 0, below_01 = 0, undifferenced_below_001 = 0;
  for (int i = 0; i < 2000; ++i) {
    const int R = 3 + i % 5;
    const Eigen::MatrixXcd res = draw(R, 400, std::vector<double>(static_cast<size_t>(R), 1.0));
    const PeriodPowerTest t = period_power_test(res);
    ASSERT_EQ(t.relative.size(), static_cast<size_t>(R));
    below_001 += t.p < 0.01;
    below_01 += t.p < 0.1;
    Eigen::MatrixXcd single = Eigen::MatrixXcd::Zero(R, 2 * res.cols());
    for (Eigen::Index k = 0; k < res.cols(); ++k) single.col(2 * k) = res.col(k);
    undifferenced_below_001 += period_power_test(single).p < 0.01;
  }
  EXPECT_GE(below_001, 5);
  EXPECT_LE(below_001, 38);
  EXPECT_GE(below_01, 150);
  EXPECT_LE(below_01, 250);
  EXPECT_GT(undifferenced_below_001, 1000);
  const PeriodPowerTest unequal = period_power_test(draw(5, 400, {1, 1.5, 0.7, 1, 1}));
  EXPECT_LT(unequal.p, 1e-6);
  EXPECT_GT(unequal.relative[1], 1.1);
  EXPECT_LT(unequal.relative[2], 0.9);
  EXPECT_EQ(period_power_test(draw(2, 400, {1, 1})).p, 1.0);   // two periods: q ≡ 1/2
  EXPECT_EQ(period_power_test(draw(5, 20, {1, 1, 1, 1, 1})).p, 1.0);  // too few lines
}

// Independent noise from period to period (period_independence_test,
// gap.hpp; issue 17: the F-16's periods disagree for a reason other than
// noise). Level: 2000 null draws (R = 4 … 8 periods, K = 400 consecutive
// lines), each with a fixed model error per line, a noise level smooth in k
// (26 dB range), a per-period leakage term T(k)(x_m − x_{m+1}) — the filter
// state at the period boundaries, shared by adjacent periods, so the
// undifferenced leakage terms are correlated at lag 1 (−1/2), which the line
// pairs' difference must cancel. 1000 draws of equal period powers: counts
// of p < 0.01 and p < 0.1 within ± 3.4 sd of Bin(1000, ·) (mean 10, sd 3.1:
// ≤ 20; mean 100, sd 9.5: [68, 132]). 1000 draws of unequal powers (0.4 …
// 1.6, shuffled), which the Monte Carlo null mean from the estimated powers
// absorbs only approximately: the level must hold (the same upper limits);
// measured somewhat conservative (a Python model of the same draws with the
// true powers: 8.5 % at 0.1, 0.5 % at 0.01). Power: the same draws plus a
// disturbance whose phasor turns by 0.6 rad per period (a hum 0.1 cycle per
// period off a line, at each line a random amplitude twice the noise's
// level): adjacent periods alike, the deviations' correlation well above
// −1/(R − 1) (p < 1e-6); R = 3 and J < 30 are not tested (p = 1).
TEST(GapDiagnosis, IndependentPeriodsTestHoldsItsLevel) {
  std::mt19937_64 g(2025);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> phase(0, 2 * M_PI);
  const auto cn = [&] { return cplx(normal(g), normal(g)) / std::sqrt(2.0); };
  auto draw = [&](int R, int K, bool unequal, double hum) {
    std::vector<double> power(static_cast<size_t>(R));
    for (int m = 0; m < R; ++m) power[static_cast<size_t>(m)] = unequal ? 0.4 + 1.2 * m / (R - 1.0) : 1.0;
    std::shuffle(power.begin(), power.end(), g);
    std::vector<cplx> x;
    for (int m = 0; m <= R; ++m) x.push_back(3.0 * cn());
    const double phi = phase(g);
    Eigen::MatrixXcd res(R, K);
    for (int k = 0; k < K; ++k) {
      const double level = std::exp(1.5 * std::sin(2 * M_PI * k / K + phi));
      const cplx error = 3.0 * cn(), amp = hum * level * cn();
      const cplx T = 1.0 / (1.0 - 0.68 * std::polar(1.0, -M_PI * k / K));
      for (int m = 0; m < R; ++m) {
        const auto i = static_cast<size_t>(m);
        res(m, k) = error + (x[i] - x[i + 1]) * T + level * std::sqrt(power[i]) * cn() +
                    amp * std::polar(1.0, 0.6 * m);
      }
    }
    std::vector<double> relative = period_power_test(res).relative;
    return period_independence_test(res, relative);
  };
  for (bool unequal : {false, true}) {
    int below_001 = 0, below_01 = 0;
    for (int i = 0; i < 1000; ++i) {
      const PeriodIndependenceTest t = draw(4 + i % 5, 400, unequal, 0.0);
      below_001 += t.p < 0.01;
      below_01 += t.p < 0.1;
    }
    std::printf("  null, %s powers: p < 0.01 in %d, p < 0.1 in %d of 1000\n", unequal ? "unequal" : "equal",
                below_001, below_01);
    EXPECT_LE(below_001, 20);
    EXPECT_LE(below_01, 132);
    if (!unequal) {
      EXPECT_GE(below_01, 68);
    }
  }
  for (int R : {4, 8}) {
    const PeriodIndependenceTest t = draw(R, 400, true, 2.0);
    EXPECT_LT(t.p, 1e-6) << "R = " << R << ": c " << t.correlation << " against " << t.expected;
    EXPECT_NEAR(t.expected, -1.0 / (R - 1), 0.02) << "R = " << R;
  }
  EXPECT_EQ(draw(3, 400, false, 1.0).p, 1.0);  // R = 3: c ≡ −1/2
  EXPECT_EQ(draw(6, 40, false, 1.0).p, 1.0);   // 20 pairs
}

// The diagnosis says so: an effect-free generated case (stationary noise) has
// no such note; the same case with periods 4 and 5's noise scaled by √2 and
// 1/√2 (power 2 and 1/2; its noise-free record is the case made without
// noise) gets it, with p(equal power) < effect_alpha.
TEST(GapDiagnosis, UnequalNoisePowerPerPeriodIsNoted) {
  GapCaseOptions o;
  o.strength = Strength::None;
  o.seed = 5;
  const GapCase c = make_gap_case(o);
  o.noise = false;
  const GapCase quiet = make_gap_case(o);
  const auto noted = [](const GapReport& r) {
    return std::any_of(r.notes.begin(), r.notes.end(),
                       [](const std::string& n) { return n.find("noise power differs between periods") != std::string::npos; });
  };
  const GapReport plain = diagnose_gap(c.sim_model, c.record, 1, c.meta);
  EXPECT_FALSE(noted(plain)) << plain.p_period_power;
  EXPECT_FALSE(plain.period_power_unequal());
  EXPECT_EQ(plain.period_power.size(), static_cast<size_t>(c.meta.periods - 1));
  Eigen::MatrixXd rec = c.record;
  const Eigen::Index P = c.meta.period;
  for (int m : {4, 5})
    rec.col(1).segment(m * P, P) = quiet.record.col(1).segment(m * P, P) +
                                   (m == 4 ? std::sqrt(2.0) : std::sqrt(0.5)) *
                                       (c.record.col(1).segment(m * P, P) - quiet.record.col(1).segment(m * P, P));
  const GapReport scaled = diagnose_gap(c.sim_model, rec, 1, c.meta);
  EXPECT_TRUE(noted(scaled)) << scaled.p_period_power;
  EXPECT_LT(scaled.p_period_power, scaled.options.effect_alpha);
  EXPECT_TRUE(scaled.period_power_unequal());
}


// What unequal noise power per period does to the tests (issue 17: the F-16's
// noise power changes by a factor 2.5 between periods). The report's note
// says they stay valid, if conservative (the reasoning at period_power in
// gap.cpp: each line's t is Student's t under unequal variances). Checked on
// 60 effect-free records of the plant whose 8 periods carry white noise of
// relative powers 0.4 … 1.6 (a 4× range, in a shuffled order; the first
// period neither the loudest nor the quietest):
//  - every line's p = P(F(2, 14) > t) below 0.01 on at most Bin(60·K, 0.01)'s
//    mean + 4 sd of the K = 38 excited lines of the 60 records (2280 lines:
//    mean 22.8, sd 4.75, so ≤ 41; a liberal test — t inflated by its
//    loudest period — would exceed it: twice the level, 45.6, is 4.8 sd);
//  - the mean gap over the records at most 1 + 4 sd of it under equal power
//    (gap_null_sd(8, 38) / √60 = 0.024);
//  - false alarms: three tests at alpha = 0.01, P(false alarm) ≤ 0.03,
//    P(Bin(60, 0.03) ≥ 8) = 4e-4 (as RightModelGivesGapOneAndFewFalseAlarms);
//  - the power test notes the spread in every record (its statistic S at
//    J = 128 line pairs, R = 7 periods of these powers: median 85, smallest
//    49 in 200 simulated draws, against χ²(6)'s 1e-3 point 22.5), and the
//    note says the tests hold, with the
//    dynamic model's transient test comparing shapes.
// Measured: 22 lines, mean gap 1.005, no false alarm, 60 of 60 noted.
TEST(GapDiagnosis, UnequalNoisePowerLeavesTheTestsValid) {
  const StateSpace g = pintelon_plant();
  const std::vector<double> power = {1.0, 1.6, 0.4, 1.2, 0.6, 1.4, 0.8, 1.0};
  ASSERT_EQ(power.size(), static_cast<size_t>(kM));
  int small_p = 0, lines_seen = 0, alarms = 0, noted = 0;
  double gap_sum = 0;
  const int runs = 60;
  for (int i = 0; i < runs; ++i) {
    RecordMeta meta;
    const Eigen::MatrixXd noisy = simulate_periodic_record(g, options(2000 + i), meta);
    const Eigen::MatrixXd clean = simulate_periodic_record(g, options(2000 + i, 0.0), meta);
    Eigen::MatrixXd rec = clean;
    for (int l = 0; l < kM; ++l)
      rec.col(1).segment(l * kP, kP) += std::sqrt(power[l]) * (noisy - clean).col(1).segment(l * kP, kP);
    const GapReport r = diagnose_gap(g, rec, 1, meta);
    for (double t : r.t_before) small_p += f2_survival(t, 2 * kM - 2) < 0.01;
    lines_seen += static_cast<int>(r.t_before.size());
    gap_sum += r.gap_before;
    if (!r.present.empty() || r.verdict != GapVerdict::NoGap) {
      ++alarms;
      std::printf("  false alarm: %s\n", verdict(r).c_str());
    }
    if (r.period_power_unequal()) {
      ++noted;
      const bool says = std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
        return n.find("leaves the gap, band and effect tests valid, if anything conservative") != std::string::npos &&
               n.find("compares the shape") != std::string::npos;
      });
      EXPECT_TRUE(says) << "record " << i;
    }
  }
  ASSERT_EQ(lines_seen, runs * static_cast<int>(lines().size()));
  const double mean = 0.01 * lines_seen, sd = std::sqrt(lines_seen * 0.01 * 0.99);
  std::printf("  lines with p < 0.01: %d of %d (null mean %.1f); mean gap %.3f; noted %d of %d\n", small_p,
              lines_seen, mean, gap_sum / runs, noted, runs);
  EXPECT_LE(small_p, mean + 4 * sd);
  EXPECT_LE(gap_sum / runs, 1.0 + 4 * gap_null_sd(kM, static_cast<int>(lines().size())) / std::sqrt(double(runs)));
  EXPECT_LE(alarms, 7);
  EXPECT_EQ(noted, runs);
}

// The nonlinearity's term is one term, the same in every period: computed
// from the mean period (x̄ = IFFT(G Ū) for a static polynomial at the output),
// it moves each line's mean residual and leaves its period-to-period scatter
// as the model as given has it. Until stop 56 the output and input forms used
// each period's own input; the scatter then carried the term's period-to-
// period variation, which a joint fit could inflate: a new user's F-16
// order-10 model on Level 7 read "explained" at gap 1.4e-3 (mode_mismatch
// moved the 7.35 Hz mode to 2e-6 Hz, the output polynomial's per-period terms
// raised the lines' scatter 1e7–1e8 times while their mean residual fell to
// 0.3 of the model's; now "not fully explained", 2.2e4). Here an output cubic
// with 2 % noise on the recorded input, so that each period's input differs:
// t(k) after the effect is recomputed from the record, the model and the
// reported a₂, a₃ with the scatter of Y_l − G U_l alone. Tolerance: t is a
// ratio of the mean residual's square to the scatter; the mean residual is a
// difference of spectra about 150 times larger (the gap before, 2e4, is its
// square), so its relative rounding is at most u · 150 · (log2 P = 9 FFT
// stages + M = 8 period sums) · 10 (a stated constant) ≈ 3e-12 relative in
// each, 6e-12 in t: 1e-10 relative.
TEST(GapDiagnosis, ANonlinearityTermIsTheSameInEveryPeriod) {
  const StateSpace g = pintelon_plant();
  RecordOptions o = options(10, 0.0);
  o.input_noise_std = 0.02;
  RecordMeta meta;
  const Eigen::MatrixXd rec = with_output(simulate_periodic_record(g, o, meta), 10,
                                          [](double, double y) { return y + 0.02 * y * y * y; });
  const GapReport r = diagnose_gap(g, rec, 1, meta);
  SCOPED_TRACE(verdict(r));
  ASSERT_EQ(names(r.present), std::vector<std::string>{"nonlinearity"});
  ASSERT_EQ(param(r, "nonlinearity", "at_input"), 0.0);
  ASSERT_EQ(param(r, "nonlinearity", "in_loop"), 0.0);
  const double a2 = param(r, "nonlinearity", "a2"), a3 = param(r, "nonlinearity", "a3");
  const int first = kM - r.periods_used, M = r.periods_used;
  numerics::UnitaryFft fft(kP);
  constexpr int kLines = kP / 2 + 1;  // UnitaryFft::forward returns the lines 0 … P/2 of a real signal
  Eigen::MatrixXcd U(kLines, M), Y(kLines, M);  // unitary DFTs of each used period (x̄'s scale is the time signal's)
  for (int l = 0; l < M; ++l) {
    U.col(l) = fft.forward(Eigen::VectorXd(rec.col(0).segment((first + l) * kP, kP)));
    Y.col(l) = fft.forward(Eigen::VectorXd(rec.col(1).segment((first + l) * kP, kP)));
  }
  Eigen::VectorXcd G(kLines);
  for (int k = 0; k < kLines; ++k) G(k) = transfer(g, std::polar(1.0, 2 * M_PI * k / kP))(0, 0);
  const Eigen::VectorXd x = fft.inverse(G.cwiseProduct(U.rowwise().mean()));
  const Eigen::VectorXcd N = a2 * fft.forward(Eigen::VectorXd(x.array().square())) +
                             a3 * fft.forward(Eigen::VectorXd(x.array().cube()));
  ASSERT_EQ(r.t_after.size(), static_cast<Eigen::Index>(lines().size()));
  for (size_t i = 0; i < lines().size(); ++i) {
    const int k = lines()[i];
    const Eigen::VectorXcd e = Y.row(k).transpose() - G(k) * U.row(k).transpose() - Eigen::VectorXcd::Constant(M, N(k));
    const std::complex<double> m = e.mean();
    const double var = (e.array() - m).abs2().sum() / (M - 1), t = M * std::norm(m) / var;
    EXPECT_NEAR(r.t_after(i), t, 1e-10 * t) << "line " << k;
  }
}

}  // namespace
}  // namespace fdsid
