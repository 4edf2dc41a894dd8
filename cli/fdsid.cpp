// fdsid command-line tool: argument parsing and formatting only; every number
// comes from the fast/ library.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/spectrum_id.hpp"
#include "high_precision.hpp"

namespace {

using nlohmann::json;

std::string sci(double x, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits, x);
  return buf;
}

void emit_json(const std::string& path, const json& j) {
  if (!path.empty()) fdsid::write_text_file(path, j.dump(2) + "\n");
}

// Prints the human summary unless the JSON goes to stdout.
struct Out {
  bool quiet;
  template <class T>
  Out& operator<<(const T& v) {
    if (!quiet) std::cout << v;
    return *this;
  }
};

fdsid::Extension parse_extension(const std::string& s) {
  if (s == "hermitian-part") return fdsid::Extension::HermitianPart;
  if (s == "conjugate") return fdsid::Extension::Conjugate;
  throw fdsid::Error(fdsid::ErrorKind::Input, "--extension", "\"" + s + "\" is not hermitian-part or conjugate");
}

int parse_order(const std::string& s) {
  if (s == "auto") return 0;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || v < 1 || v > 1000)
    throw fdsid::Error(fdsid::ErrorKind::Input, "--order", "\"" + s + "\" is neither a positive integer nor auto");
  return static_cast<int>(v);
}

int run_table1(const std::string& json_path) {
  Out out{json_path == "-"};
  const auto rows = fdsid::reproduce_table1();
  json j;
  j["source"] = "Akcay (2011) Table 1: 4th and 5th singular values of G_9 F_8 (Eq. 13), noise-free, p = 9, r = 8";
  j["rows"] = json::array();
  out << "Akcay (2011) Table 1: singular values on noise-free data, p = 9, r = 8\n";
  out << "     M   sigma4(G9F8)  sigma5(G9F8)   sigma4(Y)    sigma8(Y)\n";
  for (const auto& r : rows) {
    json row = {{"M", r.M},
                {"sigma4", r.vo_sigmas(3)},
                {"sigma5", r.vo_sigmas(4)},
                {"vo_sigmas", std::vector<double>(r.vo_sigmas.data(), r.vo_sigmas.data() + r.vo_sigmas.size())},
                {"akcay_sigmas",
                 std::vector<double>(r.akcay_sigmas.data(), r.akcay_sigmas.data() + r.akcay_sigmas.size())}};
    j["rows"].push_back(row);
    char line[160];
    std::snprintf(line, sizeof line, "%6d   %11.4g   %11.3e   %9.4g   %11.4g\n", r.M, r.vo_sigmas(3), r.vo_sigmas(4),
                  r.akcay_sigmas(3), r.akcay_sigmas(7));
    out << line;
  }
  out << "sigma5 of Van Overschee's matrix collapses geometrically with M; the 2n = 8 singular values of Y do not.\n";
  emit_json(json_path, j);
  return 0;
}

int run_table2(const std::string& json_path, const fdsid::Table2Options& o) {
  Out out{json_path == "-"};
  const auto rows = fdsid::reproduce_table2(o);
  json j;
  j["source"] = "Akcay (2011) Table 2: mean measured L2 / Linf errors of Algorithm 1, p = r = 50, eps = 1e-3";
  j["realizations"] = o.realizations;
  j["seed"] = o.seed;
  j["noise"] = {
      {"model", "s_k = eps H(z_k) v_k on the M+1 given samples k = 1..M+1 (Eq. 7), extended with the data by step 1"},
      {"epsilon", o.epsilon},
      {"variance", fdsid::to_string(o.noise)},
      {"extension", fdsid::to_string(o.extension)}};
  j["rows"] = json::array();
  out << "Akcay (2011) Table 2: " << o.realizations << " realisations, noise " << fdsid::to_string(o.noise)
      << ", extension " << fdsid::to_string(o.extension) << "\n";
  out << "      M     mean L2       mean Linf    failures   vo1997 (eps=" << sci(o.vo_epsilon, 0)
      << "): failed (at step 6), mean L2 when it returned a model\n";
  for (const auto& r : rows) {
    j["rows"].push_back({{"M", r.M},
                         {"l2", r.l2},
                         {"linf", r.linf},
                         {"l2_sd", r.l2_sd},
                         {"linf_sd", r.linf_sd},
                         {"failures", r.failures},
                         {"vo1997_runs", r.vo_runs},
                         {"vo1997_failures", r.vo_failures},
                         {"vo1997_step6_failures", r.vo_split_failures},
                         {"vo1997_l2_when_returned", std::isnan(r.vo_l2) ? json(nullptr) : json(r.vo_l2)}});
    char line[160];
    std::snprintf(line, sizeof line, "%7d   %.3e   %.3e   %5d      %d/%d (%d)   %.3e\n", r.M, r.l2, r.linf, r.failures,
                  r.vo_failures, r.vo_runs, r.vo_split_failures, r.vo_l2);
    out << line;
  }
  emit_json(json_path, j);
  return 0;
}

