#pragma once
/// Distribution-free tests for the Monte Carlo checks whose errors have no
/// usable law (Gaussian mixtures with heavy-tailed weights).
#include <vector>

namespace fdsid::testing {

// Mann–Whitney: U = #{(i, j): a_i < b_j} and P(U ≥ u) when the n + m values
// are exchangeable (continuous, so no ties). Exact: N(n, m, u), the number of
// orderings of n a's and m b's with U = u, obeys
// N(n, m, u) = N(n, m − 1, u − n) + N(n − 1, m, u) (the largest value is a b,
// above all n a's, or an a, above every b), N(n, 0, 0) = N(0, m, 0) = 1;
// divided by C(n + m, n), exact in doubles while that is below 2⁵³.
// If instead a is stochastically larger than b, U is smaller and P(U ≥ u)
// smaller still: the p-value is valid for that composite hypothesis.
inline double mann_whitney_p_value(const std::vector<double>& a, const std::vector<double>& b) {
  const int n = static_cast<int>(a.size()), m = static_cast<int>(b.size());
  int u = 0;
  for (double x : a)
    for (double y : b) u += x < y;
  // count[i][j][v]: N(i, j, v), built up in i and j.
  std::vector<std::vector<std::vector<double>>> count(n + 1, std::vector<std::vector<double>>(m + 1));
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= m; ++j) {
      count[i][j].assign(i * j + 1, 0.0);
      if (i == 0 || j == 0) {
        count[i][j][0] = 1;
        continue;
      }
      for (int v = 0; v <= i * j; ++v)
        count[i][j][v] = (v >= i && v - i <= i * (j - 1) ? count[i][j - 1][v - i] : 0.0) +
                         (v <= (i - 1) * j ? count[i - 1][j][v] : 0.0);
    }
  double tail = 0, total = 0;
  for (int v = 0; v <= n * m; ++v) {
    total += count[n][m][v];
    if (v >= u) tail += count[n][m][v];
  }
  return tail / total;
}

}  // namespace fdsid::testing
