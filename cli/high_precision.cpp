#include "high_precision.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "fdsid/compare.hpp"
#include "fdsid/error.hpp"
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

// Runs the reference, turning its errors into the library's typed errors
// (input problems and failed steps both exit 2 with one line).
reference::Result run_reference(const std::string& data_path, int order, int& p, int& r, bool vo, Extension ext,
                                int& m, int& M) {
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
    return reference::identify_spectrum(spectrum, order, p, r, vo);
  } catch (const reference::StepError& e) {
    throw Error(ErrorKind::Numerical, data_path, std::string("reference: ") + e.what());
  } catch (const reference::Error& e) {
    throw Error(ErrorKind::Input, data_path, e.what());
  }
}

}  // namespace

int identify_spectrum_high(const std::string& json_path, const std::string& data_path, int order, int p, int r,
                           bool vo, Extension ext) {
  int m = 0, M = 0;
  const reference::Result res = run_reference(data_path, order, p, r, vo, ext, m, M);
  json j = reference::result_to_json(res, vo, 40);
  j["extension"] = to_string(ext);
  j["data"] = data_path;
  j["precision"] = "high (50-digit binary floating point, Boost.Multiprecision cpp_bin_float<50>)";
  if (json_path != "-") {
    std::cout << "identified order " << res.order << " in high precision by " << (vo ? "vo1997" : "akcay2011")
              << " from M = " << M << ", m = " << m << ", p = " << res.p << ", r = " << res.r << "\npoles:";
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
  std::ifstream f(model_path);
  if (!f) throw Error(ErrorKind::Input, model_path, "cannot open candidate model");
  json cj;
  try {
    cj = json::parse(f);
  } catch (const json::parse_error& e) {
    throw Error(ErrorKind::Input, model_path, std::string("malformed JSON: ") + e.what());
  }
  const StateSpace candidate = model_from_json(cj, model_path);
  auto int_field = [&](const char* key) {
    if (!cj.contains(key)) return 0;
    if (!cj[key].is_number_integer() || cj[key].get<int>() < 1)
      throw Error(ErrorKind::Input, model_path + " field \"" + key + "\"", "must be a positive integer");
    return cj[key].get<int>();
  };
  int p = int_field("p"), r = int_field("r");
  const bool vo = cj.contains("method") && cj["method"] == "vo1997";
  const Extension ext =
      cj.contains("extension") && cj["extension"] == "conjugate" ? Extension::Conjugate : Extension::HermitianPart;
  if (candidate.order() < 1) throw Error(ErrorKind::Input, model_path, "candidate has order 0");

  int m = 0, M = 0;
  const int p_given = p, r_given = r;
  std::string note;
  reference::Result res;
  try {
    res = run_reference(data_path, candidate.order(), p, r, vo, ext, m, M);
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Numerical) throw;
    // The reference cannot identify these data at the candidate's order (a
    // step of Algorithm 1 fails, e.g. no stable/antistable split at step 6):
    // that is a disagreement about the order, not bad input. The reference is
    // run again with the order read from its singular values, and the
    // candidate is compared with that model (the orders then differ).
    p = p_given;
    r = r_given;
    res = run_reference(data_path, 0, p, r, vo, ext, m, M);
    if (res.order == candidate.order()) throw;
    const std::string what = e.what();
    const auto at = what.find("step ");
    note = "the reference fails at the candidate's order " + std::to_string(candidate.order()) +
           (at == std::string::npos ? std::string() : " (" + what.substr(at, what.find(':', at) - at) + ")") +
           "; the data support order " + std::to_string(res.order) + ", which the candidate is compared with";
  }
  OracleCheck k;
  k.note = note;
  k.candidate_path = model_path;
  k.data_path = data_path;
  k.p = p;
  k.r = r;
  k.method = vo ? Method::VanOverschee1997 : Method::Akcay2011;
  k.extension = ext;
  k.reference_model = reference::result_to_json(res, vo, 40);
  const StateSpace ref = model_from_json(k.reference_model, "reference model");  // decimal strings, correctly rounded
  k.comparison = compare_models(candidate, ref);

  // Default tolerance: what a correct double-precision implementation reaches on
  // these data (compare.hpp), with sigma1/sigma_2n from the reference's singular
  // values; poles, Markov parameters and the factor get condition numbers on top (workflow.hpp).
  const int n = res.order;
  const json& sv = k.reference_model["singular_values"];
  set_oracle_tolerances(k, ref, m, 2 * M, to_double(sv[0]) / to_double(sv[2 * n - 1]), tolerance);
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

namespace {

// The 50-digit value of a double, exactly (17 significant digits identify it).
reference::Real exact(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return reference::parse_decimal(buf);
}

// Periodic records read by fast/'s reader, turned into the reference's sample
// means and variances over the periods (Pintelon 2002 Section 4.1) in 50 digits.
reference::FrfData records_high(const FrfHighRequest& q, const std::string& domain, reference::Real& sample_time) {
  int inputs = 0;
  const Eigen::MatrixXd samples = read_records_csv(q.data_path, inputs);
  const RecordMeta meta = read_meta(q.meta_path);
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
  const reference::Real two_pi = boost::multiprecision::atan(reference::Real(1)) * 8;
  for (int k : meta.excited_lines)
    omega.push_back(two_pi * k / meta.period / (q.continuous ? sample_time : reference::Real(1)));
  return reference::sample_statistics(domain, omega, U_l, Y_l).data;
}

// The identified model's JSON, every number a 40-digit decimal string.
json frf_high_json(const reference::FrfResult& res, const FrfHighRequest& q, const std::string& where,
                   const std::string& note) {
  json j = reference::model_to_json(res.model, 40);
  j["order"] = res.order;
  j["r"] = res.r;
  j["method"] = q.continuous ? std::string("pintelon2002-alg2-") + (q.orthogonal ? "orthogonal" : "bilinear")
                             : std::string("pintelon2002-alg1");
  json sv = json::array();
  for (const auto& s : res.singular_values) sv.push_back(reference::to_decimal(s, 40));
  j["singular_values"] = sv;
  json poles = json::array();
  for (const auto& z : res.poles) poles.push_back({reference::to_decimal(z.real(), 40), reference::to_decimal(z.imag(), 40)});
  j["poles"] = poles;
  j["v_sub"] = reference::to_decimal(res.v_sub, 40);
  j["data"] = where;
  j["precision"] = "high (50-digit binary floating point, Boost.Multiprecision cpp_bin_float<50>)";
  if (!note.empty()) j["note"] = note;
  return j;
}

}  // namespace

int identify_frf_high(const std::string& json_path, const FrfHighRequest& q, const std::string& note) {
  const std::string domain = q.continuous ? "continuous" : "discrete";
  const std::string where = q.frf_path.empty() ? q.data_path : q.frf_path;
  reference::FrfResult res;
  reference::Real sample_time = 1;
  try {
    const reference::FrfData data =
        !q.frf_path.empty() ? reference::read_frf_csv(q.frf_path, domain) : records_high(q, domain, sample_time);
    reference::FrfOptions o;
    o.order = q.order;
    o.r = q.r;
    o.continuous_method = q.orthogonal ? "orthogonal" : "bilinear";
    if (q.omega_scale > 0) o.omega_scale = exact(q.omega_scale);
    res = reference::identify_frf(data, o);
  } catch (const reference::StepError& e) {
    throw Error(ErrorKind::Numerical, where, std::string("reference: ") + e.what());
  } catch (const reference::Error& e) {
    throw Error(ErrorKind::Input, where, e.what());
  }
  if (!q.data_path.empty() && !q.continuous) res.model.sample_time = sample_time;
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

}  // namespace fdsid::cli