int run_identify_spectrum(const std::string& json_path, const std::string& data_path, const std::string& order,
                          int p, int r, const std::string& method, const std::string& precision,
                          const std::string& extension) {
  Out out{json_path == "-"};
  if (precision != "double" && precision != "high")
    throw fdsid::Error(fdsid::ErrorKind::Input, "--precision", "\"" + precision + "\" is not double or high");
  fdsid::SpectrumOptions so;
  if (method == "akcay2011") so.method = fdsid::Method::Akcay2011;
  else if (method == "vo1997") so.method = fdsid::Method::VanOverschee1997;
  else throw fdsid::Error(fdsid::ErrorKind::Input, "--method", "\"" + method + "\" is not akcay2011 or vo1997");
  so.order = parse_order(order);
  if (p < 0 || r < 0) throw fdsid::Error(fdsid::ErrorKind::Input, p < 0 ? "--p" : "--r", "must be positive");
  so.p = p;
  so.r = r;
  so.extension = parse_extension(extension);
  if (precision == "high")
    return fdsid::cli::identify_spectrum_high(json_path, data_path, so.order, p, r,
                                              so.method == fdsid::Method::VanOverschee1997, so.extension);
  const fdsid::SpectrumData data = fdsid::read_spectrum_csv(data_path);
  fdsid::SpectrumResult res;
  try {
    res = fdsid::identify_spectrum(data, so);
  } catch (const fdsid::Error& e) {
    throw e.within(data_path);
  }
  json j = fdsid::result_to_json(res);
  j["data"] = data_path;
  out << "identified order " << res.order << " (" << (res.order_from_data ? "read at" : "given; gap at")
      << " sigma_" << res.gap_index << "/sigma_" << res.gap_index + 1 << " = " << sci(res.gap_ratio) << ") by "
      << fdsid::to_string(res.method) << " from M = " << data.M << ", m = " << data.m << ", p = " << res.p
      << ", r = " << res.r << "\n";
  out << "poles:";
  for (const auto& z : fdsid::poles(res.model)) out << "  " << z.real() << (z.imag() < 0 ? "" : "+") << z.imag() << "i";
  out << "\nRiccati: " << res.riccati_method << ", " << res.riccati_iterations << " iterations, residual "
      << sci(res.riccati_residual, 1) << "\n";
  emit_json(json_path, j);
  return 0;
}

