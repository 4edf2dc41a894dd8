#include "fdsid/records.hpp"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <limits>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "numerics/fft.hpp"

namespace fdsid {

FrfData frf_from_records(const SampleStatistics& stats) {
  const FrfData& d = stats.data;
  if (d.inputs() != 1 || d.outputs() != 1 || d.columns() != 1)
    throw Error(ErrorKind::Input, "records",
                "have " + std::to_string(d.inputs()) + " inputs and " + std::to_string(d.outputs()) +
                    " outputs; an FRF file holds one input and one output (choose them with --input and --output)");
  if (stats.M < 2) throw Error(ErrorKind::Input, "records", "need M >= 2 periods for a sample variance");
  const int F = d.frequencies();
  ComplexMatrixStack G(F, 1, 1);
  RealMatrixStack var(F, 1, 1);
  for (int k = 0; k < F; ++k) {
    const cplx U = d.U[k](0, 0), g = d.Y[k](0, 0) / U;
    G(k, 0, 0) = g;
    // data.variance is σ̂²_Y / M; var_U and cov_YU are not divided by M. The
    // bracket is the sample variance of Y_l − Ĝ U_l over the periods, ≥ 0
    // but for rounding (clipped: a zero, identical periods, is refused by
    // frf_data as a variance that is not positive).
    const double var_e = d.variance[k](0, 0) +
                         (std::norm(g) * stats.var_U[k](0) - 2 * std::real(std::conj(g) * stats.cov_YU[k](0, 0))) / stats.M;
    var(k, 0, 0) = std::max(var_e, 0.0) / std::norm(U);
  }
  return frf_data(d.domain, d.omega, std::move(G), std::move(var));
}

std::string frf_csv(const FrfData& data) {
  if (data.inputs() != 1 || data.outputs() != 1) throw Error(ErrorKind::Input, "FRF", "an FRF file holds one channel");
  std::string out = "omega,G_re,G_im,G_var\n";
  char buf[160];
  for (int k = 0; k < data.frequencies(); ++k) {
    const cplx g = data.Y[k](0, 0) / data.U[k](0, 0);
    std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g\n", data.omega(k), g.real(), g.imag(),
                  data.variance[k](0, 0) / std::norm(data.U[k](0, 0)));
    out += buf;
  }
  return out;
}

RecordFit fit_on_record(const StateSpace& model, const Records& records) {
  validate(model);
  const RecordMeta& meta = records.meta;
  const int m = records.inputs, p = static_cast<int>(records.samples.cols()) - m, P = meta.period, M = meta.periods;
  if (model.inputs() != m || model.outputs() != p)
    throw Error(ErrorKind::Input, "model",
                "has " + std::to_string(model.inputs()) + " inputs and " + std::to_string(model.outputs()) +
                    " outputs; the record has " + std::to_string(m) + " and " + std::to_string(p));
  // 1e-5 relative: writers print at least 6 significant digits (as gap's rule).
  if (model.domain == Domain::Discrete && std::abs(model.sample_time - meta.sample_time) > 1e-5 * meta.sample_time)
    throw Error(ErrorKind::Input, "model field \"sample_time\"",
                fmt(model.sample_time, 10) + " differs from the record's " + fmt(meta.sample_time, 10));
  require_stable(model, "to compare");
  if (records.samples.rows() != static_cast<Eigen::Index>(P) * M)
    throw Error(ErrorKind::Input, "record",
                "has " + std::to_string(records.samples.rows()) + " samples, not P M = " + std::to_string(P * M));
  // One period, averaged over the M periods.
  Eigen::MatrixXd avg = Eigen::MatrixXd::Zero(P, m + p);
  for (int l = 0; l < M; ++l) avg += records.samples.middleRows(static_cast<Eigen::Index>(l) * P, P);
  avg /= M;
  const int bins = P / 2 + 1;
  std::vector<std::vector<cplx>> U(m, std::vector<cplx>(bins));
  numerics::RealFft fft(P, "validate");
  for (int i = 0; i < m; ++i) {
    for (int t = 0; t < P; ++t) fft.time()[t] = avg(t, i);
    fft.forward();
    for (int k = 0; k < bins; ++k) U[i][k] = fft.freq()[k];
  }
  RecordFit fit;
  fit.periods = M;
  fit.lines = bins - 1;
  std::vector<Eigen::MatrixXcd> G(bins);
  for (int k = 1; k < bins; ++k) {
    const double w = 2 * M_PI * k / P;
    G[k] = transfer(model, model.domain == Domain::Discrete ? std::polar(1.0, w) : cplx(0, w / meta.sample_time));
  }
  for (int o = 0; o < p; ++o) {
    fft.freq()[0] = 0;  // DC left out
    for (int k = 1; k < bins; ++k) {
      cplx y = 0;
      for (int i = 0; i < m; ++i) y += G[k](o, i) * U[i][k];
      fft.freq()[k] = y;
    }
    if (P % 2 == 0) fft.freq()[P / 2] = fft.freq()[P / 2].real();  // the Nyquist line of a real signal
    fft.backward();  // unnormalised: divide by P
    const double mean = avg.col(m + o).mean();
    double err = 0, spread = 0;
    for (int t = 0; t < P; ++t) {
      const double y = avg(t, m + o) - mean, yhat = fft.time()[t] / P;
      err += (y - yhat) * (y - yhat);
      spread += y * y;
    }
    const double nrmse = spread > 0 ? std::sqrt(err / spread) : std::numeric_limits<double>::infinity();
    fit.nrmse.push_back(nrmse);
    fit.fit_percent.push_back(100 * (1 - nrmse));
  }
  return fit;
}

}  // namespace fdsid
