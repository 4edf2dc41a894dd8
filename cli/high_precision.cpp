#include "high_precision.hpp"
#include "reference_runs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <string>

#include "fdsid/compare.hpp"
#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/io.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/json.hpp"
#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/io.hpp"
#include "fdsid/reference/spectrum_id.hpp"
#include "fdsid/spectrum_id.hpp"
#include "fdsid/workflow.hpp"

namespace fdsid::cli {

namespace {

using nlohmann::json;

double to_double(const json& decimal) { return std::stod(decimal.get<std::string>()); }

// 2π in the reference's precision.
reference::Real two_pi() { return boost::multiprecision::atan(reference::Real(1)) * 8; }

}  // namespace

reference::Real exact(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return reference::parse_decimal(buf);
}

std::string precision_label() {
  const std::string d = std::to_string(reference::kDigits);
  return "high (" + d + "-digit binary floating point, Boost.Multiprecision cpp_bin_float<" + d + ">)";
}

PerturbationsFor spectrum_perturbations(bool vo) {
  return [vo](const reference::Result& base, int pp, int rr, int MM) {
    std::vector<reference::BackwardPerturbation> bp;
    const Eigen::VectorXcd z = zeros(model_from_json(reference::result_to_json(base, vo, 40), "reference model"));
    const OracleBackwardErrors e =
        oracle_backward_errors(pp, rr, base.model.C.rows(), MM, base.order, z.size() ? z.cwiseAbs().maxCoeff() : 0.0);
    for (unsigned seed = 1; seed <= 3; ++seed)
      bp.push_back({exact(e.data_matrix), exact(e.least_squares), exact(e.riccati), seed, nullptr});
    return bp;
  };
}

reference::Result run_reference(const std::string& data_path, int order, int& p, int& r, bool vo, Extension ext,
                                int& m, int& M, const PerturbationsFor* perturbations_for,
                                std::vector<reference::Result>* perturbed) {
  // The file is checked by fast/'s reader first, so that a bad one gets the
  // same one-line message (file and line once, the cause named: header, grid,
  // Hermitian samples, an FRF file given as a spectrum) as without
  // --precision high (review finding 21: "frf.csv: frf.csv:1: 4 columns").
  (void)read_spectrum_csv(data_path);
  try {
    reference::Spectrum spectrum = reference::read_spectrum_csv(data_path);
    if (ext == Extension::HermitianPart)
      for (auto& S : spectrum.S) S = ((S + S.adjoint()) / reference::Real(2)).eval();
    m = spectrum.m;
    M = spectrum.M;
    int dp, dr;
    default_pr(M, order, dp, dr);  // the same documented default rule as fast/
    if (p == 0) p = dp;
    if (r == 0) r = dr;
    if (!perturbations_for) return reference::identify_spectrum(spectrum, order, p, r, vo);
    reference::PerturbedResults all = reference::identify_spectrum_perturbed(
        spectrum, order, p, r, vo, [&](const reference::Result& base) { return (*perturbations_for)(base, p, r, M); });
    *perturbed = std::move(all.perturbed);
    return all.base;
  } catch (const reference::StepError& e) {
    throw Error(ErrorKind::Numerical, data_path, std::string("reference: ") + e.what());
  } catch (const reference::Error& e) {
    throw Error(ErrorKind::Input, data_path, e.what());
  }
}

namespace {

// The candidate's JSON (a model file, or an identified model of the contracts).
json read_candidate(const std::string& model_path) {
  std::ifstream f(model_path);
  if (!f) throw Error(ErrorKind::Input, model_path, "cannot open candidate model");
  try {
    return json::parse(f);
  } catch (const json::parse_error& e) {
    throw Error(ErrorKind::Input, model_path, std::string("malformed JSON: ") + e.what());
  }
}

// A setting the candidate JSON may carry: 0 when absent.
int int_field(const json& cj, const char* key, const std::string& model_path) {
  if (!cj.contains(key)) return 0;
  if (!cj[key].is_number_integer() || cj[key].get<int>() < 1)
    throw Error(ErrorKind::Input, model_path + " field \"" + key + "\"", "must be a positive integer");
  return cj[key].get<int>();
}

// A candidate that disagrees while written with fewer significant digits
// than the check resolves: the reference rounded to the same digits is
// checked the same way (`pole_distance_alike(rounded)`: its pole distance
// when it fails the check, a negative number when it passes), and when that
// rounding alone fails too, the note says so and what to do (a user review:
// 8, 10 and 12 digits of a correct model read DISAGREES with nothing about
// precision); both pole distances are printed, so that a mistake beyond the
// rounding shows. "" otherwise.
template <class PoleDistanceAlike>
std::string digits_note(const StateSpace& candidate, const StateSpace& ref, double candidate_pole_distance,
                        PoleDistanceAlike pole_distance_alike) {
  const int d = digits_carried(candidate);
  if (d >= 17) return "";
  const double rounding = pole_distance_alike(rounded_to_digits(ref, d));
  if (rounding < 0) return "";
  return "the candidate's entries carry at most " + std::to_string(d) +
         " significant digits, and the reference rounded to " + std::to_string(d) +
         " digits fails this check too (its poles move by " + sci(rounding, 2) + ", the candidate's are " +
         sci(candidate_pole_distance, 2) + " off): write the model with 17 significant digits (printf %.17g, "
         "Python repr, MATLAB num2str(x, 17)) to check the algorithm, or give --tolerance";
}

}  // namespace

int identify_spectrum_high(const std::string& json_path, const std::string& data_path, int order, int p, int r,
                           bool vo, Extension ext) {
  int m = 0, M = 0;
  const reference::Result res = run_reference(data_path, order, p, r, vo, ext, m, M);
  json j = reference::result_to_json(res, vo, 40);
  j["extension"] = to_string(ext);
  j["data"] = data_path;
  j["precision"] = precision_label();
  if (json_path != "-") {
    std::cout << "identified order " << res.order << " in high precision by "
              << to_string(vo ? Method::VanOverschee1997 : Method::Akcay2011) << " from M = " << M << ", m = " << m
              << ", p = " << res.p << ", r = " << res.r << "\npoles:";
    for (const auto& z : j["poles"]) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "  %.15g%+.15gi", to_double(z[0]), to_double(z[1]));
      std::cout << buf;
    }
    std::cout << "\n(the JSON has 40 significant digits)\n";
  }
  if (!json_path.empty()) write_text_file(json_path, j.dump(2) + "\n");
  return 0;
}

