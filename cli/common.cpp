#include "common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <tuple>
#include <vector>

#include <unistd.h>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"

namespace fdsid::cli {

const NameTable<Precision> kPrecisions = {{"double", Precision::Double}, {"high", Precision::High}};

bool unknown_subcommand(const CLI::App& app, int argc, char** argv) {
  auto find = [](const CLI::App& parent, const std::string& word) -> const CLI::App* {
    const auto found = parent.get_subcommands([&](const CLI::App* s) { return s->get_name() == word; });
    return found.empty() ? nullptr : found.front();
  };
  auto is_word = [](const std::string& w) { return !w.empty() && w[0] != '-'; };
  if (argc < 2 || !is_word(argv[1])) return false;
  const CLI::App* top = find(app, argv[1]);
  if (top == nullptr) {
    std::cerr << "fdsid: unknown subcommand \"" << argv[1] << "\" (run fdsid --help for the list)\n";
    return true;
  }
  if (top->get_name() == "reproduce" && argc > 2 && is_word(argv[2]) && find(*top, argv[2]) == nullptr) {
    std::cerr << "fdsid: reproduce: unknown target \"" << argv[2] << "\" (expected table1, table2, fig1 or fig2)\n";
    return true;
  }
  return false;
}

std::string unexpected_arguments(const CLI::App& app, int argc, char** argv, const std::string& cli11_message) {
  // The subcommand (and reproduce's target) named on the command line.
  const CLI::App* sub = nullptr;
  std::string name;
  for (int i = 1; i < argc && i <= 2; ++i) {
    const CLI::App* parent = sub ? sub : &app;
    const auto found = parent->get_subcommands([&](const CLI::App* s) { return s->get_name() == argv[i]; });
    if (found.empty()) break;
    sub = found.front();
    name += (name.empty() ? "" : " ") + sub->get_name();
  }
  if (sub == nullptr) return cli11_message;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) continue;
    const std::string opt = arg.substr(0, arg.find('='));
    std::string best;
    size_t best_d = std::string::npos;
    bool known = false;
    for (const CLI::Option* o : sub->get_options()) {
      for (const std::string& ln : o->get_lnames()) {
        if ("--" + ln == opt) known = true;
        // Near: at most one edit per three letters of the name (so --nx is
        // not taken for --p), and the nearest wins.
        const size_t d = edit_distance(opt, "--" + ln);
        if (d <= std::max<size_t>(1, ln.size() / 3) && d < best_d) best_d = d, best = "--" + ln;
      }
    }
    if (known) continue;
    return "unknown option " + opt + " of " + name + (best.empty() ? "" : " (did you mean " + best + "?)") +
           "; fdsid " + name + " --help lists them";
  }
  return cli11_message;
}

CLI::Validator order_value() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        if (s == "auto") {
          s = "0";
          return {};
        }
        char* end = nullptr;
        const long v = std::strtol(s.c_str(), &end, 10);
        if (s.empty() || *end != '\0' || v < 1 || v > 1000)
          return "\"" + s + "\" is neither a positive integer nor auto";
        return {};
      },
      "n|auto");
}

CLI::Validator count_at_least(long lo) {
  return CLI::Validator(
      [lo](std::string& s) -> std::string {
        char* end = nullptr;
        errno = 0;
        const long v = std::strtol(s.c_str(), &end, 10);
        if (s.empty() || *end != '\0' || errno != 0 || v < lo || v > std::numeric_limits<int>::max())
          return "\"" + s + "\" is not a whole number >= " + std::to_string(lo);
        return {};
      },
      "INT>=" + std::to_string(lo));
}

CLI::Validator whole_count() { return count_at_least(0); }

CLI::Validator number_where(std::function<bool(double)> accepts, const std::string& what, const std::string& type_name) {
  return CLI::Validator(
      [accepts = std::move(accepts), what](std::string& s) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(s.c_str(), &end);
        if (s.empty() || *end != '\0' || !std::isfinite(x) || !accepts(x)) return "\"" + s + "\" is not " + what;
        return {};
      },
      type_name);
}

CLI::Validator finite_number(double lo, bool lo_allowed) {
  const std::string bound = (lo_allowed ? ">= " : "> ") + fmt(lo, 6);
  return number_where([lo, lo_allowed](double x) { return lo_allowed ? x >= lo : x > lo; }, "a finite number " + bound,
                      "FLOAT" + bound);
}

CLI::Validator output_path(const std::string& option) {
  return CLI::Validator(
      [option](std::string& s) -> std::string {
        if (s.empty()) return "empty path (use - for stdout)";
        try {
          require_writable_path(s, option);
        } catch (const Error& e) {
          return e.message();
        }
        return {};
      },
      "FILE");
}

CLI::Option* add_json_option(CLI::App* sub, std::string& path, const std::string& what) {
  return sub->add_option("--json", path, what)->check(output_path("--json"));
}

