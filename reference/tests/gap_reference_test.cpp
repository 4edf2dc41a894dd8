// Tests of the high-precision reference of the sim-to-real gap statistic
// (reference/gap): a case done by hand, records with a closed-form t, the
// invariances of t, the p-value against Boost.Math's F distribution, the
// records CSV reader, and the input checks.
//
// Tolerances. u = std::numeric_limits<Real>::epsilon() ≈ 1e-50 is the unit
// roundoff of the 50-digit format. Every input below is exact (integers,
// decimals parsed from strings, or cosines computed in Real), and the only
// rounding is in the twiddles cos/sin(2πq/P), the DFT sums and the few
// operations after them: the residuals carry an absolute error of about
// √P·u·max|sample| and t a relative error of that over the spread of the
// residuals across periods. For the records here (|sample| ≤ 20, P ≤ 32,
// spread ≥ 0.1) that is ≲ 1e-46; the tests demand 1e-40 relative, six orders
// of margin, and 40 correct digits is what "oracle" means here.
#include "fdsid/reference/gap.hpp"

#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/io.hpp"
#include "test_support.hpp"

#include <boost/math/constants/constants.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace gap_reference_test {  // named: the reference_test binary is one unit (reference/CMakeLists.txt)

using namespace fdsid::reference;

const Real u = std::numeric_limits<Real>::epsilon();
const Real pi = boost::math::constants::pi<Real>();
const Real tol("1e-40");  // relative; derivation in the file comment

using test::sci;

Real rel(const Real& got, const Real& want) { return abs(got - want) / abs(want); }

// ---------------------------------------------------------------------------
// 1. By hand: P = 4, M = 3, line 1 (excited) and line 2 (unexcited).
//
// With P = 4 the twiddles e^{−j2πkt/4} are exact units, so
//   Z(1) = ½[(z0 − z2) + j(z3 − z1)],   Z(2) = ½(z0 − z1 + z2 − z3).
// Periods (u | y):
//   l = 0: u = (1, 0, −1, 0)   y = (3, 1, −1, 0)
//   l = 1: u = (2, 0, 0, 0)    y = (2, −1, −2, 1)
//   l = 2: u = (1, −1, −1, 0)  y = (1, 0, −3, 1)
// Line 1, G′(1) = 2 − j:
//   U = 1, 1, 1 + ½j;   Y = 2 − ½j, 2 + j, 2 + ½j;
//   G′U = 2 − j, 2 − j, (2 − j)(1 + ½j) = 2.5
//   E = ½j, 2j, −½ + ½j;   Ē = (−½ + 3j)/3 = −1/6 + j,  |Ē|² = 37/36
//   E − Ē = 1/6 − ½j, 1/6 + j, −1/3 − ½j:  |.|² = 10/36, 37/36, 13/36, Σ = 5/3
//   s² = (5/3)/2 = 5/6;  t = 3 (37/36)/(5/6) = 37/10;  p = (1 + 3.7/2)^−2 = 1/8.1225
//   gap (K = 1) = (1/2)·3.7 = 1.85
// Line 2, G′(2) = 1:
//   U = 0, 1, ½;   Y = ½, 0, −3/2;   E = ½, −1, −2;   Ē = −5/6, |Ē|² = 25/36
//   E − Ē = 4/3, −1/6, −7/6:  |.|² = 64/36, 1/36, 49/36, Σ = 19/6;  s² = 19/12
//   t = 3 (25/36)/(19/12) = 25/19;  p = (1 + 25/38)^−2 = (38/63)² = 1444/3969
// Both lines excited: gap = (1/2)(37/10 + 25/19)/2 = 953/760.
// ---------------------------------------------------------------------------
struct HandRecord {
  std::vector<Real> u{1, 0, -1, 0, 2, 0, 0, 0, 1, -1, -1, 0};
  std::vector<Real> y{3, 1, -1, 0, 2, -1, -2, 1, 1, 0, -3, 1};
  std::function<Complex(int)> response = [](int k) {
    return k == 1 ? Complex(Real(2), Real(-1)) : Complex(Real(1), Real(0));
  };
};