int check(const std::string& json_path, const std::string& model_path, const std::string& data_path,
          double tolerance) {
  // The candidate: a model file; p, r, method taken from it when present (an
  // identified-model JSON of the contracts), else the documented defaults.
  const json cj = read_candidate(model_path);
  const StateSpace candidate = model_from_json(cj, model_path);
  if (candidate.domain != Domain::Discrete)
    throw Error(ErrorKind::Input, model_path,
                "is a continuous-time model (\"domain\": \"continuous\"); a spectral factor of a sampled spectrum is "
                "discrete-time: give the discrete model (\"domain\": \"discrete\"), or check an FRF model with --frf "
                "or --data --meta");
  int p = int_field(cj, "p", model_path), r = int_field(cj, "r", model_path);
  // A method or extension given must be one the reference runs: a typo read
  // as the default turned a correct candidate into DISAGREES with no hint (a
  // user review: "extension": "conjugat").
  const auto spectrum_setting = [&](const char* key, const auto& names, auto absent, const std::string& frf_hint) {
    if (!cj.contains(key)) return absent;
    const std::string v = cj[key].is_string() ? cj[key].get<std::string>() : cj[key].dump();
    if (const auto value = from_name(names, v)) return *value;
    throw Error(ErrorKind::Input, model_path + " field \"" + key + "\"",
                "\"" + v + "\" is not " + name_list(names) +
                    (v.rfind("pintelon2002", 0) == 0 ? frf_hint : std::string()));
  };
  const Method method = spectrum_setting("method", method_names(), Method::Akcay2011,
                                         ": an FRF model; check it with --frf FRF.csv or --data RECORDS.csv --meta");
  const bool vo = method == Method::VanOverschee1997;
  const Extension ext = spectrum_setting("extension", extension_names(), Extension::HermitianPart, "");
  if (candidate.order() < 1) throw Error(ErrorKind::Input, model_path, "candidate has order 0");

  int m = 0, M = 0;
  const int p_given = p, r_given = r;
  std::string note;
  // The reruns of the tolerance (workflow.hpp, set_oracle_tolerances): the
  // backward errors of a correct double implementation, three random directions.
  const PerturbationsFor rule = spectrum_perturbations(vo);
  const PerturbationsFor perturbations_for = [&](const reference::Result& base, int pp, int rr, int MM) {
    return tolerance > 0 ? std::vector<reference::BackwardPerturbation>() : rule(base, pp, rr, MM);
  };
  std::vector<reference::Result> moved;
  reference::Result res;
  try {
    res = run_reference(data_path, candidate.order(), p, r, vo, ext, m, M, &perturbations_for, &moved);
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Numerical) throw;
    // The reference cannot identify these data at the candidate's order (a
    // step of Algorithm 1 fails, e.g. no stable/antistable split at step 6):
    // that is a disagreement about the order, not bad input. The reference is
    // run again with the order read from its singular values, and the
    // candidate is compared with that model (the orders then differ).
    p = p_given;
    r = r_given;
    res = run_reference(data_path, 0, p, r, vo, ext, m, M, &perturbations_for, &moved);
    if (res.order == candidate.order()) throw;
    const std::string what = e.what();
    const auto at = what.find("step ");
    note = "the reference fails at the candidate's order " + std::to_string(candidate.order()) +
           (at == std::string::npos ? std::string() : " (" + what.substr(at, what.find(':', at) - at) + ")") +
           "; the data support order " + std::to_string(res.order) + ", which the candidate is compared with";
  }
  // What the candidate did not say and the comparison assumed (the FRF check
  // names its r alike): a candidate identified with other settings differs
  // from the reference for that reason alone (a user review: p = r = 30 bare
  // compared at 50 read DISAGREES with nothing to say why).
  std::string assumed;
  const auto assume = [&](const char* key, const std::string& value) {
    if (!cj.contains(key)) assumed += (assumed.empty() ? "" : ", ") + std::string(key) + " = " + value;
  };
  assume("p", std::to_string(p) + " (the default rule for M = " + std::to_string(M) + ")");  // absent: not given
  assume("r", std::to_string(r));
  assume("method", to_string(method));
  assume("extension", to_string(ext));
  if (!assumed.empty())
    note = "compared at " + assumed + ": the candidate JSON does not give them (add \"p\", \"r\", \"method\", "
           "\"extension\" to it if it used others)" + (note.empty() ? "" : "\n" + note);
  OracleCheck k;
  k.note = note;
  k.candidate_path = model_path;
  k.data_path = data_path;
  k.p = p;
  k.r = r;
  k.method = method;
  k.extension = ext;
  k.reference_model = reference::result_to_json(res, vo, 40);
  StateSpace ref = model_from_json(k.reference_model, "reference model");  // decimal strings, correctly rounded
  // compare_models forms spectra H Hᴴ and squared differences in double: a
  // factor beyond 2^±128 (samples beyond 2^±256, which identify-spectrum
  // scales the same way) overflows there — a user review's S × 1e200 read
  // "spectrum -nan" and a zero outside the circle. Candidate, reference and
  // perturbed references are then scaled alike by a power of two in B and D
  // (exact), which every relative comparison leaves as it is.
  const double factor_size = ref.D.cwiseAbs().maxCoeff();
  const int k2 = std::isfinite(factor_size) && factor_size > 0 &&
                         (factor_size > std::ldexp(1.0, 128) || factor_size < std::ldexp(1.0, -128))
                     ? -std::ilogb(factor_size)
                     : 0;
  const auto rescaled = [k2](StateSpace g) {
    g.B *= std::ldexp(1.0, k2);
    g.D *= std::ldexp(1.0, k2);
    return g;
  };
  ref = rescaled(ref);
  const StateSpace compared = rescaled(candidate);
  k.comparison = compare_models(compared, ref);

  // Default tolerance: what a correct double-precision implementation reaches on
  // these data, measured: the reference again, three times, with that
  // implementation's backward errors in random directions (workflow.hpp).
  std::vector<StateSpace> perturbed;
  for (const reference::Result& x : moved)
    perturbed.push_back(rescaled(model_from_json(reference::result_to_json(x, vo, 40), "perturbed reference model")));
  if (tolerance <= 0 && perturbed.empty())
    throw Error(ErrorKind::Numerical, data_path,
                "the reference fails whenever these data are perturbed at rounding level, so no tolerance can be "
                "measured; give --tolerance");
  set_oracle_tolerances(k, ref, perturbed, tolerance);
  if (!k.agree())
    if (const std::string d = digits_note(compared, ref, k.comparison.pole_distance,
                                          [&](const StateSpace& rounded) {
                                            OracleCheck alike = k;
                                            alike.comparison = compare_models(rounded, ref);
                                            return alike.agree() ? -1.0 : alike.comparison.pole_distance;
                                          });
        !d.empty())
      k.note += (k.note.empty() ? "" : "\n") + d;
  if (json_path != "-") std::cout << k.summary();
  if (!json_path.empty()) write_text_file(json_path, to_json(k).dump(2) + "\n");
  return k.agree() ? 0 : 1;
}

