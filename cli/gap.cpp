// fdsid gap and gap-validate: sim-to-real gap diagnosis and its blind validation.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "fdsid/figures.hpp"
#include "fdsid/format.hpp"
#include "fdsid/io.hpp"
#include "fdsid/json.hpp"

namespace fdsid::cli {

namespace {

struct GapCommand {
  std::string model_path, data_path, meta_path, json_path, plot_path, table_path;
  GapOptions options;
  RecordSelection selection;
};

struct GapValidateCommand {
  std::string json_path;
  GapValidationOptions options;
  // Measured noise (gap_cases.hpp): records whose contrasts across periods
  // are the noise; one meta for all; the columns by header name.
  std::vector<std::string> noise_paths;
  std::string noise_meta_path;
  RecordSelection noise_selection;
  bool period_given = false, periods_given = false;
};

// The measured-noise pool of --noise-from, read and checked before any case
// is made; P is the noise records' period and M, unless given, the smaller of
// 8 and the pool's size. Fails (exit 2) naming the option: --noise-from
// without --noise-meta, --noise-input or --noise-output (or those without
// --noise-from), a --period other than the records', more --periods than
// the pool holds.
void read_noise_pool(GapValidateCommand& c) {
  GapValidationOptions& o = c.options;
  const bool any = !c.noise_meta_path.empty() || !c.noise_selection.inputs.empty() ||
                   !c.noise_selection.outputs.empty() || c.noise_selection.skip_periods > 0;
  if (c.noise_paths.empty()) {
    if (any)
      throw Error(ErrorKind::Input, "--noise-meta/--noise-input/--noise-output/--noise-skip-periods",
                  "apply to measured noise: add --noise-from DATA.csv");
    return;
  }
  if (c.noise_meta_path.empty() || c.noise_selection.inputs.size() != 1 || c.noise_selection.outputs.size() != 1)
    throw Error(ErrorKind::Input, "--noise-from",
                "needs --noise-meta META.json and one --noise-input and one --noise-output column name (e.g. "
                "--noise-input Force --noise-output Acceleration1)");
  auto pool = std::make_shared<MeasuredNoise>();
  for (const std::string& path : c.noise_paths) {
    const Records r = read_records(path, c.noise_meta_path, c.noise_selection);
    pool->period = r.meta.period;
    add_measured_noise(*pool, r.samples.col(1), path);
  }
  if (c.period_given && o.period != pool->period)
    throw Error(ErrorKind::Input, "--period",
                "the noise records have period " + std::to_string(pool->period) + ": leave --period out or give that");
  o.period = pool->period;
  const int held = static_cast<int>(pool->periods.size());
  if (!c.periods_given) o.periods = std::min(8, held);
  if (o.periods > held)
    throw Error(ErrorKind::Input, "--periods",
                "the noise records hold " + std::to_string(held) +
                    " noise periods (two per four measured periods, one per three left over): give --periods <= " +
                    std::to_string(held) + " or more --noise-from records");
  if (o.periods < 4)
    throw Error(ErrorKind::Input, "--noise-from",
                "the noise records hold " + std::to_string(held) + " noise period(s); a case needs at least 4 (8 "
                "measured periods after --noise-skip-periods, in one record or several)");
  o.measured_noise = pool;
}

std::string band_text(const std::array<double, 2>& b) { return "[" + sci(b[0], 4) + ", " + sci(b[1], 4) + "]"; }

// An effect parameter: flags and counts (series, at_input, order) as
// integers, the rest in scientific notation (they printed as 2.0000e+00).
std::string parameter_text(double v) {
  if (v == std::floor(v) && std::abs(v) < 1e6) return std::to_string(static_cast<long long>(v));
  return sci(v, 4);
}

// Plot-ready table next to the JSON: frequency, t(k) before and after, flag.
void write_gap_table(const std::string& path, const GapReport& r) {
  std::ostringstream csv;
  csv << "frequency_hz,t_before,t_after,flagged\n";
  char buf[128];
  for (Eigen::Index i = 0; i < r.frequency.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g,%d\n", r.frequency(i), r.t_before(i), r.t_after(i),
                  static_cast<int>(r.flagged[i]));
    csv << buf;
  }
  write_text_file(path, csv.str());
}

// The summary line: one of the three outcomes (GapVerdict), never
// contradicting the numbers printed beside it.
std::string verdict_line(const GapReport& r) {
  const double alpha = r.options.alpha;
  std::string effects;
  for (Effect e : r.present) effects += (effects.empty() ? "" : ", ") + std::string(fdsid::to_string(e));
  const std::string share = std::to_string(std::lround(100 * r.explained_share)) + " % of the excess gap";
  switch (r.verdict) {
    case GapVerdict::NoGap:
      return "verdict: no significant gap (p(gap) " + p_text(r.p_gap) + " at level " + fmt(alpha, 3) + ": noise alone)";
    case GapVerdict::Explained: {
      std::string line = "verdict: " + effects + " - explained: what remains is noise (p " + p_text(r.p_after) +
                         " at level " + fmt(alpha, 3) + ")";
      // Two reasons to read "explained" with care, each from its own numbers.
      for (Effect e : r.stand_ins)
        line += "; but " + std::string(fdsid::to_string(e)) +
                " is a stand-in (note below): the data do not resolve its form, only its shrink";
      if (r.p_below < alpha)
        line += "; and what remains (gap " + sci(r.gap_after) + ") is below the noise (p " + p_text(r.p_below) +
                " of so small a gap from noise): the effects fit part of the noise too, more than the data support";
      return line;
    }
    case GapVerdict::Unexplained: break;
  }
  if (r.present.empty()) {
    std::string best = "none";
    if (!r.candidates.empty())
      best = std::string(fdsid::to_string(r.candidates.front().effect())) + " (alone it leaves gap " +
             sci(r.candidates.front().gap_after) + ")";
    return "verdict: significant gap (p(gap) " + p_text(r.p_gap) +
           ") that no effect of the catalogue explains: none passes its test; best single candidate " + best;
  }
  return "verdict: " + effects + " - NOT fully explained: " + (r.present.size() > 1 ? "they remove " : "it removes ") + share + ", and what remains (gap " +
         sci(r.gap_after) + ") is still above the noise (p " + p_text(r.p_after) + " at level " + fmt(alpha, 3) + ")";
}

// The best-linear-approximation view (GapDistortion): what the detection
// lines say about nonlinear distortion on the excited lines.
std::string distortion_line(const GapReport& r) {
  const GapDistortion& d = r.distortion;
  const std::string which = std::to_string(d.lines) + (d.odd_only ? " odd" : "") + " detection lines";
  if (!d.estimable)
    return "distortion (best linear approximation view): not estimable, " + which + " (4 needed)";
  const std::string level =
      !d.level_db ? std::string("no distortion above the noise")
      : *d.level_db < 0 ? "distortion " + fmt(-*d.level_db, 3) + " dB below the noise of the mean"
                        : "distortion " + fmt(*d.level_db, 3) + " dB above the noise of the mean";
  std::string line = "distortion (best linear approximation view, " + which + "): gap " + sci(d.gap) + " there, " +
                     level + " (p " + p_text(d.p_detected) + "), " + std::to_string(std::lround(100 * d.share)) +
                     " % of the excess gap; excited lines beyond it: p " +
                     (d.p_beyond <= d.p_beyond_min ? "<= " + sci(d.p_beyond_min, 2) + " (the Monte Carlo's floor)"
                                                   : p_text(d.p_beyond));
  // What the test says and no more: the excited lines' gap is not beyond the
  // distortion at the level; where the distortion's share is below 100 %, the
  // rest is named too, and the level its p was judged at (a user review: "53 %"
  // and p 0.012 read "the gap is nonlinear distortion", without the rest).
  if (d.bla_right) {
    const double alpha = r.options.alpha;
    const long rest = std::lround(100 * (1 - d.share));
    line += " - the model is right as a best linear approximation: the gap is nonlinear distortion" +
            (d.level_db ? " " + fmt(*d.level_db, 3) + " dB above the noise" : std::string());
    if (rest > 0)
      line += ", and the " + std::to_string(rest) + " % it does not account for is not significant at level " +
              fmt(alpha, 3) + " (the p above)";
  }
  return line;
}

// The one linear effect of the chosen set that `alternatives` and
// `possible_additions` refer to (a leading leakage may precede it).
std::string linear_chosen(const GapReport& r) {
  for (const EffectFit& f : r.chosen)
    if (fdsid::is_linear(f.effect())) return fdsid::to_string(f.effect());
  return "?";
}

// The text report of one output channel.
void print_report(Out& out, const GapReport& r, int periods) {
  out << "gap before " << sci(r.gap_before) << " (1 = the model is right up to the noise; " << r.excited
      << " excited lines, M = " << periods << "), after " << sci(r.gap_after)
      << (r.periods_used < periods ? " (on the last " + std::to_string(r.periods_used) +
                                         " periods, where the model as given leaves " + sci(r.gap_model_used) + ")"
                                   : std::string())
      << "\n";
  out << verdict_line(r) << "\n";
  out << "tests: p(gap) " << p_text(r.p_gap) << ", p(nonlinearity, " << r.unexcited << " unexcited lines) "
      << p_text(r.p_nonlinearity) << " (predicted from the excited lines: " << p_text(r.p_nonlinearity_prediction)
      << "), p(leakage) " << p_text(r.p_leakage)
      << (r.period_power.empty() ? std::string() : ", p(equal noise power per period) " + p_text(r.p_period_power))
      << "\n";
  out << distortion_line(r) << "\n";
  if (!r.alternatives.empty()) {
    const std::string e = linear_chosen(r);
    out << "indistinguishable here:";
    const char* sep = " ";
    for (const auto& [g, p] : r.alternatives) {
      out << sep << fdsid::to_string(g) << " explains the record as well (" << e << " added to it: p " << p_text(p) << ")";
      sep = "; ";
    }
    out << "\n";
  }
  if (!r.alternative_pairs.empty()) {
    out << "indistinguishable here:";
    const char* sep = " ";
    for (const auto& [g, h] : r.alternative_pairs) {
      out << sep << fdsid::to_string(g) << " + " << fdsid::to_string(h) << " jointly explain the record as well as "
          << linear_chosen(r) << " (each significant beside the other)";
      sep = "; ";
    }
    out << "\n";
  }
  if (!r.possible_additions.empty()) {
    const std::string e = linear_chosen(r);
    out << "possibly also here:";
    const char* sep = " ";
    for (const auto& [g, p] : r.possible_additions) {
      out << sep << fdsid::to_string(g) << " beside " << e << " explains the record as well (added: p " << p_text(p)
          << ")";
      sep = "; ";
    }
    out << "\n";
  }
  if (!r.bands.empty()) {
    out << "bands (Hz):";
    for (const auto& b : r.bands) out << " " << band_text(b);
    out << "\n";
  }
  if (!r.peaks.empty()) {  // at most 8 intervals in the text; the JSON has all
    out << "half the excess gap lies at (Hz):";
    for (size_t i = 0; i < r.peaks.size() && i < 8; ++i) {
      const auto& p = r.peaks[i];
      out << " " << (p.band[0] == p.band[1] ? sci(p.band[0], 4) : band_text(p.band)) << " " << fmt(100 * p.share, 2) << " %";
    }
    if (r.peaks.size() > 8) out << " and " << r.peaks.size() - 8 << " more intervals";
    out << "\n";
  }
  out << "candidates (each alone):\n";
  for (const EffectFit& f : r.candidates) {
    char buf[160];
    // A shrink that rounds to zero prints 0.000, not -0.000 (a user review).
    const double shrink = std::abs(f.shrink) < 5e-4 ? 0.0 : f.shrink;
    std::snprintf(buf, sizeof buf, "  %-16s gap_after %-10.4g shrink %-8.3f p %-9s", fdsid::to_string(f.effect()),
                  f.gap_after, shrink, p_text(f.p_value, 2).c_str());
    out << buf;
    for (const auto& kv : fdsid::parameter_list(f.parameters)) out << " " << kv.first << "=" << parameter_text(kv.second);
    out << "\n";
  }
  print_notes(out, r.notes);
}

// The summary line of several outputs (MultiGapReport's verdict).
std::string multi_verdict_line(const MultiGapReport& m, const std::vector<std::string>& names) {
  const double alpha = m.channels.front().options.alpha;
  const std::string joint =
      m.joint_tested ? "joint test p " + p_text(m.p_joint) + " at level " + fmt(alpha, 3) : std::string("joint test not computed");
  std::string effects;
  for (Effect e : m.present) effects += (effects.empty() ? "" : ", ") + std::string(fdsid::to_string(e));
  switch (m.verdict) {
    case GapVerdict::NoGap:
      return "verdict: no significant gap on any of the " + std::to_string(m.channels.size()) + " outputs (" + joint +
             ": noise alone)";
    case GapVerdict::Explained:
      return "verdict: " + effects + " - explained on every output (" + joint + " on the model as given)";
    case GapVerdict::Unexplained: break;
  }
  std::string open;
  for (size_t o = 0; o < m.channels.size(); ++o)
    if (m.channels[o].verdict == GapVerdict::Unexplained) open += (open.empty() ? "" : ", ") + names[o];
  if (open.empty())
    return "verdict: a joint gap (" + joint + ") that no single output shows: the outputs' residuals disagree together";
  return "verdict: NOT fully explained: " + open + " keep" + (open.find(',') == std::string::npos ? "s" : "") +
         " a significant gap that the effects found do not remove (" + joint + "; per output below)";
}

int run_gap(const GapCommand& c) {
  refuse_overwrite(c.plot_path, {c.model_path, c.data_path, c.meta_path, c.json_path}, "--plot");
  refuse_overwrite(c.json_path, {c.model_path, c.data_path, c.meta_path}, "--json");
  refuse_overwrite(c.table_path, {c.model_path, c.data_path, c.meta_path, c.json_path}, "--table");
  Out out{c.json_path == "-"};
  const GapOptions& o = c.options;
  const ModelFile file = read_model_with_diagnostics(c.model_path);
  const StateSpace& model = file.model;
  // The model's own fault is named with the model's file (diagnose_gap checks
  // it again, and its errors are the record's: they would name the data file).
  try {
    require_stable(model, "to compare with the record");
  } catch (const Error& e) {
    throw e.within(c.model_path);
  }
  const std::string columns_note = selection_against_model(file.json, c.selection, c.model_path);
  const Records records = read_records(c.data_path, c.meta_path, c.selection);
  // What validate warns about, gap too: the model file's own unusability, and
  // the record's lines beyond the model's band (a user review: a meta with
  // sample_time in ms typed as s gave a normal diagnosis in mHz).
  std::vector<std::string> warnings;
  if (!file.unusable.empty()) warnings.push_back(file.unusable);
  if (std::string w = lines_outside_band(file.json, model, records.meta); !w.empty()) warnings.push_back(std::move(w));
  const RecordMeta& meta = records.meta;
  const int outputs = static_cast<int>(records.samples.cols()) - records.inputs;
  if (outputs > 1) {
    for (const auto& [opt, path] : {std::pair{"--plot", &c.plot_path}, std::pair{"--table", &c.table_path}})
      if (!path->empty())
        throw Error(ErrorKind::Input, opt,
                    "draws one output, the record has " + std::to_string(outputs) + ": choose one with --output NAME");
    std::vector<std::string> names;
    for (int k = 0; k < outputs; ++k)
      names.push_back(static_cast<size_t>(k) < c.selection.outputs.size() ? c.selection.outputs[k]
                                                                          : "y" + std::to_string(k + 1));
    MultiGapReport m;
    try {
      m = diagnose_gap_outputs(model, records.samples, records.inputs, meta, o);
    } catch (const Error& e) {
      throw e.within(c.data_path);
    }
    if (!columns_note.empty()) m.notes.push_back(columns_note);
    out << "gap before " << sci(m.gap_before) << " (mean over " << outputs << " outputs; 1 = the model is right up "
        << "to the noise), after " << sci(m.gap_after) << "; joint gap " << sci(m.gap_joint) << "\n";
    out << multi_verdict_line(m, names) << "\n";
    print_notes(out, m.notes);
    print_warnings(out, warnings);
    for (size_t k = 0; k < m.channels.size(); ++k) {
      out << "== output " << k + 1 << " (" << names[k] << ")\n";
      print_report(out, m.channels[k], meta.periods);
    }
    nlohmann::json j = gap_report_to_json(m);
    if (!warnings.empty()) j["warnings"] = warnings;
    for (size_t k = 0; k < m.channels.size(); ++k) j["channels"][k]["name"] = names[k];
    emit_json(c.json_path, j);
    return 0;
  }
  GapReport r;
  try {
    r = diagnose_gap(model, records.samples, records.inputs, meta, o);
  } catch (const Error& e) {
    throw e.within(c.data_path);
  }
  if (!columns_note.empty()) r.notes.push_back(columns_note);
  print_report(out, r, meta.periods);
  print_warnings(out, warnings);
  if (!c.table_path.empty()) write_gap_table(c.table_path, r);
  nlohmann::json j = to_json(r);
  if (!warnings.empty()) j["warnings"] = warnings;
  emit_json(c.json_path, j);
  emit_plot(c.plot_path, [&] { return plot::gap_figure(r, meta.periods); });
  return 0;
}

int run_gap_validate(const GapValidateCommand& given) {
  GapValidateCommand c = given;  // its options gain the progress callback and the noise pool
  GapValidationOptions& o = c.options;
  read_noise_pool(c);
  if (static_cast<long long>(o.period) * o.periods > 10000000LL)
    throw Error(ErrorKind::Input, "--period", "period x periods above 1e7 samples");
  Out out{c.json_path == "-"};
  o.progress = progress("gap-validate: cases");
  const GapValidation v = validate_gap(o);
  const nlohmann::json j = to_json(v);
  out << "gap-validate: " << v.cases << " blind cases (" << fdsid::to_string(o.family) << " family"
      << (o.continuous ? ", continuous-time" : "") << ", P = " << o.period
      << ", M = " << o.periods << ", seed " << o.seed
      << (o.measured_noise ? ", measured noise: " + std::to_string(o.measured_noise->periods.size()) + " noise periods from " +
                                 std::to_string(o.measured_noise->sources.size()) + " record(s)"
                           : std::string())
      << "), exact verdicts " << sci(v.accuracy, 3) << "\n";
  for (const auto& cat : v.by_category)
    out << "  " << cat.first << ": " << cat.second[0] << "/" << cat.second[1] << " correct\n";
  // Rates of a category with no case are NaN: "n/a", not "nan"; numbers in 4
  // digits (review finding 21: "subtle or paired nan", "median 1.0599307504305204").
  const auto rate = [](const nlohmann::json& x) {
    return x.is_number() && std::isfinite(x.get<double>()) ? fmt(x.get<double>(), 4) : std::string("n/a (no such case)");
  };
  out << "  clear single effects " << rate(j["clear_single_rate"]) << " (target >= " << fmt(kTargetClear, 2)
      << "), subtle or paired " << rate(j["subtle_or_pair_rate"]) << " (>= " << fmt(kTargetSubtleOrPair, 2)
      << "), false alarms " << rate(v.false_alarm_rate) << " (<= " << fmt(kTargetFalseAlarms, 2) << "), band hits "
      << rate(v.band_hit_rate) << "\n";
  out << "  up to the alternatives the reports name indistinguishable: clear single effects "
      << rate(j["clear_single_rate_up_to_alternatives"]) << ", subtle or paired "
      << rate(j["subtle_or_pair_rate_up_to_alternatives"]) << "\n";
  out << "  gap_after on correct verdicts: median " << rate(j["gap_after_correct"]["median"]) << ", p90 "
      << rate(j["gap_after_correct"]["p90"]) << ", max " << rate(j["gap_after_correct"]["max"])
      << ", share <= 2: " << rate(j["gap_after_correct"]["share_at_most_2"]) << "\n";
  out << "  noise power differs between periods (noted in the report): " << v.period_power_noted << " of " << v.cases
      << " cases, " << v.false_alarms_noted << " of the " << v.false_alarms << " false alarms\n";
  out << "  adjacent periods' noise alike (noted in the report): " << v.periods_dependent_noted << " of " << v.cases
      << " cases, " << v.false_alarms_dependent_noted << " of the " << v.false_alarms << " false alarms\n";
  out << "  stand-ins named (a mode effect at its search's bound): " << v.stand_in_noted << " of " << v.cases
      << " cases, " << v.stand_in_correct << " of them correct verdicts\n";
  out << "  gap after below the noise (the effects fitted noise too): " << v.below_noise << " of " << v.cases
      << " cases, " << v.below_noise_correct << " of them correct verdicts\n";
  std::string confused;  // the off-diagonal of the confusion matrix
  for (const auto& t : v.confusion)
    for (const auto& p : t.second)
      if (p.first != t.first) confused += "  " + t.first + " -> " + p.first + ": " + std::to_string(p.second) + "\n";
  // An empty block under its heading read as output lost (review finding 8 of stop 47).
  out << (confused.empty() ? "confusion: none (every verdict named its case's truth)\n"
                           : "confusion (truth -> verdict: count):\n" + confused);
  emit_json(c.json_path, j);
  const bool met = gap_validation_targets_met(v);
  // A category without cases is not tested: say so beside the verdict.
  std::string untested;
  for (const char* key : {"clear_single_rate", "subtle_or_pair_rate"})
    if (!(j[key].is_number() && std::isfinite(j[key].get<double>())))
      untested += std::string(untested.empty() ? "" : ", ") + (key[0] == 'c' ? "clear single effects" : "subtle or paired");
  out << (met ? "targets met" : "targets NOT met")
      << (untested.empty() ? std::string() : " (not tested, no such case: " + untested + ")") << "\n";
  return met ? 0 : 1;
}

void register_gap_diagnosis(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<GapCommand>();
  GapOptions& o = c->options;
  auto* gap = app.add_subcommand("gap", "sim-to-real gap: where a model and a periodic measurement disagree, and why");
  gap->add_option("--model", c->model_path, "simulation model JSON (one input; one output per record output)")->required();
  gap->add_option("--data", c->data_path, "periodic records CSV (u,y or u,y1,...,yp), M whole periods")->required();
  gap->add_option("--meta", c->meta_path, "meta JSON: period, periods, sample_time, excited_lines")->required();
  add_json_option(gap, c->json_path, "write the report here (- = stdout)");
  add_plot_option(gap, c->plot_path);
  add_record_selection_options(gap, c->selection);
  gap->add_option("--table", c->table_path, "write the plot-ready table (frequency, t before/after, flag) here")->check(output_path("--table"));
  // Levels checked at parse time, named by their option (review finding 21:
  // "--alpha 5" was blamed on the data file).
  const CLI::Validator level = number_where([](double x) { return x > 0 && x < 1; }, "a level in (0, 1)", "(0, 1)");
  gap->add_option("--alpha", o.alpha, "level of each detection test (default 0.01)")->check(level);
  gap->add_option("--effect-alpha", o.effect_alpha, "level of the test admitting an effect: a linear effect's F-test, leakage's transient test (default 1e-3)")
      ->check(level);
  gap->add_option("--fdr", o.fdr, "false-discovery rate of the bands (default 0.05)")->check(level);
  on_parsed(gap, c, chosen, run_gap);
}

void register_gap_validate(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<GapValidateCommand>();
  GapValidationOptions& o = c->options;
  auto* gval = app.add_subcommand("gap-validate", "blind validation of gap on generated cases (effects withheld)");
  gval->add_option("--cases", o.cases, "number of cases (default 100)")->check(CLI::Range(1, 100000));
  gval->add_option("--seed", o.seed, "random seed")->capture_default_str();
  gval->add_option("--period", o.period, "samples per period P (default 1024; with --noise-from the records' period)")
      ->check(CLI::Range(32, 1 << 20))
      ->each([c](const std::string&) { c->period_given = true; });
  gval->add_option("--periods", o.periods, "periods M (default 8; with --noise-from at most the noise periods held)")
      ->check(CLI::Range(4, 1000))
      ->each([c](const std::string&) { c->periods_given = true; });
  gval->add_option("--noise-from", c->noise_paths,
                   "measured noise instead of the synthetic: periodic records CSV (repeatable; one --noise-meta for "
                   "all); each 4 consecutive periods give 2 noise periods, 3 left over give 1: contrasts in which the "
                   "periodic response and a linear drift of it cancel (gap_cases.hpp)")
      ->check(CLI::ExistingFile);
  gval->add_option("--noise-meta", c->noise_meta_path, "meta JSON of the --noise-from records")->check(CLI::ExistingFile);
  gval->add_option("--noise-input", c->noise_selection.inputs, "the --noise-from records' input column (header name)");
  gval->add_option("--noise-output", c->noise_selection.outputs,
                   "the --noise-from records' output column (header name): its noise is used");
  gval->add_option("--noise-skip-periods", c->noise_selection.skip_periods,
                   "drop this many leading periods of each --noise-from record (a transient)")
      ->check(whole_count());
  gval->add_option("--family", o.family,
                   "case family: classic (default), structure (lightly damped many-mode structures, noise rising with "
                   "frequency, a spring nonlinearity in the loop) or mixed (alternating cycles of 20)")
      ->transform(choice(gap_family_names()));
  gval->add_flag("--continuous", o.continuous,
                 "continuous-time simulation models and true systems (the same draws; nonlinear stages on an 8x finer "
                 "grid, the record ideally sampled)");
  gval->add_option("--threads", o.threads, "worker threads (0 = all cores)")->check(CLI::Range(0, 1024))->capture_default_str();
  gval->add_option("--workdir", o.workdir, "write the cases' files here (default: a temporary directory)");
  gval->add_flag("--keep-files", o.keep_files, "keep each case's model.json, data.csv, meta.json and truth.json (the withheld effects, written beside them; the diagnosis reads the first three only)");
  add_json_option(gval, c->json_path, "write the scores here (- = stdout)");
  on_parsed(gval, c, chosen, run_gap_validate);
}

}  // namespace

void register_gap(CLI::App& app, Action& chosen) {
  register_gap_diagnosis(app, chosen);
  register_gap_validate(app, chosen);
}

}  // namespace fdsid::cli