TEST(GapReference, HandComputedCase) {
  const HandRecord r;
  const GapStatistic g = gap_statistic(r.u, r.y, 4, 3, {1}, {2}, r.response);
  ASSERT_EQ(g.M, 3);
  ASSERT_EQ(g.excited.t.size(), 1u);
  ASSERT_EQ(g.unexcited.t.size(), 1u);
  EXPECT_EQ(g.excited.lines, std::vector<int>{1});
  EXPECT_EQ(g.unexcited.lines, std::vector<int>{2});
  std::printf("hand case: t(1) = %s, t(2) = %s, gap = %s\n", g.excited.t[0].str(45).c_str(),
              g.unexcited.t[0].str(45).c_str(), g.gap.str(45).c_str());
  EXPECT_LT(abs(g.excited.mean_residual[0] - Complex(-Real(1) / 6, Real(1))), tol);
  EXPECT_LT(rel(g.excited.variance[0], Real(5) / 6), tol);
  EXPECT_LT(rel(g.excited.t[0], Real("3.7")), tol);
  EXPECT_LT(rel(g.excited.p[0], 1 / Real("8.1225")), tol);
  EXPECT_LT(rel(g.gap, Real("1.85")), tol);
  EXPECT_LT(abs(g.unexcited.mean_residual[0] - Complex(-Real(5) / 6, Real(0))), tol);
  EXPECT_LT(rel(g.unexcited.variance[0], Real(19) / 12), tol);
  EXPECT_LT(rel(g.unexcited.t[0], Real(25) / 19), tol);
  EXPECT_LT(rel(g.unexcited.p[0], Real(1444) / 3969), tol);

  const GapStatistic both = gap_statistic(r.u, r.y, 4, 3, {1, 2}, {}, r.response);
  EXPECT_TRUE(both.unexcited.t.empty());
  EXPECT_LT(rel(both.excited.t[1], Real(25) / 19), tol);
  EXPECT_LT(rel(both.gap, Real(953) / 760), tol);
}

// ---------------------------------------------------------------------------
// 2. Exact model response plus per-period offsets with a closed-form t.
//
// u(t) = Σ_{k∈K} A_k cos(2πkt/P + φ_k) (periodic), y = steady-state response
// Σ A_k Re(G(k) e^{j(2πkt/P + φ_k)}) plus, at each line k of both lists and in
// period l, n_l(t) = a_lk cos(2πkt/P) + b_lk sin(2πkt/P). For 0 < k < P/2,
// Eq. (4) gives DFT[cos] = √P/2 and DFT[sin] = −j√P/2 at line k and 0 at every
// other line 1 … P/2 − 1, so with the true G the residual is exactly the
// noise line: E_l(k) = (√P/2)(a_lk − j b_lk) (at unexcited lines U_l = 0). Then
//   Ē(k) = (√P/2)(ā − j b̄),  s²(k) = (P/4)·Σ_l[(a_l − ā)² + (b_l − b̄)²]/(M − 1),
//   t(k) = M(ā² + b̄²)(M − 1) / Σ_l[(a_l − ā)² + (b_l − b̄)²]
// (the √P/2 cancels in t; Ē and s² check the 1/√P scaling of Eq. 4). Done for
// a discrete first-order model and a continuous one (line k at
// ω = 2πk/(P·Ts) rad/s): evaluating G at the wrong frequency would leave
// (G − G_wrong)U in E and break t by O(1).
// ---------------------------------------------------------------------------
constexpr int kP = 32, kM = 5;
const std::vector<int> kExcited{1, 3, 4, 7}, kUnexcited{2, 5, 9};

// Exact rationals, different per period and line; lines 3 and 5 carry a
// large mean (t ≫ 1), the others are centred near 0 (t = O(1)).
Real noise_a(int l, int k) {
  const Real offset = k == 3 ? Real(2) : k == 5 ? Real(-1) : Real(0);
  return offset + Real(((3 * l + 5 * k + 1) * (l + 2)) % 7 - 3) / 8;
}
Real noise_b(int l, int k) {
  const Real offset = k == 5 ? Real("0.75") : Real(0);
  return offset + Real(((2 * l + 3 * k + 2) * (k + 1 + l)) % 5 - 2) / 16;
}