int sample_spectrum_high(const std::string& model_path, int M, const std::string& out_path) {
  try {
    const reference::Model model = reference::read_model(model_path);
    reference::write_spectrum_csv(reference::sample_spectrum(model, M), out_path, 40);
  } catch (const reference::Error& e) {
    throw Error(ErrorKind::Input, model_path, e.what());
  }
  return 0;
}




reference::SampleStatistics records_high(const FrfHighRequest& q, const std::string& domain,
                                         reference::Real& sample_time) {
  const Records rec = read_records(q.data_path, q.meta_path, q.selection);
  const Eigen::MatrixXd& samples = rec.samples;
  const int inputs = rec.inputs;
  const RecordMeta& meta = rec.meta;
  std::vector<std::vector<reference::Real>> channels(samples.cols());
  for (Eigen::Index c = 0; c < samples.cols(); ++c)
    for (Eigen::Index t = 0; t < samples.rows(); ++t) channels[c].push_back(exact(samples(t, c)));
  const auto spectra = reference::period_spectra(channels, meta.period, meta.periods, meta.excited_lines);
  std::vector<std::vector<reference::MatrixC>> U_l(meta.periods), Y_l(meta.periods);
  const Eigen::Index outputs = samples.cols() - inputs;
  for (int l = 0; l < meta.periods; ++l)
    for (size_t k = 0; k < meta.excited_lines.size(); ++k) {
      U_l[l].push_back(spectra[l][k].topRows(inputs));
      Y_l[l].push_back(spectra[l][k].bottomRows(outputs));
    }
  sample_time = exact(meta.sample_time);
  std::vector<reference::Real> omega;
  const reference::Real w0 = two_pi();
  for (int k : meta.excited_lines)
    omega.push_back(w0 * k / meta.period / (q.continuous ? sample_time : reference::Real(1)));
  return reference::sample_statistics(domain, omega, U_l, Y_l);
}

