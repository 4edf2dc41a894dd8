#pragma once
/// Files of the contracts (../shared/CONTRACTS.md): model JSON, power-spectrum
/// CSV. Every reader validates what it reads and throws Error(Input) or
/// Error(Grid) naming the file, the line or field, and what is wrong.
#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "fdsid/model.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid {

/// Model JSON: {"domain", "sample_time", "A", "B", "C", "D"}; entries JSON
/// numbers or decimal strings (parsed with strtod, correctly rounded).
StateSpace model_from_json(const nlohmann::json& j, const std::string& where = "model");
StateSpace read_model(const std::string& path);
nlohmann::json model_to_json(const StateSpace& model);

/// Identified-model JSON: the model plus order, method, singular values, poles
/// and the diagnostics of every step.
nlohmann::json result_to_json(const SpectrumResult& result);

/// Power-spectrum CSV: header omega,S_re,S_im (m = 1) or
/// omega,S11_re,S11_im,S12_re,...,Smm_im; omega on the uniform grid
/// pi (k-1)/M, k = 1..M+1 (checked to a relative 1e-9, i.e. ten significant digits).
SpectrumData read_spectrum_csv(const std::string& path);
SpectrumData parse_spectrum_csv(std::istream& in, const std::string& name);
void write_spectrum_csv(std::ostream& out, const SpectrumData& data);

/// Writes text to path atomically (temporary file in the same folder, then
/// rename), or to stdout when path is "-".
void write_text_file(const std::string& path, const std::string& text);

}  // namespace fdsid
