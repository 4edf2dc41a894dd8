#include "rounding.hpp"

#include <algorithm>
#include <limits>
#include <tuple>

#include "fdsid/format.hpp"
#include "fdsid/frf_id.hpp"
#include "numerics/eigen_instances.hpp"

namespace fdsid {

RoundingEffect::RoundingEffect(const StateSpace& base, const Eigen::VectorXd& omega)
    : omega_(omega), G0_(frequency_response(base, omega)), base_poles_(fdsid::poles(base)) {
  for (const auto& g : G0_) g0_ += g.squaredNorm();
  pole_error_.assign(base_poles_.size(), 0.0);
}

void RoundingEffect::add(const StateSpace& moved) {
  const std::vector<Eigen::MatrixXcd> G = frequency_response(moved, omega_);
  double dg = 0;
  for (size_t k = 0; k < G.size(); ++k) dg += (G[k] - G0_[k]).squaredNorm();
  g = std::max(g, g0_ > 0 ? std::sqrt(dg / g0_) : 0.0);
  const Eigen::VectorXcd q = fdsid::poles(moved);
  std::vector<std::tuple<double, Eigen::Index, Eigen::Index>> pairs;
  for (Eigen::Index i = 0; i < base_poles_.size(); ++i) {
    const double scale = std::abs(base_poles_(i)) > 0 ? std::abs(base_poles_(i)) : 1.0;
    for (Eigen::Index j = 0; j < q.size(); ++j) pairs.emplace_back(std::abs(q(j) - base_poles_(i)) / scale, i, j);
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> base_done(base_poles_.size(), false), used(q.size(), false);
  for (const auto& [err, i, j] : pairs) {
    if (base_done[i] || used[j]) continue;
    base_done[i] = used[j] = true;
    pole_error_[i] = std::max(pole_error_[i], err);
    poles = std::max(poles, err);
  }
}

void RoundingEffect::fail(const std::string& why) {
  g = poles = std::numeric_limits<double>::infinity();
  failure = why;
}

std::vector<cplx> RoundingEffect::undetermined() const {
  std::vector<cplx> out;
  for (size_t i = 0; i < pole_error_.size(); ++i)
    if (!usable_precision(pole_error_[i])) out.push_back(base_poles_(static_cast<Eigen::Index>(i)));
  return out;
}

std::string rounding_warning(const RoundingEffect& e, const std::string& moves, const std::string& bound,
                             const PrecisionAdvice& advice) {
  if (!e.failure.empty())
    return "UNUSABLE in double precision: " + moves + " moved by their rounding make the estimate fail (" + e.failure +
           "): rounding alone decides whether it exists (" + bound + "); " + advice.instead + " (--strict: exit 1)";
  const bool poles_worse = e.poles > e.g;
  const std::string details = std::string(poles_worse ? "G on the data's frequencies " + fmt(e.g, 3)
                                                      : "poles " + fmt(e.poles, 3)) +
                              "; " + moves + " moved by their rounding in " + std::to_string(kRoundingSamples) +
                              " random directions; " + bound;
  std::string w = precision_warning(std::max(e.g, e.poles), poles_worse ? "the poles" : "G on the data's frequencies",
                                    details, PrecisionEstimate::Statistical, advice);
  const std::vector<cplx> set_by_rounding = e.undetermined();
  if (set_by_rounding.empty() || w.empty()) return w;
  w += "; set by rounding, not by the data (each moves by its own size or more):";
  for (const cplx& z : set_by_rounding) w += " " + pole_text(z);
  if (e.g <= kPrecisionWarningLevel)
    w += " — G is right to 6 or more digits: the order is above what the data determine (try a lower --order)";
  return w;
}

}  // namespace fdsid