Model first_order(const std::string& domain) {
  Model model;
  model.domain = domain;
  model.A = MatrixR::Constant(1, 1, domain == "discrete" ? Real("0.8") : Real(-3));
  model.B = MatrixR::Constant(1, 1, Real(1));
  model.C = MatrixR::Constant(1, 1, Real("0.5") * (domain == "discrete" ? 1 : 4));
  model.D = MatrixR::Constant(1, 1, Real("0.25"));
  return model;
}

// G of first_order written out: D + c/(ξ − a), independent of frequency_response.
Complex first_order_response(const Model& model, int k, const Real& Ts) {
  const Real omega = 2 * pi * k / kP;
  const Complex xi = model.domain == "discrete" ? Complex(cos(omega), sin(omega))
                                                : Complex(Real(0), omega / Ts);
  return Complex(model.D(0, 0)) + Complex(model.C(0, 0)) / (xi - Complex(model.A(0, 0)));
}

struct Record {
  std::vector<Real> u, y;
};

// Steady-state multisine record through `model` (exact response), plus the
// per-period noise lines of noise_a/noise_b when `with_noise`.
Record multisine_record(const Model& model, const Real& Ts, bool with_noise) {
  Record r;
  r.u.assign(kP * kM, Real(0));
  r.y.assign(kP * kM, Real(0));
  for (std::size_t i = 0; i < kExcited.size(); ++i) {
    const int k = kExcited[i];
    const Real A = 1 + Real(static_cast<int>(i)) / 2;
    const Real phi = Real("0.9") * Real(static_cast<int>(i * i) + 1);
    const Complex G = first_order_response(model, k, Ts);
    for (int n = 0; n < kP * kM; ++n) {
      const Real angle = 2 * pi * Real((static_cast<long long>(k) * n) % kP) / kP + phi;
      const Complex e(cos(angle), sin(angle));
      r.u[n] += A * e.real();
      r.y[n] += A * (G * e).real();
    }
  }
  if (with_noise) {
    std::vector<int> all = kExcited;
    all.insert(all.end(), kUnexcited.begin(), kUnexcited.end());
    for (int k : all)
      for (int l = 0; l < kM; ++l)
        for (int t = 0; t < kP; ++t) {
          const Real angle = 2 * pi * Real((k * t) % kP) / kP;
          r.y[l * kP + t] += noise_a(l, k) * cos(angle) + noise_b(l, k) * sin(angle);
        }
  }
  return r;
}

struct Closed {
  Complex mean;
  Real variance, t;
};

Closed closed_form(int k) {
  Real a_bar = 0, b_bar = 0;
  for (int l = 0; l < kM; ++l) {
    a_bar += noise_a(l, k);
    b_bar += noise_b(l, k);
  }
  a_bar /= kM;
  b_bar /= kM;
  Real spread = 0;
  for (int l = 0; l < kM; ++l)
    spread += (noise_a(l, k) - a_bar) * (noise_a(l, k) - a_bar) +
              (noise_b(l, k) - b_bar) * (noise_b(l, k) - b_bar);
  EXPECT_GT(spread, 0) << "line " << k;
  const Real half_root_P = sqrt(Real(kP)) / 2;
  Closed c;
  c.mean = Complex(half_root_P * a_bar, -half_root_P * b_bar);
  c.variance = half_root_P * half_root_P * spread / (kM - 1);
  c.t = Real(kM) * (a_bar * a_bar + b_bar * b_bar) * (kM - 1) / spread;
  return c;
}

void check_closed_form(const std::string& domain, const Real& Ts) {
  const Model model = first_order(domain);
  const Record r = multisine_record(model, Ts, true);
  const GapStatistic g = gap_statistic(r.u, r.y, kP, kM, kExcited, kUnexcited, model, Ts);
  Real worst = 0, t_sum = 0;
  int worst_line = 0;
  auto check = [&](const LineStatistics& s) {
    for (std::size_t i = 0; i < s.lines.size(); ++i) {
      const Closed c = closed_form(s.lines[i]);
      const Real e = std::max({rel(s.t[i], c.t), abs(s.mean_residual[i] - c.mean) / abs(c.mean),
                               rel(s.variance[i], c.variance),
                               rel(s.p[i], pow(1 + c.t / (kM - 1), -Real(kM - 1)))});
      if (e > worst) {
        worst = e;
        worst_line = s.lines[i];
      }
    }
  };
  check(g.excited);
  check(g.unexcited);
  for (int k : kExcited) t_sum += closed_form(k).t;
  const Real gap = Real(kM - 2) / (kM - 1) * t_sum / Real(static_cast<int>(kExcited.size()));
  std::printf("%s: worst relative error %s at line %d (tolerance %s), gap = %s\n", domain.c_str(),
              sci(worst).c_str(), worst_line, sci(tol).c_str(), sci(g.gap).c_str());
  EXPECT_LT(worst, tol) << domain << ", line " << worst_line;
  EXPECT_LT(rel(g.gap, gap), tol) << domain;
}