int run_sample_spectrum(const std::string& model_path, int M, double epsilon, std::uint64_t seed,
                        const std::string& out_path) {
  // 10^7 samples make a ~600 MB CSV; beyond that the text file is no way to carry them.
  if (M < 1 || M > 10000000)
    throw fdsid::Error(fdsid::ErrorKind::Input, "--M", std::to_string(M) + " is outside 1 .. 10000000");
  if (!(std::isfinite(epsilon) && epsilon >= 0))
    throw fdsid::Error(fdsid::ErrorKind::Input, "--epsilon", "must be a finite number >= 0");
  const fdsid::StateSpace model = fdsid::read_model(model_path);
  if (model.order() > 0) {
    const double rho = fdsid::poles(model).cwiseAbs().maxCoeff();
    if (!(rho < 1.0))
      throw fdsid::Error(fdsid::ErrorKind::Input, model_path,
                         "A has a pole of modulus " + std::to_string(rho) +
                             " (not inside the unit circle): the power spectrum of an unstable model is not defined");
  }
  if (model.inputs() != model.outputs())
    throw fdsid::Error(fdsid::ErrorKind::Input, model_path, "a power spectrum needs a square model (as many inputs as outputs)");
  fdsid::SpectrumData d;
  d.m = model.outputs();
  d.M = M;
  d.S = fdsid::sample_spectrum(model, M);
  if (epsilon > 0) {
    if (d.m != 1) throw fdsid::Error(fdsid::ErrorKind::Input, "--epsilon", "the Section 4 noise model is scalar");
    d = fdsid::akcay_noisy_samples(d.S, M, epsilon, fdsid::NoiseVariance::UnitComplex, seed);
  }
  std::ostringstream s;
  fdsid::write_spectrum_csv(s, d);
  fdsid::write_text_file(out_path, s.str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fdsid: frequency-domain subspace identification (Akcay 2011, Pintelon 2002)"};
  app.require_subcommand(1);
  std::string json_path;

  auto* reproduce = app.add_subcommand("reproduce", "reproduce a table or figure of the papers");
  reproduce->require_subcommand(1);
  auto* t1 = reproduce->add_subcommand("table1", "Akcay (2011) Table 1");
  t1->add_option("--json", json_path, "write the JSON result here (- = stdout)");
  auto* t2 = reproduce->add_subcommand("table2", "Akcay (2011) Table 2 (Monte Carlo)");
  fdsid::Table2Options t2o;
  std::string t2_ext = "conjugate", t2_noise = "unit-complex";
  t2->add_option("--json", json_path, "write the JSON result here (- = stdout)");
  t2->add_option("--realizations", t2o.realizations, "noise realisations (paper: 100)")->check(CLI::Range(1, 1000000));
  t2->add_option("--seed", t2o.seed, "random seed");
  t2->add_option("--threads", t2o.threads, "worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  t2->add_option("--extension", t2_ext, "step 1 reading: conjugate (default: reproduces the paper) or hermitian-part");
  t2->add_option("--noise-variance", t2_noise, "unit-complex (E|v|^2 = 1, default) or unit-per-component (E|v|^2 = 2)");
  t2->add_option("--vo-epsilon", t2o.vo_epsilon, "noise level of the vo1997 runs (paper: 1e-9; 0 skips them)");
  t2->add_option("--M", t2o.Ms, "data lengths (default 1000 2000 4000 8000 16000 32000)");

  auto* ids = app.add_subcommand("identify-spectrum", "spectral factor from power-spectrum samples");
  std::string data_path, model_path, order = "auto", method = "akcay2011", precision = "double", extension = "hermitian-part";
  int p = 0, r = 0;
  ids->add_option("--data", data_path, "power-spectrum CSV")->required();
  ids->add_option("--json", json_path, "write the identified model here (- = stdout)");
  ids->add_option("--order", order, "model order n, or auto");
  ids->add_option("--p", p, "block rows of Y (default: min(50, M), at least 2n+1)");
  ids->add_option("--r", r, "block columns of Y (default: min(50, N - p), at least 2n)");
  ids->add_option("--method", method, "akcay2011 (default) or vo1997");
  ids->add_option("--precision", precision, "double (default) or high");
  ids->add_option("--extension", extension, "step 1 reading: hermitian-part (default) or conjugate");

  auto* chk = app.add_subcommand("check", "oracle: compare a candidate model with the high-precision reference");
  double tolerance = 0;
  chk->add_option("--model", model_path, "candidate model JSON")->required();
  chk->add_option("--data", data_path, "power-spectrum CSV the candidate was identified from")->required();
  chk->add_option("--json", json_path, "write the comparison here (- = stdout)");
  chk->add_option("--tolerance", tolerance, "relative tolerance (default: derived, see README)");

  auto* smp = app.add_subcommand("sample-spectrum", "sample a model's power spectrum on the uniform grid into CSV");
  std::string out_path = "-";
  int M = 0;
  double epsilon = 0;
  std::uint64_t seed = 1;
  smp->add_option("--model", model_path, "model JSON")->required();
  smp->add_option("--M", M, "grid: M+1 samples from 0 to pi")->required();
  smp->add_option("--epsilon", epsilon, "add Akcay (2011) Section 4 noise of this level");
  smp->add_option("--seed", seed, "random seed of the noise");
  smp->add_option("--out", out_path, "CSV output (- = stdout)");
  std::string smp_precision = "double";
  smp->add_option("--precision", smp_precision, "double (default) or high (50-digit reference, 40 digits written)");

  // CLI11 reports an unknown subcommand as "A subcommand is required"; name it.
  {
    const std::vector<std::string> top = {"reproduce", "identify-spectrum", "check", "sample-spectrum"};
    const std::vector<std::string> targets = {"table1", "table2"};
    auto unknown = [](const std::string& word, const std::vector<std::string>& known) {
      return !word.empty() && word[0] != '-' && std::find(known.begin(), known.end(), word) == known.end();
    };
    if (argc > 1 && unknown(argv[1], top)) {
      std::cerr << "fdsid: unknown subcommand \"" << argv[1] << "\" (run fdsid --help for the list)\n";
      return 2;
    }
    if (argc > 2 && std::string(argv[1]) == "reproduce" && unknown(argv[2], targets)) {
      std::cerr << "fdsid: reproduce: unknown target \"" << argv[2] << "\" (expected table1 or table2)\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "fdsid: " << e.what() << "\n";
    return 2;
  }

  try {
    for (const CLI::App* sub : {t1, t2, ids, chk})
      if (sub->parsed() && sub->count("--json") > 0 && json_path.empty())
        throw fdsid::Error(fdsid::ErrorKind::Input, "--json", "empty path (use - for stdout)");
    if (t1->parsed()) return run_table1(json_path);
    if (t2->parsed()) {
      t2o.extension = parse_extension(t2_ext);
      if (t2_noise == "unit-complex") t2o.noise = fdsid::NoiseVariance::UnitComplex;
      else if (t2_noise == "unit-per-component") t2o.noise = fdsid::NoiseVariance::UnitPerComponent;
      else throw fdsid::Error(fdsid::ErrorKind::Input, "--noise-variance", "\"" + t2_noise + "\" is not unit-complex or unit-per-component");
      return run_table2(json_path, t2o);
    }
    if (ids->parsed())
      return run_identify_spectrum(json_path, data_path, order, p, r, method, precision, extension);
    if (chk->parsed()) return fdsid::cli::check(json_path, model_path, data_path, tolerance);
    if (smp->parsed()) {
      if (smp_precision == "high") {
        if (epsilon != 0) throw fdsid::Error(fdsid::ErrorKind::Input, "--epsilon", "noise is only added in double precision");
        if (M < 1 || M > 100000) throw fdsid::Error(fdsid::ErrorKind::Input, "--M", "must be in 1 .. 100000 with --precision high");
        if (out_path == "-") throw fdsid::Error(fdsid::ErrorKind::Input, "--out", "--precision high writes to a file");
        return fdsid::cli::sample_spectrum_high(model_path, M, out_path);
      }
      if (smp_precision != "double")
        throw fdsid::Error(fdsid::ErrorKind::Input, "--precision", "\"" + smp_precision + "\" is not double or high");
      return run_sample_spectrum(model_path, M, epsilon, seed, out_path);
    }
  } catch (const fdsid::Error& e) {
    std::cerr << "fdsid: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "fdsid: internal error: " << e.what() << "\n";
    return 2;
  }
  return 2;
}
