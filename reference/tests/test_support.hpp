// Helpers shared by the reference tests: matrices from decimal strings (never
// through a double) and short scientific formatting for the printed errors.
#pragma once

#include "fdsid/reference/spectrum_id.hpp"

#include <initializer_list>
#include <string>

namespace fdsid::reference::test {

/// A matrix from rows of decimal strings, each parsed exactly into Real.
inline MatrixR mat(std::initializer_list<std::initializer_list<const char*>> rows) {
  MatrixR X(rows.size(), rows.begin()->size());
  Eigen::Index i = 0;
  for (const auto& row : rows) {
    Eigen::Index j = 0;
    for (const char* entry : row) X(i, j++) = Real(entry);  // decimal strings, never doubles
    ++i;
  }
  return X;
}

/// x in scientific notation with `digits` digits after the point.
inline std::string sci(const Real& x, int digits = 3) {
  return x.str(digits, std::ios_base::scientific);
}

}  // namespace fdsid::reference::test
