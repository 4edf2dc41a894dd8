// fdsid sample-spectrum: a model's power spectrum on the uniform grid, as CSV.
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/workflow.hpp"
#include "high_precision.hpp"

namespace fdsid::cli {

namespace {

struct SampleSpectrumCommand {
  std::string model_path, out_path = "-", json_path;
  int M = 0;
  double epsilon = 0;
  std::uint64_t seed = 1;
  Precision precision = Precision::Double;
};

// The --json record of what was written (the contracts: every subcommand
// takes --json; review finding 28).
nlohmann::json summary(const SampleSpectrumCommand& c, int m) {
  nlohmann::json j = {{"model", c.model_path},
                      {"out", c.out_path},
                      {"M", c.M},
                      {"m", m},
                      {"samples", c.M + 1},
                      {"grid", "omega_k = pi (k-1)/M, k = 1 ... M+1 (rad/sample)"},
                      {"precision", c.precision == Precision::High ? "high (50 digits, 40 written)" : "double"}};
  if (c.epsilon > 0)
    j["noise"] = {{"model", "Akcay (2011) Section 4: s_k = eps H(z_k) v_k"}, {"epsilon", c.epsilon}, {"seed", c.seed}};
  return j;
}

int run_high(const SampleSpectrumCommand& c) {
  if (c.epsilon != 0) throw Error(ErrorKind::Input, "--epsilon", "noise is only added in double precision");
  if (c.M < 1 || c.M > 100000) throw Error(ErrorKind::Input, "--M", "must be in 1 .. 100000 with --precision high");
  if (c.out_path == "-") throw Error(ErrorKind::Input, "--out", "--precision high writes to a file");
  const int status = sample_spectrum_high(c.model_path, c.M, c.out_path);
  if (status == 0 && !c.json_path.empty()) emit_json(c.json_path, summary(c, read_model(c.model_path).outputs()));
  return status;
}

int run(const SampleSpectrumCommand& c) {
  refuse_overwrite(c.out_path, {c.model_path}, "--out");
  refuse_overwrite(c.json_path, {c.model_path, c.out_path}, "--json");
  if (c.json_path == "-" && c.out_path == "-")
    throw Error(ErrorKind::Input, "--json", "- (stdout) needs --out FILE: the CSV goes to stdout otherwise");
  if (c.precision == Precision::High) return run_high(c);
  // 10^7 samples make a ~600 MB CSV; beyond that the text file is no way to carry them.
  if (c.M < 1 || c.M > 10000000)
    throw Error(ErrorKind::Input, "--M", std::to_string(c.M) + " is outside 1 .. 10000000");
  if (!(std::isfinite(c.epsilon) && c.epsilon >= 0))
    throw Error(ErrorKind::Input, "--epsilon", "must be a finite number >= 0");
  const StateSpace model = read_model(c.model_path);
  require_spectrum_model(model, c.model_path);
  SpectrumData d;
  d.m = model.outputs();
  d.M = c.M;
  d.S = sample_spectrum(model, c.M);
  if (c.epsilon > 0) {
    if (d.m != 1) throw Error(ErrorKind::Input, "--epsilon", "the Section 4 noise model is scalar");
    d = akcay_noisy_samples(d.S, c.M, c.epsilon, NoiseVariance::UnitComplex, c.seed);
  }
  // Noise larger than the spectrum makes samples no power spectrum can have
  // (a user review: --epsilon 10 wrote them silently and identify-spectrum
  // then failed at step 6 without naming them).
  std::vector<std::string> warnings;
  if (c.epsilon > 0) {
    const long negative = (d.S.row(0).real().array() < 0).count();
    if (negative > 0)
      warnings.push_back(std::to_string(negative) + " of " + std::to_string(c.M + 1) +
                         " noisy samples have a negative real part (the noise at --epsilon " + fmt(c.epsilon, 3) +
                         " exceeds the spectrum there): no power spectrum has them, and identify-spectrum may find "
                         "no positive-real factor");
  }
  Out err{false, &std::cerr};  // stderr, unconditionally: the CSV may be on stdout
  print_warnings(err, warnings);
  std::ostringstream s;
  write_spectrum_csv(s, d);
  write_text_file(c.out_path, s.str());
  nlohmann::json j = summary(c, d.m);
  j["warnings"] = warnings;
  emit_json(c.json_path, j);
  return 0;
}

}  // namespace

void register_sample_spectrum(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<SampleSpectrumCommand>();
  auto* smp = app.add_subcommand("sample-spectrum", "sample a model's power spectrum on the uniform grid into CSV");
  smp->add_option("--model", c->model_path, "model JSON")->required();
  smp->add_option("--M", c->M, "grid: M+1 samples from 0 to pi")->required();
  smp->add_option("--epsilon", c->epsilon, "add Akcay (2011) Section 4 noise of this level (default 0: none)");
  smp->add_option("--seed", c->seed, "random seed of the noise")->capture_default_str();
  smp->add_option("--out", c->out_path, "CSV output (- = stdout, the default)")->check(output_path("--out"));
  add_json_option(smp, c->json_path, "write what was sampled here (- = stdout, with --out FILE)");
  smp->add_option("--precision", c->precision, "double (default) or high (50-digit reference, 40 digits written)")
      ->transform(choice(kPrecisions));
  on_parsed(smp, c, chosen, run);
}

}  // namespace fdsid::cli