json frf_high_json(const reference::FrfResult& res, const FrfHighRequest& q, const std::string& where,
                   const std::string& note, int digits) {
  json j = reference::model_to_json(res.model, digits);
  j["order"] = res.order;
  j["r"] = res.r;
  j["method"] = frf_method_name(q.continuous ? Domain::Continuous : Domain::Discrete,
                                q.orthogonal ? ContinuousMethod::Orthogonal : ContinuousMethod::Bilinear, q.discrete);
  json sv = json::array();
  for (const auto& s : res.singular_values) sv.push_back(reference::to_decimal(s, digits));
  j["singular_values"] = sv;
  json poles = json::array();
  for (const auto& z : res.poles) poles.push_back({reference::to_decimal(z.real(), digits), reference::to_decimal(z.imag(), digits)});
  j["poles"] = poles;
  j["v_sub"] = reference::to_decimal(res.v_sub, digits);
  j["data"] = where;
  j["precision"] = precision_label();
  if (!note.empty()) j["note"] = note;
  return j;
}

// An FRF file read exactly, its omega column taken to rad/sample (discrete)
// or rad/s (continuous) as identify-frf's --frequency-unit/--sample-time say
// (FrequencyUnits::factor in 50 digits: 2π and the sample time's own text).
reference::FrfData reference_frf_file(const FrfHighRequest& q, const std::string& domain) {
  reference::FrfData data = reference::read_frf_csv(q.frf_path, domain);
  reference::Real factor = 1;
  if (q.units.hz) factor *= two_pi();
  if (!q.continuous && q.units.sample_time > 0) factor *= reference::parse_decimal(q.units.sample_time_text);
  for (reference::Real& w : data.omega) w *= factor;
  return data;
}

reference::FrfResult reference_frf(const FrfHighRequest& q, const reference::Real& perturbation, unsigned seed) {
  const std::string domain = to_string(q.continuous ? Domain::Continuous : Domain::Discrete);
  const std::string where = q.frf_path.empty() ? q.data_path : q.frf_path;
  reference::FrfResult res;
  reference::Real sample_time = 1;
  try {
    reference::FrfOptions o;
    o.order = q.order;
    o.r = q.r;
    o.continuous_method = q.orthogonal ? "orthogonal" : "bilinear";
    o.discrete_method = to_string(q.discrete);
    if (q.omega_scale > 0) o.omega_scale = exact(q.omega_scale);
    o.backward_perturbation = perturbation;
    o.perturbation_seed = seed;
    if (!q.frf_path.empty()) {
      res = reference::identify_frf(reference_frf_file(q, domain), o);
    } else {
      const reference::SampleStatistics stats = records_high(q, domain, sample_time);
      // Section 5 as identify-frf applies it (workflow.hpp, identify_frf_records).
      reference::RatioOptions ratio;
      ratio.min_input_snr = exact(q.min_input_snr);
      ratio.swap = q.treatment == RecordTreatment::Improper;
      switch (q.treatment) {
        case RecordTreatment::Plain:
          res = reference::identify_frf(stats.data, o);
          break;
        case RecordTreatment::Improper:
          res = reference::identify_frf(reference::ratio_estimate(stats, ratio), o);
          break;
        case RecordTreatment::ErrorsInVariables:
          res = reference::identify_frf(reference::ratio_estimate(stats, ratio), o);
          if (q.eiv_variance == EivVariance::Model) {  // Eq. (31) again at the first-pass model
            ratio.first_pass = &res.model;
            const reference::FrfData second = reference::ratio_estimate(stats, ratio);
            res = reference::identify_frf(second, o);
          }
          break;
      }
    }
  } catch (const reference::StepError& e) {
    throw Error(ErrorKind::Numerical, where, std::string("reference: ") + e.what());
  } catch (const reference::Error& e) {
    throw Error(ErrorKind::Input, where, e.what());
  }
  if (!q.data_path.empty() && !q.continuous) res.model.sample_time = sample_time;
  if (!q.frf_path.empty() && !q.continuous && q.units.sample_time > 0)
    res.model.sample_time = reference::parse_decimal(q.units.sample_time_text);
  return res;
}



std::vector<StateSpace> frf_perturbed_models(const FrfHighRequest& q, double backward_error, double sample_time) {
  const std::string where = q.frf_path.empty() ? q.data_path : q.frf_path;
  std::vector<StateSpace> models;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    StateSpace p = model_from_json(frf_high_json(reference_frf(q, exact(backward_error), seed), q, where, ""),
                                   "perturbed reference model");
    if (!q.continuous) p.sample_time = sample_time;
    models.push_back(std::move(p));
  }
  return models;
}

