#include "fdsid/format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

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

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string p_text(double p, int digits) { return p < 1e-300 ? std::string("< 1e-300") : sci(p, digits); }

std::string p_relation(double p, int digits) { return p < 1e-300 ? p_text(p, digits) : "= " + p_text(p, digits); }

std::string significant_digits_text(double estimate) {
  const int digits = static_cast<int>(std::floor(-std::log10(estimate)));
  return digits < 1 ? std::string("its order of magnitude")
                    : std::to_string(digits) + " significant digit" + (digits == 1 ? "" : "s");
}

std::string precision_warning(double estimate, const std::string& what, const std::string& details,
                              PrecisionEstimate kind, const PrecisionAdvice& advice) {
  if (estimate <= kPrecisionWarningLevel) return "";
  if (usable_precision(estimate)) {
    return "double precision may have lost accuracy: estimated relative error of " + what + " " + fmt(estimate, 3) +
           " (" + details + "): usable to about " + significant_digits_text(estimate) +
           (kind == PrecisionEstimate::FirstOrderBound ? " (a first-order bound; the true error is often smaller)"
                                                       : " (a statistical estimate from rounding-size perturbations)") +
           "; " + advice.compare;
  }
  return "UNUSABLE in double precision: estimated relative error of " + what + " " + fmt(estimate, 3) + " (" + details +
         ") leaves no correct digit; " + advice.instead + " (--strict: exit 1)";
}

}  // namespace fdsid