TEST(GapReference, ClosedFormDiscreteModel) { check_closed_form("discrete", Real(1)); }

TEST(GapReference, ClosedFormContinuousModel) { check_closed_form("continuous", Real("0.125")); }

// The Model overload and the callback with the model written out agree, and a
// continuous model is evaluated at 2πk/(P·Ts), not 2πk/P: with Ts ignored the
// residual keeps (G(jω/Ts) − G(jω))U and t changes by orders of magnitude.
TEST(GapReference, ModelOverloadMatchesCallback) {
  const Real Ts("0.125");
  const Model model = first_order("continuous");
  const Record r = multisine_record(model, Ts, true);
  const GapStatistic by_model = gap_statistic(r.u, r.y, kP, kM, kExcited, kUnexcited, model, Ts);
  const GapStatistic by_callback = gap_statistic(
      r.u, r.y, kP, kM, kExcited, kUnexcited,
      [&](int k) { return first_order_response(model, k, Ts); });
  for (std::size_t i = 0; i < kExcited.size(); ++i)
    EXPECT_LT(rel(by_model.excited.t[i], by_callback.excited.t[i]), tol);
  const GapStatistic wrong_Ts = gap_statistic(r.u, r.y, kP, kM, kExcited, kUnexcited, model, Real(1));
  Real change = 0;
  for (std::size_t i = 0; i < kExcited.size(); ++i)
    change = std::max(change, rel(wrong_Ts.excited.t[i], by_model.excited.t[i]));
  std::printf("Ts ignored: largest relative change of t %s\n", sci(change).c_str());
  EXPECT_GT(change, 1);
}

// ---------------------------------------------------------------------------
// 3. Invariances. Record: the discrete multisine plus pseudo-random noise on
// every sample (exact dyadic rationals of size ≤ 0.125, fixed seed).
//  (a) u, y → c·u, c·y: E → c·E, so Ē → cĒ, s² → c²s², t unchanged;
//  (b) y → y + w, w the same in every period and at unexcited line 5 only:
//      the DFT of w is 0 at every other line 1 … P/2 − 1 (orthogonality), so
//      t at the excited lines is unchanged, and at line 5 Ē gains
//      W = (√P/2)·3e^{j0.4} while s² is unchanged (w is identical in every
//      period): t(5) = M|Ē + W|²/s²;
//  (c) control: the same w at excited line 3 changes t(3) (Ē gains W there).
// Rounding: |c| = 2.75 and |w| ≤ 3 keep the samples ≤ 20, spread ≥ 0.1.
// ---------------------------------------------------------------------------
Record noisy_record() {
  Record r = multisine_record(first_order("discrete"), Real(1), false);
  std::mt19937_64 rng(20240611);
  for (auto& v : r.y) v += Real(static_cast<long long>(rng() % (1 << 20)) - (1 << 19)) / (1 << 22);
  return r;
}

TEST(GapReference, InvariantUnderCommonScaling) {
  const Model model = first_order("discrete");
  const Record r = noisy_record();
  const GapStatistic base = gap_statistic(r.u, r.y, kP, kM, kExcited, kUnexcited, model, Real(1));
  Record scaled = r;
  const Real c("-2.75");
  for (auto& v : scaled.u) v *= c;
  for (auto& v : scaled.y) v *= c;
  const GapStatistic g = gap_statistic(scaled.u, scaled.y, kP, kM, kExcited, kUnexcited, model, Real(1));
  Real worst = 0;
  for (std::size_t i = 0; i < kExcited.size(); ++i) worst = std::max(worst, rel(g.excited.t[i], base.excited.t[i]));
  for (std::size_t i = 0; i < kUnexcited.size(); ++i)
    worst = std::max(worst, rel(g.unexcited.t[i], base.unexcited.t[i]));
  std::printf("scaling by %s: worst relative change of t %s (tolerance %s), gap = %s\n",
              sci(c).c_str(), sci(worst).c_str(), sci(tol).c_str(), sci(base.gap).c_str());
  EXPECT_LT(worst, tol);
  EXPECT_LT(rel(g.gap, base.gap), tol);
  EXPECT_LT(rel(g.excited.variance[0], c * c * base.excited.variance[0]), tol);
}