int identify_frf_high(const std::string& json_path, const FrfHighRequest& q, const std::string& note) {
  const std::string where = q.frf_path.empty() ? q.data_path : q.frf_path;
  const reference::FrfResult res = reference_frf(q);
  const json j = frf_high_json(res, q, where, note);
  if (json_path != "-") {
    std::cout << "identified order " << res.order << " in high precision, r = " << res.r << ", V_SUB = "
              << reference::to_decimal(res.v_sub, 6) << "\npoles:";
    for (const auto& z : j["poles"]) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "  %.15g%+.15gi", to_double(z[0]), to_double(z[1]));
      std::cout << buf;
    }
    std::cout << "\n";
    if (!note.empty()) std::cout << note << "\n";
    std::cout << "(the JSON has 40 significant digits)\n";
  }
  if (!json_path.empty()) write_text_file(json_path, j.dump(2) + "\n");
  return 0;
}


namespace {

// A setting the candidate JSON names or the command line gives (both: they
// must agree); `none` when neither.
template <class T>
T setting(const char* name, const T& from_json, const T& from_cli, const T& none, const std::string& model_path,
          const std::string& shown_json, const std::string& shown_cli) {
  if (from_json != none && from_cli != none && from_json != from_cli)
    throw Error(ErrorKind::Input, "--" + std::string(name),
                shown_cli + " contradicts the candidate's " + name + " " + shown_json + " (" + model_path +
                    "); drop the option, or check a candidate made with that setting");
  return from_json != none ? from_json : from_cli;
}

// The FRF models' "method" names (frf_method_name of every basis, discrete
// then continuous), each with its domain and its basis in --method's words.
const NameTable<std::pair<Domain, const char*>>& frf_model_methods() {
  static const NameTable<std::pair<Domain, const char*>> names = [] {
    NameTable<std::pair<Domain, const char*>> t;
    for (const auto& [basis, m] : discrete_method_names())
      t.push_back(
          {frf_method_name(Domain::Discrete, ContinuousMethod::Bilinear, m), {Domain::Discrete, basis.c_str()}});
    for (const auto& [basis, m] : continuous_method_names())
      t.push_back({frf_method_name(Domain::Continuous, m), {Domain::Continuous, basis.c_str()}});
    return t;
  }();
  return names;
}

// The candidate's "method" (frf_method_name's names): the domain it belongs
// to and its basis in --method's words; an empty basis when the JSON has none.
struct CandidateMethod {
  std::string name;
  Domain domain = Domain::Discrete;
  std::string basis;
};
CandidateMethod candidate_method(const json& cj, const std::string& model_path) {
  if (!cj.contains("method")) return {};
  const std::string m = cj["method"].is_string() ? cj["method"].get<std::string>() : "";
  if (const auto known = from_name(frf_model_methods(), m)) return {m, known->first, known->second};
  if (from_name(method_names(), m))
    throw Error(ErrorKind::Input, model_path + " field \"method\"",
                "\"" + m + "\" is a spectral factor; check it against its spectrum with --data SPECTRUM.csv");
  throw Error(ErrorKind::Input, model_path + " field \"method\"", "is not " + name_list(frf_model_methods()));
}

}  // namespace

