#include "fdsid/gap_validate.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"
#include "fdsid/gap_cases.hpp"
#include "fdsid/io.hpp"
#include "progress.hpp"

namespace fdsid {
namespace {

// The effect names sorted and joined by "+"; "none" when empty.
std::string joined(const std::vector<Effect>& effects) {
  if (effects.empty()) return "none";
  std::vector<std::string> names;
  for (Effect e : effects) names.emplace_back(to_string(e));
  std::sort(names.begin(), names.end());
  std::string s;
  for (const std::string& e : names) s += (s.empty() ? "" : "+") + e;
  return s;
}

// The i-th case of the schedule in gap_validate.hpp.
GapCaseOptions schedule(const GapValidationOptions& o, int i, std::string& category) {
  GapCaseOptions c;
  c.period = o.period;
  c.periods = o.periods;
  c.seed = o.seed * 1000003ULL + static_cast<std::uint64_t>(i);
  c.structure = o.family == GapFamily::Structure || (o.family == GapFamily::Mixed && (i / 20) % 2 == 1);
  c.measured_noise = o.measured_noise;
  c.continuous = o.continuous;
  const auto& names = kAllEffects;
  const int slot = i % 20;
  if (slot < 2) {
    category = "none";
    c.strength = Strength::None;
  } else if (slot < 9) {
    category = "clear";
    c.effects = {names[slot - 2]};
    c.strength = Strength::Clear;
  } else if (slot < 16) {
    category = "subtle";
    c.effects = {names[slot - 9]};
    c.strength = Strength::Subtle;
  } else {
    category = "pair";
    std::mt19937_64 g(c.seed ^ 0x9e3779b97f4a7c15ULL);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(names.size()) - 1);
    const int a = pick(g);
    int b = pick(g);
    while (b == a) b = pick(g);
    c.effects = {names[a], names[b]};
    c.strength = Strength::Clear;
  }
  return c;
}

// Makes case i, writes the user's three files, diagnoses from the files alone,
// then scores.
GapValidationCase run_case(const GapValidationOptions& o, int i, const std::filesystem::path& dir) {
  GapValidationCase r;
  r.index = i;
  const GapCaseOptions co = schedule(o, i, r.category);
  r.seed = co.seed;
  const GapCase c = make_gap_case(co);
  r.truth = joined(c.effects);
  r.truth_bands = static_cast<int>(c.effects.empty() ? 0 : c.bands.size());
  const std::filesystem::path d = dir / ("case" + std::to_string(i));
  std::filesystem::create_directories(d);
  const std::string model_path = (d / "model.json").string(), data_path = (d / "data.csv").string(),
                    meta_path = (d / "meta.json").string();
  write_text_file(model_path, model_to_json(c.sim_model).dump(2) + "\n");
  write_text_file(data_path, records_csv(c.record));
  write_text_file(meta_path, meta_to_json(c.meta).dump() + "\n");
  // The withheld truth, for a user who keeps the files (never read below).
  if (o.keep_files) write_text_file((d / "truth.json").string(), c.truth.dump(2) + "\n");
  try {  // the diagnosis: the three files only
    const StateSpace model = read_model(model_path);
    int inputs = 0;
    const Eigen::MatrixXd rec = read_records_csv(data_path, inputs);
    const RecordMeta meta = read_meta(meta_path);
    const GapReport rep = diagnose_gap(model, rec, inputs, meta, o.gap);
    r.verdict = joined(rep.present);
    // Whether the verdict is the truth with its one linear effect swapped for
    // `swap` and/or `extra` added, as the report's named alternatives allow.
    const auto truth_with = [&](std::optional<Effect> swap, std::optional<Effect> extra) {
      std::vector<Effect> v = rep.present;
      for (Effect& e : v)
        if (swap && is_linear(e)) e = *swap;
      if (extra) v.push_back(*extra);
      return joined(v) == r.truth;
    };
    for (const auto& alt : rep.alternatives) r.correct_up_to_alternatives |= truth_with(alt.first, std::nullopt);
    for (const auto& [g, h] : rep.alternative_pairs) r.correct_up_to_alternatives |= truth_with(g, h);
    for (const auto& add : rep.possible_additions) r.correct_up_to_alternatives |= truth_with(std::nullopt, add.first);
    r.named_alternatives =
        static_cast<int>(rep.alternatives.size() + rep.alternative_pairs.size() + rep.possible_additions.size());
    r.gap_before = rep.gap_before;
    r.gap_after = rep.gap_after;
    r.p_period_power = rep.p_period_power;
    r.period_power_noted = rep.period_power_unequal();
    r.p_period_independence = rep.p_period_independence;
    r.periods_dependent_noted = rep.periods_dependent();
    r.stand_ins = static_cast<int>(rep.stand_ins.size());
    r.p_below = rep.p_below;
    const double Ts = meta.sample_time;
    for (const auto& tb : c.bands) {  // truth in cycles/sample, report in Hz
      bool hit = false;
      for (const auto& b : rep.bands) hit = hit || (b[0] * Ts <= tb[1] && b[1] * Ts >= tb[0]);
      r.bands_hit += hit && !c.effects.empty();
    }
  } catch (const Error& e) {
    r.verdict = "error";
    r.error = e.what();
  }
  r.correct = r.verdict == r.truth;
  r.correct_up_to_alternatives = r.correct_up_to_alternatives || r.correct;
  if (!o.keep_files) std::filesystem::remove_all(d);
  return r;
}

}  // namespace