CLI::Option* add_plot_option(CLI::App* sub, std::string& path) {
  return sub->add_option("--plot", path, "draw the figure into this file (.svg or .png)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            try {
              plot::check_plot_path(s);
              require_writable_path(s, "--plot");
            } catch (const Error& e) {
              return e.message();
            }
            return {};
          },
          "FILE.svg|FILE.png"));
}

void add_record_selection_options(CLI::App* sub, RecordSelection& selection) {
  sub->add_option("--input", selection.inputs,
                  "records: the input column(s) by header name, e.g. --input Force (with --output; any header, "
                  "other columns ignored)");
  sub->add_option("--output", selection.outputs, "records: the output column(s) by header name, e.g. --output Acceleration1");
  sub->add_option("--skip-periods", selection.skip_periods,
                  "records: drop this many leading periods (a transient); the meta's periods are reduced by it")
      ->check(whole_count())
      ->capture_default_str();
  sub->add_option("--use-periods", selection.use_periods,
                  "records: after the skipped periods use only this many (e.g. --skip-periods 1 --use-periods 4: "
                  "periods 2-5; the rest can validate); default all")
      ->check(CLI::PositiveNumber);
}

void add_frequency_unit_options(CLI::App* sub, FrequencyUnits& units) {
  sub->add_option("--frequency-unit", units.hz,
                  "unit of the FRF file's omega column: rad (default; rad/sample, or rad/s with --sample-time or "
                  "--domain continuous) or hz (cycles/sample, or Hz with --sample-time or --domain continuous)")
      ->transform(choice(std::map<std::string, bool>{{"rad", false}, {"hz", true}}, "is neither rad nor hz"))
      ->each([&units](const std::string&) { units.unit_given = true; })
      ->type_name("UNIT");
  sub->add_option("--sample-time", units.sample_time_text,
                  "discrete time: the FRF's omega column is per second and Ts (s) the sample time (omega x Ts in "
                  "rad/sample; the model carries Ts); default: the column is per sample")
      ->check(number_where([](double v) { return v > 0; }, "a positive number of seconds", "Ts"))
      ->each([&units](const std::string& s) { units.sample_time = std::strtod(s.c_str(), nullptr); });
}

void add_strict_option(CLI::App* sub, bool& strict) {
  sub->add_flag("--strict", strict,
                "exit 1 and write nothing when the estimate is unusable in double precision (its estimated relative "
                "error is 1 or more: no correct digit)");
}

void add_max_iterations_option(CLI::App* sub, int& value, const std::string& refine_flag) {
  sub->add_option("--max-iterations", value,
                  "Levenberg-Marquardt iterations of " + refine_flag +
                      " (default 200); raise it when the refinement stops at the iteration limit (an ill-determined "
                      "direction, e.g. a mode outside the band, can take thousands)")
      ->check(CLI::Range(1, 1000000));
}

void require_refinement_for_limit(int value, bool refine, const std::string& refine_flag) {
  if (value > 0 && !refine)
    throw Error(ErrorKind::Input, "--max-iterations", "limits " + refine_flag + "'s iterations; add " + refine_flag +
                                                          " or drop --max-iterations");
}

ModelFile read_model_with_diagnostics(const std::string& path) {
  ModelFile f;
  f.json = read_model_file(path);
  f.model = model_from_json(f.json, path);
  if (!f.json.is_object() || !f.json.contains("diagnostics")) return f;
  const nlohmann::json& d = f.json["diagnostics"];
  if (!d.is_object() || !d.contains("usable") || !d["usable"].is_boolean() || d["usable"].get<bool>()) return f;
  f.unusable = path + " says its estimate is unusable in double precision (diagnostics.usable false: no correct digit in " +
         "its G or poles), so every number computed from it here may be too; identify it again (see the file's "
         "warnings: --precision high, a lower order or another r)";
  return f;
}

namespace {
std::vector<std::string> source_columns(const nlohmann::json& model_json, const char* field) {
  if (!model_json.is_object() || !model_json.contains("source") || !model_json["source"].is_object()) return {};
  const nlohmann::json& f = model_json["source"].value(field, nlohmann::json());
  std::vector<std::string> names;
  if (!f.is_array()) return {};
  for (const nlohmann::json& n : f) {
    if (!n.is_string()) return {};
    names.push_back(n.get<std::string>());
  }
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : " ") + n;
  return s;
}
}  // namespace

std::string selection_against_model(const nlohmann::json& model_json, const RecordSelection& selection,
                                    const std::string& model_path) {
  const std::vector<std::string> ins = source_columns(model_json, "input_columns"),
                                 outs = source_columns(model_json, "output_columns");
  bool differ = false;
  for (const auto& [given, model, option] : {std::tuple{&selection.inputs, &ins, "--input"},
                                             std::tuple{&selection.outputs, &outs, "--output"}}) {
    if (given->empty() || model->empty() || *given == *model) continue;
    std::vector<std::string> a = *given, b = *model;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    if (a == b)
      throw Error(ErrorKind::Input, std::string(option) + " " + joined(*given),
                  "the model " + model_path + " was identified with these columns in the order " + joined(*model) +
                      " (its \"source\"), and its rows follow it: give " + option + " " + joined(*model));
    differ = true;
  }
  if (!differ) return "";
  return "the model was identified from input(s) " + joined(ins) + " and output(s) " + joined(outs) +
         " (its \"source\"); this record is read from " +
         (selection.inputs.empty() ? std::string("its u column(s)") : joined(selection.inputs)) + " and " +
         (selection.outputs.empty() ? std::string("its y column(s)") : joined(selection.outputs)) +
         ": the scores compare the model with these quantities";
}

