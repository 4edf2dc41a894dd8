// fdsid certify: the certified values of fixtures/certified/ (its README),
// computed by the reference in this build's precision. scripts/certify.sh runs
// it twice: in a build with 100-digit reference (--raw-out: the values at full
// precision) and in the normal 50-digit build (--against: the digits both
// share, the reference model and the perturbed models of the tolerance).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <iostream>
#include <memory>


#include "common.hpp"
#include "fdsid/certified.hpp"
#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/io.hpp"
#include "fdsid/json.hpp"
#include "fdsid/reference/io.hpp"
#include "reference_runs.hpp"

namespace fdsid::cli {

namespace {

using nlohmann::json;
using reference::Complex;
using reference::MatrixC;
using reference::MatrixR;
using reference::Real;

// A certified quantity in the reference's precision.
struct RealQuantity {
  std::string name;
  std::vector<double> omega;  // the listed frequencies (the values are at exactly these doubles)
  int rows = 1, cols = 1;
  std::vector<MatrixC> values;
};

RealQuantity points(const std::string& name, const std::vector<Complex>& z) {
  RealQuantity q{name, {}, 1, 1, {}};
  for (const Complex& x : z) q.values.push_back(MatrixC::Constant(1, 1, x));
  return q;
}

// The system a noise-free spectrum case was sampled from, read from its
// decimal strings in this build's precision: it must be the minimum-phase
// factor (poles and zeros strictly inside the unit circle, D nonsingular), so
// that its normalised G is the exact factor of the sampled spectrum.
reference::Model minimum_phase_system(const std::string& path) {
  const reference::Model g = reference::read_model(path);
  if (!reference::nonsingular(g.D))
    throw Error(ErrorKind::Input, path, "D must be square and nonsingular (a spectral factor)");
  for (const Complex& z : reference::eigenvalues(g.A))
    if (!(abs(z) < 1)) throw Error(ErrorKind::Input, path, "a pole of modulus " + reference::to_decimal(abs(z), 6) + " is not inside the unit circle");
  for (const Complex& z : reference::transmission_zeros(g))
    if (!(abs(z) < 1))
      throw Error(ErrorKind::Input, path, "a zero of modulus " + reference::to_decimal(abs(z), 6) + " is not inside the unit circle: "
                                          "not the minimum-phase factor");
  return g;
}

// The fast/ data of an FRF or records case after Section 5's treatment: its
// frequencies are the grid of the certified G, its size the backward error.
FrfData case_data(const CaseSpec& s, const std::string& suite, double& sample_time) {
  sample_time = 1;
  if (s.kind == CaseKind::Frf) return read_frf_csv(suite + "/" + s.frf, s.domain);
  int inputs = 0;
  const Eigen::MatrixXd samples = read_records_csv(suite + "/" + s.data, inputs);
  const RecordMeta meta = read_meta(suite + "/" + s.meta);
  sample_time = meta.sample_time;
  const SampleStatistics stats = record_statistics(samples, inputs, meta, s.domain);
  if (s.treatment == RecordTreatment::Plain) return stats.data;
  FrfOptions o;
  o.order = s.order;
  o.r = s.r;
  o.continuous = s.continuous_method;
  o.omega_scale = s.omega_scale;
  return identify_frf_records(stats, o, s.treatment, s.eiv_variance, s.min_input_snr).data;
}

struct CaseResult {
  std::vector<RealQuantity> quantities;
  json reference_model, info;
  std::vector<StateSpace> perturbed;
};

CaseResult compute_case(const CaseSpec& s, const std::string& suite, bool with_perturbed) {
  CaseResult out;
  if (s.kind == CaseKind::Spectrum) {
    int p = s.p, r = s.r, m = 0, M = 0;
    const bool vo = s.spectrum_method == Method::VanOverschee1997;
    const PerturbationsFor rule = spectrum_perturbations(vo);
    std::vector<reference::Result> moved;
    const reference::Result res = run_reference(suite + "/" + s.data, s.order, p, r, vo, Extension::HermitianPart, m,
                                                M, with_perturbed ? &rule : nullptr, &moved);
    out.reference_model = reference::result_to_json(res, vo, 40);
    for (const reference::Result& x : moved)
      out.perturbed.push_back(model_from_json(reference::result_to_json(x, vo, 40), "perturbed reference model"));
    out.quantities.push_back(points("poles", res.poles));
    out.quantities.push_back(points("zeros", reference::transmission_zeros(res.model)));
    RealQuantity S{"S", {}, m, m, {}}, G{"factor", {}, m, m, {}}, X{"exact_factor", {}, m, m, {}};
    reference::Model system;
    if (!s.system.empty()) system = minimum_phase_system(suite + "/" + s.system);
    for (int k = 0; k <= M; ++k) {
      const double w = M_PI * k / M;  // the grid point as a double reads it
      const Real wr = exact(w);
      S.omega.push_back(w);
      G.omega.push_back(w);
      S.values.push_back(reference::spectrum_of(res.model, Complex(cos(wr), sin(wr))));
      G.values.push_back(reference::normalised_factor_response(res.model, wr));
      if (!s.system.empty()) {
        X.omega.push_back(w);
        X.values.push_back(reference::normalised_factor_response(system, wr));
      }
    }
    out.quantities.push_back(S);
    out.quantities.push_back(G);
    if (!s.system.empty()) out.quantities.push_back(X);
    return out;
  }
  FrfHighRequest q;
  if (s.kind == CaseKind::Frf) q.frf_path = suite + "/" + s.frf;
  else {
    q.data_path = suite + "/" + s.data;
    q.meta_path = suite + "/" + s.meta;
  }
  q.continuous = s.domain == Domain::Continuous;
  q.orthogonal = s.continuous_method == ContinuousMethod::Orthogonal;
  q.omega_scale = s.omega_scale;
  q.order = s.order;
  q.r = s.r;
  q.treatment = s.treatment;
  q.eiv_variance = s.eiv_variance;
  q.min_input_snr = s.min_input_snr;
  double sample_time = 1;
  const FrfData data = case_data(s, suite, sample_time);
  const reference::FrfResult res = reference_frf(q);
  out.reference_model = frf_high_json(res, q, s.kind == CaseKind::Frf ? s.frf : s.data, "", 40);
  out.info["v_sub"] = reference::to_decimal(res.v_sub, 40);
  if (with_perturbed) out.perturbed = frf_perturbed_models(q, frf_backward_error(data, s.r), sample_time);
  out.quantities.push_back(points("poles", res.poles));
  RealQuantity G{"G", {}, data.outputs(), data.inputs(), {}};
  for (Eigen::Index k = 0; k < data.omega.size(); ++k) {
    G.omega.push_back(data.omega(k));
    G.values.push_back(reference::frequency_response(res.model, exact(data.omega(k))));
  }
  out.quantities.push_back(G);
  return out;
}

json quantity_json(const RealQuantity& q, int digits, const std::vector<int>* certified_digits) {
  json j;
  if (!q.omega.empty()) {
    json w = json::array();
    for (double x : q.omega) w.push_back(fmt(x, 17));
    j["omega"] = w;
  }
  j["shape"] = {q.rows, q.cols};
  json values = json::array();
  for (const MatrixC& X : q.values) {
    json v = json::array();
    for (int i = 0; i < X.rows(); ++i)
      for (int k = 0; k < X.cols(); ++k)
        v.push_back({reference::to_decimal(X(i, k).real(), digits), reference::to_decimal(X(i, k).imag(), digits)});
    values.push_back(v);
  }
  j["values"] = values;
  if (certified_digits) j["digits"] = *certified_digits;
  return j;
}

MatrixC matrix_from_json(const json& v, int rows, int cols) {
  MatrixC X(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int k = 0; k < cols; ++k)
      X(i, k) = Complex(reference::parse_decimal(v.at(i * cols + k).at(0).get<std::string>()),
                        reference::parse_decimal(v.at(i * cols + k).at(1).get<std::string>()));
  return X;
}

Real abs2(const Complex& z) { return z.real() * z.real() + z.imag() * z.imag(); }

// The significant digits two computations of a value share, relative to its
// Frobenius norm: ⌊−log10(‖X − Y‖ / ‖Y‖)⌋, at most kMaxDigits (what is written).
constexpr int kMaxDigits = 40;
int shared_digits(const MatrixC& X, const MatrixC& Y) {
  Real diff = 0, norm = 0;
  for (Eigen::Index i = 0; i < X.size(); ++i) {
    diff += abs2(X(i) - Y(i));
    norm += abs2(Y(i));
  }
  if (diff == 0) return kMaxDigits;
  const Real rel = norm > 0 ? sqrt(diff / norm) : sqrt(diff);
  const int d = static_cast<int>(floor(-log10(rel)).convert_to<double>());
  return std::max(0, std::min(kMaxDigits, d));
}

// Digits of each value of `q` against the other precision's `other` (same
// quantity): grids value by value; poles and zeros each against the nearest
// value of the other set. A count that differs certifies nothing (0 digits).
std::vector<int> digits_against(const RealQuantity& q, const json& other, const std::string& where) {
  std::vector<MatrixC> theirs;
  for (const auto& v : other.at("values")) theirs.push_back(matrix_from_json(v, q.rows, q.cols));
  std::vector<int> d(q.values.size(), 0);
  if (theirs.size() != q.values.size()) {
    std::cerr << where << ": " << q.name << ": " << q.values.size() << " values here, " << theirs.size()
              << " in the other precision; certified with 0 digits\n";
    return d;
  }
  const bool sets = q.omega.empty();
  for (std::size_t i = 0; i < q.values.size(); ++i) {
    std::size_t j = i;
    if (sets) {
      Real best = -1;
      for (std::size_t t = 0; t < theirs.size(); ++t) {
        const Real e = abs2(q.values[i](0, 0) - theirs[t](0, 0));
        if (best < 0 || e < best) best = e, j = t;
      }
    }
    d[i] = shared_digits(q.values[i], theirs[j]);
  }
  return d;
}

struct CertifyCommand {
  std::string suite = "fixtures/certified";
  std::vector<std::string> cases;
  std::string raw_out, against;
};

int run(const CertifyCommand& c) {
  if (c.raw_out.empty() == c.against.empty())
    throw Error(ErrorKind::Input, "certify", "give --raw-out DIR (the second precision) or --against DIR (its output)");
  std::vector<CaseSpec> specs = read_suite_manifest(c.suite);
  for (const std::string& name : c.cases) {
    bool found = false;
    for (const auto& s : specs) found = found || s.name == name;
    if (!found) throw Error(ErrorKind::Input, "--case", "\"" + name + "\" is not in " + c.suite + "/cases.json");
  }
  const bool raw = !c.raw_out.empty();
  for (const CaseSpec& s : specs) {
    if (!c.cases.empty() && std::find(c.cases.begin(), c.cases.end(), s.name) == c.cases.end()) continue;
    const auto t0 = std::chrono::steady_clock::now();
    CaseResult res;
    try {
      res = compute_case(s, c.suite, !raw);
    } catch (const Error& e) {
      throw e.within("case " + s.name);
    }
    json j;
    j["case"] = s.name;
    std::string digit_summary;
    if (raw) {
      j["digits"] = reference::kDigits;
      for (const RealQuantity& q : res.quantities) j["quantities"][q.name] = quantity_json(q, reference::kDigits - 2, nullptr);
      write_text_file(c.raw_out + "/" + s.name + ".raw.json", j.dump(1) + "\n");
    } else {
      const std::string other_path = c.against + "/" + s.name + ".raw.json";
      std::ifstream f(other_path);
      if (!f) throw Error(ErrorKind::Input, other_path, "cannot open: run the other precision with --raw-out first");
      const json other = json::parse(f);
      j["format"] = "fdsid-certified-1";
      j["generator"] = "fdsid certify (scripts/certify.sh): the reference in " + std::to_string(reference::kDigits) +
                       " and " + std::to_string(other.at("digits").get<int>()) +
                       " digits; digits = the significant digits both share (fixtures/certified/README.md)";
      j["tier"] = s.tier;
      j["kind"] = to_string(s.kind);
      j["description"] = s.description;
      j["inputs"] = case_inputs_json(s);
      for (const RealQuantity& q : res.quantities) {
        const std::vector<int> d = digits_against(q, other.at("quantities").at(q.name), s.name);
        j["certified"][q.name] = quantity_json(q, kMaxDigits, &d);
        digit_summary += " " + q.name + " " + std::to_string(d.empty() ? 0 : *std::min_element(d.begin(), d.end()));
      }
      j["reference_model"] = res.reference_model;
      json perturbed = json::array();
      for (const StateSpace& m : res.perturbed) perturbed.push_back(to_json(m));
      j["perturbed_models"] = perturbed;
      if (!res.info.empty()) j["information"] = res.info;
      write_text_file(c.suite + "/" + s.name + ".json", j.dump(1) + "\n");
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%-44s %-7s %5.1f s%s\n", s.name.c_str(), s.tier.c_str(), secs,
                digit_summary.empty() ? "" : ("  digits:" + digit_summary).c_str());
  }
  return 0;
}

}  // namespace

void register_certify(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<CertifyCommand>();
  auto* sub = app.add_subcommand("certify", "regenerate the certified reference suite (fixtures/certified; scripts/certify.sh)");
  sub->add_option("--suite", c->suite, "suite folder with cases.json (default fixtures/certified)");
  sub->add_option("--case", c->cases, "only these cases");
  sub->add_option("--raw-out", c->raw_out, "write each case's values at this build's full precision here")
      ->check(CLI::ExistingDirectory);
  sub->add_option("--against", c->against, "folder of --raw-out of the other precision: write the certified cases")
      ->check(CLI::ExistingDirectory);
  on_parsed(sub, c, chosen, run);
}

}  // namespace fdsid::cli
