#pragma once
// Shared pieces of the fdsid subcommands: how each registers itself, the
// options every command has (--json, --plot), enum options mapped by CLI11,
// and the output helpers (JSON, figure, progress, summary, overwrite guard).
#include <CLI/CLI.hpp>

#include <functional>
#include <initializer_list>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "fdsid/format.hpp"
#include "fdsid/io.hpp"
#include "fdsid/names.hpp"
#include "fdsid/plot.hpp"

namespace fdsid::cli {

/// What main runs once the command line is parsed: the chosen subcommand's
/// action (validation, then work). Each subcommand's parse callback sets it.
using Action = std::function<int()>;

/// Registers `sub` to run `run(options)` with its own options object. `run`
/// is a function of Options, so that each file's `run` is picked by its
/// parameter type (the cli/ files are compiled as one unit: CMakeLists.txt).
template <class Options>
void on_parsed(CLI::App* sub, std::shared_ptr<Options> options, Action& chosen, int (*run)(const Options&)) {
  sub->callback([options, &chosen, run] { chosen = [options, run] { return run(*options); }; });
}

// ---------------------------------------------------------------------------
// Registration of each subcommand (one file each in cli/)

void register_reproduce(CLI::App& app, Action& chosen);          // reproduce.cpp
void register_identify_spectrum(CLI::App& app, Action& chosen);  // identify_spectrum.cpp
void register_identify_frf(CLI::App& app, Action& chosen);       // identify_frf.cpp
void register_check(CLI::App& app, Action& chosen);              // check.cpp
void register_certify(CLI::App& app, Action& chosen);            // certify.cpp
void register_conformance(CLI::App& app, Action& chosen);        // conformance.cpp
void register_sample_spectrum(CLI::App& app, Action& chosen);    // sample_spectrum.cpp
void register_simulate_records(CLI::App& app, Action& chosen);   // simulate.cpp
void register_gap(CLI::App& app, Action& chosen);                // gap.cpp (gap, gap-validate)
void register_records(CLI::App& app, Action& chosen);            // records.cpp (frf, validate)

/// "fdsid: unknown subcommand ..." (or reproduce target) on stderr and true
/// when argv names one that is not registered: CLI11 alone would say "A
/// subcommand is required".
bool unknown_subcommand(const CLI::App& app, int argc, char** argv);

/// The message for arguments CLI11 did not expect: "unknown option --realisations
/// of reproduce table2 (did you mean --realizations?)" when an argument looks
/// like an option of the chosen subcommand misspelt (one edit per three letters), else
/// CLI11's own text.
std::string unexpected_arguments(const CLI::App& app, int argc, char** argv, const std::string& cli11_message);

// ---------------------------------------------------------------------------
// Options

enum class Precision { Double, High };

/// An enum option mapped by CLI::CheckedTransformer from its names; anything
/// else is refused as "\"VALUE\" <refusal>" (e.g. `is not double or high`).
template <class E>
CLI::Validator choice(const std::map<std::string, E>& names, const std::string& refusal) {
  const CLI::CheckedTransformer map(names);
  std::string desc;
  for (const auto& kv : names) desc += (desc.empty() ? "{" : ",") + kv.first;
  return CLI::Validator(
      [map, names, refusal](std::string& value) -> std::string {
        // Only the names: CheckedTransformer would also take the enum's numbers.
        if (names.count(value) == 0) return "\"" + value + "\" " + refusal;
        return map(value);
      },
      desc + "}");
}

/// choice() of an enumeration's name table (fdsid/names.hpp): "is not a, b or c".
template <class E>
CLI::Validator choice(const NameTable<E>& names) {
  return choice(std::map<std::string, E>(names.begin(), names.end()), "is not " + name_list(names));
}

extern const NameTable<Precision> kPrecisions;  // double, high

/// --order: a positive integer (<= 1000) or auto (stored as 0).
CLI::Validator order_value();
/// A count that may be 0 (--skip-periods): a whole number in [0, 2^31 − 1];
/// CLI11's NonNegativeNumber printed the largest double, 309 digits, in its
/// refusal (review finding 8 of stop 47).
CLI::Validator whole_count();
/// A whole number in [lo, 2^31 − 1] (--r: 0 there had meant "choose it"
/// silently, a user review found).
CLI::Validator count_at_least(long lo);
/// A finite decimal number x (the whole text) with accepts(x); anything else
/// is refused at parse time as "\"TEXT\" is not <what>", which CLI11 prefixes
/// with the option's name. type_name: the value's name in --help.
CLI::Validator number_where(std::function<bool(double)> accepts, const std::string& what, const std::string& type_name);
/// A finite number above lo (or at least lo): nan, inf and out-of-range
/// values are refused by the option's name (--omega-scale -1 and nan were
/// silently replaced by the default, a user review found).
CLI::Validator finite_number(double lo, bool lo_allowed);

/// An output file option (--out, --json, ...): checked at parse time, before
/// any work (fdsid::require_writable_path: folder exists and is writable, the
/// path is no folder); "-" (stdout) passes.
CLI::Validator output_path(const std::string& option);
/// --json FILE (- = stdout); an empty path is refused.
CLI::Option* add_json_option(CLI::App* sub, std::string& path, const std::string& what);
/// --plot FILE (.svg or .png); checked when given.
CLI::Option* add_plot_option(CLI::App* sub, std::string& path);
/// --input NAME, --output NAME (repeatable: the records' columns by header
/// name) and --skip-periods K (leading periods dropped), for commands that
/// read periodic records (fdsid::RecordSelection).
void add_record_selection_options(CLI::App* sub, RecordSelection& selection);
/// --frequency-unit rad|hz and --sample-time Ts: how an FRF file's omega
/// column is read (fdsid::FrequencyUnits; review findings 11 and 36).
void add_frequency_unit_options(CLI::App* sub, FrequencyUnits& units);
/// --strict: an estimate unusable in double precision (fdsid::usable_precision
/// false) exits 1 and writes nothing (review finding 38).
void add_strict_option(CLI::App* sub, bool& strict);
/// --max-iterations N (1 … 10⁶) of the refinement `refine_flag` names: the
/// Levenberg–Marquardt iteration limit; `value` stays 0 when not given. The
/// command refuses it without its refinement (require_refinement_for_limit).
void add_max_iterations_option(CLI::App* sub, int& value, const std::string& refine_flag);
/// Error(Input) when --max-iterations was given (`value` > 0) but not the
/// refinement it limits (a limit that would silently do nothing).
void require_refinement_for_limit(int value, bool refine, const std::string& refine_flag);
/// With --strict and an unusable estimate: one line on stderr, true (the
/// caller returns 1 before writing anything).
bool refused_as_unusable(bool strict, double error_estimate);
/// A model file as validate, gap and simulate-records read it: its JSON (the
/// fields beside the model, e.g. "omega_band"), the model, and the warning
/// when the file's own diagnostics say it is unusable in double precision
/// ("usable": false; review finding 2 of stop 48: they said nothing), or "".
struct ModelFile {
  nlohmann::json json;
  StateSpace model;
  std::string unusable;
};
ModelFile read_model_with_diagnostics(const std::string& path);
/// The record's columns against those the model was identified from (its
/// "source": input_columns, output_columns, which identify-frf writes when
/// columns are named); validate and gap read models whose rows are outputs
/// in that order (a user review: the F-16's three outputs given in another
/// order were scored and labelled against the wrong rows, exit 0).
/// Error(Input) when the names given are the model's in another order;
/// a note when they differ otherwise (another record of the same quantities,
/// e.g. the cascaded tanks' uVal, yVal beside uEst, yEst, is legitimate);
/// "" when they agree or either side names none.
std::string selection_against_model(const nlohmann::json& model_json, const RecordSelection& selection,
                                    const std::string& model_path);

// ---------------------------------------------------------------------------
// Output

using fdsid::sci;  // fdsid/format.hpp: the one home of the number formats

/// Writes j.dump(2) to `path` (- = stdout) when a path was given.
void emit_json(const std::string& path, const nlohmann::json& j);
/// Builds the figure and draws it into `path` only when a path was given
/// (at F = 10⁶ an unused figure was 240 MB of identify-frf's peak).
void emit_plot(const std::string& path, const std::function<plot::Figure()>& figure);
/// Progress of a long run on stderr, only when stderr is a terminal (quiet in
/// pipes, logs and tests).
std::function<void(int, int)> progress(const std::string& what);

/// "Nothing lost": an output may not be one of the command's inputs (it would
/// be replaced by the result, or half-written on a failure). Compared as files
/// when both exist, else by their normalised paths.
void refuse_overwrite(const std::string& output, std::initializer_list<std::string> inputs, const char* option);

/// Prints the human summary unless the JSON goes to stdout.
struct Out {
  bool quiet;
  std::ostream* to = &std::cout;  ///< std::cerr where stdout carries the command's data (e.g. --out -)
  template <class T>
  Out& operator<<(const T& v) {
    if (!quiet) *to << v;
    return *this;
  }
};

/// "poles:  re+imi  ..." and a newline.
void print_poles(Out& out, const Eigen::VectorXcd& poles);

/// One "note: …" line per note, one "warning: …" line per warning: the
/// prefixes every command's summary gives them.
void print_notes(Out& out, const std::vector<std::string>& notes);
void print_warnings(Out& out, const std::vector<std::string>& warnings);

/// The record's excited lines outside the band the model was identified on
/// (its JSON's "omega_band", identify-frf writes it), as a warning: "" when
/// all lie inside or the model has no band. validate and gap both give it.
std::string lines_outside_band(const nlohmann::json& model_json, const StateSpace& model, const RecordMeta& meta);

}  // namespace fdsid::cli
