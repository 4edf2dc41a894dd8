#include "fdsid/json.hpp"

#include <cmath>
#include <limits>
#include <utility>

namespace fdsid {

using nlohmann::json;

namespace {

std::vector<double> vec(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

}  // namespace

json to_json(const StateSpace& model) { return model_to_json(model); }

json to_json(const SpectrumResult& result, const std::string& data_path) {
  json j = result_to_json(result);
  j["data"] = data_path;
  return j;
}

json to_json(const FrfSource& s) {
  json j;
  if (!s.frf_path.empty()) {
    j = {{"frf", s.frf_path},
         {"variance", !s.known_variance ? "none (unit weights)"
                      : s.periods > 0   ? "G_var column, a sample variance over the periods (--frf-periods)"
                                        : "G_var column (known)"}};
    if (s.periods > 0) j["periods"] = s.periods;
    if (s.units.hz || s.units.unit_given) j["frequency_unit"] = s.units.hz ? "hz" : "rad";
    if (s.units.sample_time > 0) j["sample_time"] = s.units.sample_time_text;
    return j;
  }
  j = {{"data", s.data_path},
       {"meta", s.meta_path},
       {"periods", s.periods},
       {"variance", s.noise_std.empty() ? "sample variance over the periods / M (Pintelon 2002 Eq. 25)"
                                        : "known: the output noise std per sample (--noise-std), squared / M"}};
  if (!s.noise_std.empty()) j["noise_std"] = s.noise_std;
  if (!s.selection.inputs.empty()) {
    j["input_columns"] = s.selection.inputs;
    j["output_columns"] = s.selection.outputs;
  }
  if (s.selection.skip_periods > 0) j["skip_periods"] = s.selection.skip_periods;
  if (s.selection.use_periods > 0) j["use_periods"] = s.selection.use_periods;
  if (s.treatment == RecordTreatment::ErrorsInVariables)
    j["errors_in_variables"] = {{"variance", s.eiv_variance == EivVariance::Model ? "Eq. (31) at the first-pass model"
                                                                                  : "Eq. (31), corrected (conj U)"},
                                {"dropped_lines", s.dropped_lines},
                                {"min_input_snr", s.min_input_snr}};
  else if (s.treatment == RecordTreatment::Improper)
    j["improper"] = {{"represents", "inverse: the model maps output to input (1/G)"},
                     {"dropped_lines", s.dropped_lines},
                     {"min_input_snr", s.min_input_snr}};
  return j;
}

json to_json(const FrfResult& result, const std::string& method, const FrfSource& source) {
  json j = frf_result_to_json(result, method);
  j["source"] = to_json(source);
  if (source.frf_path.empty() && source.treatment == RecordTreatment::Improper) j["represents"] = "inverse";
  return j;
}

json to_json(const RecordMeta& meta) { return meta_to_json(meta); }

json to_json(const FitVerdict& f) {
  if (!f.available) return {{"available", false}, {"v_sub", f.v_sub}, {"reason", "no noise model (unit weights)"}};
  return {{"available", true}, {"v_sub", f.v_sub},   {"terms", f.terms},     {"periods", f.periods},
          {"expected", f.expected}, {"std", f.std},   {"ratio", f.ratio},     {"z", f.z},
          {"p_bound", f.p_bound},   {"p_bound_method", "Fisher: -2 sum ln S(t) against chi-square(2T), S the Exp(1) or F(2, 2M - 2) survival"},
          {"misfit", f.misfit},     {"summary", f.summary()}};
}

json to_json(const std::vector<Table1Row>& rows) {
  json j;
  j["source"] = "Akcay (2011) Table 1: 4th and 5th singular values of G_9 F_8 (Eq. 13), noise-free, p = 9, r = 8";
  j["rows"] = json::array();
  for (const auto& r : rows)
    j["rows"].push_back({{"M", r.M},
                         {"sigma4", r.vo_sigmas(3)},
                         {"sigma5", r.vo_sigmas(4)},
                         {"vo_sigmas", vec(r.vo_sigmas)},
                         {"akcay_sigmas", vec(r.akcay_sigmas)}});
  return j;
}

json to_json(const std::vector<Table2Row>& rows, const Table2Options& o) {
  json j;
  j["source"] = "Akcay (2011) Table 2: mean measured L2 / Linf errors of Algorithm 1, p = r = 50, eps = 1e-3";
  j["realizations"] = o.realizations;
  j["seed"] = o.seed;
  j["noise"] = {
      {"model", "s_k = eps H(z_k) v_k on the M+1 given samples k = 1..M+1 (Eq. 7), extended with the data by step 1"},
      {"epsilon", o.epsilon},
      {"variance", to_string(o.noise)},
      {"extension", to_string(o.extension)}};
  if (o.refine)
    j["refinement"] = "refine_spectrum (weighted nonlinear least squares of the factor on the Hermitian part of the "
                      "samples, weights 1/(eps^2 |H(z_k)|^2)) started from each Algorithm 1 estimate";
  j["rows"] = json::array();
  auto number_or_null = [](double x) { return std::isnan(x) ? json(nullptr) : json(x); };
  for (const auto& r : rows) {
    j["rows"].push_back({{"M", r.M},
                         {"l2", number_or_null(r.l2)},  // null: no realisation returned a model
                         {"linf", number_or_null(r.linf)},
                         {"l2_sd", number_or_null(r.l2_sd)},
                         {"linf_sd", number_or_null(r.linf_sd)},
                         {"failures", r.failures},
                         {"vo1997_runs", r.vo_runs},
                         {"vo1997_failures", r.vo_failures},
                         {"vo1997_step6_failures", r.vo_split_failures},
                         {"vo1997_l2_when_returned", number_or_null(r.vo_l2)}});
    if (!r.first_failure.empty()) j["rows"].back()["first_failure"] = r.first_failure;
    if (o.refine) {
      json& row = j["rows"].back();
      row["l2_refined"] = number_or_null(r.l2_refined);
      row["linf_refined"] = number_or_null(r.linf_refined);
      row["l2_refined_sd"] = number_or_null(r.l2_refined_sd);
      row["linf_refined_sd"] = number_or_null(r.linf_refined_sd);
      row["refine_failures"] = r.refine_failures;
    }
  }
  return j;
}

json to_json(const FigureResult& res, int figure, const FigureOptions& o) {
  return {{"figure", figure},
          {"source", std::string("Pintelon (2002) Section 6.1, Fig. ") + (figure == 1 ? "1b" : "2b")},
          {"frequency", vec(res.frequency)},
          {"frequency_unit", "f/fs"},
          {"ratio", vec(res.ratio)},
          {"theory", vec(res.theory)},
          {"bound", res.bound},
          {"median_ratio", res.median_ratio},
          {"runs", res.runs},
          {"failures", res.failures},
          {"M", o.M},
          {"F", o.F},
          {"r", o.r},
          {"order", o.order},
          {"input_level", o.input_level},
          {"seed", o.seed},
          {"std_subspace", vec(res.std_subspace)},
          {"std_sample_subspace", vec(res.std_sample)},
          {"std_known_alpha", vec(res.std_known_alpha)},
          {"first_failure", res.first_failure.empty() ? json(nullptr) : json(res.first_failure)}};
}

json to_json(const GapReport& report) { return gap_report_to_json(report); }

json to_json(const GapValidation& validation) { return gap_validation_to_json(validation); }

namespace {
// Each compared quantity with its distance, tolerance and their ratio (<= 1: within).
json oracle_quantities(const OracleCheck& k) {
  const ModelComparison& c = k.comparison;
  const std::pair<const char*, std::pair<double, double>> q[] = {
      {"poles", {c.pole_distance, k.pole_tolerance}},
      {"spectrum", {c.spectrum_error, k.spectrum_tolerance}},
      {"summand_markov", {c.markov_error, k.markov_tolerance}},
      {"factor_zeros", {c.zero_distance, k.zero_tolerance}},
      {"factor_markov", {c.factor_markov_error, k.factor_tolerance}}};
  json out = json::array();
  for (const auto& [name, dt] : q)
    out.push_back({{"quantity", name}, {"distance", dt.first}, {"tolerance", dt.second},
                   {"ratio", dt.second > 0 ? dt.first / dt.second : std::numeric_limits<double>::infinity()}});
  return out;
}
}  // namespace

json to_json(const OracleCheck& k) {
  const ModelComparison& c = k.comparison;
  return {{"agree", k.agree()},
          {"quantities", oracle_quantities(k)},
          {"candidate", k.candidate_path},
          {"data", k.data_path},
          {"order", {{"candidate", c.candidate_order}, {"reference", c.reference_order}}},
          {"p", k.p},
          {"r", k.r},
          {"method", to_string(k.method)},
          {"extension", to_string(k.extension)},
          {"pole_distance", c.pole_distance},
          {"spectrum_error", c.spectrum_error},
          {"spectrum_error_omega", c.spectrum_error_omega},
          {"markov_error", c.markov_error},
          {"markov_error_k", c.markov_error_k},
          {"factor",
           {{"agree", k.factor_agrees()},
            {"zero_distance", c.zero_distance},
            {"markov_error", c.factor_markov_error},
            {"markov_error_k", c.factor_markov_error_k},
            {"candidate_max_zero_modulus", c.candidate_zero_modulus},
            {"reference_max_zero_modulus", c.reference_zero_modulus},
            {"minimum_phase", !c.candidate_not_minimum_phase()}}},
          {"summary", k.summary()},
          {"note", k.note},
          {"tolerance",
           {{"spectrum", k.spectrum_tolerance},
            {"poles", k.pole_tolerance},
            {"summand_markov", k.markov_tolerance},
            {"factor_markov", k.factor_tolerance},
            {"factor_zeros", k.zero_tolerance},
            {"rule", k.tolerance_given
                         ? "given by --tolerance"
                         : "10 x (the largest change of each quantity when the reference is rerun with the "
                           "backward errors of a correct double implementation in 3 random directions: "
                           "Y by (log2 N + sqrt(pm rm)) u, step 8 by sqrt(rows cols) u, E and F by 4 n u; plus "
                           "the largest change when the reference model's A, B, C, D move by 4 n u) "
                           "(fdsid/workflow.hpp, set_oracle_tolerances)"}}},
          {"reference_model", k.reference_model}};
}


json to_json(const FrfOracleCheck& k) {
  const FrfModelComparison& c = k.comparison;
  json quantities = json::array();
  const std::pair<const char*, const OracleQuantity*> q[] = {
      {"g_data_grid", &c.g_data}, {"g_dense_grid", &c.g_dense}, {"poles", &c.poles}};
  for (const auto& [name, x] : q) {
    json e = {{"quantity", name}, {"distance", x->distance}, {"tolerance", x->tolerance}, {"ratio", x->ratio}};
    if (x != &c.poles) e["omega"] = x->omega;
    quantities.push_back(e);
  }
  json j = {{"agree", k.agree()},
            {"quantities", quantities},
            {"candidate", k.candidate_path},
            {"data", k.data_path},
            {"order", {{"candidate", c.candidate_order}, {"reference", c.reference_order}}},
            {"r", k.r},
            {"domain", to_string(k.domain)},
            {"method", k.method_name},
            {"g_relative", c.g_relative},
            {"summary", k.summary()},
            {"note", k.settings_note},
            {"order_note", k.order_note},
            {"tolerance",
             {{"backward_perturbation", k.backward_perturbation},
              {"safety_factor", FrfTolerance::kSafety},
              {"rule", k.tolerance.given > 0
                           ? "given by --tolerance (G relative to max |G_ref|; poles absolute, relative in "
                             "continuous time)"
                           : "10 x the largest change of G (per frequency) and of each pole when the reference "
                             "is rerun with Z and C_Y moved by sqrt(rows cols) u in 3 random directions (the "
                             "backward error of a correct double implementation), plus 4 n u times the "
                             "first-order sensitivity for the candidate's own rounding (fdsid/compare.hpp)"}}},
            {"reference_model", k.reference_model}};
  if (!k.meta_path.empty()) j["meta"] = k.meta_path;
  if (k.domain == Domain::Continuous || k.omega_scale > 0) j["omega_scale"] = k.omega_scale;
  return j;
}

}  // namespace fdsid
