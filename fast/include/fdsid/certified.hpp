#pragma once
/// The certified reference suite (fixtures/certified/, its README): cases in
/// three tiers for both papers, each with its data, the settings of the
/// identification, and certified values — what the algorithm returns on those
/// exact data, computed by the reference in 50 and in 100 digits, with the
/// digits the two share. `fdsid certify` writes the cases, `fdsid conformance`
/// scores another implementation's models against them.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fdsid/compare.hpp"
#include "fdsid/model.hpp"
#include "fdsid/names.hpp"
#include "fdsid/spectrum_id.hpp"
#include "fdsid/workflow.hpp"

namespace fdsid {

enum class CaseKind {
  Spectrum,  ///< Akçay (2011) Algorithm 1 on a power-spectrum CSV
  Frf,       ///< Pintelon (2002) on an FRF CSV (known variance)
  Records    ///< Pintelon (2002) on periodic records (sample mean and variance, Section 4.1/5)
};
const char* to_string(CaseKind k);
/// The manifest's "kind" names: spectrum, frf, records.
const NameTable<CaseKind>& case_kind_names();
/// The manifest's "treatment" names of a records case: plain (Section 4.1) or
/// eiv (errors in variables, identify-frf --eiv). No certified case treats an
/// improper G, so RecordTreatment::Improper has no name here.
const NameTable<RecordTreatment>& case_treatment_names();

/// One case of the suite's manifest (cases.json): what was identified, how.
/// Paths are as the manifest gives them, relative to the suite folder.
struct CaseSpec {
  std::string name, tier, description, made_by;
  CaseKind kind = CaseKind::Spectrum;
  std::string data, frf, meta;  ///< spectrum or records CSV; FRF CSV; records meta
  /// Noise-free spectrum cases: the minimum-phase system the data were sampled
  /// from (its exact factor is certified as "exact_factor").
  std::string system;
  int order = 0;
  int p = 0, r = 0;             ///< p: spectra only
  Method spectrum_method = Method::Akcay2011;
  Domain domain = Domain::Discrete;
  ContinuousMethod continuous_method = ContinuousMethod::Bilinear;
  double omega_scale = 0;       ///< continuous FRF/records: ω_s (always given in the manifest)
  RecordTreatment treatment = RecordTreatment::Plain;
  EivVariance eiv_variance = EivVariance::Data;
  double min_input_snr = 10;
  /// The arguments of fdsid's own command for the case (identify-spectrum /
  /// identify-frf, without --json), paths under `suite`.
  std::string fdsid_arguments(const std::string& suite) const;
  /// The "method" name an identified-model JSON carries (akcay2011, pintelon2002-alg1, …).
  std::string method_name() const;
};

/// The "inputs" object a certified case repeats from the manifest (what
/// read_certified_case compares, so that a stale case is named).
nlohmann::json case_inputs_json(const CaseSpec& spec);

/// Purpose: the cases of the suite in `suite`/cases.json, in its order.
/// Fails: Error(Input) naming the file and the field for a missing or
/// malformed manifest, a duplicate case name, an unknown tier or kind.
std::vector<CaseSpec> read_suite_manifest(const std::string& suite);

/// One certified quantity: values (each a rows × cols matrix, row-major),
/// at the frequencies `omega` (empty for poles and zeros), each with its
/// number of certified significant digits (relative to its Frobenius norm).
struct CertifiedQuantity {
  std::string name;  ///< "poles", "zeros", "S" (spectrum), "factor", "exact_factor", "G"
  std::vector<double> omega;
  int rows = 1, cols = 1;
  std::vector<Eigen::MatrixXcd> values;
  std::vector<int> digits;
};

/// A certified case as `fdsid certify` wrote it (`suite`/<case>.json).
struct CertifiedCase {
  CaseSpec spec;
  std::vector<CertifiedQuantity> certified;
  StateSpace reference;                ///< the reference's model (40 digits, correctly rounded to double)
  std::vector<StateSpace> perturbed;   ///< the reference at perturbed inputs: the tolerance (check's rule)
  const CertifiedQuantity* quantity(const std::string& name) const;  ///< nullptr when absent
};

/// Purpose: read `suite`/<spec.name>.json.
/// Fails: Error(Input) naming the file for a missing or malformed case, or one
/// whose inputs differ from the manifest's (regenerate with scripts/certify.sh).
CertifiedCase read_certified_case(const std::string& suite, const CaseSpec& spec);

/// How a candidate scores on one quantity: the log relative error (StRD's
/// LRE, −log10 of the relative error), the smallest over the values, each
/// capped at the value's certified digits, and the smallest certified digits.
struct QuantityScore {
  std::string name;
  double lre = 0;
  int certified_digits = 0;
};

/// A candidate model judged on one certified case.
struct CaseScore {
  bool pass = false;
  std::string verdict;  ///< one line: check's summary (what failed first), or why no comparison was made
  std::vector<QuantityScore> quantities;
  nlohmann::json comparison;  ///< check's JSON of the comparison (quantities, tolerances)
};

/// Purpose: judge a candidate model against a certified case.
/// Method: pass/fail exactly as `fdsid check` judges it against the reference
/// (spectra: compare_models + set_oracle_tolerances; FRF and records:
/// compare_frf_models with FrfTolerance), from the stored reference and
/// perturbed models — nothing is recomputed; the LRE of each certified
/// quantity for the table (poles and zeros matched to the nearest candidate
/// value; the factor normalised by the orthogonal polar factor of D, so
/// that G and GQ score alike).
/// Fails: never; a candidate of the wrong shape, domain or order fails the case
/// with the reason as verdict.
CaseScore score_candidate(const CertifiedCase& c, const StateSpace& candidate);

/// The minimum-phase factor made unique: G(ξ) Q with Q = V Uᵀ from D = U Σ Vᵀ,
/// so that G(∞) Q = U Σ Uᵀ is symmetric positive semidefinite (m = 1: sign D).
/// Any G Q₀ with Q₀ orthogonal gives the same value when D is nonsingular.
Eigen::MatrixXcd normalised_factor(const StateSpace& model, cplx xi);

}  // namespace fdsid