TEST(GapReference, PeriodicSignalAtUnexcitedLineOnlyChangesThatLine) {
  const Model model = first_order("discrete");
  const Record r = noisy_record();
  const GapStatistic base = gap_statistic(r.u, r.y, kP, kM, kExcited, kUnexcited, model, Real(1));
  auto add_line = [&](int k) {
    Record out = r;
    for (int n = 0; n < kP * kM; ++n)
      out.y[n] += 3 * cos(2 * pi * Real((k * n) % kP) / kP + Real("0.4"));
    return out;
  };
  const Complex W = sqrt(Real(kP)) / 2 * 3 * Complex(cos(Real("0.4")), sin(Real("0.4")));

  const Record at5 = add_line(5);
  const GapStatistic g = gap_statistic(at5.u, at5.y, kP, kM, kExcited, kUnexcited, model, Real(1));
  Real worst = 0;
  for (std::size_t i = 0; i < kExcited.size(); ++i) worst = std::max(worst, rel(g.excited.t[i], base.excited.t[i]));
  std::printf("periodic line 5: worst relative change of excited t %s (tolerance %s)\n",
              sci(worst).c_str(), sci(tol).c_str());
  EXPECT_LT(worst, tol);
  EXPECT_LT(rel(g.gap, base.gap), tol);
  const std::size_t i5 = 1;  // kUnexcited = {2, 5, 9}
  ASSERT_EQ(g.unexcited.lines[i5], 5);
  const Real t5 = Real(kM) * std::norm(base.unexcited.mean_residual[i5] + W) / base.unexcited.variance[i5];
  EXPECT_LT(rel(g.unexcited.variance[i5], base.unexcited.variance[i5]), tol);
  EXPECT_LT(rel(g.unexcited.t[i5], t5), tol);
  EXPECT_GT(g.unexcited.t[i5], 100 * base.unexcited.t[i5]);  // the detector sees it
  EXPECT_LT(rel(g.unexcited.t[0], base.unexcited.t[0]), tol);
  EXPECT_LT(rel(g.unexcited.t[2], base.unexcited.t[2]), tol);

  // Control: at an excited line the same signal is model error and moves t.
  const Record at3 = add_line(3);
  const GapStatistic h = gap_statistic(at3.u, at3.y, kP, kM, kExcited, kUnexcited, model, Real(1));
  EXPECT_GT(rel(h.excited.t[1], base.excited.t[1]), Real("1e-3"));
}

