// Sim-to-real gap statistic in 50-digit arithmetic (see gap.hpp), and the
// periodic-records CSV reader. No Eigen decomposition is instantiated here:
// the DFTs are the direct sums of period_spectra, the model response is
// frequency_response (both frf_id.cpp).
#include "fdsid/reference/gap.hpp"

#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/io.hpp"

#include "common.hpp"

#include <boost/math/constants/constants.hpp>
#include <boost/math/special_functions/gamma.hpp>

#include <cctype>
#include <fstream>
#include <set>
#include <sstream>

namespace fdsid::reference {
namespace {

using detail::finite;
using detail::fmt;

// The lines of one list: each in 1 … period/2 and not yet in `seen` (which
// collects the lines of both lists, so the lists must also be disjoint).
void check_lines(const std::vector<int>& lines, const char* which, int period, std::set<int>* seen) {
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int k = lines[i];
    if (k < 1 || k > period / 2)
      throw InputError("gap_statistic: " + std::string(which) + " line " + std::to_string(k) +
                       " (entry " + std::to_string(i) + ") is outside 1 ... period/2 = " +
                       std::to_string(period / 2));
    if (!seen->insert(k).second)
      throw InputError("gap_statistic: " + std::string(which) + " line " + std::to_string(k) +
                       " (entry " + std::to_string(i) + ") is repeated or also in the other list");
  }
}

// Ē, s², t and p at the lines of `which` (index `offset` … into the spectra).
LineStatistics line_statistics(const std::vector<std::vector<MatrixC>>& spectra, std::size_t offset,
                               const std::vector<int>& lines,
                               const std::function<Complex(int)>& response, int M,
                               const char* which) {
  LineStatistics out;
  out.lines = lines;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int k = lines[i];
    const Complex G = response(k);
    if (!finite(G.real()) || !finite(G.imag()))
      throw InputError("gap_statistic: response at " + std::string(which) + " line " +
                       std::to_string(k) + " is not finite");
    // E_l(k) = Y_l(k) − G′(k) U_l(k); spectra[l][j] = (U_l, Y_l) at line j.
    std::vector<Complex> E(M);
    Complex mean(0);
    for (int l = 0; l < M; ++l) {
      const MatrixC& Z = spectra[l][offset + i];
      E[l] = Z(1, 0) - G * Z(0, 0);
      mean += E[l];
    }
    mean /= Real(M);
    Real variance = 0;  // two-pass: Σ |E_l − Ē|², no cancellation
    for (int l = 0; l < M; ++l) variance += std::norm(E[l] - mean);
    variance /= Real(M - 1);
    if (variance == 0)
      throw InputError("gap_statistic: the residual at " + std::string(which) + " line " +
                       std::to_string(k) + " is identical in all " + std::to_string(M) +
                       " periods (sample variance 0): t is undefined");
    const Real t = Real(M) * std::norm(mean) / variance;
    out.mean_residual.push_back(mean);
    out.variance.push_back(variance);
    out.t.push_back(t);
    out.p.push_back(gap_p_value(t, M));
  }
  return out;
}

}  // namespace

Real gap_p_value(const Real& t, int M) {
  if (M < 2) throw InputError("gap_p_value: M = " + std::to_string(M) + " < 2");
  if (!(t >= 0)) throw InputError("gap_p_value: t = " + fmt(t) + " is not >= 0");
  // Survival function of F(2, 2M−2) (gap.hpp): (1 + 2t/d)^{−d/2}, d = 2M − 2.
  const Real half_d = Real(M - 1);
  return pow(1 + t / half_d, -half_d);
}

GapStatistic gap_statistic(const std::vector<Real>& u, const std::vector<Real>& y, int period,
                           int periods, const std::vector<int>& excited_lines,
                           const std::vector<int>& unexcited_lines,
                           const std::function<Complex(int)>& response) {
  if (period < 2) throw InputError("gap_statistic: period = " + std::to_string(period) + " < 2");
  if (periods < 3)
    throw InputError("gap_statistic: periods M = " + std::to_string(periods) +
                     " < 3 (the sample variance needs M >= 2, the normalisation "
                     "(M-2)/(M-1) of the mean of F(2, 2M-2) needs M >= 3)");
  const std::size_t length = static_cast<std::size_t>(period) * static_cast<std::size_t>(periods);
  if (u.size() != length || y.size() != length)
    throw InputError("gap_statistic: u has " + std::to_string(u.size()) + " and y has " +
                     std::to_string(y.size()) + " samples, period * periods = " +
                     std::to_string(length));
  if (excited_lines.empty()) throw InputError("gap_statistic: no excited lines");
  if (!response) throw InputError("gap_statistic: no response given");
  std::set<int> seen;
  check_lines(excited_lines, "excited", period, &seen);
  check_lines(unexcited_lines, "unexcited", period, &seen);

  // Eq. (4) per period, both lists in one call: [l][j] = (U_l(k_j), Y_l(k_j))ᵀ.
  std::vector<int> all = excited_lines;
  all.insert(all.end(), unexcited_lines.begin(), unexcited_lines.end());
  const auto spectra = period_spectra({u, y}, period, periods, all);

  GapStatistic out;
  out.M = periods;
  out.excited = line_statistics(spectra, 0, excited_lines, response, periods, "excited");
  out.unexcited =
      line_statistics(spectra, excited_lines.size(), unexcited_lines, response, periods, "unexcited");
  Real sum = 0;
  for (const Real& t : out.excited.t) sum += t;
  const Real K = Real(static_cast<long long>(excited_lines.size()));
  out.gap = (Real(periods - 2) / Real(periods - 1)) * sum / K;
  return out;
}

