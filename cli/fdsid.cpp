// fdsid command-line tool: argument parsing and formatting only; every number
// comes from the fast/ library.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <filesystem>
#include <initializer_list>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "fdsid/error.hpp"
#include "fdsid/figures.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/gap.hpp"
#include "fdsid/gap_validate.hpp"
#include "fdsid/io.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/simulate.hpp"
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

// --plot FILE: draws the figure when a path was given.
void emit_plot(const std::string& path, const fdsid::plot::Figure& fig) {
  if (!path.empty()) fdsid::plot::render(fig, path);
}

// Progress of a long run on stderr, only when stderr is a terminal (quiet in
// pipes, logs and tests).
std::function<void(int, int)> terminal_progress(const std::string& what) {
  if (!isatty(fileno(stderr))) return {};
  return [what](int done, int total) {
    std::fprintf(stderr, "\r%s: %d/%d", what.c_str(), done, total);
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
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

// "Nothing lost": an output may not be one of the command's inputs (it would be
// replaced by the result, or half-written on a failure). Compared as files when
// both exist, else by their normalised paths.
void refuse_overwrite(const std::string& output, std::initializer_list<std::string> inputs, const char* option) {
  if (output.empty() || output == "-") return;
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string& in : inputs) {
    if (in.empty()) continue;
    const bool same = fs::exists(output, ec) && fs::exists(in, ec) ? fs::equivalent(output, in, ec)
                                                                   : fs::weakly_canonical(output, ec) ==
                                                                         fs::weakly_canonical(in, ec);
    if (same)
      throw fdsid::Error(fdsid::ErrorKind::Input, option,
                         "\"" + output + "\" is also an input of this command; refusing to overwrite it");
  }
}

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

int run_table1(const std::string& json_path, const std::string& plot_path) {
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
  emit_plot(plot_path, fdsid::plot::table1_figure(rows));
  return 0;
}

int run_table2(const std::string& json_path, const std::string& plot_path, fdsid::Table2Options o) {
  Out out{json_path == "-"};
  o.progress = terminal_progress("table2: realisations");
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
  emit_plot(plot_path, fdsid::plot::table2_figure(rows, o));
  return 0;
}

int run_identify_spectrum(const std::string& json_path, const std::string& plot_path, const std::string& data_path,
                          const std::string& order, int p, int r, const std::string& method,
                          const std::string& precision, const std::string& extension) {
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
  if (precision == "high" && !plot_path.empty())
    throw fdsid::Error(fdsid::ErrorKind::Input, "--plot", "is drawn from the double-precision result; not with --precision high");
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
  for (const std::string& w : res.warnings) out << "warning: " << w << "\n";
  emit_json(json_path, j);
  emit_plot(plot_path, fdsid::plot::spectrum_figure(data, res));
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

struct FrfCommand {
  std::string frf_path, data_path, meta_path, plot_path;
  std::string order = "auto", domain = "discrete", method = "bilinear", precision = "double";
  std::string eiv_variance = "data";
  int r = 0, r_max = 0;
  double omega_scale = 0, min_input_snr = 10;
  bool eiv = false, improper = false;
};

fdsid::Domain parse_domain(const std::string& s) {
  if (s == "discrete") return fdsid::Domain::Discrete;
  if (s == "continuous") return fdsid::Domain::Continuous;
  throw fdsid::Error(fdsid::ErrorKind::Input, "--domain", "\"" + s + "\" is neither discrete nor continuous");
}

void print_poles(Out& out, const Eigen::VectorXcd& poles) {
  out << "poles:";
  for (Eigen::Index i = 0; i < poles.size(); ++i)
    out << "  " << poles(i).real() << (poles(i).imag() < 0 ? "" : "+") << poles(i).imag() << "i";
  out << "\n";
}

int run_identify_frf(const std::string& json_path, const FrfCommand& c) {
  Out out{json_path == "-"};
  const bool from_frf = !c.frf_path.empty();
  if (from_frf == (!c.data_path.empty() || !c.meta_path.empty()))
    throw fdsid::Error(fdsid::ErrorKind::Input, "identify-frf", "give either --frf FILE or --data FILE --meta FILE");
  if (!from_frf && (c.data_path.empty() || c.meta_path.empty()))
    throw fdsid::Error(fdsid::ErrorKind::Input, c.data_path.empty() ? "--data" : "--meta",
                       "periodic records need both --data and --meta");
  if (c.precision != "double" && c.precision != "high")
    throw fdsid::Error(fdsid::ErrorKind::Input, "--precision", "\"" + c.precision + "\" is not double or high");
  if (c.method != "bilinear" && c.method != "orthogonal")
    throw fdsid::Error(fdsid::ErrorKind::Input, "--method", "\"" + c.method + "\" is not bilinear or orthogonal");
  if (c.r < 0 || c.r_max < 0) throw fdsid::Error(fdsid::ErrorKind::Input, "--r", "must be positive");
  if ((c.eiv || c.improper) && from_frf)
    throw fdsid::Error(fdsid::ErrorKind::Input, c.eiv ? "--eiv" : "--improper",
                       "needs periodic records (--data, --meta): the input noise is estimated over the periods");
  if (c.eiv && c.improper)
    throw fdsid::Error(fdsid::ErrorKind::Input, "--improper", "cannot be combined with --eiv (both use ratio data)");
  if (c.eiv_variance != "data" && c.eiv_variance != "model")
    throw fdsid::Error(fdsid::ErrorKind::Input, "--eiv-variance", "\"" + c.eiv_variance + "\" is not data or model");
  const fdsid::Domain domain = parse_domain(c.domain);
  fdsid::FrfOptions o;
  o.order = parse_order(c.order);
  o.r = c.r;
  o.r_max = c.r_max;
  o.continuous = c.method == "orthogonal" ? fdsid::ContinuousMethod::Orthogonal : fdsid::ContinuousMethod::Bilinear;
  o.omega_scale = c.omega_scale;
  const std::string where = from_frf ? c.frf_path : c.data_path;

  fdsid::FrfData data;
  json source;
  int periods = 0, dropped = 0;
  fdsid::SampleStatistics stats;
  {
    if (from_frf) {
      data = fdsid::read_frf_csv(c.frf_path, domain);
      source = {{"frf", c.frf_path}, {"variance", data.has_noise_model ? "G_var column (known)" : "none (unit weights)"}};
    } else {
      int inputs = 0;
      const Eigen::MatrixXd samples = fdsid::read_records_csv(c.data_path, inputs);
      const fdsid::RecordMeta meta = fdsid::read_meta(c.meta_path);
      periods = meta.periods;
      if (meta.periods < 4)
        throw fdsid::Error(fdsid::ErrorKind::Input, c.meta_path + " field \"periods\"",
                           "M = " + std::to_string(meta.periods) +
                               " periods: the sample-subspace estimates of B and D need M >= 4, those of A and C "
                               "M >= 2 (Pintelon 2002 Theorem 2)");
      try {
        stats = fdsid::record_statistics(samples, inputs, meta, domain);
      } catch (const fdsid::Error& e) {
        throw e.within(c.data_path + " with " + c.meta_path);
      }
      data = stats.data;
      source = {{"data", c.data_path}, {"meta", c.meta_path}, {"periods", meta.periods},
                {"variance", "sample variance over the periods / M (Pintelon 2002 Eq. 25)"}};
    }
  }
  if (c.precision == "high") {
    if (!c.plot_path.empty())
      throw fdsid::Error(fdsid::ErrorKind::Input, "--plot", "is drawn from the double-precision result; not with --precision high");
    if (c.eiv || c.improper)
      throw fdsid::Error(fdsid::ErrorKind::Input, "--precision", "high is not available with --eiv or --improper");
    fdsid::cli::FrfHighRequest q;
    q.frf_path = c.frf_path;
    q.data_path = c.data_path;
    q.meta_path = c.meta_path;
    q.continuous = domain == fdsid::Domain::Continuous;
    q.orthogonal = o.continuous == fdsid::ContinuousMethod::Orthogonal;
    q.omega_scale = c.omega_scale;
    q.order = o.order;
    q.r = o.r;
    std::string note;
    if (q.order == 0 || q.r == 0) {
      // The reference identifies for a given order and r; the automatic choices
      // (Section 5) are made once, in double precision, and reported.
      fdsid::FrfResult sel;
      try {
        sel = fdsid::identify_frf(data, o);
      } catch (const fdsid::Error& e) {
        throw e.within(where);
      }
      note = "order " + std::to_string(sel.order) + " and r " + std::to_string(sel.r) +
             " chosen by the double-precision selection (singular values / V_SUB, Pintelon 2002 Section 5)";
      q.order = sel.order;
      q.r = sel.r;
    }
    return fdsid::cli::identify_frf_high(json_path, q, note);
  }
  std::string method = domain == fdsid::Domain::Discrete ? "pintelon2002-alg1"
                                                         : std::string("pintelon2002-alg2-") + c.method;
  fdsid::FrfResult res;
  try {
    if (c.eiv) {
      // Section 5: Ĝ = Ŷ/Û with the corrected Eq. (31); with --eiv-variance
      // model, a second pass evaluates the variance at the first-pass model.
      data = fdsid::errors_in_variables(stats, nullptr, c.min_input_snr, &dropped);
      res = fdsid::identify_frf(data, o);
      if (c.eiv_variance == "model") {
        data = fdsid::errors_in_variables(stats, &res.model, c.min_input_snr, &dropped);
        fdsid::FrfOptions o2 = o;
        o2.order = res.order;
        o2.r = res.r;
        res = fdsid::identify_frf(data, o2);
      }
      source["errors_in_variables"] = {
          {"variance", c.eiv_variance == "model" ? "Eq. (31) at the first-pass model" : "Eq. (31), corrected (conj U)"},
          {"dropped_lines", dropped}, {"min_input_snr", c.min_input_snr}};
    } else if (c.improper) {
      data = fdsid::swap_input_output(stats, c.min_input_snr, &dropped);
      res = fdsid::identify_frf(data, o);
      source["improper"] = {{"represents", "inverse: the model maps output to input (1/G)"}, {"dropped_lines", dropped}};
    } else {
      res = fdsid::identify_frf(data, o);
    }
  } catch (const fdsid::Error& e) {
    throw e.within(where);
  }
  if (!from_frf && domain == fdsid::Domain::Discrete) res.model.sample_time = data.sample_time;
  json j = fdsid::frf_result_to_json(res, method);
  j["source"] = source;
  if (c.improper) j["represents"] = "inverse";
  out << "identified order " << res.order << (o.order == 0 ? " (read from the singular values)" : "") << " by "
      << method << " from F = " << data.frequencies() << " frequencies"
      << (periods > 0 ? ", M = " + std::to_string(periods) + " periods" : std::string()) << ", r = " << res.r
      << (o.r == 0 ? " (minimising V_SUB)" : "") << "\n";
  print_poles(out, res.poles);
  out << "V_SUB = " << sci(res.v_sub) << " (Eq. 35; about F when model and noise model are right, F (M-1)/(M-2) with sample variances)\n";
  if (c.improper) out << "the model is the inverse system 1/G (improper G, Pintelon 2002 Section 5)\n";
  for (const std::string& w : res.warnings) out << "warning: " << w << "\n";
  emit_json(json_path, j);
  emit_plot(c.plot_path, fdsid::plot::frf_figure(data, res));
  return 0;
}

int run_simulate_records(const std::string& model_path, fdsid::RecordOptions o, const std::string& out_path,
                         const std::string& meta_path) {
  if (out_path == meta_path) throw fdsid::Error(fdsid::ErrorKind::Input, "--meta-out", "must differ from --out");
  const fdsid::StateSpace model = fdsid::read_model(model_path);
  fdsid::RecordMeta meta;
  const Eigen::MatrixXd rec = fdsid::simulate_periodic_record(model, o, meta);
  fdsid::write_text_file(out_path, fdsid::records_csv(rec));
  fdsid::write_text_file(meta_path, fdsid::meta_to_json(meta).dump(2) + "\n");
  return 0;
}

int run_figure(const std::string& json_path, const std::string& plot_path, int figure, fdsid::FigureOptions o) {
  Out out{json_path == "-"};
  if (o.order == 0) o.order = figure == 1 ? 4 : 1;
  o.progress = terminal_progress(std::string("fig") + std::to_string(figure) + ": runs");
  const fdsid::FigureResult res = fdsid::reproduce_pintelon_figure(o);
  const int F = static_cast<int>(res.frequency.size());
  auto vec = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
  json j = {{"figure", figure},
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
            {"std_known_alpha", vec(res.std_known_alpha)}};
  std::vector<double> r(res.ratio.data(), res.ratio.data() + F);
  std::sort(r.begin(), r.end());
  out << "Pintelon (2002) Fig. " << figure << "b: std(G(theta_S)) / std(G(theta)), n_a = " << o.order << ", M = " << o.M
      << ", F = " << o.F << ", r = " << o.r << ", |U| = " << o.input_level << ", " << res.runs << " runs ("
      << res.failures << " failed)\n";
  out << "ratio across frequency: min " << r.front() << ", median " << res.median_ratio << ", max " << r.back()
      << "; bound sqrt((M-2)/(M-3)) = " << res.bound << "\n";
  // Monte Carlo error of one ratio of standard deviations: each sample std
  // has relative sd ≈ 1/sqrt(2 N_r); their ratio at most sqrt(2) times that.
  out << "Monte Carlo standard error of one ratio <= " << std::sqrt(2.0) / std::sqrt(2.0 * res.runs) << "\n";
  emit_json(json_path, j);
  emit_plot(plot_path, fdsid::plot::std_ratio_figure(res, figure, o));
  return 0;
}

}  // namespace

std::string band_text(const std::array<double, 2>& b) {
  return "[" + sci(b[0], 4) + ", " + sci(b[1], 4) + "]";
}

// Plot-ready table next to the JSON: frequency, t(k) before and after, flag.
void write_gap_table(const std::string& path, const fdsid::GapReport& r) {
  std::ostringstream csv;
  csv << "frequency_hz,t_before,t_after,flagged\n";
  char buf[128];
  for (Eigen::Index i = 0; i < r.frequency.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g,%d\n", r.frequency(i), r.t_before(i), r.t_after(i),
                  static_cast<int>(r.flagged[i]));
    csv << buf;
  }
  fdsid::write_text_file(path, csv.str());
}

