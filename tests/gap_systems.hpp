#pragma once
/// Systems with a known unmodelled effect for the gap tests (gap_test.cpp,
/// gap_vs_reference_test.cpp, cli_frf_test.cpp).
#include <Eigen/Dense>

#include "fdsid/model.hpp"

namespace fdsid::testing {

/// g with its output one sample late: y(t) = y₀(t − 1), G'(z) = z⁻¹ G(z)
/// (one extra state holding C x + D u).
inline StateSpace one_sample_delay(const StateSpace& g) {
  const int n = g.order();
  StateSpace d = g;
  d.A = Eigen::MatrixXd::Zero(n + 1, n + 1);
  d.A.topLeftCorner(n, n) = g.A;
  d.A.block(n, 0, 1, n) = g.C;
  d.B.resize(n + 1, 1);
  d.B << g.B, g.D;
  d.C = Eigen::MatrixXd::Zero(1, n + 1);
  d.C(0, n) = 1;
  d.D.setZero();
  return d;
}

}  // namespace fdsid::testing
