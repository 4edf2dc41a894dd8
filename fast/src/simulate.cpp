#include "fdsid/simulate.hpp"

#include <cmath>
#include <random>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "numerics/fft.hpp"

namespace fdsid {

Eigen::MatrixXd simulate_periodic_record(const StateSpace& model, const RecordOptions& o, RecordMeta& meta) {
  validate(model);
  if (model.domain != Domain::Discrete || model.inputs() != 1 || model.outputs() != 1)
    throw Error(ErrorKind::Input, "model", "records are simulated for discrete-time SISO models");
  if (o.period < 4 || o.periods < 1)
    throw Error(ErrorKind::Input, "record", "needs period >= 4 and periods >= 1");
  if (!(o.rms > 0) || !(o.output_noise_std >= 0) || !(o.input_noise_std >= 0))
    throw Error(ErrorKind::Input, "record", "rms must be positive and noise levels non-negative");
  const int P = o.period;
  std::vector<int> lines = o.lines;
  if (lines.empty())
    for (int k = 1; k < P / 4; k += 2) lines.push_back(k);
  for (int k : lines)
    if (k < 1 || k >= P / 2)
      throw Error(ErrorKind::Input, "record", "excited line " + std::to_string(k) + " is outside 1 ... P/2 - 1");
  // identify-frf refuses a meta that lists a line twice; so does the simulation.
  if (const int k = repeated_line(lines); k >= 0)
    throw Error(ErrorKind::Input, "record", "excited line " + std::to_string(k) + " is listed twice");
  // The records are the periodic steady state, computed line by line as
  // G(e^{jw_k}) U_k. An unstable model has none: the frequency-domain formula
  // would still give a periodic signal, the non-causal one, which no
  // experiment can produce.
  const double rho = spectral_radius(model);
  if (!(rho < 1.0))
    throw Error(ErrorKind::Input, "model",
                "has a pole of modulus " + fmt(rho, 6) +
                    " (not inside the unit circle): an unstable model has no periodic steady state to record");
  std::mt19937_64 gen(o.seed);
  std::uniform_real_distribution<double> phase(0.0, 2 * M_PI);
  const int bins = P / 2 + 1;
  // One period of u and y by unnormalised c2r transforms of their lines.
  numerics::RealFft fu(P), fy(P);
  for (int k = 0; k < bins; ++k) fu.freq()[k] = fy.freq()[k] = 0;
  for (int k : lines) {
    const cplx u = std::polar(1.0, phase(gen));
    fu.freq()[k] = u;
    fy.freq()[k] = transfer(model, std::polar(1.0, 2 * M_PI * k / P))(0, 0) * u;
  }
  fu.backward();
  fy.backward();
  const std::vector<double> u(fu.time(), fu.time() + P), y(fy.time(), fy.time() + P);
  double ss = 0;
  for (double v : u) ss += v * v;
  const double scale = o.rms / std::sqrt(ss / P);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd rec(static_cast<Eigen::Index>(P) * o.periods, 2);
  for (int l = 0; l < o.periods; ++l)
    for (int t = 0; t < P; ++t) {
      const Eigen::Index i = static_cast<Eigen::Index>(l) * P + t;
      rec(i, 0) = scale * u[t] + o.input_noise_std * normal(gen);
      rec(i, 1) = scale * y[t] + o.output_noise_std * normal(gen);
    }
  meta = RecordMeta{};
  meta.period = P;
  meta.periods = o.periods;
  meta.sample_time = model.sample_time;
  meta.excited_lines = lines;
  return rec;
}

}  // namespace fdsid
