#include "fdsid/certified.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <set>

#include <Eigen/SVD>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/io.hpp"
#include "fdsid/json.hpp"
#include "numerics/eigen_instances.hpp"

namespace fdsid {

using nlohmann::json;

const NameTable<CaseKind>& case_kind_names() {
  static const NameTable<CaseKind> names = {
      {"spectrum", CaseKind::Spectrum}, {"frf", CaseKind::Frf}, {"records", CaseKind::Records}};
  return names;
}

const char* to_string(CaseKind k) { return name_of(case_kind_names(), k); }

const NameTable<RecordTreatment>& case_treatment_names() {
  static const NameTable<RecordTreatment> names = {{"plain", RecordTreatment::Plain},
                                                   {"eiv", RecordTreatment::ErrorsInVariables}};
  return names;
}

namespace {

json read_json_file(const std::string& path, const std::string& fix) {
  std::ifstream f(path);
  if (!f) throw Error(ErrorKind::Input, path, "cannot open; " + fix);
  try {
    return json::parse(f);
  } catch (const json::parse_error& e) {
    throw Error(ErrorKind::Input, path, std::string("malformed JSON (") + e.what() + "); " + fix);
  }
}

// Field readers naming the file, the case and the field.
struct Fields {
  const json& j;
  std::string where;
  bool has(const char* key) const { return j.contains(key) && !j[key].is_null(); }
  std::string text(const char* key, const std::string& none = "") const {
    if (!has(key)) return none;
    if (!j[key].is_string()) throw Error(ErrorKind::Input, where + " field \"" + key + "\"", "must be a string");
    return j[key].get<std::string>();
  }
  std::string required_text(const char* key) const {
    if (!has(key)) throw Error(ErrorKind::Input, where, std::string("has no \"") + key + "\"");
    return text(key);
  }
  int integer(const char* key) const {
    if (!has(key)) return 0;
    if (!j[key].is_number_integer() || j[key].get<int>() < 1)
      throw Error(ErrorKind::Input, where + " field \"" + key + "\"", "must be a positive integer");
    return j[key].get<int>();
  }
  double number(const char* key, double none) const {
    if (!has(key)) return none;
    if (!j[key].is_number() || !(j[key].get<double>() > 0))
      throw Error(ErrorKind::Input, where + " field \"" + key + "\"", "must be a positive number");
    return j[key].get<double>();
  }
  // A value of `names` (`none` when the field is absent; no `none`: the
  // field is required); else refused with the names, after `use`.
  template <class E>
  E named(const char* key, const NameTable<E>& names, std::optional<E> none, const std::string& use = "use ") const {
    if (!has(key) && !none)
      throw Error(ErrorKind::Input, where, std::string("has no \"") + key + "\"; " + use + name_list(names));
    const std::optional<E> e = has(key) ? from_name(names, text(key)) : none;
    if (!e) throw Error(ErrorKind::Input, where + " field \"" + key + "\"", use + name_list(names));
    return *e;
  }
};

CaseSpec spec_from_json(const json& j, const std::string& where) {
  CaseSpec s;
  Fields f{j, where};
  s.name = f.required_text("case");
  const Fields g{j, where + " case \"" + s.name + "\""};
  s.tier = g.required_text("tier");
  if (s.tier != "lower" && s.tier != "average" && s.tier != "higher")
    throw Error(ErrorKind::Input, g.where + " field \"tier\"", "is \"" + s.tier + "\"; use lower, average or higher");
  s.kind = g.named<CaseKind>("kind", case_kind_names(), {});
  s.description = g.text("description");
  s.made_by = g.text("made_by");
  s.data = g.text("data");
  s.frf = g.text("frf");
  s.meta = g.text("meta");
  s.system = g.text("system");
  if (!s.system.empty() && s.kind != CaseKind::Spectrum)
    throw Error(ErrorKind::Input, g.where + " field \"system\"", "only a spectrum case names its system");
  if ((s.kind == CaseKind::Frf) != !s.frf.empty() || (s.kind != CaseKind::Frf && s.data.empty()) ||
      (s.kind == CaseKind::Records) != !s.meta.empty())
    throw Error(ErrorKind::Input, g.where,
                "a spectrum case names \"data\", an frf case \"frf\", a records case \"data\" and \"meta\"");
  s.order = g.integer("order");
  if (s.order < 1) throw Error(ErrorKind::Input, g.where, "has no \"order\"");
  s.p = g.integer("p");
  s.r = g.integer("r");
  if (s.r < 1 || (s.kind == CaseKind::Spectrum && s.p < 1))
    throw Error(ErrorKind::Input, g.where, "needs \"r\" (and \"p\" for a spectrum case)");
  const std::string method = g.text("method");
  s.domain = g.named<Domain>("domain", domain_names(), Domain::Discrete);
  if (s.kind == CaseKind::Spectrum) {
    s.spectrum_method = g.named<Method>("method", method_names(), {}, "a spectrum case uses ");
    if (s.domain != Domain::Discrete) throw Error(ErrorKind::Input, g.where, "a spectrum case is discrete");
  } else if (s.domain == Domain::Continuous) {
    s.continuous_method = g.named<ContinuousMethod>("method", continuous_method_names(), {}, "a continuous case uses ");
    s.omega_scale = g.number("omega_scale", 0);
    if (s.omega_scale <= 0) throw Error(ErrorKind::Input, g.where, "a continuous case gives \"omega_scale\"");
  } else if (method != "discrete") {
    throw Error(ErrorKind::Input, g.where + " field \"method\"", "a discrete FRF/records case uses \"discrete\"");
  }
  s.treatment = g.named<RecordTreatment>("treatment", case_treatment_names(), RecordTreatment::Plain);
  if (s.treatment != RecordTreatment::Plain && s.kind != CaseKind::Records)
    throw Error(ErrorKind::Input, g.where, "errors-in-variables needs a records case");
  s.eiv_variance = g.named<EivVariance>("eiv_variance", eiv_variance_names(), EivVariance::Data);
  s.min_input_snr = g.number("min_input_snr", s.min_input_snr);
  // Both settle Eq. (31)'s variance and Eq. (34)'s line rule; on any other
  // case they would be read and have no effect.
  for (const char* key : {"eiv_variance", "min_input_snr"})
    if (s.treatment != RecordTreatment::ErrorsInVariables && g.has(key))
      throw Error(ErrorKind::Input, g.where + " field \"" + key + "\"",
                  "applies to \"treatment\": \"eiv\" only; drop it, or give that treatment");
  return s;
}

}  // namespace

json case_inputs_json(const CaseSpec& s) {
  json j = {{"case", s.name}, {"tier", s.tier}, {"kind", to_string(s.kind)}, {"order", s.order}, {"r", s.r}};
  if (!s.data.empty()) j["data"] = s.data;
  if (!s.frf.empty()) j["frf"] = s.frf;
  if (!s.meta.empty()) j["meta"] = s.meta;
  if (!s.system.empty()) j["system"] = s.system;
  if (s.kind == CaseKind::Spectrum) {
    j["p"] = s.p;
    j["method"] = to_string(s.spectrum_method);
  } else {
    j["domain"] = to_string(s.domain);
    j["method"] = s.domain == Domain::Continuous ? to_string(s.continuous_method) : "discrete";
    if (s.domain == Domain::Continuous) j["omega_scale"] = s.omega_scale;
    j["treatment"] = name_of(case_treatment_names(), s.treatment);
    // They change the certified values (Eq. 31's variance, the lines Eq. 34
    // keeps), so a certified file made with other settings is stale.
    if (s.treatment == RecordTreatment::ErrorsInVariables) {
      j["eiv_variance"] = name_of(eiv_variance_names(), s.eiv_variance);
      j["min_input_snr"] = s.min_input_snr;
    }
  }
  return j;
}

namespace {

cplx complex_value(const json& pair, const std::string& where) {
  if (!pair.is_array() || pair.size() != 2 || !pair[0].is_string() || !pair[1].is_string())
    throw Error(ErrorKind::Input, where, "a value is not a [re, im] pair of decimal strings");
  return {std::stod(pair[0].get<std::string>()), std::stod(pair[1].get<std::string>())};
}

CertifiedQuantity quantity_from_json(const std::string& name, const json& q, const std::string& where) {
  CertifiedQuantity c;
  c.name = name;
  const std::string at = where + " quantity \"" + name + "\"";
  if (!q.contains("shape") || !q.contains("values") || !q.contains("digits") || !q["values"].is_array())
    throw Error(ErrorKind::Input, at, "needs shape, values and digits");
  c.rows = q["shape"].at(0).get<int>();
  c.cols = q["shape"].at(1).get<int>();
  if (q.contains("omega"))
    for (const auto& w : q["omega"]) c.omega.push_back(std::stod(w.get<std::string>()));
  for (const auto& v : q["values"]) {
    if (!v.is_array() || v.size() != std::size_t(c.rows) * c.cols)
      throw Error(ErrorKind::Input, at, "a value does not have rows x cols entries");
    Eigen::MatrixXcd X(c.rows, c.cols);
    for (int i = 0; i < c.rows; ++i)
      for (int k = 0; k < c.cols; ++k) X(i, k) = complex_value(v[i * c.cols + k], at);
    c.values.push_back(X);
  }
  for (const auto& d : q["digits"]) c.digits.push_back(d.get<int>());
  if (c.digits.size() != c.values.size() || (!c.omega.empty() && c.omega.size() != c.values.size()))
    throw Error(ErrorKind::Input, at, "values, digits and omega differ in length");
  return c;
}

// −log10 of the relative error, capped at the certified digits (StRD's LRE).
double lre(const Eigen::MatrixXcd& candidate, const Eigen::MatrixXcd& certified, int digits) {
  const double norm = certified.norm(), err = (candidate - certified).norm();
  if (!std::isfinite(err)) return 0;
  const double rel = norm > 0 ? err / norm : err;
  if (rel == 0) return digits;
  return std::clamp(-std::log10(rel), 0.0, double(digits));
}

// LRE of a set of points (poles, zeros): each certified value against its
// nearest candidate value; a candidate with another count scores 0.
QuantityScore score_points(const CertifiedQuantity& q, const Eigen::VectorXcd& candidate) {
  QuantityScore s{q.name, std::numeric_limits<double>::infinity(), 99};
  for (int d : q.digits) s.certified_digits = std::min(s.certified_digits, d);
  if (q.values.empty()) s.certified_digits = 0;
  if (candidate.size() != Eigen::Index(q.values.size())) {
    s.lre = 0;
    return s;
  }
  for (std::size_t i = 0; i < q.values.size(); ++i) {
    const cplx z = q.values[i](0, 0);
    Eigen::Index j = 0;
    if (candidate.size()) (candidate.array() - z).abs().minCoeff(&j);
    Eigen::MatrixXcd c(1, 1);
    c(0, 0) = candidate.size() ? candidate(j) : cplx(std::numeric_limits<double>::quiet_NaN(), 0);
    s.lre = std::min(s.lre, lre(c, q.values[i], q.digits[i]));
  }
  if (!std::isfinite(s.lre)) s.lre = s.certified_digits;
  return s;
}

template <class Eval>
QuantityScore score_grid(const CertifiedQuantity& q, Eval eval) {
  QuantityScore s{q.name, std::numeric_limits<double>::infinity(), 99};
  for (std::size_t i = 0; i < q.values.size(); ++i) {
    s.certified_digits = std::min(s.certified_digits, q.digits[i]);
    const Eigen::MatrixXcd c = eval(q.omega[i]);
    s.lre = std::min(s.lre, c.rows() == q.rows && c.cols() == q.cols ? lre(c, q.values[i], q.digits[i]) : 0.0);
  }
  if (q.values.empty()) s.lre = s.certified_digits = 0;
  return s;
}

}  // namespace

std::string CaseSpec::method_name() const {
  if (kind == CaseKind::Spectrum) return to_string(spectrum_method);
  return frf_method_name(domain, continuous_method);
}

std::string CaseSpec::fdsid_arguments(const std::string& suite) const {
  const std::string dir = suite.empty() || suite.back() == '/' ? suite : suite + "/";
  const std::string n = std::to_string(order);
  if (kind == CaseKind::Spectrum)
    return "identify-spectrum --data " + dir + data + " --order " + n + " --p " + std::to_string(p) + " --r " +
           std::to_string(r) + " --method " + to_string(spectrum_method);
  std::string a = "identify-frf " + (kind == CaseKind::Frf ? "--frf " + dir + frf
                                                          : "--data " + dir + data + " --meta " + dir + meta) +
                  " --order " + n + " --r " + std::to_string(r) + " --domain " + to_string(domain);
  if (domain == Domain::Continuous)
    a += std::string(" --method ") + to_string(continuous_method) + " --omega-scale " + fmt(omega_scale, 17);
  if (treatment == RecordTreatment::ErrorsInVariables) {
    a += " --eiv";
    if (eiv_variance != EivVariance::Data) a += std::string(" --eiv-variance ") + name_of(eiv_variance_names(), eiv_variance);
    if (min_input_snr != CaseSpec{}.min_input_snr) a += " --min-input-snr " + fmt(min_input_snr, 17);
  }
  return a;
}

std::vector<CaseSpec> read_suite_manifest(const std::string& suite) {
  const std::string path = suite + "/cases.json";
  const json j = read_json_file(path, "give the suite folder with --suite (fixtures/certified of the repository)");
  if (!j.contains("cases") || !j["cases"].is_array())
    throw Error(ErrorKind::Input, path, "has no \"cases\" array");
  std::vector<CaseSpec> cases;
  std::set<std::string> names;
  for (const auto& c : j["cases"]) {
    if (!c.is_object()) throw Error(ErrorKind::Input, path, "a case is not an object");
    cases.push_back(spec_from_json(c, path));
    if (!names.insert(cases.back().name).second)
      throw Error(ErrorKind::Input, path, "case \"" + cases.back().name + "\" appears twice");
  }
  return cases;
}

const CertifiedQuantity* CertifiedCase::quantity(const std::string& name) const {
  for (const auto& q : certified)
    if (q.name == name) return &q;
  return nullptr;
}

CertifiedCase read_certified_case(const std::string& suite, const CaseSpec& spec) {
  const std::string path = suite + "/" + spec.name + ".json";
  const std::string fix = "regenerate the suite with scripts/certify.sh (fixtures/certified/README.md)";
  const json j = read_json_file(path, fix);
  CertifiedCase c;
  c.spec = spec;
  try {
    if (!j.contains("inputs") || j["inputs"] != case_inputs_json(spec))
      throw Error(ErrorKind::Input, path, "its inputs differ from cases.json; " + fix);
    for (const auto& [name, q] : j.at("certified").items()) c.certified.push_back(quantity_from_json(name, q, path));
    c.reference = model_from_json(j.at("reference_model"), path + " reference_model");
    for (const auto& m : j.at("perturbed_models")) c.perturbed.push_back(model_from_json(m, path + " perturbed_models"));
  } catch (const json::exception& e) {
    throw Error(ErrorKind::Input, path, std::string("malformed certified case (") + e.what() + "); " + fix);
  }
  if (c.perturbed.empty()) throw Error(ErrorKind::Input, path, "has no perturbed_models; " + fix);
  return c;
}

Eigen::MatrixXcd normalised_factor(const StateSpace& model, cplx xi) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(model.D, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::MatrixXd Q = svd.matrixV() * svd.matrixU().transpose();
  return transfer(model, xi) * Q.cast<cplx>();
}

CaseScore score_candidate(const CertifiedCase& c, const StateSpace& candidate) {
  CaseScore s;
  const bool discrete = c.spec.domain == Domain::Discrete;
  const auto at = [discrete](double w) { return discrete ? std::polar(1.0, w) : cplx(0, w); };
  bool comparable = false;  // the candidate's domain, sample time and sizes are the case's
  try {
    if (candidate.domain != c.reference.domain)
      throw Error(ErrorKind::Input, "candidate", std::string("is ") + to_string(candidate.domain) +
                                                     "-time; the case is " + to_string(c.reference.domain) + "-time");
    if (candidate.inputs() != c.reference.inputs() || candidate.outputs() != c.reference.outputs())
      throw Error(ErrorKind::Input, "candidate",
                  "has " + std::to_string(candidate.inputs()) + " inputs and " + std::to_string(candidate.outputs()) +
                      " outputs; the case has " + std::to_string(c.reference.inputs()) + " and " +
                      std::to_string(c.reference.outputs()));
    // The sample time is metadata copied from the case, not computed: a
    // writer with 10 significant digits reproduces it to 1e-9 (a user review:
    // "sample_time": 0.001 on every case passed without a note).
    if (discrete && !(std::abs(candidate.sample_time - c.reference.sample_time) <= 1e-9 * c.reference.sample_time))
      throw Error(ErrorKind::Input, "candidate",
                  "has sample_time " + fmt(candidate.sample_time, 10) + " s; the case's is " +
                      fmt(c.reference.sample_time, 10) + " s (its lines are per sample: write the case's)");
    comparable = true;
    if (c.spec.kind == CaseKind::Spectrum) {
      OracleCheck k;
      k.p = c.spec.p;
      k.r = c.spec.r;
      k.method = c.spec.spectrum_method;
      k.comparison = compare_models(candidate, c.reference);
      set_oracle_tolerances(k, c.reference, c.perturbed, 0);
      s.pass = k.agree();
      s.verdict = k.summary();
      s.comparison = to_json(k);
    } else {
      FrfOracleCheck k;
      k.order = c.reference.order();
      k.r = c.spec.r;
      k.domain = c.spec.domain;
      k.method = c.spec.continuous_method;
      k.omega_scale = c.spec.omega_scale;
      k.method_name = c.spec.method_name();
      k.tolerance.perturbed = c.perturbed;
      k.tolerance.method = c.spec.continuous_method;
      k.tolerance.omega_scale = c.spec.omega_scale > 0 ? c.spec.omega_scale : 1;
      const CertifiedQuantity* g = c.quantity("G");
      if (!g) throw Error(ErrorKind::Input, c.spec.name, "has no certified G");
      const Eigen::VectorXd omega = Eigen::Map<const Eigen::VectorXd>(g->omega.data(), Eigen::Index(g->omega.size()));
      StateSpace ref = c.reference, cand = candidate;
      if (discrete) cand.sample_time = ref.sample_time;  // G and poles are compared per sample
      k.comparison = compare_frf_models(cand, ref, omega, dense_frequency_grid(c.spec.domain, omega), k.tolerance);
      s.pass = k.agree();
      s.verdict = k.summary();
      s.comparison = to_json(k);
    }
  } catch (const Error& e) {
    s.pass = false;
    s.verdict = std::string("DISAGREES: ") + e.what();
  }
  if (!s.verdict.empty() && s.verdict.back() == '\n') s.verdict.pop_back();
  // A candidate of another domain, sample time or size has no scores: its
  // matrices evaluated as the case's would print a pass's digits on a FAIL row
  // (a user review).
  if (!comparable) return s;
  for (const auto& q : c.certified) {
    if (q.name == "poles") s.quantities.push_back(score_points(q, poles(candidate)));
    else if (q.name == "zeros") s.quantities.push_back(score_points(q, zeros(candidate)));
    else if (q.name == "S") s.quantities.push_back(score_grid(q, [&](double w) { return power_spectrum(candidate, at(w)); }));
    else if (q.name == "factor" || q.name == "exact_factor")
      s.quantities.push_back(score_grid(q, [&](double w) { return normalised_factor(candidate, at(w)); }));
    else if (q.name == "G") s.quantities.push_back(score_grid(q, [&](double w) { return transfer(candidate, at(w)); }));
  }
  return s;
}

}  // namespace fdsid
