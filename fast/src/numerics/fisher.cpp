#include "numerics/fisher.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>

namespace fdsid::numerics {

double fisher_statistic(const Eigen::Ref<const Eigen::VectorXd>& t, int periods) {
  if (periods == 0) return 2 * t.sum();
  double X = 0;
  for (double v : t) X += 2.0 * (periods - 1) * std::log1p(v / (periods - 1));
  return X;
}

double fisher_p(const Eigen::Ref<const Eigen::VectorXd>& t, int periods, int q) {
  const double dof = 2.0 * static_cast<double>(t.size()) - q;
  if (t.size() == 0 || !(dof > 0)) return 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), fisher_statistic(t, periods)));
}

double fisher_p_below(const Eigen::Ref<const Eigen::VectorXd>& t, int periods, int q) {
  const double dof = 2.0 * static_cast<double>(t.size()) - q;
  if (t.size() == 0 || !(dof > 0)) return 1.0;
  return boost::math::cdf(boost::math::chi_squared(dof), fisher_statistic(t, periods));
}

}  // namespace fdsid::numerics
