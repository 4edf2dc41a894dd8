#pragma once
/// Bridge between the 50-digit reference's models and fast/'s double models,
/// for the tests that compare the two (properties/*_vs_reference_property.cpp,
/// tests/hard_systems_test.cpp). Rounds each entry to the nearest double; the
/// other way (to_reference) is exact: every double is a 50-digit number.
#include <Eigen/Dense>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "fdsid/reference/frf_id.hpp"
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

inline reference::MatrixR to_reference(const Eigen::MatrixXd& X) {
  reference::MatrixR R(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index j = 0; j < X.cols(); ++j) R(i, j) = reference::Real(X(i, j));
  return R;
}

inline reference::MatrixC to_reference(const Eigen::MatrixXcd& X) {
  reference::MatrixC R(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < X.size(); ++i)
    R(i) = reference::Complex(reference::Real(X(i).real()), reference::Real(X(i).imag()));
  return R;
}

inline reference::Model to_reference(const StateSpace& g) {
  reference::Model m;
  m.domain = g.domain == Domain::Discrete ? "discrete" : "continuous";
  m.A = to_reference(g.A);
  m.B = to_reference(g.B);
  m.C = to_reference(g.C);
  m.D = to_reference(g.D);
  return m;
}

inline reference::FrfData to_reference(const FrfData& d) {
  reference::FrfData r;
  r.domain = d.domain == Domain::Discrete ? "discrete" : "continuous";
  for (int k = 0; k < d.frequencies(); ++k) {
    r.omega.push_back(reference::Real(d.omega(k)));
    r.U.push_back(to_reference(Eigen::MatrixXcd(d.U[k])));
    r.Y.push_back(to_reference(Eigen::MatrixXcd(d.Y[k])));
    r.variance.push_back(to_reference(Eigen::MatrixXd(d.variance[k])));
  }
  return r;
}

}  // namespace fdsid::testing
