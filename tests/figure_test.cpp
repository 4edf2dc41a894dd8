// Pintelon (2002) Section 6.1, Figs. 1b and 2b, as statistical tests of
// fdsid::reproduce_pintelon_figure (fast/include/fdsid/paper.hpp).
//
// Claim (Eq. 30): without model errors (n_a = 4, M = 7) the ratio
//   std(G(θ̂_S)) / std(G(θ̂))   (sample-subspace over subspace estimate)
// lies in [1, √((M − 2)/(M − 3))] = [1, √(5/4)] = [1, 1.118].
//
// Monte Carlo margin δ: each std is a sample std over N_r complex values, with
// relative standard error ≈ 1/√(2 N_r) (chi distribution with 2 N_r real
// degrees of freedom, first order). The ratio of two such has relative standard
// error at most √2 · 1/√(2 N_r) = 1/√N_r (equality for independent numerator and
// denominator; they share the data, so positively correlated, which only
// shrinks it). With the ratio ≤ 1.118 its standard error is ≤ 1.118/√N_r.
// δ = 4 standard errors: the two-sided normal tail beyond 4 SE is 6.3e-5 per
// frequency. The median over the 999 frequencies exceeds b + δ only if at least
// half of the frequencies do, so by Markov's inequality its failure
// probability is at most 2 × 6.3e-5 whatever the correlation between
// frequencies: the median is at least as reliable as one frequency.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "fdsid/paper.hpp"

namespace fdsid {
namespace {

double median(const Eigen::VectorXd& v) {
  std::vector<double> x(v.data(), v.data() + v.size());
  std::sort(x.begin(), x.end());
  const size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

constexpr int kRuns = 1000;
constexpr std::uint64_t kSeed = 20020601;

/// δ = 4 standard errors of one ratio near the bound (see the file comment).
double monte_carlo_margin(int runs, double bound) { return 4.0 * bound / std::sqrt(static_cast<double>(runs)); }

FigureResult run(int order, int runs, int threads) {
  FigureOptions o;
  o.runs = runs;
  o.seed = kSeed;
  o.order = order;
  o.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  FigureResult r = reproduce_pintelon_figure(o);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("reproduce_pintelon_figure(order %d, runs %d, threads %d): %.2f s, %d runs ok, %d failed, median ratio %.4f\n",
              order, runs, threads, s, r.runs, r.failures, r.median_ratio);
  return r;
}

TEST(PintelonFigure1, MedianRatioWithinEq30BoundWithoutModelErrors) {
  const FigureResult r = run(4, kRuns, 0);
  const double bound = std::sqrt(5.0 / 4.0);  // Eq. (30), M = 7
  ASSERT_NEAR(r.bound, bound, 4 * 0x1p-53 * bound);
  ASSERT_EQ(r.ratio.size(), 999);
  // Failed runs shrink the effective N_r: the margin is taken with the runs that succeeded.
  ASSERT_GE(r.runs, kRuns * 9 / 10) << "more than 10% of the Monte Carlo runs failed: " << r.failures;
  const double delta = monte_carlo_margin(r.runs, bound);
  const double med = median(r.ratio);
  EXPECT_DOUBLE_EQ(med, r.median_ratio);
  EXPECT_GE(med, 1.0 - delta) << "delta = " << delta;
  EXPECT_LE(med, bound + delta) << "delta = " << delta;
  std::printf("fig1: median %.4f in [%.4f, %.4f] (delta %.4f)\n", med, 1.0 - delta, bound + delta, delta);
}

TEST(PintelonFigure2, MedianRatioExceedsBoundWithModelErrors) {
  const FigureResult r = run(1, kRuns, 0);
  const double bound = std::sqrt(5.0 / 4.0);
  ASSERT_EQ(r.ratio.size(), 999);
  ASSERT_GE(r.runs, kRuns * 9 / 10) << "more than 10% of the Monte Carlo runs failed: " << r.failures;
  // With model errors the ratio is larger than the bound, so its standard
  // error is ≤ ratio / √N_r; the one-sided 4-SE test uses that of the median.
  const double med = median(r.ratio);
  const double delta = 4.0 * med / std::sqrt(static_cast<double>(r.runs));
  EXPECT_GT(med, bound + delta) << "delta = " << delta << " (the paper: the ratio is much larger than the bound)";
  std::printf("fig2: median %.4f > %.4f (bound %.4f + delta %.4f)\n", med, bound + delta, bound, delta);
}

TEST(PintelonFigure, IndependentOfThreadCount) {
  // paper.hpp: run i draws from its own generator seeded by (seed, i) and the
  // block sums are merged in block order, so the result is bitwise the same.
  for (int order : {4, 1}) {
    const FigureResult one = run(order, 64, 1);
    const FigureResult two = run(order, 64, 2);
    ASSERT_EQ(one.ratio.size(), two.ratio.size());
    EXPECT_EQ(one.runs, two.runs);
    for (Eigen::Index k = 0; k < one.ratio.size(); ++k) {
      ASSERT_EQ(one.ratio(k), two.ratio(k)) << "order " << order << ", frequency index " << k;
      ASSERT_EQ(one.std_subspace(k), two.std_subspace(k)) << "order " << order << ", frequency index " << k;
    }
    EXPECT_EQ(one.median_ratio, two.median_ratio);
  }
}

}  // namespace
}  // namespace fdsid
