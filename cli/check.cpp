// fdsid check: the validation oracle (a candidate against the 50-digit reference).
#include <memory>

#include "common.hpp"
#include "high_precision.hpp"

namespace fdsid::cli {

namespace {

struct CheckCommand {
  std::string model_path, data_path, json_path;
  double tolerance = 0;  // 0: the derived default
};

int run(const CheckCommand& c) {
  refuse_overwrite(c.json_path, {c.model_path, c.data_path}, "--json");
  return check(c.json_path, c.model_path, c.data_path, c.tolerance);
}

}  // namespace

void register_check(CLI::App& app, Action& chosen) {
  auto c = std::make_shared<CheckCommand>();
  auto* chk = app.add_subcommand("check", "oracle: compare a candidate model with the high-precision reference");
  chk->add_option("--model", c->model_path, "candidate model JSON")->required();
  chk->add_option("--data", c->data_path, "power-spectrum CSV the candidate was identified from")->required();
  add_json_option(chk, c->json_path, "write the comparison here (- = stdout)");
  chk->add_option("--tolerance", c->tolerance, "relative tolerance (default: derived, see README)");
  on_parsed(chk, c, chosen, run);
}

}  // namespace fdsid::cli
