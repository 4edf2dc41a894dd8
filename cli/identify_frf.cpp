// fdsid identify-frf: frequency-domain subspace identification from FRF
// samples or periodic input/output records (Pintelon 2002).
#include <algorithm>
#include <limits>
#include <memory>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "fdsid/figures.hpp"
#include "fdsid/io.hpp"
#include "fdsid/json.hpp"
#include "fdsid/refine.hpp"
#include "fdsid/workflow.hpp"
#include "high_precision.hpp"

namespace fdsid::cli {

namespace {

struct IdentifyFrfCommand {
  std::string frf_path, data_path, meta_path, json_path, plot_path;
  FrfOptions options;  // order 0 = auto, r 0 = minimise V_SUB
  Domain domain = Domain::Discrete;
  std::string method;  ///< --method; empty: the domain's default (set_frf_method)
  Precision precision = Precision::Double;
  EivVariance eiv_variance = EivVariance::Data;
  double min_input_snr = 10;
  bool min_input_snr_given = false;  ///< --min-input-snr applies to --eiv and --improper only
  bool eiv = false, improper = false, strict = false;
  bool refine = false;          ///< --refine ml: maximum-likelihood refinement of the subspace estimate (issue 15)
  bool allow_unstable = false;  ///< keep unstable poles (else reflected into the stable region)
  int max_iterations = 0;       ///< --max-iterations of --refine ml (0: not given, RefineOptions' default)
  int frf_periods = 0;          ///< --frf-periods M: the FRF file's G_var is a sample variance over M periods
  RecordSelection selection;
  FrequencyUnits units;  ///< --frequency-unit, --sample-time (FRF files)
  std::vector<double> noise_std;  ///< --noise-std: known output noise (records), else the sample variance
};

// The lines of `stats` at the frequencies of `kept` (the errors-in-variables
// treatment drops lines of low input SNR, Eq. 34; the refinement and its
// uncertainty bands use the same lines as the subspace estimate).
SampleStatistics lines_of(const SampleStatistics& stats, const Eigen::VectorXd& kept) {
  SampleStatistics s = stats;
  s.data.U.clear();
  s.data.Y.clear();
  s.data.variance.clear();
  s.var_U.clear();
  s.cov_YU.clear();
  std::vector<double> omega;
  for (int k = 0, j = 0; k < stats.data.frequencies() && j < kept.size(); ++k)
    if (stats.data.omega(k) == kept(j)) {
      omega.push_back(kept(j++));
      s.data.U.push_back(stats.data.U[k]);
      s.data.Y.push_back(stats.data.Y[k]);
      s.data.variance.push_back(stats.data.variance[k]);
      s.var_U.push_back(stats.var_U[k]);
      s.cov_YU.push_back(stats.cov_YU[k]);
    }
  s.data.omega = Eigen::Map<const Eigen::VectorXd>(omega.data(), static_cast<Eigen::Index>(omega.size()));
  return s;
}

// The noise model the data's variances stand for (RefineNoise); --eiv: the
// sample variances of input and output and their covariance (Section 5's
// errors-in-variables noise), on the lines the subspace estimate used.
RefineOptions refine_options(const IdentifyFrfCommand& c, const FrfData& data, const FrfSource& source,
                             const SampleStatistics* eiv_lines) {
  RefineOptions o;
  o.allow_unstable = c.allow_unstable;
  if (c.max_iterations > 0) o.max_iterations = c.max_iterations;
  if (eiv_lines) {
    o.noise = RefineNoise::Sample;
    o.periods = source.periods;
    eiv_input_noise(*eiv_lines, o);
  } else if (!c.frf_path.empty()) {
    o.noise = !data.has_noise_model ? RefineNoise::None : c.frf_periods > 0 ? RefineNoise::Sample : RefineNoise::Known;
    o.periods = c.frf_periods;
  } else if (!c.noise_std.empty()) {
    o.noise = RefineNoise::Known;
  } else {
    o.noise = RefineNoise::Sample;
    o.periods = source.periods;
  }
  return o;
}

// The warnings about the subspace estimate's poles and rounding, once the model
// written is another (reflected or refined): they are recomputed for it.
void drop_subspace_model_warnings(FrfResult& res, bool refined) {
  auto stale = [refined](const std::string& w) {
    return w.rfind("the identified model is unstable", 0) == 0 || w.rfind("pole pair ", 0) == 0 ||
           (refined && (w.rfind("double precision may have lost", 0) == 0 || w.rfind("UNUSABLE in double", 0) == 0));
  };
  res.warnings.erase(std::remove_if(res.warnings.begin(), res.warnings.end(), stale), res.warnings.end());
}

std::string reflected_note(const std::vector<cplx>& reflected, Domain domain) {
  std::string s;
  for (const cplx z : reflected) s += (s.empty() ? "" : ", ") + pole_text(z);
  return "unstable subspace pole(s) " + s + " reflected into the stable region (" +
         (domain == Domain::Discrete ? "z -> 1/conj(z)" : "s -> -conj(s)") +
         ") and B, D refitted; --allow-unstable keeps them";
}

nlohmann::json refinement_json(const RefineResult& r, const RefineOptions& o) {
  using nlohmann::json;
  const RefineNoise noise = o.noise;
  json j = {{"method", "ml"},
            {"noise_model", to_string(noise)},
            {"errors_in_variables", o.input_variance.size() > 0},
            {"parametrisation", "real modal form: 2x2 blocks [a b; -b a] per pole pair (discrete: polar rho, phi), "
                                "1x1 real poles, B, C, D free; continuous time in s / omega_scale"},
            {"solver", "Ceres Solver, Levenberg-Marquardt, dense QR, analytic Jacobian"},
            {"cost_subspace", r.cost_subspace},
            {"cost_start", r.cost_start},
            {"cost", r.cost},
            {"terms", r.terms},
            {"parameters", r.parameters},
            {"free_parameters", r.free_parameters},
            {"iterations", r.iterations},
            {"max_iterations", o.max_iterations},
            {"termination", r.termination},
            {"g_stopping_estimate", r.g_stopping_estimate},
            {"pole_stopping_estimate", r.pole_stopping_estimate},
            {"at_stability_bound", r.at_stability_bound}};
  if (noise != RefineNoise::None) {
    j["expected_cost"] = r.expected_cost;
    j["p_value"] = r.p_value;
    j["p_value_method"] = "chi-square(2T - q) tail of Fisher's combination of the terms (2V for known variances)";
  }
  j["reflected_poles"] = json::array();
  for (const cplx z : r.reflected) j["reflected_poles"].push_back({z.real(), z.imag()});
  j["poles"] = json::array();
  for (const PoleUncertainty& p : r.poles) {
    json q = {{"pole", {p.pole.real(), p.pole.imag()}}, {"frequency", p.frequency}, {"damping", p.damping}};
    if (noise != RefineNoise::None) {
      q["frequency_sd"] = p.frequency_sd;
      q["damping_sd"] = p.damping_sd;
    }
    j["poles"].push_back(q);
  }
  if (!r.magnitude_sd.empty()) {
    auto mats = [](const std::vector<Eigen::MatrixXd>& v) {
      json a = json::array();
      for (const Eigen::MatrixXd& M : v) {
        json rows = json::array();
        for (Eigen::Index i = 0; i < M.rows(); ++i) {
          json row = json::array();
          for (Eigen::Index k = 0; k < M.cols(); ++k) row.push_back(M(i, k));
          rows.push_back(row);
        }
        a.push_back(rows);
      }
      return a;
    };
    j["magnitude_sd"] = mats(r.magnitude_sd);
    j["phase_sd"] = mats(r.phase_sd);
  }
  j["warnings"] = r.warnings;
  return j;
}

void print_refinement(Out& out, const RefineResult& r, const RefineOptions& o, Domain domain, double sample_time) {
  const RefineNoise noise = o.noise;
  out << "refined by maximum likelihood (" << to_string(noise)
      << (o.input_variance.size() > 0 ? ", errors-in-variables" : "") << "): V " << sci(r.cost_subspace) << " -> "
      << sci(r.cost)
      << " in " << r.iterations << " iterations";
  if (noise != RefineNoise::None)
    out << "; expected " << fmt(r.expected_cost, 5) << " under a right model, p " << p_relation(r.p_value, 2);
  out << "\n";
  const std::string unit = domain == Domain::Continuous || sample_time != 1.0 ? "rad/s" : "rad/sample";
  for (const PoleUncertainty& p : r.poles) {
    out << "  pole " << pole_text(p.pole) << ": frequency " << fmt(p.frequency, 6);
    if (noise != RefineNoise::None) out << " +- " << sci(p.frequency_sd, 2);
    out << " " << unit << ", damping " << fmt(p.damping, 5);
    if (noise != RefineNoise::None) out << " +- " << sci(p.damping_sd, 2);
    out << "\n";
  }
}

// --precision high: the reference identifies for a given order and r; the
// automatic choices (Section 5) are made once, in double precision, and reported.
// `chosen`: the command's options with --method resolved (set_frf_method).
int run_high(const IdentifyFrfCommand& c, const FrfOptions& chosen, const FrfData& data, const SampleStatistics& stats,
             const FrfSource& source, const std::string& where) {
  if (!c.plot_path.empty())
    throw Error(ErrorKind::Input, "--plot", "is drawn from the double-precision result; not with --precision high");
  FrfHighRequest q;
  q.treatment = source.treatment;
  q.eiv_variance = source.eiv_variance;
  q.min_input_snr = source.min_input_snr;
  q.frf_path = c.frf_path;
  q.units = c.units;
  q.data_path = c.data_path;
  q.meta_path = c.meta_path;
  q.selection = c.selection;
  q.continuous = c.domain == Domain::Continuous;
  q.orthogonal = chosen.continuous == ContinuousMethod::Orthogonal;
  q.discrete = chosen.discrete;
  q.omega_scale = c.options.omega_scale;
  std::string note;
  OrderAndR sel{c.options.order, c.options.r};
  if (sel.order == 0 || sel.r == 0) {
    const FrfOptions& o = chosen;  // the selection with the method the reference will use
    try {
      if (source.treatment == RecordTreatment::Plain) {
        sel = select_order_and_r(data, o);
      } else {  // the selection on the data of Section 5's treatment
        const FrfRun run = identify_frf_records(stats, o, source.treatment, source.eiv_variance, source.min_input_snr);
        sel = {run.result.order, run.result.r};
      }
    } catch (const Error& e) {
      throw e.within(where);
    }
    // Name only what was chosen (review finding 21: a given order was reported as chosen).
    if (c.options.order == 0)
      note = "order " + std::to_string(sel.order) + (c.options.r == 0 ? " and r " + std::to_string(sel.r) : "") +
             " chosen by the double-precision selection (singular values" + (c.options.r == 0 ? ", V_SUB" : "") +
             "; Pintelon 2002 Section 5)";
    else
      note = "r " + std::to_string(sel.r) + " chosen by the double-precision selection (minimal V_SUB, Pintelon 2002 "
             "Section 5) for the given order " + std::to_string(sel.order);
  }
  q.order = sel.order;
  q.r = sel.r;
  return identify_frf_high(c.json_path, q, note);
}

int run(const IdentifyFrfCommand& c) {
  const bool from_frf = !c.frf_path.empty();
  if (!from_frf && c.data_path.empty())
    throw Error(ErrorKind::Input, "identify-frf", "give either --frf FILE or --data FILE --meta FILE");
  if (from_frf && !c.selection.empty())
    throw Error(ErrorKind::Input, "--input/--output/--skip-periods", "apply to periodic records (--data --meta), not to --frf");
  require_frequency_units(c.units, c.domain, from_frf);
  if (c.precision == Precision::High && !c.noise_std.empty())  // before any work: refused, not computed and refused
    throw Error(ErrorKind::Input, "--noise-std",
                "the 50-digit reference reads records with their sample variance only; drop --precision high "
                "(or give M >= 4 periods without --noise-std)");
  if (c.refine && c.improper)
    throw Error(ErrorKind::Input, "--refine ml",
                "refines G (with output or errors-in-variables noise), not the inverse model of --improper: drop one");
  if (c.refine && c.precision == Precision::High)
    throw Error(ErrorKind::Input, "--refine ml", "refines the double-precision estimate; not with --precision high");
  require_refinement_for_limit(c.max_iterations, c.refine, "--refine ml");
  if (c.min_input_snr_given && !c.eiv && !c.improper)
    throw Error(ErrorKind::Input, "--min-input-snr",
                "is the line rule of --eiv and --improper (Eq. 34); add one of them or drop --min-input-snr");
  refuse_overwrite(c.plot_path, {c.frf_path, c.data_path, c.meta_path, c.json_path}, "--plot");
  refuse_overwrite(c.json_path, {c.frf_path, c.data_path, c.meta_path}, "--json");
  Out out{c.json_path == "-"};
  FrfOptions o = c.options;
  set_frf_method(c.method, c.domain, o);
  if (c.domain == Domain::Discrete && o.discrete == DiscreteMethod::Monomial && o.omega_scale > 0)
    throw Error(ErrorKind::Input, "--omega-scale",
                "scales Algorithm 2's bases; Algorithm 1's monomial basis (discrete time) has none: drop it, or give "
                "--method bilinear or orthogonal");
  const std::string where = from_frf ? c.frf_path : c.data_path;

  FrfSource source;
  SampleStatistics stats;
  FrfData data;
  std::vector<std::string> noise_warnings;  // --noise-std against the periods' scatter
  if (from_frf) {
    data = read_frf_csv(c.frf_path, c.domain, c.units);
    source.frf_path = c.frf_path;
    source.units = c.units;
    source.known_variance = data.has_noise_model;
    if (c.frf_periods > 0 && !data.has_noise_model)
      throw Error(ErrorKind::Input, "--frf-periods",
                  "says the G_var column is a sample variance, and " + c.frf_path + " has none: drop --frf-periods");
    source.periods = c.frf_periods;
  } else {
    const Records rec = read_records(c.data_path, c.meta_path, c.selection);
    const RecordMeta& meta = rec.meta;
    if (c.noise_std.empty()) require_sample_subspace_periods(meta, c.meta_path, c.selection);
    try {
      if (c.noise_std.empty()) {
        stats = record_statistics(rec.samples, rec.inputs, meta, c.domain);
        data = stats.data;
      } else {
        data = record_known_noise(rec.samples, rec.inputs, meta, c.domain, c.noise_std, &noise_warnings);
      }
    } catch (const Error& e) {
      throw e.within(c.data_path + " with " + c.meta_path);
    }
    source.noise_std = c.noise_std;
    source.data_path = c.data_path;
    source.meta_path = c.meta_path;
    source.periods = meta.periods;
    source.selection = c.selection;
    source.treatment = c.eiv        ? RecordTreatment::ErrorsInVariables
                       : c.improper ? RecordTreatment::Improper
                                    : RecordTreatment::Plain;
    source.eiv_variance = c.eiv_variance;
    source.min_input_snr = c.min_input_snr;
  }
  if (c.precision == Precision::High) return run_high(c, o, data, stats, source, where);

  const std::string method = frf_method_name(c.domain, o.continuous, o.discrete);
  FrfResult res;
  try {
    if (from_frf || !c.noise_std.empty()) {
      res = identify_frf(data, o);
    } else {
      FrfRun run = identify_frf_records(stats, o, source.treatment, c.eiv_variance, c.min_input_snr);
      data = std::move(run.data);
      res = std::move(run.result);
      source.dropped_lines = run.dropped_lines;
    }
  } catch (const Error& e) {
    throw e.within(where);
  }
  res.warnings.insert(res.warnings.begin(), noise_warnings.begin(), noise_warnings.end());
  // Stable models (issue 15): unstable subspace poles are reflected, and the
  // refinement keeps them stable, unless --allow-unstable.
  // --eiv: the refinement fits G to (Û, Ŷ) of the lines kept, not to their ratio.
  const bool eiv_refine = c.refine && c.eiv;
  const SampleStatistics eiv_lines = eiv_refine ? lines_of(stats, data.omega) : SampleStatistics{};
  const RefineOptions ro = refine_options(c, data, source, eiv_refine ? &eiv_lines : nullptr);
  RefineResult refined;
  std::string stabilised;
  try {
    if (c.refine) {
      refined = refine_ml(eiv_refine ? eiv_lines.data : data, res.model, ro);
      res.model = refined.model;
      res.v_sub = eiv_refine ? v_sub(refined.model, data) : refined.cost;
      if (!refined.reflected.empty()) stabilised = reflected_note(refined.reflected, res.model.domain);
    } else if (!c.allow_unstable) {
      std::vector<cplx> reflected;
      const StateSpace s = reflect_unstable_poles(data, res.model, &reflected);
      if (!reflected.empty()) {
        res.model = s;
        res.v_sub = v_sub(s, data);
        stabilised = reflected_note(reflected, res.model.domain);
      }
    }
  } catch (const Error& e) {
    throw e.within(where);
  }
  if (c.refine || !stabilised.empty()) {
    res.poles = poles(res.model);
    drop_subspace_model_warnings(res, c.refine);
    if (c.refine) {  // the ML optimum does not inherit the subspace estimate's rounding; its own (refine_ml warns)
      res.condition = refined.condition;
      res.error_estimate = std::numeric_limits<double>::epsilon() / 2 * refined.condition;  // u κ
      res.error_estimate_of = "the refined modal parameters (u x the Jacobian's condition, a first-order bound)";
      res.rounding_assessed = true;
      // The refined model is usable to the digits both the rounding and the
      // optimiser's stopping leave (refinement.g/pole_stopping_estimate).
      res.g_error_estimate = std::max(refined.g_error_estimate, refined.g_stopping_estimate);
      res.pole_error_estimate = std::max(refined.pole_error_estimate, refined.pole_stopping_estimate);
      res.rounding_moves = "the residuals and the Jacobian at the ML optimum moved by their rounding in random "
                           "directions, one Gauss-Newton step each; and the optimiser's stopping error (the Gauss-Newton "
                           "direction from the result, as far as V stays within its rounding), the larger";
    }
    // No instability warning to recompute: reflection leaves no unstable pole,
    // the refinement keeps none, and refine_ml names those --allow-unstable kept.
    const double lo = data.omega.minCoeff(), hi = data.omega.maxCoeff();
    if (const std::string w = out_of_band_warning(resonances_outside_band(res.poles, res.model.domain, lo, hi),
                                                  res.model.domain, lo, hi, "the data's frequencies");
        !w.empty())
      res.warnings.push_back(w);
    res.warnings.insert(res.warnings.end(), refined.warnings.begin(), refined.warnings.end());
  }
  const bool capped = o.order == 0 && res.order_at_search_cap;
  out << "identified order " << res.order
      << (o.order == 0 ? (capped ? " (the top of the searched range; see the warning)" : " (read from the singular values)")
                       : "")
      << " by "
      << method << " from F = " << data.frequencies() << " frequencies"
      << (source.periods > 0 ? ", M = " + std::to_string(source.periods) + " periods" : std::string())
      << ", r = " << res.r << (o.r > 0 ? "" : res.r_unusable_least_v_sub > 0 ? " (least V_SUB of the r with a usable estimate)" : " (minimising V_SUB)") << "\n";
  print_poles(out, res.poles);
  print_notes(out, res.notes);
  if (!stabilised.empty()) out << "note: " << stabilised << "\n";
  if (c.refine) print_refinement(out, refined, ro, res.model.domain, res.model.sample_time);
  FitVerdict fit = fit_verdict(res, data, source);
  fit.refined = c.refine;
  if (fit.misfit) res.warnings.push_back(fit.warning());
  out << fit.summary() << "\n";
  if (c.improper) out << "the model is the inverse system 1/G (improper G, Pintelon 2002 Section 5)\n";
  print_warnings(out, res.warnings);
  if (refused_as_unusable(c.strict, res.usability_estimate())) return 1;
  nlohmann::json j = to_json(res, method, source);
  // The band the data cover, in the model's omega (rad/sample; rad/s in
  // continuous time): validate names a record's lines outside it.
  j["omega_band"] = {data.omega.minCoeff(), data.omega.maxCoeff()};
  j["fit"] = to_json(fit);
  if (c.refine) j["refinement"] = refinement_json(refined, ro);
  if (!stabilised.empty()) j["stabilised"] = stabilised;
  emit_json(c.json_path, j);
  emit_plot(c.plot_path, [&] { return plot::frf_figure(data, res, c.refine ? &refined.magnitude_sd : nullptr); });
  return 0;
}

}  // namespace

void register_identify_frf(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<IdentifyFrfCommand>();
  FrfOptions& o = c->options;
  auto* idf =
      app.add_subcommand("identify-frf", "subspace identification from FRF samples or periodic records (Pintelon 2002)");
  auto* frf = idf->add_option("--frf", c->frf_path, "FRF CSV: omega,G_re,G_im[,G_var]");
  auto* data = idf->add_option("--data", c->data_path, "periodic input/output records CSV: u,y (or u1,...,y1,...)");
  auto* meta =
      idf->add_option("--meta", c->meta_path, "meta JSON of the records: period, periods, sample_time, excited_lines");
  frf->excludes(data)->excludes(meta);
  // A user review: fdsid frf writes G_var as a sample variance over the
  // periods, and identify-frf --frf judged it as known: the right model at the
  // right order was flagged (p 3.6e-4 from the FRF, 0.074 from the records).
  idf->add_option("--frf-periods", c->frf_periods,
                  "--frf: the G_var column is a sample variance over M >= 4 periods (as fdsid frf writes it), not a "
                  "known variance: the fit test and --refine ml then use its law (F(2, 2M - 2) terms, the sample ML "
                  "estimator)")
      ->check(count_at_least(4))
      ->needs(frf);
  data->needs(meta);
  meta->needs(data);
  add_json_option(idf, c->json_path, "write the identified model here (- = stdout)");
  add_plot_option(idf, c->plot_path);
  add_strict_option(idf, c->strict);
  add_record_selection_options(idf, c->selection);
  add_frequency_unit_options(idf, c->units);
  idf->add_option("--order", o.order, "model order n_a, or auto (the default: from the singular values of step 1c, Pintelon 2002 Section 5)")
      ->transform(order_value());
  idf->add_option("--max-order", o.max_order, "largest order --order auto considers (default min(20, r p - 1))")
      ->check(CLI::Range(1, 1000));
  // 0 (the defaults' "choose") is refused when given: it had silently meant "choose" (a user review).
  idf->add_option("--r", o.r, "number of basis functions r > n_a (default: the r in [1.5 n_a, 6 n_a] that minimises the weighted fit V_SUB, Eq. 35)")
      ->check(count_at_least(2));
  idf->add_option("--r-max", o.r_max, "upper end of the r search (default 6 n_a)")->check(count_at_least(2));
  idf->add_option("--domain", c->domain, "discrete (omega in rad/sample, default) or continuous (rad/s)")
      ->transform(choice(domain_names()));
  idf->add_option("--method", c->method,
                  "the basis: continuous time bilinear (Algorithm 2.1, default) or orthogonal (2.2); discrete time "
                  "monomial (Algorithm 1, default), bilinear or orthogonal (Algorithm 2.1 / 2.2 on the Tustin "
                  "frequencies tan(omega/2): for a band that covers a small arc of the unit circle)");
  idf->add_option("--omega-scale", o.omega_scale,
                  "frequency scaling of Algorithm 2 (default sqrt(w_min w_max); discrete bilinear/orthogonal: rad/sample "
                  "in (0, pi), default 2 atan sqrt(tan(w_min/2) tan(w_max/2)))")
      ->check(finite_number(0, false));
  idf->add_option("--precision", c->precision, "double (default) or high")
      ->transform(choice(kPrecisions));
  auto* eiv = idf->add_flag("--eiv", c->eiv,
                            "noisy input: identify from G = Y/U with the variance of Eq. (31) (Section 5; needs "
                            "--data, --meta: the input noise is estimated over the periods)");
  auto* eiv_variance = idf->add_option("--eiv-variance", c->eiv_variance,
                  "data (the default: Eq. 31 from the noisy ratio) or model (re-evaluated at a first-pass model: consistent)")
      ->transform(choice(eiv_variance_names()));
  auto* improper =
      idf->add_flag("--improper", c->improper,
                    "improper G: identify 1/G by swapping input and output (Section 5; needs --data, --meta)");
  // Both need periodic records: the input noise is estimated over the periods.
  eiv->needs(data)->excludes(improper);
  eiv_variance->needs(eiv);  // review finding 49: it was ignored without --eiv
  improper->needs(data);
  idf->add_option("--min-input-snr", c->min_input_snr,
                  "--eiv, --improper: drop lines whose input SNR is below this (default 10)")
      ->check(finite_number(0, true))
      ->each([c](const std::string&) { c->min_input_snr_given = true; });
  auto* noise = idf->add_option("--noise-std", c->noise_std,
                                "records: the known std of the white output noise per sample (one value, or one per "
                                "output); the variance then comes from it, not from the periods, so M >= 1 period "
                                "suffices (default: the sample variance over M >= 4 periods)");
  noise->needs(data)->excludes(eiv)->excludes(improper);
  idf->add_option("--refine", c->refine,
                  "ml: refine the subspace estimate by maximum likelihood (Levenberg-Marquardt, Ceres) for the data's "
                  "noise model (with --eiv: input and output noise), with Cramer-Rao uncertainties of the poles and of G")
      ->transform(choice(std::map<std::string, bool>{{"ml", true}, {"none", false}}, "is not ml or none"));
  add_max_iterations_option(idf, c->max_iterations, "--refine ml");
  idf->add_flag("--allow-unstable", c->allow_unstable,
                "keep unstable poles (default: reflect them into the stable region and refit B, D; a warning names "
                "any unstable pole that remains)");
  on_parsed(idf, c, chosen, run);
}

}  // namespace fdsid::cli
