#pragma once
/// Bridge between the 50-digit reference's models and fast/'s double models,
/// for the tests that compare the two (properties/*_vs_reference_property.cpp,
/// tests/hard_systems_test.cpp). Rounds each entry to the nearest double.
#include <Eigen/Dense>

#include "fdsid/model.hpp"
#include "fdsid/reference/spectrum_id.hpp"

namespace fdsid::testing {

inline Eigen::MatrixXd to_double(const reference::MatrixR& X) {
  Eigen::MatrixXd Y(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index j = 0; j < X.cols(); ++j) Y(i, j) = X(i, j).convert_to<double>();
  return Y;
}

inline StateSpace to_double(const reference::Model& m) {
  StateSpace s;
  s.A = to_double(m.A);
  s.B = to_double(m.B);
  s.C = to_double(m.C);
  s.D = to_double(m.D);
  return s;
}

}  // namespace fdsid::testing
