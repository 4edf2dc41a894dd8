// Property: fast/ (double, FFT, Eq. 19) agrees with reference/ (50 digits,
// Kronecker products, Eq. 16) on random systems, with noise-free and noisy
// spectra, within the accuracy a backward-stable double computation can reach.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <random>

#include "linalg.hpp"
#include "fdsid/error.hpp"
#include "fdsid/reference/spectrum_id.hpp"
#include "fdsid/spectrum_id.hpp"
#include "rc_generators.hpp"
#include "reference_bridge.hpp"
#include "tolerance.hpp"

namespace fdsid::testing {
namespace {

reference::Spectrum to_reference(const SpectrumData& d) {
  reference::Spectrum s;
  s.m = d.m;
  s.M = d.M;
  for (int k = 0; k <= d.M; ++k) {
    reference::MatrixC S(d.m, d.m);
    for (int a = 0; a < d.m; ++a)
      for (int b = 0; b < d.m; ++b)  // every double is exactly representable in 50 digits
        S(a, b) = reference::Complex(reference::Real(d.at(a, b, k).real()), reference::Real(d.at(a, b, k).imag()));
    s.S.push_back(S);
  }
  return s;
}


RC_GTEST_PROP(FastVsReference, AgreeOnNoiseFreeAndNoisySpectra, ()) {
  const SystemSpec spec = *gen_system_spec(2, 4);
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.outputs();
  const int p = 2 * n + 1, r = 2 * n;
  const int M = *rc::gen::inRange((p + r + 1) / 2 + 1, 41);
  const bool noisy = *rc::gen::arbitrary<bool>();
  RC_CLASSIFY(noisy, "noisy");
  RC_CLASSIFY(m > 1, "MIMO");

  SpectrumData d = noise_free(sys, M);
  if (noisy) {  // Hermitian noise of 1e-3 relative size: a perturbed but positive spectrum
    std::mt19937_64 gen(*rc::gen::arbitrary<std::uint64_t>());
    std::normal_distribution<double> g(0.0, 1e-3 * d.S.cwiseAbs().maxCoeff());
    for (int k = 0; k <= M; ++k) {
      Eigen::MatrixXcd X(m, m);
      for (int i = 0; i < m * m; ++i) X(i) = cplx(g(gen), g(gen));
      const Eigen::MatrixXcd H = 0.5 * (X + X.adjoint());
      d.S.col(k) += Eigen::Map<const Eigen::VectorXcd>(H.data(), m * m);
    }
  }
  SpectrumOptions o;
  o.order = n;
  o.p = p;
  o.r = r;
  o.extension = Extension::Conjugate;  // the reference's reading (identical on Hermitian data)
  SpectrumResult f;
  try {
    f = identify_spectrum(d, o);
  } catch (const fdsid::Error& e) {
    RC_DISCARD(std::string("noise made the data unusable: ") + e.what());  // e.g. no positive fit
  }
  reference::Result ref;
  try {
    ref = reference::identify_spectrum(to_reference(d), n, p, r, false);
  } catch (const reference::StepError& e) {
    // Known open discrepancy (issue 13, item 4): on rare noisy cases with
    // M ~ 10-20 the reference fails where fast/ returns a factor — its step 6
    // finds no stable/antistable split, or its step-9 Newton iteration stalls
    // outside the basin of the stabilising solution (measured with the
    // safeguarded Newton of reference/src/spectrum_id.cpp: 3 of 4000 cases,
    // all noisy). Noise-free cases must never get here.
    RC_ASSERT(noisy);
    RC_DISCARD(std::string("reference failed on noisy data: ") + e.what());
  }
  const StateSpace g = to_double(ref.model);

  // Tolerance: compare.hpp's bound for the double computation, with the Wedin gap
  // σ_2n - σ_2n+1 (not σ_2n) since noisy 𝒴 is not of rank 2n; the reference is
  // exact to ~1e-45 in comparison. Times 1/(1 − ρ²), ρ the reference's largest
  // pole modulus: steps 8-9 solve Stein/Riccati-type equations in Â whose
  // operator P ↦ P − Â P Âᵀ has smallest singular value ≤ 1 − ρ² (the same
  // factor fast/'s error_estimate carries; spectrum_id.hpp). Poles: times the
  // condition number of the eigenvalues of the shift matrix.
  const double s1 = ref.singular_values_Y[0].convert_to<double>();
  const double gap = (ref.singular_values_Y[2 * n - 1] -
                      (ref.singular_values_Y.size() > static_cast<size_t>(2 * n) ? ref.singular_values_Y[2 * n] : 0))
                         .convert_to<double>();
  double rho = 0;
  for (const auto& l : ref.poles) rho = std::max(rho, abs(l).convert_to<double>());
  const double tol = double_precision_spectrum_tolerance(p, r, m, 2 * M, s1 / gap) / (1 - rho * rho);
  double err = 0, scale = 0;
  for (int k = 0; k <= 2 * M; ++k) {
    const cplx z = std::polar(1.0, M_PI * k / (2.0 * M));
    const Eigen::MatrixXcd S = power_spectrum(g, z);
    err = std::max(err, (power_spectrum(f.model, z) - S).norm());
    scale = std::max(scale, S.norm());
  }
  const double perr = pole_error(g, f.model);
  const double ptol = eigenvalue_condition(shift_matrix(
                          fdsid::testing::left_singular_vectors(
                              akcay_matrix(fourier_coefficients(d, o.extension), m, p, r), 2 * n),
                          m)) *
                      tol;
  RC_LOG() << "M = " << M << ", noisy = " << noisy << ", relative spectrum difference " << err / scale
           << ", tolerance " << tol << ", pole difference " << perr << ", tolerance " << ptol
           << ", reference 1 - rho = " << 1 - rho << ", fast/ split margin " << f.split_margin << ", estimate "
           << f.error_estimate << ", warnings " << f.warnings.size() << "\n";
  if (noisy && !(err / scale <= tol && perr <= ptol)) {
    // Noise can put a pole pair on the unit circle (1 − |λ| = 1e-14 in a case
    // found by this property: Ã's eigenvalues λ and 1/λ̄ then coincide to
    // rounding and the step-8 fit cancels 1e9-sized Ê, F̂). Double precision
    // cannot agree there; the rule (as in tests/hard_systems_test.cpp) is that
    // fast/ then says so: a warning on its result, never a silent disagreement.
    RC_CLASSIFY(true, "ill-conditioned, fast/ warned");
    RC_ASSERT(!f.warnings.empty());
    return;
  }
  RC_ASSERT(err / scale <= tol);
  if (!noisy) {
    // Both interpolate (Theorem 1): the reference's model, rounded to double, has the
    // true spectrum up to the rounding of the double samples it was given, which
    // the same bound covers.
    double terr = 0;
    for (int k = 0; k <= 2 * M; ++k) {
      const cplx z = std::polar(1.0, M_PI * k / (2.0 * M));
      terr = std::max(terr, (power_spectrum(g, z) - power_spectrum(sys, z)).norm());
    }
    RC_ASSERT(terr / scale <= tol);
  }
  RC_ASSERT(perr <= ptol);
}

}  // namespace
}  // namespace fdsid::testing
