// identify_spectrum on small spectra decoded from the input:
//   byte 0: m (1..2), byte 1: M (0..64), byte 2: method (bit 0) and extension
//   (bit 1), byte 3: order (0..6), bytes 4, 5: p, r (0 = default, else
//   1..2M+2, so both valid and invalid requests occur), then the real and
//   imaginary parts of the m*m*(M+1) samples as tagged doubles (Reader::value:
//   raw bit patterns, NaN, Inf, denormals, ±1e±300, 0, small values). Byte 6
//   bit 0 symmetrises the samples (S_k Hermitian) to reach the later steps.
// Accepted: a model with finite matrices, or an fdsid::Error.
#include "fdsid/error.hpp"
#include "fdsid/spectrum_id.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fdsid_fuzz::Reader in(data, size);
  fdsid::SpectrumData d;
  d.m = in.range(1, 2);
  d.M = in.range(0, 64);
  fdsid::SpectrumOptions opt;
  const uint8_t flags = in.byte();
  opt.method = (flags & 1u) ? fdsid::Method::VanOverschee1997 : fdsid::Method::Akcay2011;
  opt.extension = (flags & 2u) ? fdsid::Extension::Conjugate : fdsid::Extension::HermitianPart;
  opt.order = in.range(0, 6);
  const uint8_t pb = in.byte(0), rb = in.byte(0);
  opt.p = pb == 0 ? 0 : 1 + pb % (2 * d.M + 2);
  opt.r = rb == 0 ? 0 : 1 + rb % (2 * d.M + 2);
  const bool hermitian = in.byte(0) & 1u;
  const int m = d.m;
  d.S.resize(static_cast<Eigen::Index>(m) * m, d.M + 1);
  for (int k = 0; k <= d.M; ++k)
    for (int b = 0; b < m; ++b)
      for (int a = 0; a < m; ++a) {
        if (hermitian && a > b) {
          d.S(a + m * b, k) = std::conj(d.S(b + m * a, k));
          continue;
        }
        const double re = in.value();
        const double im = (hermitian && a == b) ? 0.0 : in.value();
        d.S(a + m * b, k) = fdsid::cplx(re, im);
      }
  try {
    const fdsid::SpectrumResult res = fdsid::identify_spectrum(d, opt);
    fdsid_fuzz::check_model(res.model, "identify_spectrum");
    if (res.model.order() != res.order) fdsid_fuzz::fail("identify_spectrum: order differs from A");
    if (res.model.outputs() != m || res.model.inputs() != m) fdsid_fuzz::fail("identify_spectrum: not m x m");
  } catch (const fdsid::Error&) {
  }
  return 0;
}
