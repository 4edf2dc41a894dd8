#include "numerics/autoregression.hpp"

#include <algorithm>
#include <cmath>

namespace fdsid::numerics {

Eigen::VectorXd whitening_filter(const Eigen::VectorXd& r, int p_max, double N) {
  p_max = std::min<int>(p_max, static_cast<int>(r.size()) - 1);
  Eigen::VectorXd a = Eigen::VectorXd::Ones(1), best = a;
  double sigma2 = r(0);
  if (!(sigma2 > 0)) return best;
  double best_bic = N * std::log(sigma2);
  for (int p = 1; p <= p_max; ++p) {
    double acc = r(p);
    for (int i = 1; i < p; ++i) acc += a(i) * r(p - i);
    const double k = -acc / sigma2;  // reflection coefficient
    if (!(std::abs(k) < 1)) break;
    Eigen::VectorXd next(p + 1);
    next(0) = 1;
    for (int i = 1; i < p; ++i) next(i) = a(i) + k * a(p - i);
    next(p) = k;
    a = std::move(next);
    sigma2 *= 1 - k * k;
    if (!(sigma2 > 0)) break;
    const double bic = N * std::log(sigma2) + p * std::log(N);
    if (bic < best_bic) {
      best_bic = bic;
      best = a;
    }
  }
  return best;
}

}  // namespace fdsid::numerics
