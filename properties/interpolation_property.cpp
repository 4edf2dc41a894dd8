// Property: Akçay (2011) Algorithm 1 in fast/ is interpolatory (Theorem 1) on
// random systems meeting Assumption 2.1: from M+1 noise-free samples it
// recovers the spectrum, on and between grid points, and the poles.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "fdsid/error.hpp"
#include "fdsid/spectrum_id.hpp"
#include "rc_generators.hpp"
#include "tolerance.hpp"

namespace fdsid::testing {
namespace {

RC_GTEST_PROP(Interpolation, FastRecoversRandomSystems, ()) {
  const SystemSpec spec = *gen_system_spec();
  const StateSpace sys = make_system(spec);
  const int n = sys.order(), m = sys.outputs();
  // Smallest M with room for p = 2n + 1, r = 2n (p + r <= 2M), up to 400.
  const int M = *rc::gen::inRange(2 * n + 1, 401);
  RC_CLASSIFY(m == 1, "SISO");
  RC_CLASSIFY(m > 1, "MIMO");
  RC_TAG(n);

  SpectrumOptions o;
  o.order = n;
  const SpectrumResult r = identify_spectrum(noise_free(sys, M), o);

  // Tolerance: tolerance.hpp, 4 (p + r) m log2(N) u σ1/σ2n, and κ(A) times it for the poles.
  const double tol = spectrum_tolerance(r.p, r.r, m, r.N, r.singular_values(0) / r.singular_values(2 * n - 1));
  double err = 0, scale = 0;
  for (int k = 0; k <= 2 * M; ++k) {
    const cplx z = std::polar(1.0, M_PI * k / (2.0 * M));
    const Eigen::MatrixXcd S = power_spectrum(sys, z);
    err = std::max(err, (power_spectrum(r.model, z) - S).norm());
    scale = std::max(scale, S.norm());
  }
  RC_LOG() << "M = " << M << ", relative spectrum error " << err / scale << ", tolerance " << tol << "\n";
  RC_ASSERT(err / scale <= tol);

  RC_ASSERT(pole_error(sys, r.model) <= eigenvalue_condition(sys.A) * tol);
}

}  // namespace
}  // namespace fdsid::testing