GapValidation validate_gap(const GapValidationOptions& o) {
  if (o.cases < 1) throw Error(ErrorKind::Input, "--cases", "must be at least 1");
  namespace fs = std::filesystem;
  // Without --workdir: a fresh folder of its own (mkdtemp). A name made from
  // the seed alone was shared by two runs with the same seed, which then
  // removed each other's files (CliFrf.GapValidate* in parallel under ctest -j2).
  fs::path dir = o.workdir;
  std::error_code ec;
  if (o.workdir.empty()) {
    std::string pattern = (fs::temp_directory_path() / ("fdsid-gap-validate-" + std::to_string(o.seed) + "-XXXXXX")).string();
    if (!mkdtemp(pattern.data()))
      throw Error(ErrorKind::Input, "gap-validate", "cannot create a folder under " + fs::temp_directory_path().string());
    dir = pattern;
  }
  fs::create_directories(dir, ec);
  if (ec) throw Error(ErrorKind::Input, "--workdir", "cannot create \"" + dir.string() + "\": " + ec.message());
  GapValidation v;
  v.cases = o.cases;
  v.rows.resize(o.cases);
  if (o.measured_noise) {
    v.noise_sources = o.measured_noise->sources;
    v.noise_pool = static_cast<int>(o.measured_noise->periods.size());
  }
  std::atomic<int> next{0};
  std::mutex mu;
  ProgressCounter progress(o.progress, o.cases);
  std::string failure;
  auto worker = [&] {
    for (int i; (i = next++) < o.cases;) {
      try {
        v.rows[i] = run_case(o, i, dir);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mu);
        if (failure.empty()) failure = "case " + std::to_string(i) + ": " + e.what();
      }
      progress.add();
    }
  };
  const int threads = std::max(1, std::min(o.cases, o.threads > 0 ? o.threads
                                                                    : static_cast<int>(std::thread::hardware_concurrency())));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  if (o.workdir.empty() && !o.keep_files) fs::remove_all(dir, ec);
  if (!failure.empty()) throw Error(ErrorKind::Numerical, "gap-validate", failure);

  int correct = 0, none = 0, alarms = 0, bands = 0, hits = 0;
  for (const GapValidationCase& r : v.rows) {
    correct += r.correct;
    ++v.confusion[r.truth][r.verdict];
    auto& c = v.by_category[r.category];
    c[0] += r.correct;
    ++c[1];
    v.correct_up_to_alternatives[r.category] += r.correct_up_to_alternatives;
    v.period_power_noted += r.period_power_noted;
    v.periods_dependent_noted += r.periods_dependent_noted;
    v.stand_in_noted += r.stand_ins > 0;
    v.stand_in_correct += r.stand_ins > 0 && r.correct;
    const bool below = r.p_below < o.gap.alpha;
    v.below_noise += below;
    v.below_noise_correct += below && r.correct;
    if (r.category == "none") {
      ++none;
      alarms += r.verdict != "none";
      v.false_alarms_noted += r.verdict != "none" && r.period_power_noted;
      v.false_alarms_dependent_noted += r.verdict != "none" && r.periods_dependent_noted;
    } else {
      bands += r.truth_bands;
      hits += r.bands_hit;
      if (r.correct) v.gap_after_correct.push_back(r.gap_after);
    }
  }
  std::sort(v.gap_after_correct.begin(), v.gap_after_correct.end());
  v.accuracy = static_cast<double>(correct) / o.cases;
  v.false_alarms = alarms;
  v.false_alarm_rate = none ? static_cast<double>(alarms) / none : 0.0;
  v.band_hit_rate = bands ? static_cast<double>(hits) / bands : 0.0;
  return v;
}

