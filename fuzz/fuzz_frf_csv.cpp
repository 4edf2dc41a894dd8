// parse_frf_csv on arbitrary bytes; the first byte picks the domain
// (even: discrete, odd: continuous), the rest is the CSV. A parsed FrfData
// must pass validate() again.
#include <sstream>
#include <string>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const fdsid::Domain domain = (data[0] & 1u) ? fdsid::Domain::Continuous : fdsid::Domain::Discrete;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  fdsid::FrfData d;
  try {
    d = fdsid::parse_frf_csv(in, "fuzz.csv", domain);
  } catch (const fdsid::Error&) {
    return 0;
  }
  if (d.domain != domain) fdsid_fuzz::fail("frf: domain not kept");
  if (d.frequencies() < 1) fdsid_fuzz::fail("frf: no frequencies accepted");
  try {
    fdsid::validate(d, "fuzz");
  } catch (const fdsid::Error& e) {
    std::fprintf(stderr, "parsed FRF data fails validate(): %s\n", e.what());
    fdsid_fuzz::fail("frf: parse_frf_csv returned data that validate() rejects");
  }
  return 0;
}
