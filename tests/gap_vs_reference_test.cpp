// fast/'s gap statistic (FFTW DFTs, LU transfer, double) against the 50-digit
// reference (direct DFT sums; reference/src/gap.cpp): t(k) on every excited
// line and the gap, for the model as given and for the effects the diagnosis
// fitted, rebuilt in 50 digits from their reported parameters.
#include <gtest/gtest.h>

#include <cmath>
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
// G U, each off by at most c u (|Y_l| + |G U_l|) with c = 4 (log2 P + n + 4)
// (FFT depth, the LU solve of order n for G, the subtraction); hence
// δt/t ≤ c u S (2/|Ē| + 2/s), S = max_l (|Y_l| + |G U_l|), s = √s².
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

}  // namespace
}  // namespace fdsid
