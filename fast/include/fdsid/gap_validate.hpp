#pragma once
/// Blind validation of the gap diagnosis (`fdsid gap-validate`, CONTRACTS.md):
/// cases from fdsid/gap_cases.hpp whose effects are withheld. For each case
/// the three files a user would have (model JSON, u,y CSV, meta JSON) are
/// written to a working directory and read back through the same readers as
/// `fdsid gap`; the diagnosis sees nothing else. Scoring happens afterwards
/// against the truth kept in memory.
///
/// Schedule (cycle of 20 cases): 2 effect-free, the 7 effects alone at Clear
/// strength, the 7 alone at Subtle strength, 4 pairs of distinct effects
/// (drawn at random, Clear). Case i uses seed (seed · 1000003 + i).
/// Families (gap_cases.hpp): classic (the default), structure (every case
/// from the structure family: lightly damped many-mode structures, noise
/// rising with frequency, the nonlinearity a spring in the loop), or mixed
/// (cycles of 20 alternate: classic, structure, classic, …). Any of them can
/// be continuous-time (`continuous`; gap_cases.hpp). Either family
/// can take measured noise instead of its synthetic noise (`measured_noise`;
/// gap_cases.hpp): the same draws otherwise, P the noise record's.
#include <cstdint>
#include <memory>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fdsid/gap.hpp"
#include "fdsid/gap_cases.hpp"
#include "fdsid/names.hpp"

namespace fdsid {

struct GapValidationOptions {
  int cases = 100;
  GapFamily family = GapFamily::Classic;
  bool continuous = false;  ///< continuous-time models and true systems (gap_cases.hpp)
  std::uint64_t seed = 1;
  int period = 1024, periods = 8;
  std::string workdir;  ///< where the case files go (created; removed afterwards unless keep_files)
  bool keep_files = false;  ///< keep the case files, and each case's truth.json (the withheld truth)
  int threads = 0;      ///< 0: hardware concurrency
  std::shared_ptr<const MeasuredNoise> measured_noise;  ///< null: each family's synthetic noise
  GapOptions gap;
  std::function<void(int done, int total)> progress;  ///< called from the worker threads, serialised
};

struct GapValidationCase {
  int index = 0;
  std::uint64_t seed = 0;
  std::string category;   ///< "none", "clear", "subtle", "pair"
  std::string truth, verdict;  ///< effect sets joined by "+", "none" when empty
  bool correct = false;
  /// correct, or the verdict with its one linear effect replaced by one of the
  /// report's alternatives (GapReport::alternatives: indistinguishable on
  /// the record) or with one of its possible additions
  /// (GapReport::possible_additions) added is the truth
  bool correct_up_to_alternatives = false;
  /// What the report named beside its verdict: alternatives + possible additions
  int named_alternatives = 0;
  double gap_before = 0, gap_after = 0;
  int truth_bands = 0, bands_hit = 0;  ///< truth bands overlapped by a reported band
  /// The report's equal-noise-power-per-period test (GapReport::p_period_power)
  /// and whether it was noted (p < effect_alpha).
  double p_period_power = 1;
  bool period_power_noted = false;
  /// The report's independent-periods test (GapReport::p_period_independence)
  /// and whether it was noted.
  double p_period_independence = 1;
  bool periods_dependent_noted = false;
  /// Chosen mode effects the report names stand-ins (GapReport::stand_ins).
  int stand_ins = 0;
  /// GapReport::p_below: what remains is below the noise when < the level.
  double p_below = 1;
  std::string error;      ///< the diagnosis refused the case (counted as wrong)
};

struct GapValidation {
  int cases = 0;
  double accuracy = 0;  ///< exact verdict sets, all cases
  std::map<std::string, std::map<std::string, int>> confusion;  ///< truth → verdict → count
  std::map<std::string, std::array<int, 2>> by_category;        ///< category → {correct, total}
  std::map<std::string, int> correct_up_to_alternatives;         ///< category → cases (GapValidationCase)
  double false_alarm_rate = 0;  ///< effect-free cases with a non-empty verdict
  double band_hit_rate = 0;     ///< truth bands hit / truth bands, over cases with effects
  int false_alarms = 0;         ///< effect-free cases with a non-empty verdict
  /// Cases whose report notes that the noise power differs between periods,
  /// and how many of the false alarms carry that note.
  int period_power_noted = 0, false_alarms_noted = 0;
  /// The same for the note that adjacent periods' noise is alike.
  int periods_dependent_noted = 0, false_alarms_dependent_noted = 0;
  /// Cases whose report names a stand-in (GapReport::stand_ins), and how many
  /// of them are correct verdicts (a stand-in there is a false note).
  int stand_in_noted = 0, stand_in_correct = 0;
  /// Cases whose remaining gap lies below the noise (p_below under the
  /// level: the effects fitted noise too), and how many are correct verdicts.
  int below_noise = 0, below_noise_correct = 0;
  std::vector<double> gap_after_correct;  ///< sorted, correct verdicts with effects
  std::vector<GapValidationCase> rows;
  std::vector<std::string> noise_sources;  ///< measured noise's records (empty: synthetic noise)
  int noise_pool = 0;                      ///< noise periods they held
};

/// Issue 17's targets: clear single effects ≥ 0.99, subtle singles and pairs
/// ≥ 0.90, false alarms ≤ 0.02, gap_after ≤ 2 on every correct verdict.
inline constexpr double kTargetClear = 0.99, kTargetSubtleOrPair = 0.90, kTargetFalseAlarms = 0.02;

GapValidation validate_gap(const GapValidationOptions& options);

/// CONTRACTS.md's gap-validate JSON ({"cases", "accuracy", "confusion", …}) with
/// the per-category rates, the targets of the gap issue and whether each is met.
nlohmann::json gap_validation_to_json(const GapValidation& v);

/// Whether the targets are met: ≥ 95 % correct on clear single
/// effects, ≥ 80 % on subtle or paired effects, ≤ 5 % false alarms, and
/// gap_after ≤ 2 on (at least 90 % of) the correct verdicts.
bool gap_validation_targets_met(const GapValidation& v);

}  // namespace fdsid