bool refused_as_unusable(bool strict, double error_estimate) {
  if (!strict || usable_precision(error_estimate)) return false;
  std::cerr << "fdsid: --strict: the estimate is unusable in double precision (estimated relative error "
            << fmt(error_estimate, 3) << "); nothing written\n";
  return true;
}

void emit_json(const std::string& path, const nlohmann::json& j) {
  if (!path.empty()) write_text_file(path, j.dump(2) + "\n");
}

void emit_plot(const std::string& path, const std::function<plot::Figure()>& figure) {
  if (!path.empty()) plot::render(figure(), path);
}

std::function<void(int, int)> progress(const std::string& what) {
  if (!isatty(fileno(stderr))) return {};
  return [what](int done, int total) {
    std::fprintf(stderr, "\r%s: %d/%d", what.c_str(), done, total);
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
}

void refuse_overwrite(const std::string& output, std::initializer_list<std::string> inputs, const char* option) {
  if (output.empty() || output == "-") return;
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string& in : inputs) {
    if (in.empty()) continue;
    const bool same = fs::exists(output, ec) && fs::exists(in, ec)
                          ? fs::equivalent(output, in, ec)
                          : fs::weakly_canonical(output, ec) == fs::weakly_canonical(in, ec);
    if (same)
      throw Error(ErrorKind::Input, option,
                  "\"" + output + "\" is also an input of this command; refusing to overwrite it");
  }
}

void print_poles(Out& out, const Eigen::VectorXcd& poles) {
  out << "poles:";
  for (Eigen::Index i = 0; i < poles.size(); ++i)
    out << "  " << poles(i).real() << (poles(i).imag() < 0 ? "" : "+") << poles(i).imag() << "i";
  out << "\n";
}

namespace {
void print_prefixed(Out& out, const char* prefix, const std::vector<std::string>& lines) {
  for (const std::string& line : lines) out << prefix << line << "\n";
}
}  // namespace

void print_notes(Out& out, const std::vector<std::string>& notes) { print_prefixed(out, "note: ", notes); }

void print_warnings(Out& out, const std::vector<std::string>& warnings) { print_prefixed(out, "warning: ", warnings); }

// Review finding 5 of stop 47: an F-16 model identified on 2-15 Hz scored
// -4.06 % on a record to 60 Hz without a word. A model from identify-frf
// carries the band of its data ("omega_band"); the record's excited lines
// beyond it (by more than rounding, 1e-9 relative) are extrapolation and
// named. A model without the field (another tool's) is scored as before.
std::string lines_outside_band(const nlohmann::json& model_json, const StateSpace& model, const RecordMeta& meta) {
  const nlohmann::json* band = model_json.contains("omega_band") ? &model_json["omega_band"] : nullptr;
  if (!band || !band->is_array() || band->size() != 2 || !(*band)[0].is_number() || !(*band)[1].is_number()) return "";
  const double lo = (*band)[0].get<double>(), hi = (*band)[1].get<double>();
  // ω of line k: 2πk/P rad/sample, or 2πk/(P Ts) rad/s in continuous time.
  const double per_line = 2 * M_PI / meta.period / (model.domain == Domain::Continuous ? meta.sample_time : 1.0);
  const double to_hz = 1 / (2 * M_PI * (model.domain == Domain::Continuous ? 1.0 : meta.sample_time));
  int below = 0, above = 0;
  double lowest = lo, highest = hi;
  for (int k : meta.excited_lines) {
    const double w = k * per_line;
    if (w < lo * (1 - 1e-9)) ++below, lowest = std::min(lowest, w);
    if (w > hi * (1 + 1e-9)) ++above, highest = std::max(highest, w);
  }
  if (below + above == 0) return "";
  std::string where;
  if (below > 0) where = std::to_string(below) + " below it (down to " + fmt(lowest * to_hz, 4) + " Hz)";
  if (above > 0)
    where += (below > 0 ? ", " : "") + std::to_string(above) + " above it (up to " + fmt(highest * to_hz, 4) + " Hz)";
  return std::to_string(below + above) + " of the record's " + std::to_string(meta.excited_lines.size()) +
         " excited lines lie outside the band the model was identified on (" + fmt(lo * to_hz, 4) + " to " +
         fmt(hi * to_hz, 4) + " Hz; Hz = cycles/sample when Ts = 1): " + where +
         "; the model is extrapolated there";
}

}  // namespace fdsid::cli
