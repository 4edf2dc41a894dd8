// Properties of Akçay (2011) Section 3 on random noise-free systems:
// the rank collapse of Van Overschee's matrix (Eq. 12 vs Eq. 18, Table 1), and
// invariance of the identified model under similarity transforms (of the true
// realisation, of the SVD basis U_2n, and of the estimate after the Pintelon
// (2002) Eq. (14) referral).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "linalg.hpp"
#include "fdsid/spectrum_id.hpp"
#include "rc_generators.hpp"
#include "tolerance.hpp"

namespace fdsid::testing {
namespace {

Eigen::MatrixXd matrix_power(const Eigen::MatrixXd& A, int k) {
  Eigen::MatrixXd P = Eigen::MatrixXd::Identity(A.rows(), A.cols());
  for (int i = 0; i < k; ++i) P = P * A;
  return P;
}

double sigma_min(const Eigen::MatrixXd& X) { return fdsid::testing::singular_values(Eigen::MatrixXd(X)).minCoeff(); }
double norm2(const Eigen::MatrixXd& X) { return fdsid::testing::singular_values(Eigen::MatrixXd(X))(0); }

RC_GTEST_PROP(Table1RankCollapse, VanOversheeLosesRankAkcayDoesNot, ()) {
  const SystemSpec spec = *gen_system_spec();
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.outputs();
  const int p = 2 * n + 1, r = 2 * n;
  const int M = *rc::gen::inRange((p + r + 1) / 2, 151);
  const int N = 2 * M;
  const SpectralSummands s = spectral_summands(sys);
  const SpectrumData d = noise_free(sys, M);
  const Eigen::MatrixXd shat = fourier_coefficients(d, Extension::HermitianPart);
  const Eigen::VectorXd sv_vo = fdsid::testing::singular_values(Eigen::MatrixXd(van_overschee_matrix(shat, m, p, r)));
  const Eigen::VectorXd sv_y = fdsid::testing::singular_values(Eigen::MatrixXd(akcay_matrix(shat, m, p, r)));

  // Factors of Eqs. (12) and (17): O_p = [O_c O_a], Δ_r = [Δ_c; Δ_a], I_N = (I - A^N)^{-1}.
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd IN = fdsid::testing::inverse(Eigen::MatrixXd(I - matrix_power(s.A, N)));
  Eigen::MatrixXd Oc(p * m, n), Oa(p * m, n), Dc(n, r * m), Da(n, r * m);
  for (int k = 0; k < p; ++k) {
    Oc.middleRows(k * m, m) = s.C * matrix_power(s.A, k);
    Oa.middleRows(k * m, m) = s.F.transpose() * matrix_power(s.A.transpose(), p - 1 - k);
  }
  for (int l = 0; l < r; ++l) {
    Dc.middleCols(l * m, m) = matrix_power(s.A, l) * s.F;
    Da.middleCols(l * m, m) = matrix_power(s.A.transpose(), r - 1 - l) * s.C.transpose();
  }
  // Rounding floor of the computed matrices (tolerance.hpp with σ1/σ2n = 1).
  const double floor = spectrum_tolerance(p, r, m, N, 1.0) * d.S.cwiseAbs().maxCoeff();

  // Eq. (12): Ĝ_pF_r = O_c I_N Δ_c + O_a (A^T)^{N-p-r} I_N^T Δ_a; the first term has
  // rank n, so by Weyl σ_{n+1} <= ||second term|| <= c ρ(A)^{N-p-r} with
  // c = κ(V) ||O_a|| ||I_N|| ||Δ_a|| (||A^k|| <= κ(V) ρ^k, V the eigenvectors of A).
  const double rho = fdsid::testing::eigenvalues(s.A).cwiseAbs().maxCoeff();
  const double c = eigenvalue_condition_number_of_basis(s.A) * norm2(Oa) * norm2(IN) * norm2(Da);
  const double bound = c * std::pow(rho, N - p - r) + floor;
  RC_LOG() << "M = " << M << ", sigma_{n+1}(G_pF_r) = " << sv_vo(n) << ", bound " << bound << "\n";
  RC_ASSERT(sv_vo(n) <= bound);

  // Eq. (17): 𝒴 = O_p E Δ_r with E = (I + diag(A, A^T)^{N-p-r}) diag(I_N, I_N^T), so
  // σ_2n(𝒴) >= σ_min(O_p) σ_min(E) σ_min(Δ_r) > 0 at every N: no collapse.
  Eigen::MatrixXd Op(p * m, 2 * n), Dr(2 * n, r * m), E = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  Op << Oc, Oa;
  Dr << Dc, Da;
  E.topLeftCorner(n, n) = (I + matrix_power(s.A, N - p - r)) * IN;
  E.bottomRightCorner(n, n) = (I + matrix_power(s.A.transpose(), N - p - r)) * IN.transpose();
  const double lower = sigma_min(Op) * sigma_min(E) * sigma_min(Dr) - floor;
  RC_LOG() << "sigma_2n(Y) = " << sv_y(2 * n - 1) << ", lower bound " << lower << "\n";
  RC_ASSERT(sv_y(2 * n - 1) >= lower);
  RC_ASSERT(lower > 0.0);
}

RC_GTEST_PROP(Similarity, EigenvaluesAndSpectrumDoNotDependOnTheRealisation, ()) {
  const SystemSpec spec = *gen_system_spec();
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.outputs();
  const Eigen::MatrixXd T = *gen_similarity(n);
  StateSpace other = sys;
  other.A = fdsid::testing::solve(T, Eigen::MatrixXd(sys.A * T));
  other.B = fdsid::testing::solve(T, sys.B);
  other.C = sys.C * T;
  const int M = *rc::gen::inRange(4 * n + 1, 201);
  SpectrumOptions o;
  o.order = n;
  const SpectrumResult a = identify_spectrum(noise_free(sys, M), o);
  const SpectrumResult b = identify_spectrum(noise_free(other, M), o);
  // Each run is within the interpolation tolerance of the (common) truth, so they
  // are within twice of it of each other; poles within κ(A) times that.
  const double tol = 2 * std::max(spectrum_tolerance(a.p, a.r, m, a.N, a.singular_values(0) / a.singular_values(2 * n - 1)),
                                  spectrum_tolerance(b.p, b.r, m, b.N, b.singular_values(0) / b.singular_values(2 * n - 1)));
  double err = 0, scale = 0;
  for (int k = 0; k <= 64; ++k) {
    const cplx z = std::polar(1.0, M_PI * (k + 0.5) / 65.0);
    const Eigen::MatrixXcd S = power_spectrum(a.model, z);
    err = std::max(err, (power_spectrum(b.model, z) - S).norm());
    scale = std::max(scale, S.norm());
  }
  RC_ASSERT(err / scale <= tol);
  RC_ASSERT(pole_error(a.model, b.model) <= eigenvalue_condition(sys.A) * tol);
}

RC_GTEST_PROP(Similarity, RotatingTheSvdBasisLeavesTheEigenvaluesOfAUnchanged, ()) {
  // Step 5 with U_2n Q, Q orthogonal: (J_d U Q)^† J_u U Q = Q^T Ã Q, same eigenvalues.
  // Backward error of the QR least squares is ~ c u ||Ã|| cond(J_d U) per solve;
  // eigenvalues move by κ_λ times that: tol = 16 p m u κ(Ã) ||Ã|| cond(J_d U).
  const SystemSpec spec = *gen_system_spec();
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.outputs(), M = 64, p = 2 * n + 2, r = 2 * n + 1;
  const Eigen::MatrixXd Y =
      akcay_matrix(fourier_coefficients(noise_free(sys, M), Extension::HermitianPart), m, p, r);
  const Eigen::MatrixXd U = fdsid::testing::left_singular_vectors(Y, 2 * n);
  const std::vector<double> q = *rc::gen::container<std::vector<double>>(4 * n * n, gen_unit_interval());
  const Eigen::MatrixXd Q = fdsid::testing::thin_q(Eigen::MatrixXd(Eigen::Map<const Eigen::MatrixXd>(q.data(), 2 * n, 2 * n) +
                                                                     3.0 * Eigen::MatrixXd::Identity(2 * n, 2 * n)));
  const Eigen::MatrixXd A1 = shift_matrix(U, m), A2 = shift_matrix(U * Q, m);
  const Eigen::MatrixXd JdU = U.topRows(U.rows() - m);
  const double tol = 16.0 * p * m * kU * eigenvalue_condition(A1) * norm2(A1) * norm2(JdU) / sigma_min(JdU);
  const Eigen::VectorXcd e1 = fdsid::testing::eigenvalues(A1), e2 = fdsid::testing::eigenvalues(A2);
  double worst = 0;
  for (Eigen::Index i = 0; i < e1.size(); ++i) worst = std::max(worst, (e2.array() - e1(i)).abs().minCoeff());
  RC_LOG() << "eigenvalue difference " << worst << ", tolerance " << tol << "\n";
  RC_ASSERT(worst <= tol);
}

RC_GTEST_PROP(Similarity, Eq14ReferralIsInvariantAndRecoversTheTrueRealisation, ()) {
  // Pintelon (2002) Eq. (14): referring the estimate to the true (A, C) removes any
  // similarity P applied to the estimate. The generator's systems have D = I, so
  // they are already the minimum-phase innovation form and the referred estimate
  // equals the true (A, B, C, D) up to the interpolation error, amplified by the
  // condition of the referral, cond(O_r) cond(T).
  const SystemSpec spec = *gen_system_spec();
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.outputs(), M = 128;
  SpectrumOptions o;
  o.order = n;
  const SpectrumResult res = identify_spectrum(noise_free(sys, M), o);
  const Eigen::MatrixXd P = *gen_similarity(n);
  StateSpace moved = res.model;
  moved.A = fdsid::testing::solve(P, Eigen::MatrixXd(res.model.A * P));
  moved.B = fdsid::testing::solve(P, res.model.B);
  moved.C = res.model.C * P;
  const int r = 2 * n;
  const StateSpace ref1 = refer_realization(res.model, sys, r), ref2 = refer_realization(moved, sys, r);
  const Eigen::MatrixXd Or = observability(sys.A, sys.C, r);
  const double cond_O = norm2(Or) / sigma_min(Or);
  const double base = spectrum_tolerance(res.p, res.r, m, res.N, res.singular_values(0) / res.singular_values(2 * n - 1));
  const double tol = cond_O * cond_O * 10.0 * base;  // cond(P) <= 10
  RC_LOG() << "cond(O_r) = " << cond_O << ", tolerance " << tol << "\n";
  RC_ASSERT((ref1.A - ref2.A).norm() <= tol * (1 + sys.A.norm()));
  RC_ASSERT((ref1.B - ref2.B).norm() <= tol * (1 + sys.B.norm()));
  RC_ASSERT((ref1.C - ref2.C).norm() <= tol * (1 + sys.C.norm()));
  RC_ASSERT((ref1.A - sys.A).norm() <= tol * (1 + sys.A.norm()));
  RC_ASSERT((ref1.B - sys.B).norm() <= tol * (1 + sys.B.norm()));
  RC_ASSERT((ref1.C - sys.C).norm() <= tol * (1 + sys.C.norm()));
  RC_ASSERT((res.model.D - sys.D).norm() <= tol * sys.D.norm());
}

}  // namespace
}  // namespace fdsid::testing