// ---------------------------------------------------------------------------
// 4. Input checks.
// ---------------------------------------------------------------------------
TEST(GapReference, InputErrors) {
  const HandRecord r;
  EXPECT_NO_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {2}, r.response));
  std::vector<Real> short_u(r.u.begin(), r.u.end() - 1);
  EXPECT_THROW(gap_statistic(short_u, r.y, 4, 3, {1}, {2}, r.response), InputError);  // size ≠ P·M
  EXPECT_THROW(gap_statistic(r.u, short_u, 4, 3, {1}, {2}, r.response), InputError);
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 2, {1}, {2}, r.response), InputError);  // size ≠ P·M
  EXPECT_THROW(gap_statistic(r.u, r.y, 6, 2, {1}, {2}, r.response), InputError);  // M = 2 < 3
  EXPECT_THROW(gap_statistic(r.u, r.y, 12, 1, {1}, {2}, r.response), InputError);  // M = 1
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {0}, {2}, r.response), InputError);   // line 0 (DC)
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {3}, {}, r.response), InputError);    // line > P/2
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {3}, r.response), InputError);   // unexcited > P/2
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1, 1}, {}, r.response), InputError); // repeated
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {1}, r.response), InputError);   // in both lists
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {}, {2}, r.response), InputError);    // no excited line
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {2}, std::function<Complex(int)>()), InputError);
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {2},
                             [](int) { return Complex(std::numeric_limits<Real>::infinity()); }),
               InputError);
  // s²(k) == 0: a record with no variation over the periods (all zeros).
  const std::vector<Real> zeros(12, Real(0));
  try {
    gap_statistic(zeros, zeros, 4, 3, {1}, {}, r.response);
    ADD_FAILURE() << "no InputError for s^2 = 0";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 1"), std::string::npos) << e.what();
  }
  // Model overload: non-SISO model, continuous with Ts ≤ 0, unknown domain.
  Model two = first_order("discrete");
  two.B = MatrixR::Constant(1, 2, Real(1));
  two.D = MatrixR::Constant(1, 2, Real(0));
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {}, two, Real(1)), InputError);
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {}, first_order("continuous"), Real(0)), InputError);
  Model odd = first_order("discrete");
  odd.domain = "sampled";
  EXPECT_THROW(gap_statistic(r.u, r.y, 4, 3, {1}, {}, odd, Real(1)), InputError);
  EXPECT_THROW(gap_p_value(Real(1), 1), InputError);
  EXPECT_THROW(gap_p_value(Real(-1), 3), InputError);
}

// ---------------------------------------------------------------------------
// 5. p(k) = (1 + t/(M−1))^{−(M−1)} against Boost.Math's F(2, 2M−2): the
// complement of the cdf (an incomplete beta function, computed by Boost in
// the same 50-digit type, documented to a few hundred ε), and the pdf against
// a central difference of p (step h = 1e-12: truncation h²·|p'''|/6 ≲ 1e-23,
// cancellation u/h ≈ 1e-38, so 1e-20 relative). Also p(0) = 1 exactly.
// ---------------------------------------------------------------------------
TEST(GapReference, PValueIsFisherSurvivalFunction) {
  const Real h("1e-12");
  Real worst_cdf = 0, worst_pdf = 0;
  for (int M : {3, 4, 10, 64})
    for (const char* text : {"0.01", "0.5", "1", "3.7", "20", "200"}) {
      const Real t(text);
      const boost::math::fisher_f_distribution<Real> F(2, 2 * M - 2);
      const Real p = gap_p_value(t, M);
      const Real boost_p = cdf(complement(F, t));
      const Real density = -(gap_p_value(t + h, M) - gap_p_value(t - h, M)) / (2 * h);
      worst_cdf = std::max(worst_cdf, rel(p, boost_p));
      worst_pdf = std::max(worst_pdf, rel(density, pdf(F, t)));
      EXPECT_LT(rel(p, boost_p), tol) << "M = " << M << ", t = " << text;
      EXPECT_LT(rel(density, pdf(F, t)), Real("1e-20")) << "M = " << M << ", t = " << text;
    }
  std::printf("p vs Boost F(2, 2M-2): worst relative error %s (tolerance %s); density %s (1e-20)\n",
              sci(worst_cdf).c_str(), sci(tol).c_str(), sci(worst_pdf).c_str());
  EXPECT_EQ(gap_p_value(Real(0), 5), Real(1));
  // F(2, 2M−2) has mean (M−1)/(M−2): the median of t is far below it for small M.
  EXPECT_LT(gap_p_value(Real(2), 3), Real("0.25") + u);  // (1 + 2/2)^−2 = 1/4 exactly
  EXPECT_GT(gap_p_value(Real(2), 3), Real("0.25") - u);
}

// ---------------------------------------------------------------------------
// read_records_csv: exact decimals, blank lines, bad header / cell / row.
// ---------------------------------------------------------------------------
void write_file(const std::string& path, const char* text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs(text, f);
  std::fclose(f);
}

