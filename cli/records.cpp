// fdsid frf and fdsid validate: measured periodic records as users have them
// (issue 14). frf turns a record into an FRF file with its variance (Pintelon
// 2002 Section 4.1); validate scores a model on a record it was not
// identified from (the NRMSE fit of MATLAB's compare).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fdsid/records.hpp"
#include "fdsid/workflow.hpp"

namespace fdsid::cli {

namespace {

struct FrfCommand {
  std::string data_path, meta_path, out_path, json_path;
  RecordSelection selection;
  Domain domain = Domain::Discrete;
};

int run_frf(const FrfCommand& c) {
  refuse_overwrite(c.out_path, {c.data_path, c.meta_path}, "--out");
  refuse_overwrite(c.json_path, {c.data_path, c.meta_path, c.out_path}, "--json");
  if (c.json_path == "-" && c.out_path == "-")
    throw Error(ErrorKind::Input, "--json", "- (stdout) needs --out FILE: the CSV goes to stdout otherwise");
  const Records rec = read_records(c.data_path, c.meta_path, c.selection);
  if (rec.inputs != 1 || rec.samples.cols() != 2)
    throw Error(ErrorKind::Input, c.data_path,
                "has " + std::to_string(rec.inputs) + " input and " + std::to_string(rec.samples.cols() - rec.inputs) +
                    " output columns; an FRF file holds one input and one output: choose them with --input NAME "
                    "--output NAME");
  FrfData frf;
  try {
    frf = frf_from_records(record_statistics(rec.samples, rec.inputs, rec.meta, c.domain));
  } catch (const Error& e) {
    throw e.within(c.data_path + " with " + c.meta_path);
  }
  write_text_file(c.out_path, frf_csv(frf));
  // With the CSV on stdout (--out -) the summary goes to stderr: on stdout
  // it followed the rows, and identify-frf refused the file (a user review).
  Out out{c.json_path == "-", c.out_path == "-" ? &std::cerr : &std::cout};
  // The command that identifies from the file (summary and JSON "identify").
  const std::string identify =
      "identify-frf --frf " + (c.out_path == "-" ? std::string("FILE") : c.out_path) +
      (c.domain == Domain::Continuous ? " --domain continuous" : "") +
      (rec.meta.periods >= 4 ? " --frf-periods " + std::to_string(rec.meta.periods) : std::string());
  out << "wrote " << c.out_path << ": G = Y/U and G_var at " << frf.frequencies() << " excited lines from M = "
      << rec.meta.periods << " periods (omega in " << (c.domain == Domain::Discrete ? "rad/sample" : "rad/s")
      << "; " << identify << ")\n";
  // G_var is a sample variance over the periods (identify-frf --frf-periods
  // says so); below 4 periods its law has no finite variance (the F(2, 2M − 2)
  // terms), and identify-frf from records refuses such M.
  if (rec.meta.periods < 4)
    out << "warning: G_var is a sample variance over only M = " << rec.meta.periods
        << " periods: identify-frf --frf reads it as a known variance and judges the fit by that law, which is far "
           "off at this M (identify-frf needs M >= 4 for the sample law: use more periods)\n";
  emit_json(c.json_path, {{"data", c.data_path},
                          {"meta", c.meta_path},
                          {"out", c.out_path},
                          {"domain", to_string(c.domain)},
                          {"frequencies", frf.frequencies()},
                          {"periods", rec.meta.periods},
                          {"variance", "first-order E|dG|^2 of Y/U from the sample (co)variances over the periods / M"},
                          {"identify", identify}});
  return 0;
}

struct ValidateCommand {
  std::string model_path, data_path, meta_path, json_path;
  RecordSelection selection;
  double min_fit = -1e300;  // percent; below it: exit 1
};

int run_validate(const ValidateCommand& c) {
  refuse_overwrite(c.json_path, {c.model_path, c.data_path, c.meta_path}, "--json");
  const ModelFile file = read_model_with_diagnostics(c.model_path);
  const StateSpace& model = file.model;
  std::vector<std::string> notes;
  if (std::string n = selection_against_model(file.json, c.selection, c.model_path); !n.empty())
    notes.push_back(std::move(n));
  // A user review: validating on the very record the model was identified
  // from printed fit 99 % as if the model had been validated.
  if (file.json.contains("source") && file.json["source"].is_object() && file.json["source"].contains("data") &&
      file.json["source"]["data"].is_string()) {
    std::error_code ec;
    if (std::filesystem::equivalent(file.json["source"]["data"].get<std::string>(), c.data_path, ec) && !ec)
      notes.push_back("this is the record the model was identified from (its source.data): the fit is in-sample, "
                      "not a validation; give a record the identification did not see");
  }
  const Records rec = read_records(c.data_path, c.meta_path, c.selection);
  std::vector<std::string> warnings;
  if (!file.unusable.empty()) warnings.push_back(file.unusable);
  if (std::string w = lines_outside_band(file.json, model, rec.meta); !w.empty()) warnings.push_back(std::move(w));
  RecordFit fit;
  try {
    fit = fit_on_record(model, rec);
  } catch (const Error& e) {
    throw e.within(c.model_path + " on " + c.data_path);
  }
  Out out{c.json_path == "-"};
  const int m = rec.inputs;
  nlohmann::json outputs = nlohmann::json::array();
  bool below = false;
  for (size_t o = 0; o < fit.nrmse.size(); ++o) {
    const std::string name =
        c.selection.outputs.empty() ? "output " + std::to_string(o + 1) : c.selection.outputs[o];
    out << name << ": fit " << fmt(fit.fit_percent[o], 4) << " % (NRMSE " << fmt(fit.nrmse[o], 4) << ")\n";
    outputs.push_back({{"output", name}, {"column", m + static_cast<int>(o) + 1}, {"nrmse", fit.nrmse[o]},
                       {"fit_percent", fit.fit_percent[o]}});
    below = below || fit.fit_percent[o] < c.min_fit;
  }
  out << "the model's periodic steady-state response to the record's input against its output, both averaged over "
      << fit.periods << (fit.periods == 1 ? " period" : " periods") << ", DC left out (fit = 100 (1 - ||y - yhat|| / ||y - mean y||), as MATLAB's compare)\n";
  if (below) out << "below --min-fit " << fmt(c.min_fit, 4) << " %\n";
  print_notes(out, notes);
  print_warnings(out, warnings);
  emit_json(c.json_path, {{"model", c.model_path},
                          {"data", c.data_path},
                          {"meta", c.meta_path},
                          {"periods_averaged", fit.periods},
                          {"lines", fit.lines},
                          {"outputs", outputs},
                          {"warnings", warnings},
                          {"notes", notes},
                          {"pass", !below}});
  return below ? 1 : 0;
}

}  // namespace

void register_records(CLI::App& app, Action& chosen) {
  auto f = std::make_shared<FrfCommand>();
  auto* frf = app.add_subcommand("frf", "periodic records to an FRF file (G = Y/U with its variance, SISO)");
  frf->add_option("--data", f->data_path, "periodic records CSV")->required();
  frf->add_option("--meta", f->meta_path, "meta JSON of the records")->required();
  frf->add_option("--out", f->out_path, "FRF CSV to write: omega,G_re,G_im,G_var")->check(output_path("--out"))->required();
  frf->add_option("--domain", f->domain, "discrete (omega in rad/sample) or continuous (rad/s)")
      ->transform(choice(domain_names()))
      ->default_str(to_string(Domain::Discrete));
  add_json_option(frf, f->json_path, "write a record of what was written here (- = stdout)");
  add_record_selection_options(frf, f->selection);
  on_parsed(frf, f, chosen, run_frf);

  auto v = std::make_shared<ValidateCommand>();
  auto* val = app.add_subcommand("validate", "fit of a model on a periodic record (NRMSE per output, as MATLAB's compare)");
  val->add_option("--model", v->model_path, "model JSON (discrete with the record's sample time, or continuous)")
      ->required();
  val->add_option("--data", v->data_path, "periodic records CSV")->required();
  val->add_option("--meta", v->meta_path, "meta JSON of the records")->required();
  val->add_option("--min-fit", v->min_fit, "exit 1 when an output's fit is below this many percent (default: no threshold)")
      // a fit is 100 % at best: --min-fit 150 always failed
      ->check(number_where([](double v) { return v <= 100; }, "a percentage <= 100", "PERCENT<=100"));
  add_json_option(val, v->json_path, "write the fit here (- = stdout)");
  add_record_selection_options(val, v->selection);
  on_parsed(val, v, chosen, run_validate);
}

}  // namespace fdsid::cli