int run_gap(const std::string& json_path, const std::string& plot_path, const std::string& model_path,
            const std::string& data_path, const std::string& meta_path, const std::string& table_path,
            const fdsid::GapOptions& o) {
  Out out{json_path == "-"};
  const fdsid::StateSpace model = fdsid::read_model(model_path);
  int inputs = 0;
  const Eigen::MatrixXd rec = fdsid::read_records_csv(data_path, inputs);
  const fdsid::RecordMeta meta = fdsid::read_meta(meta_path);
  fdsid::GapReport r;
  try {
    r = fdsid::diagnose_gap(model, rec, inputs, meta, o);
  } catch (const fdsid::Error& e) {
    throw e.within(data_path);
  }
  out << "gap before " << sci(r.gap_before) << " (1 = the model is right up to the noise; " << r.excited
      << " excited lines, M = " << meta.periods << "), after " << sci(r.gap_after) << "\n";
  out << "verdict: ";
  if (r.present.empty()) out << "no significant gap (noise alone at level " << o.alpha << ")\n";
  for (size_t i = 0; i < r.present.size(); ++i) out << (i ? ", " : "") << fdsid::to_string(r.present[i]);
  if (!r.present.empty()) out << "\n";
  out << "tests: p(gap) " << sci(r.p_gap) << ", p(nonlinearity, " << r.unexcited << " unexcited lines) "
      << sci(r.p_nonlinearity) << ", p(leakage) " << sci(r.p_leakage) << "\n";
  if (!r.bands.empty()) {
    out << "bands (Hz):";
    for (const auto& b : r.bands) out << " " << band_text(b);
    out << "\n";
  }
  out << "candidates (each alone):\n";
  for (const fdsid::EffectFit& f : r.candidates) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "  %-16s gap_after %-10.4g shrink %-8.3f p %-9.2e", fdsid::to_string(f.effect()), f.gap_after,
                  f.shrink, f.p_value);
    out << buf;
    for (const auto& kv : fdsid::parameter_list(f.parameters)) out << " " << kv.first << "=" << sci(kv.second, 4);
    out << "\n";
  }
  for (const std::string& n : r.notes) out << "note: " << n << "\n";
  if (!table_path.empty()) write_gap_table(table_path, r);
  emit_json(json_path, fdsid::gap_report_to_json(r));
  emit_plot(plot_path, fdsid::plot::gap_figure(r, meta.periods));
  return 0;
}

