#include "fdsid/format.hpp"

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

}  // namespace fdsid
