#pragma once
// Subcommands served by the high-precision reference (reference/): kept apart
// from the subcommand files so that only this file sees the multiprecision types.
#include <string>

#include "fdsid/io.hpp"

#include "fdsid/spectrum_id.hpp"
#include "fdsid/workflow.hpp"

namespace fdsid::cli {

/// `identify-spectrum --precision high`: Algorithm 1 in 50 digits; the JSON
/// carries every number as a decimal string of 40 significant digits.
/// The reference implements the paper's conjugate extension; the Hermitian-part
/// reading is obtained by replacing each sample by (S + S^H)/2 first (exact in 50
/// digits), which is what that reading means.
int identify_spectrum_high(const std::string& json_path, const std::string& data_path, int order, int p, int r,
                           bool van_overschee, Extension extension);

/// `check`: identify with the reference and compare the candidate in
/// similarity-invariant terms, with the candidate's p, r, method and extension
/// when its JSON names them. tolerance <= 0 uses the derived default.
int check(const std::string& json_path, const std::string& model_path, const std::string& data_path,
          double tolerance);

/// `check --frf FILE` / `check --data REC.csv --meta META.json`: what the
/// candidate is checked against; r, method and omega_scale are taken from the
/// candidate JSON when it carries them, else from these options (0 / empty:
/// r by fdsid's V_SUB selection at the candidate's order, bilinear, the
/// default omega_scale).
struct FrfCheckRequest {
  std::string model_path, frf_path, data_path, meta_path;
  int r = 0;
  std::string method;  ///< "", "bilinear" or "orthogonal"
  double omega_scale = 0;
  double tolerance = 0;  ///< 0: the derived rule
  /// Records: --eiv / --improper / --eiv-variance model / --min-input-snr when the candidate JSON has no "source".
  bool eiv = false, improper = false, eiv_model_variance = false;
  double min_input_snr = 0;  ///< 0: from the JSON, else 10 (identify-frf's default)
  RecordSelection selection;  ///< records: columns by name, skipped periods (as the candidate's identification read them)
  FrequencyUnits units;       ///< FRF file: its omega column's unit (when the candidate's "source" names none)
};

/// Identify with the reference at the candidate's settings and compare G on
/// the data grid and on a dense grid, and the poles (compare_frf_models).
/// Exit 0 agree, 1 disagree.
int check_frf(const std::string& json_path, const FrfCheckRequest& request);

/// `sample-spectrum --precision high`: the model's spectrum from its decimal
/// entries in 50 digits, written with 40 significant digits.
int sample_spectrum_high(const std::string& model_path, int M, const std::string& out_path);

/// What identify-frf hands to the reference: the file(s), the order and r
/// (chosen by the double-precision selection when the user gave none).
struct FrfHighRequest {
  std::string frf_path;              ///< FRF CSV, or empty
  FrequencyUnits units;              ///< how the FRF CSV's omega column is read
  std::string data_path, meta_path;  ///< periodic records + meta, or empty
  bool continuous = false;
  bool orthogonal = false;
  DiscreteMethod discrete = DiscreteMethod::Monomial;  ///< discrete time: the basis (--method)
  double omega_scale = 0;
  int order = 0, r = 0;
  /// Records only: Section 5's treatment (errors-in-variables, improper), as identify-frf applies it.
  RecordTreatment treatment = RecordTreatment::Plain;
  EivVariance eiv_variance = EivVariance::Data;
  double min_input_snr = 10;
  RecordSelection selection;  ///< records: columns by name, skipped periods
};

/// `identify-frf --precision high`: Pintelon (2002) Algorithm 1/2 in 50
/// digits (reference/frf_id). FRF files are parsed exactly from their decimal
/// text; periodic records go through the reference's direct DFT (Eq. 4) from
/// the double values of the samples. JSON numbers are 40-digit strings.
int identify_frf_high(const std::string& json_path, const FrfHighRequest& request, const std::string& note);

}  // namespace fdsid::cli
