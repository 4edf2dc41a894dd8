#include "fdsid/error.hpp"

namespace fdsid {

const char* to_string(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Input: return "input";
    case ErrorKind::Grid: return "grid";
    case ErrorKind::Dimension: return "dimension";
    case ErrorKind::Order: return "order";
    case ErrorKind::Split: return "split";
    case ErrorKind::Positivity: return "positivity";
    case ErrorKind::Riccati: return "riccati";
    case ErrorKind::Numerical: return "numerical";
  }
  return "unknown";
}

Error::Error(ErrorKind kind, std::string where, const std::string& message)
    : std::runtime_error(where + ": " + message), kind_(kind), where_(std::move(where)), message_(message) {}

}  // namespace fdsid