GapStatistic gap_statistic(const std::vector<Real>& u, const std::vector<Real>& y, int period,
                           int periods, const std::vector<int>& excited_lines,
                           const std::vector<int>& unexcited_lines, const Model& model,
                           const Real& sample_time) {
  if (model.B.cols() != 1 || model.C.rows() != 1 || model.D.rows() != 1 || model.D.cols() != 1)
    throw InputError("gap_statistic: the model is not SISO (B is " + std::to_string(model.B.rows()) +
                     "x" + std::to_string(model.B.cols()) + ", C is " +
                     std::to_string(model.C.rows()) + "x" + std::to_string(model.C.cols()) + ")");
  const bool continuous = model.domain == "continuous";
  if (!continuous && model.domain != "discrete")
    throw InputError("gap_statistic: model domain \"" + model.domain +
                     "\" is neither discrete nor continuous");
  if (continuous && !(sample_time > 0 && finite(sample_time)))
    throw InputError("gap_statistic: sample_time = " + fmt(sample_time) + " is not > 0");
  if (period < 2) throw InputError("gap_statistic: period = " + std::to_string(period) + " < 2");
  const Real two_pi = 2 * boost::math::constants::pi<Real>();
  // Line k: ω = 2πk/P rad/sample (ξ = e^{jω}), or 2πk/(P·Ts) rad/s (ξ = jω).
  const Real scale = continuous ? two_pi / (Real(period) * sample_time) : two_pi / Real(period);
  const std::function<Complex(int)> response = [&](int k) {
    return frequency_response(model, scale * Real(k))(0, 0);
  };
  return gap_statistic(u, y, period, periods, excited_lines, unexcited_lines, response);
}

namespace {

Real squared_sum(const std::vector<Complex>& d) {
  Real total = 0;
  for (const Complex& x : d) total += norm(x);
  return total;
}

// d_m(j) for every pair j (gap.hpp: the lines differenced in disjoint adjacent
// pairs, then the deviations from the periods' mean), the pairs with
// Σ_m |d_m|² = 0 left out. Throws InputError for fewer than 1 period or rows
// of unequal length.
std::vector<std::vector<Complex>> pair_deviations(const std::vector<std::vector<Complex>>& r) {
  if (r.empty()) throw InputError("period tests: no periods");
  const std::size_t R = r.size(), K = r[0].size();
  for (const auto& row : r)
    if (row.size() != K) throw InputError("period tests: the periods' residual rows differ in length");
  std::vector<std::vector<Complex>> out;
  for (std::size_t j = 0; 2 * j + 1 < K; ++j) {
    std::vector<Complex> d(R);
    Complex mean(Real(0), Real(0));
    for (std::size_t m = 0; m < R; ++m) {
      d[m] = r[m][2 * j] - r[m][2 * j + 1];
      mean += d[m];
    }
    mean /= Real(static_cast<long long>(R));
    for (Complex& x : d) x -= mean;
    if (squared_sum(d) > 0) out.push_back(std::move(d));
  }
  return out;
}

}  // namespace

PeriodPowerStatistic period_power_statistic(const std::vector<std::vector<Complex>>& residuals) {
  const auto d = pair_deviations(residuals);
  const int R = static_cast<int>(residuals.size());
  PeriodPowerStatistic out;
  out.pairs = static_cast<int>(d.size());
  if (R < 3 || out.pairs < 30) return out;
  const Real Rr = Real(R), J = Real(out.pairs);
  std::vector<Real> Q(static_cast<std::size_t>(R), Real(0));
  Real v = 0;
  for (const auto& dj : d) {
    const Real total = squared_sum(dj);
    for (int m = 0; m < R; ++m) {
      const Real q = norm(dj[static_cast<std::size_t>(m)]) / total;
      Q[static_cast<std::size_t>(m)] += q;
      v += (q - 1 / Rr) * (q - 1 / Rr);
    }
  }
  out.v = v / (J * Rr);
  if (!(out.v > 0)) return out;
  Real spread = 0;
  for (Real& x : Q) {
    x /= J;
    spread += (x - 1 / Rr) * (x - 1 / Rr);
    out.relative.push_back(Rr * x);
  }
  out.S = J * (Rr - 1) / (out.v * Rr) * spread;
  out.p = boost::math::gamma_q((Rr - 1) / 2, out.S / 2);
  out.tested = true;
  return out;
}

PeriodCorrelation period_lag_correlation(const std::vector<std::vector<Complex>>& residuals) {
  const auto d = pair_deviations(residuals);
  const std::size_t R = residuals.size();
  PeriodCorrelation out;
  out.pairs = static_cast<int>(d.size());
  if (R < 4 || out.pairs < 30) return out;
  std::vector<Real> c;
  for (const auto& dj : d) {
    Real lag = 0;
    for (std::size_t m = 0; m < R; ++m) lag += real(dj[m] * conj(dj[(m + 1) % R]));
    c.push_back(lag / squared_sum(dj));
  }
  const Real J = Real(out.pairs);
  for (const Real& x : c) out.mean += x;
  out.mean /= J;
  for (const Real& x : c) out.variance += (x - out.mean) * (x - out.mean);  // two-pass
  out.variance /= J - 1;
  out.tested = true;
  return out;
}

}  // namespace fdsid::reference