int run_gap_validate(const std::string& json_path, fdsid::GapValidationOptions o) {
  Out out{json_path == "-"};
  o.progress = terminal_progress("gap-validate: cases");
  const fdsid::GapValidation v = fdsid::validate_gap(o);
  const json j = fdsid::gap_validation_to_json(v);
  out << "gap-validate: " << v.cases << " blind cases (P = " << o.period << ", M = " << o.periods
      << ", seed " << o.seed << "), exact verdicts " << sci(v.accuracy, 3) << "\n";
  for (const auto& c : v.by_category)
    out << "  " << c.first << ": " << c.second[0] << "/" << c.second[1] << " correct\n";
  out << "  clear single effects " << j["clear_single_rate"].get<double>() << " (target >= 0.95), subtle or paired "
      << j["subtle_or_pair_rate"].get<double>() << " (>= 0.80), false alarms " << v.false_alarm_rate
      << " (<= 0.05), band hits " << v.band_hit_rate << "\n";
  out << "  gap_after on correct verdicts: median " << j["gap_after_correct"]["median"].dump() << ", p90 "
      << j["gap_after_correct"]["p90"].dump() << ", max " << j["gap_after_correct"]["max"].dump()
      << ", share <= 2: " << j["gap_after_correct"]["share_at_most_2"].dump() << "\n";
  out << "confusion (truth -> verdict: count):\n";
  for (const auto& t : v.confusion)
    for (const auto& p : t.second)
      if (p.first != t.first) out << "  " << t.first << " -> " << p.first << ": " << p.second << "\n";
  emit_json(json_path, j);
  const bool met = fdsid::gap_validation_targets_met(v);
  out << (met ? "targets met\n" : "targets NOT met\n");
  return met ? 0 : 1;
}