namespace {
// up_to_alternatives: count GapValidationCase::correct_up_to_alternatives.
double rate(const GapValidation& v, std::initializer_list<const char*> cats, bool up_to_alternatives) {
  int c = 0, n = 0;
  for (const char* k : cats) {
    const auto it = v.by_category.find(k);
    if (it != v.by_category.end()) {
      const auto a = v.correct_up_to_alternatives.find(k);
      c += up_to_alternatives ? (a == v.correct_up_to_alternatives.end() ? 0 : a->second) : it->second[0];
      n += it->second[1];
    }
  }
  return n ? static_cast<double>(c) / n : NAN;
}
double subtle_or_pair_rate(const GapValidation& v) { return rate(v, {"subtle", "pair"}, false); }
double share_at_most_2(const GapValidation& v) {
  if (v.gap_after_correct.empty()) return NAN;
  return static_cast<double>(std::upper_bound(v.gap_after_correct.begin(), v.gap_after_correct.end(), 2.0) -
                             v.gap_after_correct.begin()) /
         v.gap_after_correct.size();
}
}  // namespace

bool gap_validation_targets_met(const GapValidation& v) {
  auto ok = [](double r, double target, bool above) { return std::isnan(r) || (above ? r >= target : r <= target); };
  return ok(rate(v, {"clear"}, false), kTargetClear, true) && ok(subtle_or_pair_rate(v), kTargetSubtleOrPair, true) &&
         ok(v.false_alarm_rate, kTargetFalseAlarms, false) && ok(share_at_most_2(v), 1.0, true);
}

nlohmann::json gap_validation_to_json(const GapValidation& v) {
  nlohmann::json j;
  j["cases"] = v.cases;
  j["accuracy"] = v.accuracy;
  j["confusion"] = nlohmann::json::object();
  for (const auto& t : v.confusion)
    for (const auto& p : t.second) j["confusion"][t.first][p.first] = p.second;
  for (const auto& c : v.by_category) j["by_category"][c.first] = {{"correct", c.second[0]}, {"cases", c.second[1]}};
  j["clear_single_rate"] = rate(v, {"clear"}, false);
  j["subtle_or_pair_rate"] = subtle_or_pair_rate(v);
  j["clear_single_rate_up_to_alternatives"] = rate(v, {"clear"}, true);
  j["subtle_or_pair_rate_up_to_alternatives"] = rate(v, {"subtle", "pair"}, true);
  j["false_alarm_rate"] = v.false_alarm_rate;
  j["band_hit_rate"] = v.band_hit_rate;
  j["noise"] = v.noise_sources.empty()
                   ? nlohmann::json{{"measured", false}}
                   : nlohmann::json{{"measured", true}, {"sources", v.noise_sources}, {"pool", v.noise_pool}};
  j["period_power_noted"] = {{"cases", v.period_power_noted}, {"false_alarms", v.false_alarms_noted}};
  j["periods_dependent_noted"] = {{"cases", v.periods_dependent_noted},
                                  {"false_alarms", v.false_alarms_dependent_noted}};
  j["stand_in_noted"] = {{"cases", v.stand_in_noted}, {"correct", v.stand_in_correct}};
  j["below_noise"] = {{"cases", v.below_noise}, {"correct", v.below_noise_correct}};
  const auto& g = v.gap_after_correct;
  auto q = [&](double p) { return g.empty() ? NAN : g[static_cast<size_t>(p * (g.size() - 1))]; };
  j["gap_after_correct"] = {{"n", g.size()},     {"median", q(0.5)}, {"p90", q(0.9)},
                            {"max", q(1.0)},      {"share_at_most_2", share_at_most_2(v)}};
  j["targets"] = {{"clear_single_rate", ">= " + fmt(kTargetClear, 2)},
                  {"subtle_or_pair_rate", ">= " + fmt(kTargetSubtleOrPair, 2)},
                  {"false_alarm_rate", "<= " + fmt(kTargetFalseAlarms, 2)},
                  {"gap_after_correct", "<= 2 on every correct verdict"},
                  {"met", gap_validation_targets_met(v)}};
  j["rows"] = nlohmann::json::array();
  for (const GapValidationCase& r : v.rows) {
    nlohmann::json row = {{"index", r.index},         {"seed", r.seed},           {"category", r.category},
                          {"truth", r.truth},         {"verdict", r.verdict},     {"correct", r.correct},
                          {"gap_before", r.gap_before}, {"gap_after", r.gap_after}, {"truth_bands", r.truth_bands},
                          {"bands_hit", r.bands_hit}, {"correct_up_to_alternatives", r.correct_up_to_alternatives},
                          {"named_alternatives", r.named_alternatives},
                          {"p_period_power", r.p_period_power}, {"p_period_independence", r.p_period_independence},
                          {"stand_ins", r.stand_ins}, {"p_below", r.p_below}};
    if (!r.error.empty()) row["error"] = r.error;
    j["rows"].push_back(row);
  }
  return j;
}

}  // namespace fdsid
