#include "numerics/optimize.hpp"

#include <algorithm>
#include <array>
#include <boost/math/tools/minima.hpp>
#include <cmath>

namespace fdsid::numerics {

std::pair<double, double> minimize_1d(const std::function<double(double)>& f, double lo, double hi, int n,
                                      const Minimize1dOptions& o) {
  double best = lo, fbest = f(lo);
  const double h = (hi - lo) / (n - 1);
  for (int i = 1; i < n; ++i) {
    const double x = lo + i * h, v = f(x);
    if (v < fbest) {
      fbest = v;
      best = x;
    }
  }
  const auto r =
      boost::math::tools::brent_find_minima(f, std::max(lo, best - h), std::min(hi, best + h), o.brent_bits);
  return r.second < fbest ? r : std::make_pair(best, fbest);
}

Eigen::Vector2d nelder_mead(const std::function<double(const Eigen::Vector2d&)>& f, Eigen::Vector2d x0,
                            Eigen::Vector2d step, const NelderMeadOptions& o) {
  std::array<Eigen::Vector2d, 3> x = {x0, x0 + Eigen::Vector2d(step(0), 0), x0 + Eigen::Vector2d(0, step(1))};
  std::array<double, 3> v = {f(x[0]), f(x[1]), f(x[2])};
  for (int it = 0; it < o.iterations; ++it) {
    std::array<int, 3> ord = {0, 1, 2};
    std::sort(ord.begin(), ord.end(), [&](int a, int b) { return v[a] < v[b]; });
    const int b = ord[0], m = ord[1], w = ord[2];
    if (std::abs(v[w] - v[b]) <= o.relative_tolerance * std::abs(v[b]) + o.absolute_tolerance) break;
    const Eigen::Vector2d c = 0.5 * (x[b] + x[m]);
    const Eigen::Vector2d r = c + (c - x[w]);
    const double fr = f(r);
    if (fr < v[b]) {
      const Eigen::Vector2d e = c + 2.0 * (c - x[w]);
      const double fe = f(e);
      if (fe < fr) {
        x[w] = e;
        v[w] = fe;
      } else {
        x[w] = r;
        v[w] = fr;
      }
    } else if (fr < v[m]) {
      x[w] = r;
      v[w] = fr;
    } else {
      const Eigen::Vector2d k = c + 0.5 * (x[w] - c);
      const double fk = f(k);
      if (fk < v[w]) {
        x[w] = k;
        v[w] = fk;
      } else {
        for (int i : {m, w}) {
          x[i] = x[b] + 0.5 * (x[i] - x[b]);
          v[i] = f(x[i]);
        }
      }
    }
  }
  return x[std::min_element(v.begin(), v.end()) - v.begin()];
}

}  // namespace fdsid::numerics
