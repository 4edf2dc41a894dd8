// Properties of Pintelon (2002) Algorithms 1 and 2 (fdsid/frf_id.hpp) on
// random systems meeting Section 2.1's assumptions (stable, minimal —
// observable and controllable by the Gramian test of generators.hpp —,
// distinct eigenvalues 0.05 apart; the generator also makes them minimum
// phase, which FRF data do not need but do not mind):
//   - noise-free exactness on random non-uniform grids (discrete) and random
//     five-decade grids (continuous, bilinear),
//   - invariance under similarity of the true realisation, and the Eq. (14)
//     referral of the estimate to the truth.
// Consistency as F grows (Theorems 1 and 2): frf_consistency_property.cpp.
// Tolerances: tests/frf_tolerance.hpp; the statistical margins beside each check.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <random>

#include "linalg.hpp"
#include "fdsid/frf_id.hpp"
#include "frf_tolerance.hpp"
#include "rc_generators.hpp"
#include "tolerance.hpp"

namespace fdsid::testing {
namespace {

// Stratified random grids: stratum k of F equal strata of the band holds one
// point at a random offset (lattice of 1/1000 of a stratum), so the grid is
// non-uniform but covers the band (largest gap < 2 strata; Assumption 8 with a
// bounded density). Offsets shrink towards 0, i.e. towards a uniform grid.
// Not generated: grids crowded into a narrow band. There error_estimate = u κ
// misses the conditioning of the data-to-pole map (see the report: for n = 1
// κ = 1 whatever the grid), so the rounding tolerance does not apply.
rc::Gen<std::vector<int>> gen_offsets(int F) { return rc::gen::container<std::vector<int>>(F, rc::gen::inRange(0, 1000)); }

// Discrete: ω_k = π (k + o_k/1000) / F in [0, π).
rc::Gen<Eigen::VectorXd> gen_discrete_grid(int F) {
  return rc::gen::map(gen_offsets(F), [F](const std::vector<int>& o) {
    Eigen::VectorXd w(F);
    for (int k = 0; k < F; ++k) w(k) = M_PI * (k + o[k] / 1000.0) / F;
    return w;
  });
}

// Continuous: five decades [10^lo, 10^(lo+5)], stratified in log ω.
rc::Gen<Eigen::VectorXd> gen_five_decades(int F, double lo) {
  return rc::gen::map(gen_offsets(F), [F, lo](const std::vector<int>& o) {
    Eigen::VectorXd w(F);
    for (int k = 0; k < F; ++k) w(k) = std::pow(10.0, lo + 5.0 * (k + o[k] / 1000.0) / F);
    return w;
  });
}

// Shows the margins reached: worst error / tolerance of G and of the poles.
void tag_margin(const char* what, double ratio) {
  const std::string w(what);
  RC_CLASSIFY(ratio < 1e-2, w + " ratio < 0.01");
  RC_CLASSIFY(ratio >= 1e-2 && ratio < 0.1, w + " ratio in [0.01, 0.1)");
  RC_CLASSIFY(ratio >= 0.1, w + " ratio >= 0.1");
}

void tag_condition(double eps_A) {
  RC_CLASSIFY(eps_A < 1e-12, "eps_A < 1e-12");
  RC_CLASSIFY(eps_A >= 1e-12 && eps_A < 1e-9, "eps_A in [1e-12, 1e-9)");
  RC_CLASSIFY(eps_A >= 1e-9, "eps_A >= 1e-9");
}

RC_GTEST_PROP(FrfExactness, DiscreteNoiseFreeOnRandomNonUniformGrids, ()) {
  const SystemSpec spec = *gen_system_spec(2, 6);
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.inputs();
  const int r = *rc::gen::inRange(n + 1, 3 * n + 3);
  // FRF form: c = m columns, 2 F m ≥ r · 2m ⇔ F ≥ r; a margin of 4.
  const int F = *rc::gen::inRange(r + 4, 150);
  const Eigen::VectorXd w = *gen_discrete_grid(F);
  const FrfData d = noise_free_frf(sys, w);
  RC_TAG(m == 1 ? "SISO" : "2x2");
  RC_LOG() << spec << "\nr = " << r << ", F = " << F << "\n";
  const FrfResult res = identify_frf_fixed(d, n, r);
  const NoiseFreeCheck c = check_noise_free(sys, res, d);
  tag_condition(c.eps_A);
  tag_margin("G", c.g_ratio);
  tag_margin("pole", c.pole_ratio);
  RC_LOG() << c.describe() << "\n";
  RC_ASSERT(c.g_ratio <= 1.0);
  RC_ASSERT(c.pole_ratio <= 1.0);
}

RC_GTEST_PROP(FrfExactness, ContinuousBilinearNoiseFreeOnFiveDecades, ()) {
  // Truth: a generated discrete system read as a w-domain model and mapped by
  // bilinear_to_continuous (checked against G_w(w(jω)) in frf_id_test.cpp):
  // stable (|λ_w| ≤ 0.95 ⇒ Re s < 0), minimal (a similarity-free change of
  // variable), poles within ω_t · [0.026, 39]. The data band is five decades
  // around ω_t, the identification's ω_s is its default √(ω_min ω_max).
  const SystemSpec spec = *gen_system_spec(1, 6);
  const double log_wt = *rc::gen::inRange(-20, 21) / 10.0;
  const StateSpace wsys = make_system(spec);
  const StateSpace sys = bilinear_to_continuous(wsys, std::pow(10.0, log_wt));
  const int n = sys.order();
  const int r = *rc::gen::inRange(n + 1, 2 * n + 3);
  const int F = *rc::gen::inRange(r + 4, 100);
  const Eigen::VectorXd w = *gen_five_decades(F, log_wt - 2.5);
  const FrfData d = noise_free_frf(sys, w);
  RC_LOG() << spec << "\nomega_t = 10^" << log_wt << ", r = " << r << ", F = " << F << "\n";
  const FrfResult res = identify_frf_fixed(d, n, r, ContinuousMethod::Bilinear);
  // The truth's poles carry the rounding of bilinear_to_continuous:
  // 4n u cond(I − A_w) ‖A_c‖ κ(A_c).
  const Eigen::VectorXd sv = fdsid::testing::singular_values(Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n) - wsys.A));
  const double truth_acc = 4.0 * n * kU * sv(0) / sv(n - 1) * spectral_norm(sys.A.cast<cplx>()) * eigenvalue_condition(sys.A);
  const NoiseFreeCheck c = check_noise_free(sys, res, d, ContinuousMethod::Bilinear, 0, truth_acc);
  tag_condition(c.eps_A);
  tag_margin("G", c.g_ratio);
  tag_margin("pole", c.pole_ratio);
  RC_LOG() << c.describe() << "\n";
  RC_ASSERT(c.g_ratio <= 1.0);
  RC_ASSERT(c.pole_ratio <= 1.0);
}

