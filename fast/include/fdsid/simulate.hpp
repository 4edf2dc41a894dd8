#pragma once
/// Periodic experiments in simulation: random-phase multisines and the exact
/// steady-state response of a model to them, with optional output and input
/// noise. These make the bundled example data, the command-line tests and
/// teaching cases for identify-frf (Pintelon 2002 Section 4's setting).
#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"

namespace fdsid {

struct RecordOptions {
  int period = 256;
  int periods = 8;
  std::vector<int> lines;         ///< excited DFT lines (1 … P/2); empty: every odd line below P/4
  double rms = 1.0;               ///< RMS of the input multisine
  double output_noise_std = 0.0;  ///< white Gaussian noise added to y (sample std)
  double input_noise_std = 0.0;   ///< white Gaussian noise added to the recorded u (errors-in-variables)
  std::uint64_t seed = 1;
};

/// A random-phase multisine over the excited lines, one period of P samples,
/// scaled to the requested RMS, and the model's exact steady-state response
/// y = IDFT(G(e^{j2πk/P}) U(k)) repeated over M periods (SISO models; discrete
/// time, sample index = time). Returns P·M rows × 2 columns (u, y) with the noise
/// added; `meta` receives the matching meta data.
Eigen::MatrixXd simulate_periodic_record(const StateSpace& model, const RecordOptions& options, RecordMeta& meta);

}  // namespace fdsid