TEST(GapReference, ReadRecordsCsv) {
  const std::string path = ::testing::TempDir() + "gap_reference_test.csv";
  write_file(path, "u,y\n0.1,0.8876\n\n-1.5e-1, 3\r\n");
  const Records rec = read_records_csv(path);
  ASSERT_EQ(rec.u.size(), 2u);
  ASSERT_EQ(rec.y.size(), 2u);
  EXPECT_EQ(rec.u[0], Real("0.1"));
  EXPECT_EQ(rec.y[0], Real("0.8876"));  // not the double 0.8876
  EXPECT_NE(rec.y[0], Real(0.8876));
  EXPECT_EQ(rec.u[1], Real("-0.15"));
  EXPECT_EQ(rec.y[1], Real(3));
  for (const char* bad : {"u1,y1\n1,2\n", "u,y\n1\n", "u,y\n1,2,3\n", "u,y\n1,abc\n", "u,y\n", "u,y\n1,nan\n"}) {
    write_file(path, bad);
    EXPECT_THROW(read_records_csv(path), InputError) << bad;
  }
  std::remove(path.c_str());
  EXPECT_THROW(read_records_csv(path), InputError);  // missing file
}

// The period tests by hand (gap.hpp): R = 4 periods, J = 30 line pairs, every
// pair with r(2j) = (3, 0, 0, 0) over the periods and r(2j+1) = 0, so
// e = (3, 0, 0, 0), ē = 3/4, d = (9/4, −3/4, −3/4, −3/4), Σ|d|² = 27/4:
//   q = (3/4, 1/12, 1/12, 1/12) in every pair, Q = q, relative = 4q = (3, 1/3, 1/3, 1/3);
//   v = (1/4) Σ (q − 1/4)² = (1/4)(1/4 + 3/36) = 1/12;
//   S = J (R − 1)/(v R) Σ (Q − 1/4)² = 30 · 3 · 12/4 · (1/3) = 90;
//   p = Q(3/2, 45) = P[χ²₃ > 90];
//   c = (d₀d₁ + d₁d₂ + d₂d₃ + d₃d₀)/Σ|d|² = (−27 + 9 + 9 − 27)/16 / (27/4) = −1/3
// in every pair (mean −1/3 = −1/(R − 1), variance 0). Rows of a line pair
// whose differences are all equal (d = 0) are left out: 5 such pairs added
// change nothing.
TEST(GapReference, PeriodTestsByHand) {
  std::vector<std::vector<Complex>> r(4, std::vector<Complex>(70, Complex(Real(0), Real(0))));
  for (int j = 0; j < 30; ++j) r[0][static_cast<std::size_t>(2 * j)] = Complex(Real(3), Real(0));
  for (int j = 30; j < 35; ++j)
    for (auto& row : r) row[static_cast<std::size_t>(2 * j)] = Complex(Real(2), Real(-1));  // d = 0: left out
  const PeriodPowerStatistic pw = period_power_statistic(r);
  ASSERT_TRUE(pw.tested);
  EXPECT_EQ(pw.pairs, 30);
  EXPECT_LT(rel(pw.v, Real(1) / 12), tol);
  EXPECT_LT(rel(pw.S, Real(90)), tol);
  // P[χ²₃ > x] = erfc(√(x/2)) + √(2x/π) e^{−x/2} (the χ² survival function for 3 degrees of freedom)
  const Real x(90);
  EXPECT_LT(rel(pw.p, boost::math::erfc(sqrt(x / 2)) + sqrt(2 * x / pi) * exp(-x / 2)), tol);
  ASSERT_EQ(pw.relative.size(), 4u);
  EXPECT_LT(rel(pw.relative[0], Real(3)), tol);
  for (int m = 1; m < 4; ++m) EXPECT_LT(rel(pw.relative[static_cast<std::size_t>(m)], Real(1) / 3), tol);
  const PeriodCorrelation pc = period_lag_correlation(r);
  ASSERT_TRUE(pc.tested);
  EXPECT_LT(rel(pc.mean, Real(-1) / 3), tol);
  EXPECT_LT(abs(pc.variance), tol);
  // Too few pairs or periods: not tested.
  r.resize(3);
  EXPECT_FALSE(period_lag_correlation(r).tested);  // R = 3: c ≡ −1/2
  for (auto& row : r) row.resize(58);              // 29 pairs
  EXPECT_FALSE(period_power_statistic(r).tested);
  r[1].pop_back();
  EXPECT_THROW(period_power_statistic(r), InputError);  // rows of unequal length
  EXPECT_THROW(period_lag_correlation({}), InputError);  // no periods
}

}  // namespace
