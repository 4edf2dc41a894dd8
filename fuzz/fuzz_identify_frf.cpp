// identify_frf and identify_frf_fixed on small FRF data decoded from the input:
//   byte 0: domain (bit 0), omega grid (bit 1: uniform grid, else decoded
//     values), noise model (bit 2), continuous method (bit 3), omega_scale
//     (bit 4: decoded, else 0), call (bit 5: also identify_frf_fixed);
//   byte 1: F (0..64), byte 2: inputs m (1..2), byte 3: outputs p (1..2),
//   byte 4: order (0..6), byte 5: r (0..12), bytes 6, 7: r_min, r_max (0..12),
//   byte 8: max_order (0..6); then omega (if decoded), G (p x m complex per
//   frequency), variances (if a noise model), omega_scale: tagged doubles
//   (Reader::value: raw bit patterns, NaN, Inf, denormals, ±1e±300, 0, ...).
// Accepted: a model with finite matrices, or an fdsid::Error.
#include <vector>

#include "fdsid/error.hpp"
#include "fdsid/frf_id.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fdsid_fuzz::Reader in(data, size);
  const uint8_t flags = in.byte(0);
  const fdsid::Domain domain = (flags & 1u) ? fdsid::Domain::Continuous : fdsid::Domain::Discrete;
  const bool grid = flags & 2u;
  const bool noise = flags & 4u;
  const fdsid::ContinuousMethod cm =
      (flags & 8u) ? fdsid::ContinuousMethod::Orthogonal : fdsid::ContinuousMethod::Bilinear;
  const bool scale = flags & 16u;
  const bool fixed = flags & 32u;
  const int F = in.range(0, 64);
  const int m = in.range(1, 2);
  const int p = in.range(1, 2);
  fdsid::FrfOptions opt;
  opt.order = in.range(0, 6);
  opt.r = in.range(0, 12);
  opt.r_min = in.range(0, 12);
  opt.r_max = in.range(0, 12);
  opt.max_order = in.range(0, 6);
  opt.continuous = cm;

  Eigen::VectorXd omega(F);
  for (int k = 0; k < F; ++k) {
    if (grid) {
      // Distinct and in range for both domains: (k+1) pi / (F+1).
      omega(k) = (k + 1) * 3.141592653589793 / (F + 1);
    } else {
      omega(k) = in.value();
    }
  }
  std::vector<Eigen::MatrixXcd> G(F, Eigen::MatrixXcd(p, m));
  for (int k = 0; k < F; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < p; ++i) {
        const double re = in.value();
        const double im = in.value();
        G[k](i, j) = fdsid::cplx(re, im);
      }
  std::vector<Eigen::MatrixXd> var;
  if (noise) {
    var.assign(F, Eigen::MatrixXd(p, m));
    for (int k = 0; k < F; ++k)
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < p; ++i) var[k](i, j) = in.value();
  }
  opt.omega_scale = scale ? in.value() : 0.0;

  fdsid::FrfData d;
  try {
    d = fdsid::frf_data(domain, omega, G, var);
  } catch (const fdsid::Error&) {
    return 0;
  }
  try {
    const fdsid::FrfResult res = fdsid::identify_frf(d, opt);
    fdsid_fuzz::check_model(res.model, "identify_frf");
    if (res.model.order() != res.order) fdsid_fuzz::fail("identify_frf: order differs from A");
  } catch (const fdsid::Error&) {
  }
  if (fixed) {
    try {
      const fdsid::FrfResult res = fdsid::identify_frf_fixed(d, opt.order, opt.r, cm, opt.omega_scale);
      fdsid_fuzz::check_model(res.model, "identify_frf_fixed");
    } catch (const fdsid::Error&) {
    }
  }
  return 0;
}