namespace {

// How the candidate treated periodic records (Section 5): from its JSON's
// "source" (identify-frf writes it) or, without one, from the options.
struct RecordSettings {
  RecordTreatment treatment = RecordTreatment::Plain;
  EivVariance eiv_variance = EivVariance::Data;
  double min_input_snr = 10;
  RecordSelection selection;
};

// The candidate's column selection and skipped periods (identify-frf writes
// them into "source"): taken when the command line gives none; a command line
// that gives others contradicts the candidate (exit 2).
void read_selection(const json& src, const FrfCheckRequest& q, RecordSettings& s) {
  RecordSelection json_sel;
  try {
    if (src.contains("input_columns")) json_sel.inputs = src["input_columns"].get<std::vector<std::string>>();
    if (src.contains("output_columns")) json_sel.outputs = src["output_columns"].get<std::vector<std::string>>();
    if (src.contains("skip_periods")) json_sel.skip_periods = src["skip_periods"].get<int>();
    if (src.contains("use_periods")) json_sel.use_periods = src["use_periods"].get<int>();
  } catch (const json::exception&) {
    throw Error(ErrorKind::Input, q.model_path + " field \"source\"",
                "input_columns/output_columns must be arrays of names, skip_periods and use_periods integers");
  }
  if (q.selection.empty()) {
    s.selection = json_sel;
  } else {
    // A source without a selection used every column and period: options
    // that select contradict it as much as different ones (a user review:
    // --skip-periods 1 against an 8-period candidate read DISAGREES).
    if (json_sel.inputs != q.selection.inputs || json_sel.outputs != q.selection.outputs ||
        json_sel.skip_periods != q.selection.skip_periods || json_sel.use_periods != q.selection.use_periods)
      throw Error(ErrorKind::Input, "--input/--output/--skip-periods/--use-periods",
                  "contradict the candidate's \"source\" (" + src.dump() +
                      (json_sel.empty() ? ", which selects nothing: every column and period" : std::string()) +
                      "); drop the options: check repeats what the candidate JSON says it did");
    s.selection = q.selection;
  }
}

RecordSettings record_settings(const json& cj, const FrfCheckRequest& q) {
  RecordSettings s;
  const bool has_source = cj.contains("source") && cj["source"].is_object() && cj["source"].contains("data");
  if (!has_source) {
    s.treatment = q.eiv ? RecordTreatment::ErrorsInVariables
                  : q.improper ? RecordTreatment::Improper
                               : RecordTreatment::Plain;
    s.eiv_variance = q.eiv_model_variance ? EivVariance::Model : EivVariance::Data;
    if (q.min_input_snr > 0) s.min_input_snr = q.min_input_snr;
    s.selection = q.selection;
    return s;
  }
  const json& src = cj["source"];
  if (src.contains("noise_std"))
    throw Error(ErrorKind::Input, q.model_path + " field \"source\"",
                "the candidate was identified with a known noise level (--noise-std); the reference repeats "
                "identifications from the sample variance of M >= 4 periods only");
  read_selection(src, q, s);
  const json* treated = src.contains("errors_in_variables") ? &src["errors_in_variables"]
                        : src.contains("improper")          ? &src["improper"]
                                                            : nullptr;
  s.treatment = src.contains("errors_in_variables") ? RecordTreatment::ErrorsInVariables
                : src.contains("improper")          ? RecordTreatment::Improper
                                                    : RecordTreatment::Plain;
  if (treated && treated->is_object()) {
    if (treated->contains("variance") && (*treated)["variance"].is_string() &&
        (*treated)["variance"].get<std::string>().find("first-pass model") != std::string::npos)
      s.eiv_variance = EivVariance::Model;
    if (treated->contains("min_input_snr") && (*treated)["min_input_snr"].is_number())
      s.min_input_snr = (*treated)["min_input_snr"].get<double>();
  }
  const bool json_eiv = s.treatment == RecordTreatment::ErrorsInVariables;
  const bool json_improper = s.treatment == RecordTreatment::Improper;
  if ((q.eiv && !json_eiv) || (q.improper && !json_improper) || (q.eiv_model_variance && s.eiv_variance != EivVariance::Model) ||
      (q.min_input_snr > 0 && q.min_input_snr != s.min_input_snr))
    throw Error(ErrorKind::Input, "--eiv/--improper/--eiv-variance/--min-input-snr",
                "contradict the candidate's \"source\" (" + src.dump() +
                    "); drop the options: check repeats what the candidate JSON says it did");
  return s;
}

// What check repeats of the candidate's identification: read from its JSON,
// completed by the options (settings) and by the data (data_and_settings).
struct CandidateSettings {
  Domain domain = Domain::Discrete;
  ContinuousMethod method = ContinuousMethod::Bilinear;
  DiscreteMethod discrete = DiscreteMethod::Monomial;
  int r = 0;          ///< 0 until chosen
  double ws = 0;      ///< ω_s; 0 until the data give the default
  RecordSettings rec;
  FrequencyUnits units;  ///< FRF file: as the candidate's "source" or the options say
  std::string note;   ///< what was not read from the candidate, "; "-separated
};

// The FRF file's frequency unit and sample time (identify-frf writes them
// into "source" when not the default): taken when the options give none; a
// command line that gives others contradicts the candidate (exit 2).
FrequencyUnits frf_units(const json& cj, const FrfCheckRequest& q) {
  FrequencyUnits from_json;
  if (cj.contains("source") && cj["source"].is_object()) {
    const json& src = cj["source"];
    try {
      if (src.contains("frequency_unit")) {
        from_json.hz = src["frequency_unit"].get<std::string>() == "hz";
        from_json.unit_given = true;
      }
      if (src.contains("sample_time")) {
        from_json.sample_time_text = src["sample_time"].get<std::string>();
        from_json.sample_time = std::stod(from_json.sample_time_text);
      }
    } catch (const std::exception&) {
      throw Error(ErrorKind::Input, q.model_path + " field \"source\"",
                  "frequency_unit must be \"hz\" or \"rad\" and sample_time a decimal string of seconds");
    }
  }
  if (q.units.is_default() && !q.units.unit_given) return from_json;
  if ((from_json.unit_given || !from_json.is_default()) &&
      (from_json.hz != q.units.hz || from_json.sample_time != q.units.sample_time))
    throw Error(ErrorKind::Input, "--frequency-unit/--sample-time",
                "contradict the candidate's \"source\"; drop the options: check repeats what the candidate JSON says it did");
  return q.units;
}

CandidateSettings candidate_settings(const json& cj, const FrfCheckRequest& q, const StateSpace& candidate) {
  CandidateSettings c;
  c.rec = record_settings(cj, q);
  c.domain = candidate.domain;
  c.units = frf_units(cj, q);
  require_frequency_units(c.units, c.domain, !q.frf_path.empty());
  const CandidateMethod jm = candidate_method(cj, q.model_path);
  if (!jm.basis.empty() && jm.domain != c.domain)
    throw Error(ErrorKind::Input, q.model_path,
                std::string(c.domain == Domain::Discrete ? "a discrete-time model with a continuous-time method \""
                                                         : "a continuous-time model with a discrete-time method \"") +
                    jm.name + "\"");
  FrfOptions chosen;
  set_frf_method(q.method, c.domain, chosen);  // a name of the other domain: refused as such
  const std::string method_s =
      setting<std::string>("method", jm.basis, q.method, "", q.model_path, jm.basis, q.method);
  set_frf_method(method_s, c.domain, chosen);
  c.method = chosen.continuous;
  c.discrete = chosen.discrete;
  if (c.domain == Domain::Continuous && method_s.empty())
    c.note += "method: bilinear (Algorithm 2.1; neither the candidate nor --method names one); ";
  const int json_r = int_field(cj, "r", q.model_path);
  c.r = setting<int>("r", json_r, q.r, 0, q.model_path, std::to_string(json_r), std::to_string(q.r));
  const double json_ws = cj.contains("omega_scale") && cj["omega_scale"].is_number() ? cj["omega_scale"].get<double>() : 0;
  c.ws = setting<double>("omega-scale", json_ws, q.omega_scale, 0, q.model_path, fmt(json_ws, 17), fmt(q.omega_scale, 17));
  if (!q.frf_path.empty() && c.rec.treatment != RecordTreatment::Plain)
    throw Error(ErrorKind::Input, q.model_path, "was identified with --eiv or --improper, which need periodic "
                                                "records: give --data RECORDS.csv --meta META.json");
  return c;
}

// The data as the candidate's identification saw them (fast/'s readers: one
// line naming the cause; Section 5's treatment of records, the lines that
// remain after Eq. 34), completing the default ω_s and the V_SUB choice of r.
FrfData data_and_settings(const FrfCheckRequest& q, const StateSpace& candidate, CandidateSettings& c) {
  const bool from_frf = !q.frf_path.empty();
  const std::string where = from_frf ? q.frf_path : q.data_path;
  FrfData data;
  SampleStatistics stats;
  if (from_frf) {
    data = read_frf_csv(q.frf_path, c.domain, c.units);
  } else {
    const Records rec = read_records(q.data_path, q.meta_path, c.rec.selection);
    const RecordMeta& meta = rec.meta;
    require_sample_subspace_periods(meta, q.meta_path, c.rec.selection);
    if (c.domain == Domain::Discrete && std::abs(candidate.sample_time - meta.sample_time) > 1e-5 * meta.sample_time)
      throw Error(ErrorKind::Input, q.model_path + " field \"sample_time\"",
                  fmt(candidate.sample_time, 10) + " differs from the records' " + fmt(meta.sample_time, 10) + " (" +
                      q.meta_path + "): the candidate was identified from other data");
    try {
      stats = record_statistics(rec.samples, rec.inputs, meta, c.domain);
    } catch (const Error& e) {
      throw e.within(q.data_path + " with " + q.meta_path);
    }
    data = stats.data;
  }
  if (candidate.inputs() != data.inputs() || candidate.outputs() != data.outputs())
    throw Error(ErrorKind::Input, q.model_path,
                "has " + std::to_string(candidate.inputs()) + " inputs and " + std::to_string(candidate.outputs()) +
                    " outputs; the data have " + std::to_string(data.inputs()) + " and " +
                    std::to_string(data.outputs()));
  if (c.domain == Domain::Continuous && c.ws == 0) c.ws = std::sqrt(data.omega.minCoeff() * data.omega.maxCoeff());
  if (c.domain == Domain::Discrete && c.discrete != DiscreteMethod::Monomial && c.ws == 0)
    c.ws = default_discrete_scale(data.omega);
  if (c.r > 0 && c.rec.treatment == RecordTreatment::Plain) return data;
  FrfOptions o;
  o.order = candidate.order();
  o.r = c.r;
  o.continuous = c.method;
  o.discrete = c.discrete;
  o.omega_scale = c.ws;
  try {
    if (from_frf) {
      c.r = select_order_and_r(data, o).r;
    } else {
      FrfRun run = identify_frf_records(stats, o, c.rec.treatment, c.rec.eiv_variance, c.rec.min_input_snr);
      data = std::move(run.data);
      if (c.r == 0) c.r = run.result.r;
    }
  } catch (const Error& e) {
    throw e.within(where);
  }
  if (o.r == 0)
    c.note += "r = " + std::to_string(c.r) +
              " by fdsid's V_SUB selection (Pintelon 2002 Section 5; the candidate JSON has no r, give --r); ";
  return data;
}

// The order the data support at the candidate's settings: fdsid's automatic
// order (identify-frf --order auto, the largest gap of step 1c's singular
// values above the noise level) at r; 0 when none can be read.
int supported_order(const FrfData& data, const CandidateSettings& c) {
  FrfOptions o;
  o.order = 0;
  o.r = c.r;
  o.continuous = c.method;
  o.discrete = c.discrete;
  o.omega_scale = c.ws;
  try {
    return identify_frf(data, o).order;
  } catch (const Error&) {
    return 0;
  }
}

}  // namespace

