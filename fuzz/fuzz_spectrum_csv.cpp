// parse_spectrum_csv on arbitrary bytes. Accepted outcomes: a validated
// SpectrumData or an fdsid::Error.
#include <sstream>
#include <string>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const fdsid::SpectrumData d = fdsid::parse_spectrum_csv(in, "fuzz.csv");
    if (d.m < 1 || d.M < 1) fdsid_fuzz::fail("spectrum: m or M < 1 accepted");
    if (d.S.rows() != static_cast<Eigen::Index>(d.m) * d.m || d.S.cols() != d.M + 1)
      fdsid_fuzz::fail("spectrum: S has the wrong shape");
    if (!fdsid_fuzz::finite(d.S)) fdsid_fuzz::fail("spectrum: non-finite sample accepted");
  } catch (const fdsid::Error&) {
  }
  return 0;
}
