#pragma once
/// Measured periodic records as users have them (issue 14, "real data as it
/// comes"): the FRF of a record with its variance (`fdsid frf`, Pintelon 2002
/// Section 4.1), and how well a model reproduces a record it was not
/// identified from (`fdsid validate`, the NRMSE fit of MATLAB's `compare`).
#include <string>
#include <vector>

#include "fdsid/frf_id.hpp"
#include "fdsid/io.hpp"
#include "fdsid/model.hpp"

namespace fdsid {

/// Purpose: the nonparametric FRF estimate of a SISO record at its excited
/// lines, Ĝ(k) = Ŷ(k)/Û(k) from the sample means over the M periods, with
/// G_var = E|δĜ|² to first order:
///   (σ̂²_Y + |Ĝ|² σ̂²_U − 2 Re(conj(Ĝ) σ̂_YU)) / (M |Û|²),
/// σ̂² the sample variances over the periods (1/(M−1) form, Eq. 25) and σ̂_YU
/// the sample covariance (Eq. 32): δĜ ≈ (δŶ − Ĝ δÛ)/Û.
/// Fails: Error(Input) for a record that is not SISO (the FRF file holds one
/// channel) or for M < 2 (no sample variance).
FrfData frf_from_records(const SampleStatistics& stats);

/// The FRF CSV (omega,G_re,G_im,G_var; %.17g) of SISO FRF data.
std::string frf_csv(const FrfData& data);

/// How well a model reproduces a periodic record.
struct RecordFit {
  int periods = 0;                 ///< M periods averaged into the measured output
  int lines = 0;                   ///< DFT lines 1 … P/2 simulated (DC left out)
  std::vector<double> nrmse;       ///< per output: ‖y − ŷ‖ / ‖y − ȳ‖
  std::vector<double> fit_percent; ///< per output: 100 (1 − nrmse), MATLAB compare's fit
};

/// Purpose: the model's periodic steady-state response to the record's
/// input, against the record's output, per output channel.
/// Method: u and y are averaged over the M periods (the noise falls by √M;
/// the steady state is the same in every period); ŷ = IDFT(G(ξ_k) U(k)) over
/// every line k = 1 … P/2, ξ_k = e^{j2πk/P} (discrete) or j2πk/(P Ts)
/// (continuous); the DC line is left out of both (sensor offsets are not
/// modelled), so y is compared after removing its mean.
/// Fails: Error(Input) when the model's inputs/outputs differ from the
/// record's, a discrete model's sample time differs from the record's
/// (1e-5 relative), or the model is unstable (no periodic steady state).
RecordFit fit_on_record(const StateSpace& model, const Records& records);

}  // namespace fdsid
