// fdsid check: the validation oracle (a candidate against the 50-digit reference).
#include <memory>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "high_precision.hpp"

namespace fdsid::cli {

namespace {

struct CheckCommand {
  std::string json_path;
  FrfCheckRequest frf;  // model_path, frf_path, data_path, meta_path, r, method, omega_scale, tolerance
};

int run(const CheckCommand& c) {
  const FrfCheckRequest& q = c.frf;
  refuse_overwrite(c.json_path, {q.model_path, q.data_path, q.frf_path, q.meta_path}, "--json");
  const bool pintelon = !q.frf_path.empty() || !q.meta_path.empty();
  if (!pintelon) {
    if (q.data_path.empty())
      throw Error(ErrorKind::Input, "check",
                  "give the data the candidate was identified from: --data SPECTRUM.csv (Akcay 2011), --frf FRF.csv "
                  "or --data RECORDS.csv --meta META.json (Pintelon 2002)");
    if (!q.selection.empty())
      throw Error(ErrorKind::Input, "--input/--output/--skip-periods", "apply to periodic records (--data with --meta)");
    require_frequency_units(q.units, Domain::Discrete, false);
    if (q.r > 0 || !q.method.empty() || q.omega_scale > 0)
      throw Error(ErrorKind::Input, q.r > 0 ? "--r" : !q.method.empty() ? "--method" : "--omega-scale",
                  "applies to FRF and record candidates (--frf, or --data with --meta); a spectral factor's p and "
                  "r come from its JSON");
    return check(c.json_path, q.model_path, q.data_path, q.tolerance);
  }
  return check_frf(c.json_path, q);
}

}  // namespace

void register_check(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<CheckCommand>();
  FrfCheckRequest& q = c->frf;
  auto* chk = app.add_subcommand("check", "oracle: compare a candidate model with the high-precision reference");
  chk->add_option("--model", q.model_path, "candidate model JSON")->required();
  auto* data = chk->add_option("--data", q.data_path,
                               "power-spectrum CSV the candidate was identified from, or periodic records (with --meta)");
  auto* frf = chk->add_option("--frf", q.frf_path, "FRF CSV the candidate was identified from (Pintelon 2002)");
  auto* meta = chk->add_option("--meta", q.meta_path, "meta JSON of the records given by --data");
  frf->excludes(data)->excludes(meta);
  meta->needs(data);
  add_json_option(chk, c->json_path, "write the comparison here (- = stdout)");
  add_record_selection_options(chk, q.selection);
  add_frequency_unit_options(chk, q.units);
  chk->add_option("--tolerance", q.tolerance, "relative tolerance (default: derived, see README)");
  chk->add_option("--r", q.r, "FRF/records: r of the candidate when its JSON has none (default: V_SUB selection)")
      ->check(CLI::Range(2, 100000));
  chk->add_option("--method", q.method,
                  "FRF/records: the basis when the JSON has none (continuous time: bilinear or orthogonal; discrete "
                  "time: monomial, bilinear or orthogonal)");
  chk->add_option("--omega-scale", q.omega_scale, "FRF/records, Algorithm 2's bases: omega_scale when the JSON has none")
      ->check(CLI::PositiveNumber);
  auto* eiv = chk->add_flag("--eiv", q.eiv, "records: the candidate was identified with --eiv (when its JSON has no source)");
  chk->add_flag("--eiv-model-variance", q.eiv_model_variance, "records: ... with --eiv --eiv-variance model")->needs(eiv);
  auto* improper = chk->add_flag("--improper", q.improper, "records: ... with --improper (the candidate is 1/G)");
  eiv->excludes(improper)->needs(meta);
  improper->needs(meta);
  chk->add_option("--min-input-snr", q.min_input_snr, "records, --eiv/--improper: the line rule's SNR (default 10)")
      ->check(CLI::PositiveNumber);
  on_parsed(chk, c, chosen, run);
}

}  // namespace fdsid::cli