int check_frf(const std::string& json_path, const FrfCheckRequest& q) {
  const json cj = read_candidate(q.model_path);
  // fdsid's own steps after the subspace estimate (not in the papers, not in
  // the reference) make a model the reference cannot repeat: compared with
  // the subspace estimate, a correct candidate would DISAGREE (review finding
  // 1 of stop 47: the default F-16 order-16 model, ratio 2.2e8).
  if (cj.contains("stabilised"))
    throw Error(ErrorKind::Input, q.model_path + " field \"stabilised\"",
                "the candidate's unstable subspace poles were reflected and B, D refitted (identify-frf's default, "
                "not in the papers), which the reference does not repeat; check the subspace estimate: identify-frf "
                "--allow-unstable");
  if (cj.contains("refinement"))
    throw Error(ErrorKind::Input, q.model_path + " field \"refinement\"",
                "the candidate is the --refine ml optimum, which the reference does not repeat; check the subspace "
                "estimate: identify-frf without --refine (with --allow-unstable if it has unstable poles)");
  const StateSpace candidate = model_from_json(cj, q.model_path);
  if (candidate.order() < 1) throw Error(ErrorKind::Input, q.model_path, "candidate has order 0");
  CandidateSettings c = candidate_settings(cj, q, candidate);
  const FrfData data = data_and_settings(q, candidate, c);
  const std::string where = q.frf_path.empty() ? q.data_path : q.frf_path;

  FrfHighRequest hq;
  hq.frf_path = q.frf_path;
  hq.units = c.units;
  hq.data_path = q.data_path;
  hq.meta_path = q.meta_path;
  hq.continuous = c.domain == Domain::Continuous;
  hq.orthogonal = c.method == ContinuousMethod::Orthogonal;
  hq.discrete = c.discrete;
  hq.omega_scale = c.ws;
  hq.order = candidate.order();
  hq.r = c.r;
  hq.treatment = c.rec.treatment;
  hq.eiv_variance = c.rec.eiv_variance;
  hq.min_input_snr = c.rec.min_input_snr;
  hq.selection = c.rec.selection;
  reference::FrfResult res;
  std::string order_note;
  try {
    res = reference_frf(hq);
  } catch (const Error& e) {
    // The reference cannot identify these data at the candidate's order (a
    // step fails): a disagreement about the order, not bad input. The
    // reference identifies them at the order they support, and the candidate
    // is compared with that model (the orders then differ), as for spectra.
    const int supported = supported_order(data, c);
    if (e.kind() != ErrorKind::Numerical || supported < 1 || supported == candidate.order() || supported >= c.r) throw;
    const std::string what = e.what();
    const auto at = what.find("step ");
    order_note = "the reference fails at the candidate's order " + std::to_string(candidate.order()) +
                 (at == std::string::npos ? std::string() : " (" + what.substr(at, what.find(':', at) - at) + ")") +
                 "; the data support order " + std::to_string(supported) + ", which the candidate is compared with";
    hq.order = supported;
    res = reference_frf(hq);
  }

  FrfOracleCheck k;
  k.candidate_path = q.model_path;
  k.data_path = where;
  k.meta_path = q.meta_path;
  k.order = res.order;
  k.r = c.r;
  k.domain = c.domain;
  k.method = c.method;
  k.omega_scale = c.ws;
  k.method_name = frf_method_name(c.domain, c.method, c.discrete);
  if (!c.note.empty()) k.settings_note = c.note.substr(0, c.note.size() - 2);
  k.reference_model = frf_high_json(res, hq, where, "");
  StateSpace ref = model_from_json(k.reference_model, "reference model");  // decimal strings, correctly rounded
  if (c.domain == Domain::Discrete) ref.sample_time = candidate.sample_time;
  // The tolerance (compare.hpp, FrfTolerance): the reference again, three
  // times, with Z and C_Y moved by the backward error of a correct double
  // implementation in independent random directions.
  k.backward_perturbation = frf_backward_error(data, c.r);
  if (q.tolerance <= 0) k.tolerance.perturbed = frf_perturbed_models(hq, k.backward_perturbation, candidate.sample_time);
  k.tolerance.given = q.tolerance;
  k.tolerance.method = c.method;
  k.tolerance.omega_scale = c.ws;
  const Eigen::VectorXd dense = dense_frequency_grid(c.domain, data.omega);
  k.comparison = compare_frf_models(candidate, ref, data.omega, dense, k.tolerance);
  if (!k.agree())
    if (const std::string d = digits_note(candidate, ref, k.comparison.poles.distance,
                                          [&](const StateSpace& rounded) {
                                            FrfOracleCheck alike = k;
                                            alike.comparison = compare_frf_models(rounded, ref, data.omega, dense,
                                                                                  k.tolerance);
                                            return alike.agree() ? -1.0 : alike.comparison.poles.distance;
                                          });
        !d.empty())
      k.settings_note += (k.settings_note.empty() ? "" : "\n") + d;
  k.order_note = order_note;
  if (order_note.empty()) {
    // The comparison is at the candidate's order (a setting of the
    // algorithm, like r); say when the data show another.
    const int supported = supported_order(data, c);
    if (supported > 0 && supported != candidate.order())
      k.order_note = "note: the data support order " + std::to_string(supported) +
                     " (identify-frf --order auto at r = " + std::to_string(c.r) +
                     "); the candidate has order " + std::to_string(candidate.order()) +
                     ", and is compared with the reference at its own order";
  }
  if (json_path != "-") std::cout << k.summary();
  if (!json_path.empty()) write_text_file(json_path, to_json(k).dump(2) + "\n");
  return k.agree() ? 0 : 1;
}

}  // namespace fdsid::cli