int main(int argc, char** argv) {
  CLI::App app{"fdsid: frequency-domain subspace identification (Akcay 2011, Pintelon 2002)"};
  app.require_subcommand(1);
  std::string json_path, plot_path;
  const char* plot_help = "draw the figure into this file (.svg or .png)";

  auto* reproduce = app.add_subcommand("reproduce", "reproduce a table or figure of the papers");
  reproduce->require_subcommand(1);
  auto* t1 = reproduce->add_subcommand("table1", "Akcay (2011) Table 1");
  t1->add_option("--json", json_path, "write the JSON result here (- = stdout)");
  t1->add_option("--plot", plot_path, plot_help);
  auto* t2 = reproduce->add_subcommand("table2", "Akcay (2011) Table 2 (Monte Carlo)");
  fdsid::Table2Options t2o;
  std::string t2_ext = "conjugate", t2_noise = "unit-complex";
  t2->add_option("--json", json_path, "write the JSON result here (- = stdout)");
  t2->add_option("--plot", plot_path, plot_help);
  t2->add_option("--realizations", t2o.realizations, "noise realisations (paper: 100)")->check(CLI::Range(1, 1000000));
  t2->add_option("--seed", t2o.seed, "random seed");
  t2->add_option("--threads", t2o.threads, "worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  t2->add_option("--extension", t2_ext, "step 1 reading: conjugate (default: reproduces the paper) or hermitian-part");
  t2->add_option("--noise-variance", t2_noise, "unit-complex (E|v|^2 = 1, default) or unit-per-component (E|v|^2 = 2)");
  t2->add_option("--vo-epsilon", t2o.vo_epsilon, "noise level of the vo1997 runs (paper: 1e-9; 0 skips them)");
  t2->add_option("--M", t2o.Ms, "data lengths (default 1000 2000 4000 8000 16000 32000)")->check(CLI::Range(1, 10000000));

  fdsid::FigureOptions figo;
  CLI::App* figs[2];
  for (int f = 0; f < 2; ++f) {
    figs[f] = reproduce->add_subcommand(f == 0 ? "fig1" : "fig2",
                                        f == 0 ? "Pintelon (2002) Fig. 1: sample-subspace std ratio, no model errors"
                                               : "Pintelon (2002) Fig. 2: std ratio with model errors (n_a = 1)");
    figs[f]->add_option("--json", json_path, "write the JSON result here (- = stdout)");
    figs[f]->add_option("--plot", plot_path, plot_help);
    figs[f]->add_option("--runs", figo.runs, "Monte Carlo runs N_r (paper: 10000)")->check(CLI::Range(2, 10000000));
    figs[f]->add_option("--seed", figo.seed, "random seed");
    figs[f]->add_option("--threads", figo.threads, "worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
    figs[f]->add_option("--input-level", figo.input_level,
                        "|U(k)| (default 1; sqrt(2000)/2 = 22.36 is a unit sine under Eq. 4's DFT scaling)");
    figs[f]->add_option("--M", figo.M, "experiments per run (paper: 7)")->check(CLI::Range(4, 10000));
    figs[f]->add_option("--r", figo.r, "r of Algorithm 1 (paper: 8)")->check(CLI::Range(2, 200));
    figs[f]->add_option("--F", figo.F, "frequencies k/2000, k = 1..F (paper: 999)")->check(CLI::Range(2, 999));
  }
  figo.order = 0;

  auto* idf = app.add_subcommand("identify-frf", "subspace identification from FRF samples or periodic records (Pintelon 2002)");
  FrfCommand frf;
  idf->add_option("--frf", frf.frf_path, "FRF CSV: omega,G_re,G_im[,G_var]");
  idf->add_option("--data", frf.data_path, "periodic input/output records CSV: u,y (or u1,...,y1,...)");
  idf->add_option("--meta", frf.meta_path, "meta JSON of the records: period, periods, sample_time, excited_lines");
  idf->add_option("--json", json_path, "write the identified model here (- = stdout)");
  idf->add_option("--plot", frf.plot_path, plot_help);
  idf->add_option("--order", frf.order, "model order n_a, or auto (from the singular values of step 1c)");
  idf->add_option("--r", frf.r, "r > n_a (default: minimise V_SUB, Eq. 35, over [1.5 n_a, 6 n_a])");
  idf->add_option("--r-max", frf.r_max, "upper end of the r search (default 6 n_a)");
  idf->add_option("--domain", frf.domain, "discrete (omega in rad/sample, default) or continuous (rad/s)");
  idf->add_option("--method", frf.method, "continuous time: bilinear (Algorithm 2.1, default) or orthogonal (2.2)");
  idf->add_option("--omega-scale", frf.omega_scale, "frequency scaling of Algorithm 2 (default sqrt(w_min w_max))");
  idf->add_option("--precision", frf.precision, "double (default) or high");
  idf->add_flag("--eiv", frf.eiv, "noisy input: identify from G = Y/U with the variance of Eq. (31) (Section 5)");
  idf->add_option("--eiv-variance", frf.eiv_variance,
                  "data (Eq. 31 from the noisy ratio) or model (re-evaluated at a first-pass model: consistent)");
  idf->add_flag("--improper", frf.improper, "improper G: identify 1/G by swapping input and output (Section 5)");
  idf->add_option("--min-input-snr", frf.min_input_snr, "drop lines whose input SNR is below this (default 10)");

  auto* sim = app.add_subcommand("simulate-records", "periodic multisine experiment on a model: u,y CSV and meta JSON");
  fdsid::RecordOptions rec;
  std::string rec_out, rec_meta, rec_model;
  sim->add_option("--model", rec_model, "discrete SISO model JSON")->required();
  sim->add_option("--out", rec_out, "records CSV (u,y)")->required();
  sim->add_option("--meta-out", rec_meta, "meta JSON")->required();
  sim->add_option("--period", rec.period, "samples per period")->check(CLI::Range(4, 1 << 24));
  sim->add_option("--periods", rec.periods, "periods M")->check(CLI::Range(1, 100000));
  sim->add_option("--lines", rec.lines, "excited DFT lines (default: odd lines below P/4)");
  sim->add_option("--rms", rec.rms, "input RMS (default 1)");
  sim->add_option("--noise-std", rec.output_noise_std, "white output noise std (default 0)");
  sim->add_option("--input-noise-std", rec.input_noise_std, "white input measurement noise std (default 0)");
  sim->add_option("--seed", rec.seed, "random seed");

  auto* ids = app.add_subcommand("identify-spectrum", "spectral factor from power-spectrum samples");
  std::string data_path, model_path, order = "auto", method = "akcay2011", precision = "double", extension = "hermitian-part";
  int p = 0, r = 0;
  ids->add_option("--data", data_path, "power-spectrum CSV")->required();
  ids->add_option("--json", json_path, "write the identified model here (- = stdout)");
  ids->add_option("--plot", plot_path, plot_help);
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

  auto* gap = app.add_subcommand("gap", "sim-to-real gap: where a model and a periodic measurement disagree, and why");
  std::string gap_data, gap_meta, gap_table;
  fdsid::GapOptions gapo;
  gap->add_option("--model", model_path, "simulation model JSON (SISO)")->required();
  gap->add_option("--data", gap_data, "periodic records CSV (u,y), M whole periods")->required();
  gap->add_option("--meta", gap_meta, "meta JSON: period, periods, sample_time, excited_lines")->required();
  gap->add_option("--json", json_path, "write the report here (- = stdout)");
  gap->add_option("--plot", plot_path, plot_help);
  gap->add_option("--table", gap_table, "write the plot-ready table (frequency, t before/after, flag) here");
  gap->add_option("--alpha", gapo.alpha, "level of each detection test (default 0.01)");
  gap->add_option("--effect-alpha", gapo.effect_alpha, "level of the F-test admitting an effect (default 1e-3)");
  gap->add_option("--fdr", gapo.fdr, "false-discovery rate of the bands (default 0.05)");

  auto* gval = app.add_subcommand("gap-validate", "blind validation of gap on generated cases (effects withheld)");
  fdsid::GapValidationOptions gvo;
  gval->add_option("--cases", gvo.cases, "number of cases (default 100)")->check(CLI::Range(1, 100000));
  gval->add_option("--seed", gvo.seed, "random seed");
  gval->add_option("--period", gvo.period, "samples per period P (default 1024)")->check(CLI::Range(32, 1 << 20));
  gval->add_option("--periods", gvo.periods, "periods M (default 8)")->check(CLI::Range(4, 1000));
  gval->add_option("--threads", gvo.threads, "worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  gval->add_option("--workdir", gvo.workdir, "write the cases' files here (default: a temporary directory)");
  gval->add_flag("--keep-files", gvo.keep_files, "keep each case's model.json, data.csv, meta.json");
  gval->add_option("--json", json_path, "write the scores here (- = stdout)");

  // CLI11 reports an unknown subcommand as "A subcommand is required"; name it.
  {
    const std::vector<std::string> top = {"reproduce", "identify-spectrum", "identify-frf", "check",
                                          "sample-spectrum", "simulate-records", "gap", "gap-validate"};
    const std::vector<std::string> targets = {"table1", "table2", "fig1", "fig2"};
    auto unknown = [](const std::string& word, const std::vector<std::string>& known) {
      return !word.empty() && word[0] != '-' && std::find(known.begin(), known.end(), word) == known.end();
    };
    if (argc > 1 && unknown(argv[1], top)) {
      std::cerr << "fdsid: unknown subcommand \"" << argv[1] << "\" (run fdsid --help for the list)\n";
      return 2;
    }
    if (argc > 2 && std::string(argv[1]) == "reproduce" && unknown(argv[2], targets)) {
      std::cerr << "fdsid: reproduce: unknown target \"" << argv[2] << "\" (expected table1, table2, fig1 or fig2)\n";
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
    for (const CLI::App* sub : {t1, t2, ids, chk, idf, figs[0], figs[1], gap, gval})
      if (sub->parsed() && sub->count("--json") > 0 && json_path.empty())
        throw fdsid::Error(fdsid::ErrorKind::Input, "--json", "empty path (use - for stdout)");
    if (idf->parsed()) plot_path = frf.plot_path;
    for (const CLI::App* sub : {t1, t2, ids, idf, figs[0], figs[1], gap})
      if (sub->parsed() && sub->count("--plot") > 0) {
        fdsid::plot::check_plot_path(plot_path);
        refuse_overwrite(plot_path, {data_path, model_path, frf.frf_path, frf.data_path, frf.meta_path, gap_data, gap_meta, json_path}, "--plot");
      }
    if (ids->parsed()) refuse_overwrite(json_path, {data_path}, "--json");
    if (chk->parsed()) refuse_overwrite(json_path, {model_path, data_path}, "--json");
    if (idf->parsed()) refuse_overwrite(json_path, {frf.frf_path, frf.data_path, frf.meta_path}, "--json");
    if (smp->parsed()) refuse_overwrite(out_path, {model_path}, "--out");
    if (gval->parsed()) {
      if (static_cast<long long>(gvo.period) * gvo.periods > 10000000LL)
        throw fdsid::Error(fdsid::ErrorKind::Input, "--period", "period x periods above 1e7 samples");
      return run_gap_validate(json_path, gvo);
    }
    if (gap->parsed()) {
      refuse_overwrite(json_path, {model_path, gap_data, gap_meta}, "--json");
      refuse_overwrite(gap_table, {model_path, gap_data, gap_meta, json_path}, "--table");
      return run_gap(json_path, plot_path, model_path, gap_data, gap_meta, gap_table, gapo);
    }
    if (sim->parsed()) {
      refuse_overwrite(rec_out, {rec_model}, "--out");
      refuse_overwrite(rec_meta, {rec_model}, "--meta-out");
    }
    if (t1->parsed()) return run_table1(json_path, plot_path);
    if (figs[0]->parsed()) return run_figure(json_path, plot_path, 1, figo);
    if (figs[1]->parsed()) return run_figure(json_path, plot_path, 2, figo);
    if (idf->parsed()) return run_identify_frf(json_path, frf);
    if (sim->parsed()) {
      if (static_cast<long long>(rec.period) * rec.periods > 100000000LL)
        throw fdsid::Error(fdsid::ErrorKind::Input, "--period", "period x periods above 1e8 samples");
      return run_simulate_records(rec_model, rec, rec_out, rec_meta);
    }
    if (t2->parsed()) {
      t2o.extension = parse_extension(t2_ext);
      if (t2_noise == "unit-complex") t2o.noise = fdsid::NoiseVariance::UnitComplex;
      else if (t2_noise == "unit-per-component") t2o.noise = fdsid::NoiseVariance::UnitPerComponent;
      else throw fdsid::Error(fdsid::ErrorKind::Input, "--noise-variance", "\"" + t2_noise + "\" is not unit-complex or unit-per-component");
      return run_table2(json_path, plot_path, t2o);
    }
    if (ids->parsed())
      return run_identify_spectrum(json_path, plot_path, data_path, order, p, r, method, precision, extension);
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
