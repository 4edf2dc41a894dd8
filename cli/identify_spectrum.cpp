// fdsid identify-spectrum: minimum-phase spectral factor from power-spectrum
// samples (Akcay 2011 Algorithm 1, or Van Overschee 1997).
#include <memory>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "fdsid/figures.hpp"
#include "fdsid/io.hpp"
#include "fdsid/json.hpp"
#include "fdsid/refine.hpp"
#include "fdsid/spectrum_id.hpp"
#include "high_precision.hpp"

namespace fdsid::cli {

namespace {

struct IdentifySpectrumCommand {
  std::string data_path, json_path, plot_path;
  SpectrumOptions options;  // order 0 = auto, p and r 0 = default_pr
  Precision precision = Precision::Double;
  bool strict = false;
  bool refine = false;  ///< --refine: weighted NLS of the factor from Algorithm 1's estimate (issue 15)
  int max_iterations = 0;  ///< --max-iterations of --refine (0: not given, refine_spectrum's default)
};

nlohmann::json refinement_json(const SpectrumRefineResult& r, const SpectrumResult& start) {
  nlohmann::json j = {{"method", "weighted nonlinear least squares of the factor on the Hermitian part of the samples "
                                 "(Levenberg-Marquardt, real modal form, poles kept stable), then minimum phase by step 9"},
                      {"weights", r.weighted ? "1 / S_var (the data's noise variance)" : "unit (no S_var column)"},
                      {"cost_start", r.cost_start},
                      {"cost", r.cost},
                      {"terms", r.terms},
                      {"parameters", r.parameters},
                      {"iterations", r.iterations},
                      {"max_iterations", r.max_iterations},
                      {"termination", r.termination},
                      {"at_stability_bound", r.at_stability_bound},
                      {"max_zero_modulus", r.max_zero_modulus},
                      {"warnings", r.warnings}};
  nlohmann::json a = model_to_json(start.model);
  a["poles"] = poles_to_json(start.model);
  j["algorithm1_model"] = a;
  return j;
}

int run(const IdentifySpectrumCommand& c) {
  if (c.precision == Precision::High && c.refine)
    throw Error(ErrorKind::Input, "--refine", "refines the double-precision estimate; not with --precision high");
  require_refinement_for_limit(c.max_iterations, c.refine, "--refine");
  if (c.precision == Precision::High && !c.plot_path.empty())
    throw Error(ErrorKind::Input, "--plot", "is drawn from the double-precision result; not with --precision high");
  refuse_overwrite(c.plot_path, {c.data_path, c.json_path}, "--plot");
  refuse_overwrite(c.json_path, {c.data_path}, "--json");
  const SpectrumOptions& so = c.options;
  if (c.precision == Precision::High)
    return identify_spectrum_high(c.json_path, c.data_path, so.order, so.p, so.r,
                                  so.method == Method::VanOverschee1997, so.extension);
  Out out{c.json_path == "-"};
  const SpectrumData data = read_spectrum_csv(c.data_path);
  SpectrumResult res;
  try {
    res = identify_spectrum(data, so);
  } catch (const Error& e) {
    throw e.within(c.data_path);
  }
  out << "identified order " << res.order << " (" << (res.order_from_data ? "read at" : "given; gap at")
      << " sigma_" << res.gap_index << "/sigma_" << res.gap_index + 1 << " = " << sci(res.gap_ratio) << ") by "
      << to_string(res.method) << " from M = " << data.M << ", m = " << data.m << ", p = " << res.p
      << ", r = " << res.r << "\n";
  print_poles(out, poles(res.model));
  out << "Riccati: " << res.riccati_method << ", " << res.riccati_iterations << " iterations, residual "
      << sci(res.riccati_residual, 1) << "\n";
  print_warnings(out, res.warnings);
  if (refused_as_unusable(c.strict, res.error_estimate)) return 1;
  if (!c.refine) {
    emit_json(c.json_path, to_json(res, c.data_path));
    emit_plot(c.plot_path, [&] { return plot::spectrum_figure(data, res); });
    return 0;
  }
  SpectrumRefineResult refined;
  try {
    refined = c.max_iterations > 0 ? refine_spectrum(data, res.model, c.max_iterations) : refine_spectrum(data, res.model);
  } catch (const Error& e) {
    throw e.within(c.data_path);
  }
  out << "refined (" << (refined.weighted ? "weights 1/S_var" : "unit weights") << "): V " << sci(refined.cost_start)
      << " -> " << sci(refined.cost) << " over " << refined.terms << " terms, " << refined.iterations << " iterations ("
      << refined.termination << "), largest |zero| " << fmt(refined.max_zero_modulus, 6) << "\n";
  print_poles(out, poles(refined.model));
  print_warnings(out, refined.warnings);
  SpectrumResult shown = res;  // the written model is the refined factor; Algorithm 1's goes under "refinement"
  shown.model = refined.model;
  shown.summands = spectral_summands(refined.model);
  shown.max_zero_modulus = refined.max_zero_modulus;
  nlohmann::json j = to_json(shown, c.data_path);
  j["refinement"] = refinement_json(refined, res);
  emit_json(c.json_path, j);
  emit_plot(c.plot_path, [&] { return plot::spectrum_figure(data, shown); });
  return 0;
}

}  // namespace

void register_identify_spectrum(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<IdentifySpectrumCommand>();
  SpectrumOptions& o = c->options;
  o.method = Method::Akcay2011;
  o.extension = Extension::HermitianPart;
  auto* ids = app.add_subcommand("identify-spectrum", "spectral factor from power-spectrum samples");
  ids->add_option("--data", c->data_path, "power-spectrum CSV")->required();
  add_json_option(ids, c->json_path, "write the identified model here (- = stdout)");
  add_plot_option(ids, c->plot_path);
  add_strict_option(ids, c->strict);
  ids->add_option("--order", o.order, "model order n, or auto (the default: from the singular values)")->transform(order_value());
  ids->add_option("--p", o.p, "block rows of Y (default: min(50, M), at least 2n+1)")->check(count_at_least(1));
  ids->add_option("--r", o.r, "block columns of Y (default: min(50, N - p), at least 2n)")->check(count_at_least(1));
  ids->add_option("--method", o.method, "akcay2011 (default) or vo1997")
      ->transform(choice(method_names()));
  ids->add_option("--precision", c->precision, "double (default) or high")
      ->transform(choice(kPrecisions));
  ids->add_option("--extension", o.extension, "step 1 reading: hermitian-part (default) or conjugate")
      ->transform(choice(extension_names()));
  ids->add_flag("--refine", c->refine,
                "refine Algorithm 1's factor by weighted nonlinear least squares on the samples (weights 1/S_var when "
                "the CSV has an S_var column, else unit), kept stable and minimum phase");
  add_max_iterations_option(ids, c->max_iterations, "--refine");
  on_parsed(ids, c, chosen, run);
}

}  // namespace fdsid::cli
