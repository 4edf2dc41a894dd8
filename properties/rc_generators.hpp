#pragma once
/// RapidCheck generators for SystemSpec (generators.hpp). Every number is drawn
/// on an integer grid and scaled, so shrinking moves towards small orders, one
/// channel, moduli near 0.1 and couplings near -1 .. 0; a failing case prints the
/// SystemSpec (operator<<) and RapidCheck's reproduce string.
#include <rapidcheck.h>

#include "generators.hpp"
#include "linalg.hpp"

namespace fdsid::testing {

inline rc::Gen<Mode> gen_mode() {
  return rc::gen::map(rc::gen::tuple(rc::gen::inRange(10, 91), rc::gen::inRange(0, 286), rc::gen::arbitrary<bool>()),
                      [](const std::tuple<int, int, bool>& t) {
                        const int angle = std::get<1>(t);
                        // angle 0 .. 14 encodes a real mode; 15 .. 285 a pair at 0.15 .. 2.85 rad
                        return Mode{std::get<0>(t) / 100.0, angle < 15 ? 0.0 : angle / 100.0, std::get<2>(t)};
                      });
}

inline rc::Gen<double> gen_unit_interval() {
  return rc::gen::map(rc::gen::inRange(-100, 101), [](int v) { return v / 100.0; });
}

/// Random well-conditioned similarity: T = I + 0.3 X, X with entries in
/// [-1, 1] on the grid of gen_unit_interval (shrinking towards X = 0, T = I),
/// accepted when cond₂(T) <= 10.
inline rc::Gen<Eigen::MatrixXd> gen_similarity(int n) {
  auto raw = rc::gen::map(rc::gen::container<std::vector<double>>(n * n, gen_unit_interval()), [n](const std::vector<double>& v) {
    Eigen::MatrixXd T = Eigen::MatrixXd::Identity(n, n) + 0.3 * Eigen::Map<const Eigen::MatrixXd>(v.data(), n, n);
    return T;
  });
  return rc::gen::suchThat(raw, [](const Eigen::MatrixXd& T) {
    const Eigen::VectorXd s = singular_values(Eigen::MatrixXd(T));
    return s(0) / s(s.size() - 1) <= 10.0;
  });
}

/// Systems of order 1..max_order with 1..max_channels channels meeting
/// Assumption 2.1 with margins that keep the problem well conditioned in double
/// precision: eigenvalues at least 0.05 apart, |λ| <= 0.95 for the poles and
/// zeros, Gramians with smallest/largest eigenvalue >= 1e-4 (far from
/// non-minimal). Harder systems (clusters, near non-minimal, |λ| -> 1) belong
/// to the robustness envelope, not to this exactness property.
inline rc::Gen<SystemSpec> gen_system_spec(int max_channels = 3, int max_order = 6) {
  auto raw = rc::gen::mapcat(
      rc::gen::tuple(rc::gen::inRange(1, max_channels + 1), rc::gen::container<std::vector<Mode>>(gen_mode())),
      [=](const std::tuple<int, std::vector<Mode>>& t) {
        SystemSpec s;
        s.channels = std::get<0>(t);
        for (const Mode& m : std::get<1>(t))
          if (spec_order(s) + (m.angle == 0.0 ? 1 : 2) <= max_order) s.modes.push_back(m);
        if (s.modes.empty()) s.modes.push_back({0.5, 0.0, false});
        const int n = spec_order(s), m = s.channels;
        return rc::gen::map(rc::gen::tuple(rc::gen::container<std::vector<double>>(n * n, gen_unit_interval()),
                                           rc::gen::container<std::vector<double>>(n * m, gen_unit_interval()),
                                           rc::gen::container<std::vector<double>>(m * n, gen_unit_interval()),
                                           rc::gen::inRange(1, 11)),
                            [s](const std::tuple<std::vector<double>, std::vector<double>, std::vector<double>, int>& v) {
                              SystemSpec out = s;
                              out.mixing = std::get<0>(v);
                              out.b = std::get<1>(v);
                              out.c = std::get<2>(v);
                              out.gain = std::get<3>(v) / 10.0;
                              return out;
                            });
      });
  return rc::gen::suchThat(raw, [](const SystemSpec& s) { return meets_assumption_2_1(make_system(s), 0.95, 0.05, 1e-4); });
}

}  // namespace fdsid::testing
