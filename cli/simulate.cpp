// fdsid simulate-records: a periodic multisine experiment on a model.
#include <algorithm>
#include <cmath>
#include <memory>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/io.hpp"
#include "fdsid/json.hpp"
#include "fdsid/model.hpp"
#include "fdsid/simulate.hpp"

namespace fdsid::cli {

namespace {

struct SimulateRecordsCommand {
  std::string model_path, out_path, meta_path, json_path;
  RecordOptions options;
};

int run(const SimulateRecordsCommand& c) {
  refuse_overwrite(c.out_path, {c.model_path}, "--out");
  refuse_overwrite(c.meta_path, {c.model_path}, "--meta-out");
  refuse_overwrite(c.json_path, {c.model_path, c.out_path, c.meta_path}, "--json");
  if (static_cast<long long>(c.options.period) * c.options.periods > 100000000LL)
    throw Error(ErrorKind::Input, "--period", "period x periods above 1e8 samples");
  if (c.out_path == c.meta_path) throw Error(ErrorKind::Input, "--meta-out", "must differ from --out");
  const ModelFile file = read_model_with_diagnostics(c.model_path);
  const StateSpace& model = file.model;
  RecordMeta meta;
  const Eigen::MatrixXd rec = simulate_periodic_record(model, c.options, meta);
  // Finite options can still overflow (a user review: --rms 1e300 was taken
  // and identify-frf then blamed the file's lines). The readers square the
  // samples (the periods' sample variances) and sum up to 1e8 of them, so
  // every sample must stay below 2^495: 2^990 x 1e8 (< 2^27) < 2^1024.
  const double largest = rec.allFinite() ? rec.cwiseAbs().maxCoeff() : INFINITY;
  if (!(largest < std::ldexp(1.0, 495)))
    throw Error(ErrorKind::Input, "--rms",
                "the simulated record reaches " + fmt(largest, 3) + " (input RMS " + fmt(c.options.rms, 3) +
                    ", output noise " + fmt(c.options.output_noise_std, 3) + ", input noise " +
                    fmt(c.options.input_noise_std, 3) +
                    ", times the model's gain), beyond 2^495 = 1e149 whose squares the periods' variances sum; "
                    "give smaller levels");
  // A resonance of the model outside the excited lines (review finding 29:
  // the default lines stop below P/4 and the Pintelon plant resonates at
  // 0.379 cycles/sample): the records will not determine it.
  std::string outside;
  if (!meta.excited_lines.empty()) {
    const auto [lo_line, hi_line] = std::minmax_element(meta.excited_lines.begin(), meta.excited_lines.end());
    const Eigen::VectorXd omega = line_frequencies(meta, Domain::Discrete);
    const double lo = omega.minCoeff(), hi = omega.maxCoeff();
    outside = out_of_band_warning(resonances_outside_band(poles(model), Domain::Discrete, lo, hi), Domain::Discrete,
                                  lo, hi,
                                  "the excited lines " + std::to_string(*lo_line) + " to " + std::to_string(*hi_line) +
                                      " of P = " + std::to_string(meta.period) + " (--lines" +
                                      (c.options.lines.empty() ? "; default: odd lines below P/4" : "") + ")");
  }
  const std::string& unusable = file.unusable;
  std::vector<std::string> warnings;  // the JSON's: the band's without "the model's"
  if (!unusable.empty()) warnings.push_back(unusable);
  if (!outside.empty()) warnings.push_back(outside);
  Out out{c.json_path == "-"};
  if (!unusable.empty()) out << "warning: " << unusable << "\n";
  if (!outside.empty()) out << "warning: the model's " << outside << "\n";
  write_text_file(c.out_path, records_csv(rec));
  write_text_file(c.meta_path, to_json(meta).dump(2) + "\n");
  // The --json record of the experiment (review finding 28).
  emit_json(c.json_path, {{"model", c.model_path},
                          {"out", c.out_path},
                          {"meta_out", c.meta_path},
                          {"meta", to_json(meta)},
                          {"rms", c.options.rms},
                          {"output_noise_std", c.options.output_noise_std},
                          {"input_noise_std", c.options.input_noise_std},
                          {"seed", c.options.seed},
                          {"samples", rec.rows()},
                          {"warnings", warnings}});
  return 0;
}

}  // namespace

void register_simulate_records(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<SimulateRecordsCommand>();
  RecordOptions& rec = c->options;
  auto* sim = app.add_subcommand("simulate-records", "periodic multisine experiment on a model: u,y CSV and meta JSON");
  sim->add_option("--model", c->model_path, "discrete SISO model JSON")->required();
  sim->add_option("--out", c->out_path, "records CSV (u,y)")->check(output_path("--out"))->required();
  sim->add_option("--meta-out", c->meta_path, "meta JSON")->check(output_path("--meta-out"))->required();
  add_json_option(sim, c->json_path, "write a record of the experiment here (- = stdout)");
  sim->add_option("--period", rec.period, "samples per period P")->check(CLI::Range(4, 1 << 24))->capture_default_str();
  sim->add_option("--periods", rec.periods, "periods M")->check(CLI::Range(1, 100000))->capture_default_str();
  sim->add_option("--lines", rec.lines,
                  "excited DFT lines, 1-based k = 1 ... P/2 at k/(P Ts) Hz (default: odd lines below P/4, i.e. up to "
                  "0.25 cycles/sample; a warning names a resonance of the model outside them)");
  sim->add_option("--rms", rec.rms, "input RMS")->check(finite_number(0, false))->capture_default_str();
  sim->add_option("--noise-std", rec.output_noise_std, "white output noise std")
      ->check(finite_number(0, true))
      ->capture_default_str();
  sim->add_option("--input-noise-std", rec.input_noise_std, "white input measurement noise std")
      ->check(finite_number(0, true))
      ->capture_default_str();
  sim->add_option("--seed", rec.seed, "random seed")->capture_default_str();
  on_parsed(sim, c, chosen, run);
}

}  // namespace fdsid::cli