RC_GTEST_PROP(FrfSimilarity, SameGAndPolesForASimilarTruthAndEq14RecoversIt, ()) {
  const SystemSpec spec = *gen_system_spec(2, 5);
  const StateSpace sys = make_system(spec);
  const int n = sys.order();
  const Eigen::MatrixXd T = *gen_similarity(n);
  StateSpace other = sys;
  other.A = fdsid::testing::solve(T, Eigen::MatrixXd(sys.A * T));
  other.B = fdsid::testing::solve(T, sys.B);
  other.C = sys.C * T;
  const int r = 2 * n + 1, F = 80;
  const Eigen::VectorXd w = *gen_discrete_grid(F);
  const FrfData da = noise_free_frf(sys, w), db = noise_free_frf(other, w);
  const FrfResult a = identify_frf_fixed(da, n, r), b = identify_frf_fixed(db, n, r);
  RC_LOG() << spec << "\nT =\n" << T << "\n";
  // Each estimate is within its noise-free tolerance of the common G (the data
  // of the two realisations differ only by rounding in frequency_response, a
  // perturbation ≤ the tolerance's D term): the two within the sum.
  const NoiseFreeCheck ca = check_noise_free(sys, a, da), cb = check_noise_free(other, b, db);
  RC_LOG() << ca.describe() << "\n" << cb.describe() << "\n";
  RC_ASSERT(ca.g_ratio <= 1.0);
  RC_ASSERT(cb.g_ratio <= 1.0);
  double worst = 0;
  for (int k = 0; k <= 64; ++k) {
    const double om = M_PI * (k + 0.5) / 65.0;
    const double err = (frequency_response(a.model, om) - frequency_response(b.model, om)).norm();
    const double tol = ca.eps_A * fdsid::testing::transfer_sensitivity(a.model, std::polar(1.0, om)) +
                       cb.eps_A * fdsid::testing::transfer_sensitivity(b.model, std::polar(1.0, om));
    worst = std::max(worst, err / tol);
  }
  RC_LOG() << "G(a) vs G(b): worst error / tolerance " << worst << "\n";
  RC_ASSERT(worst <= 1.0);
  RC_ASSERT(pole_error(a.model, b.model) <= ca.pole_tol + cb.pole_tol);

  // Eq. (14): T₁₄ = Ô_r⁺ O_r refers (Â, B̂, Ĉ) to the truth's (A, C). With Ô_r
  // = O_r T₀ (1 + ε) (ε ≤ ε_A r, the r row blocks Ĉ Â^i each carry ≤ i ε_A
  // to first order), T₁₄ = T₀ (1 + δ) with ‖δ‖ ≤ cond(O_r) r ε_A, and
  // X_T − X = O(cond(T₁₄) (ε_A + 2‖δ‖)) ‖X‖ for X = A, B, C:
  //   tol = cond(T₁₄) (1 + 2 r cond(O_r)) ε_A.
  const StateSpace ref = refer_realization(a.model, sys, r);
  const Eigen::MatrixXd Or = observability(sys.A, sys.C, r);
  const Eigen::MatrixXd T14 = fdsid::testing::least_squares(observability(a.model.A, a.model.C, r), Or);
  auto cond = [](const Eigen::MatrixXd& X) {
    const Eigen::VectorXd s = fdsid::testing::singular_values(Eigen::MatrixXd(X));
    return s(0) / s(s.size() - 1);
  };
  const double tol = cond(T14) * (1 + 2 * r * cond(Or)) * ca.eps_A;
  const double eA = (ref.A - sys.A).norm() / sys.A.norm(), eB = (ref.B - sys.B).norm() / sys.B.norm(),
               eC = (ref.C - sys.C).norm() / sys.C.norm(), eD = (ref.D - sys.D).norm() / sys.D.norm();
  RC_LOG() << "Eq. 14 relative errors A " << eA << " B " << eB << " C " << eC << " D " << eD << ", tolerance " << tol
           << "\n";
  RC_ASSERT(eA <= tol);
  RC_ASSERT(eB <= tol);
  RC_ASSERT(eC <= tol);
  RC_ASSERT(eD <= tol);
  // The referral is invariant under a similarity P of the estimate: b's estimate
  // referred to `sys` gives the same realisation (b's data came from T⁻¹AT).
  const StateSpace ref_b = refer_realization(b.model, sys, r);
  RC_ASSERT((ref_b.A - sys.A).norm() / sys.A.norm() <= cond(T) * tol + tol);
}

}  // namespace
}  // namespace fdsid::testing
