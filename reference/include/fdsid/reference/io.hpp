// File formats of shared/CONTRACTS.md in high precision: model JSON and
// power-spectrum CSV, every number parsed from its decimal text.
#pragma once

#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/spectrum_id.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace fdsid::reference {

/// Parses a decimal number ("-0.8876", "1.76e-1", "3") exactly into Real
/// (correctly rounded to the 50-digit format, no binary double in between).
/// Throws InputError naming the text if it is not a finite decimal number.
Real parse_decimal(const std::string& text);

/// Decimal text with `digits` significant digits (scientific notation).
std::string to_decimal(const Real& x, int digits = 40);

/// Model from the JSON of the contracts: {"domain", "sample_time", "A", "B",
/// "C", "D"}, row-major nested arrays. Entries may be decimal strings (parsed
/// exactly) or JSON numbers. A JSON number reaches us as a binary double whose
/// original text is lost; it is converted through its shortest round-trip
/// decimal, which recovers the original text exactly whenever that text had
/// at most 15 significant digits (0.8876 becomes exactly 0.8876). Longer
/// numbers carry the double's error (~1e-17 relative); write them as strings.
/// Throws InputError naming the field (and row) on bad shapes or entries:
/// A n×n (n ≥ 1), B n×q, C p×n, D p×q.
Model model_from_json(const nlohmann::json& json);

/// Model as JSON, every number (sample_time included) a decimal string with
/// `digits` significant digits (default 40; at least 30 is required).
nlohmann::json model_to_json(const Model& model, int digits = 40);

/// Reads a model JSON file; InputError names the file on failure.
Model read_model(const std::string& path);

/// Identified model in the format of the contracts (`--precision high`): the
/// model plus "order", "method" ("akcay2011" or "vo1997"), "p", "r",
/// "singular_values" (those the order was read from), "poles" [[re, im], …],
/// "E", "F", "P"; every number a decimal string with `digits` digits.
nlohmann::json result_to_json(const Result& result, bool van_overschee = false,
                              int digits = 40);

/// Reads the power-spectrum CSV of the contracts: header `omega,S_re,S_im`
/// (m = 1) or `omega,S11_re,S11_im,S12_re,…,Smm_im`, one row per ω_k. Every
/// cell is parsed as a decimal string (parse_decimal). The grid must be
/// ω_k = π(k−1)/M, k = 1 … M+1 with M = rows − 1 ≥ 1, to within 1e-9·π
/// (the omegas are only checked, the algorithm uses the exact grid).
/// Throws InputError "<path>:<line>: …" on any malformed line, cell or grid.
Spectrum read_spectrum_csv(const std::string& path);

/// Writes `spectrum` in that CSV format, omega and every entry with `digits`
/// significant digits. Throws InputError if the file cannot be written.
void write_spectrum_csv(const Spectrum& spectrum, const std::string& path,
                        int digits = 40);

/// Reads the frequency-response CSV of the contracts: header `omega,G_re,G_im`
/// or `omega,G_re,G_im,G_var`, one row per ω_k, every cell parsed exactly
/// (parse_decimal). Returns FRF data for Pintelon (2002): U[k] = 1, Y[k] = G_k,
/// variance[k] = G_var (1 for every sample when the column is absent), in the
/// given domain ("discrete": rad/sample, "continuous": rad/s). Ranges and
/// distinctness of ω are checked by identify_frf. Throws InputError
/// "<path>:<line>: …" on a malformed header, line or cell, or G_var ≤ 0.
FrfData read_frf_csv(const std::string& path, const std::string& domain = "discrete");

/// One SISO periodic input/output record (CONTRACTS.md "Periodic input/output
/// records"), every sample parsed exactly from its decimal text.
struct Records {
  std::vector<Real> u, y;
};

/// Reads the records CSV: header `u,y`, then one row `u,y` per sample (blank
/// lines skipped), each cell parsed exactly by parse_decimal (io.hpp), no
/// binary double in between. Throws InputError "<path>:<line>: …" on a missing
/// file, another header (several channels are not supported here), a row
/// without exactly two cells, a cell that is not a finite decimal, or no rows.
Records read_records_csv(const std::string& path);

}  // namespace fdsid::reference
