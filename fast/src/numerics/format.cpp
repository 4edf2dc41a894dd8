#include "fdsid/format.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace fdsid {

std::string fmt(double x, int digits) {
  std::ostringstream s;
  s.precision(digits);
  s << x;
  return s.str();
}

std::string sci(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits, x);
  return buf;
}

std::string p_text(double p, int digits) { return p < 1e-300 ? std::string("< 1e-300") : sci(p, digits); }

std::string precision_warning(double estimate, const std::string& what, const std::string& details) {
  if (estimate <= 1e-6) return "";
  if (usable_precision(estimate)) {
    const int digits = static_cast<int>(std::floor(-std::log10(estimate)));
    return "double precision may have lost accuracy: estimated relative error of " + what + " " + fmt(estimate, 3) +
           " (" + details + "): usable to about " +
           (digits < 1 ? std::string("its order of magnitude")
                       : std::to_string(digits) + " significant digit" + (digits == 1 ? "" : "s")) +
           " (a first-order bound; the true error is often smaller); compare with --precision high";
  }
  return "UNUSABLE in double precision: estimated relative error of " + what + " " + fmt(estimate, 3) + " (" + details +
         ") leaves no correct digit; use --precision high, a lower order or another r (--strict: exit 1)";
}

}  // namespace fdsid
