#pragma once
/// Files of the contracts (../shared/CONTRACTS.md): model JSON, power-spectrum
/// CSV. Every reader validates what it reads and throws Error(Input) or
/// Error(Grid) naming the file, the line or field, and what is wrong.
#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid {

/// Model JSON: {"domain", "sample_time", "A", "B", "C", "D"}; entries JSON
/// numbers or decimal strings (parsed with strtod, correctly rounded).
StateSpace model_from_json(const nlohmann::json& j, const std::string& where = "model");
StateSpace read_model(const std::string& path);
/// The model file's JSON as read_model reads it (readable, no key twice), for
/// the fields beside the model (identify-frf's "omega_band", "source").
nlohmann::json read_model_file(const std::string& path);
nlohmann::json model_to_json(const StateSpace& model);
/// The model's poles as [[re, im], ...] (the "poles" field of an identified model).
nlohmann::json poles_to_json(const StateSpace& model);

/// Identified-model JSON: the model plus order, method, singular values, poles
/// and the diagnostics of every step.
nlohmann::json result_to_json(const SpectrumResult& result);

/// Power-spectrum CSV: header omega,S_re,S_im (m = 1) or
/// omega,S11_re,S11_im,S12_re,...,Smm_im; omega on the uniform grid
/// pi (k-1)/M, k = 1..M+1 (checked to a relative 1e-9, i.e. ten significant digits).
SpectrumData read_spectrum_csv(const std::string& path);
SpectrumData parse_spectrum_csv(std::istream& in, const std::string& name);
void write_spectrum_csv(std::ostream& out, const SpectrumData& data);

/// Frequency-response CSV: header omega,G_re,G_im with an optional G_var
/// column (variance of each complex sample, > 0). omega in rad/sample
/// (discrete) or rad/s (continuous); validated by validate(FrfData). Without
/// G_var every sample gets weight 1 and has_noise_model is false.
FrfData read_frf_csv(const std::string& path, Domain domain);
FrfData parse_frf_csv(std::istream& in, const std::string& name, Domain domain);

/// How the omega column of an FRF file is read (review findings 11 and 36;
/// MATLAB's idfrd(..., Ts, 'FrequencyUnit', 'Hz'), python-control's frd in
/// rad/s): `hz` reads cycles per second (cycles per sample without a sample
/// time), else radians; a sample time Ts > 0 says the column is per second,
/// so a discrete-time ω becomes rad/sample by × Ts and the model carries Ts.
/// The default (rad, no Ts) is the format's own unit: rad/sample (discrete),
/// rad/s (continuous).
struct FrequencyUnits {
  bool hz = false;
  double sample_time = 0;        ///< Ts in seconds; 0: not given
  std::string sample_time_text;  ///< Ts as the user wrote it (the reference reads it exactly)
  bool unit_given = false;       ///< --frequency-unit was written (rad given so silences the cycles/sample guard)
  bool is_default() const { return !hz && sample_time == 0; }
  /// The factor that takes the column to rad/sample (discrete) or rad/s
  /// (continuous): (hz ? 2π : 1) × (discrete and Ts given ? Ts : 1).
  double factor(Domain domain) const;
  /// The column's unit in words: "Hz", "rad/s", "cycles/sample", "rad/sample".
  std::string column_unit(Domain domain) const;
};
/// Purpose: an FRF file whose omega column is in `units`; the data's omega in
/// the format's unit and, with a sample time, data.sample_time = Ts.
/// Fails: as read_frf_csv; a frequency outside [0, π] rad/sample after the
/// conversion names the column's value, its unit and the Nyquist frequency;
/// with no unit given, a discrete-time column on a DFT grid k/P no higher than
/// 1/2 (cycles/sample written where rad/sample is read) names the grid and both
/// ways out (--frequency-unit hz, or rad when it is rad/sample).
FrfData read_frf_csv(const std::string& path, Domain domain, const FrequencyUnits& units);
/// Refuses units where they mean nothing (Error(Input) naming the option):
/// for records (`from_frf` false: their meta has Ts) or for spectra, and a
/// sample time for a continuous-time FRF (its omega is per second already).
void require_frequency_units(const FrequencyUnits& units, Domain domain, bool from_frf);

/// Periodic input/output records CSV: header u,y or u1,…,uq,y1,…,yp (inputs
/// first), one row per sample. Returns the samples (rows × (q + p)) and sets
/// `inputs` = q.
Eigen::MatrixXd read_records_csv(const std::string& path, int& inputs);
Eigen::MatrixXd parse_records_csv(std::istream& in, const std::string& name, int& inputs);
/// The SISO records CSV text (header u,y; %.17g, so a double reads back exactly).
std::string records_csv(const Eigen::MatrixXd& samples);

/// Real records as they come (issue 14): the input and output columns chosen
/// by their header names (any header; the other columns, even with empty
/// cells, are ignored), and leading periods dropped (a transient).
struct RecordSelection {
  std::vector<std::string> inputs, outputs;  ///< header names; both empty: the u…, y… header of the format
  int skip_periods = 0;                      ///< leading whole periods dropped; the meta's M is reduced by it
  int use_periods = 0;                       ///< after the skipped ones, only this many periods (0: all the rest)
  bool empty() const { return inputs.empty() && outputs.empty() && skip_periods == 0 && use_periods == 0; }
};

/// A records CSV read with its meta and a selection: samples (P·M rows, the
/// inputs then the outputs), the number of inputs, the meta with M reduced by
/// the skipped periods.
struct Records {
  Eigen::MatrixXd samples;
  int inputs = 0;
  RecordMeta meta;
};

/// Purpose: read `data_path` and `meta_path` as `selection` says.
/// Fails: Error(Input) naming the file: a named column not in the header (the
/// header's names listed), --input without --output or the reverse, a name
/// given twice, an empty or non-numeric cell in a chosen column (its line),
/// skip_periods < 0 or ≥ the meta's periods, use_periods < 0 or more than
/// remain after the skipped ones, fewer rows than the skipped periods need.
Records read_records(const std::string& data_path, const std::string& meta_path, const RecordSelection& selection = {});
Eigen::MatrixXd parse_records_csv(std::istream& in, const std::string& name, int& inputs,
                                  const RecordSelection& selection);

/// Meta JSON: {"period": P, "periods": M, "sample_time": Ts, "excited_lines": [k, …]}.
RecordMeta read_meta(const std::string& path);
RecordMeta meta_from_json(const nlohmann::json& j, const std::string& where);
nlohmann::json meta_to_json(const RecordMeta& meta);

/// Identified-model JSON of identify-frf: the model plus order, method, r,
/// singular values (those the order was read from), poles, V_SUB and the r scan.
nlohmann::json frf_result_to_json(const FrfResult& result, const std::string& method);

/// Checks, before any work, that write_text_file (or a figure) can create
/// `path`: "-" (stdout) passes; a symbolic link is judged by the file it
/// points to; an existing device or FIFO must be writable; else the folder
/// must exist and be writable and the path must not be a folder. Throws
/// Error(Input) at `option`.
void require_writable_path(const std::string& path, const std::string& option);

/// Writes text to path atomically (temporary file in the same folder, then
/// rename), or to stdout when path is "-". A symbolic link is followed (its
/// target written, the link kept); an existing device or FIFO is written in
/// place, never replaced.
void write_text_file(const std::string& path, const std::string& text);

}  // namespace fdsid
