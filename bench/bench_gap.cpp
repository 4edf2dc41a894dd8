// Benchmarks of the sim-to-real gap diagnosis (fdsid/gap.hpp) against the
// issue's figures: one diagnosis of an 8 × 1024-sample record under 1 s, and
// gap-validate with 100 cases under 60 s on 2 cores. See bench/README.md.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "fdsid/gap.hpp"
#include "fdsid/gap_cases.hpp"
#include "fdsid/gap_validate.hpp"

namespace {

// One diagnosis of a blind case (P = state.range(0), M = 8) with `effects` withheld.
void BM_Diagnose(benchmark::State& state, std::vector<fdsid::Effect> effects) {
  fdsid::GapCaseOptions o;
  o.period = static_cast<int>(state.range(0));
  o.effects = effects;
  o.strength = effects.empty() ? fdsid::Strength::None : fdsid::Strength::Clear;
  o.seed = 11;
  const fdsid::GapCase c = fdsid::make_gap_case(o);
  for (auto _ : state) {
    const fdsid::GapReport r = fdsid::diagnose_gap(c.sim_model, c.record, 1, c.meta);
    benchmark::DoNotOptimize(r.gap_after);
  }
}
// P = 1024 (stop-era figure: under 1 s) and P = 8192 (issue 17: one 8-period
// record of P = 8192 diagnosed in at most 0.5 s on 2 cores).
BENCHMARK_CAPTURE(BM_Diagnose, none, std::vector<fdsid::Effect>{})->Arg(1024)->Arg(8192)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Diagnose, unmodelled_mode, std::vector<fdsid::Effect>{fdsid::Effect::UnmodelledMode})
    ->Arg(1024)->Arg(8192)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Diagnose, delay_and_nonlinearity, std::vector<fdsid::Effect>{fdsid::Effect::Delay, fdsid::Effect::Nonlinearity})
    ->Arg(1024)->Arg(8192)->Unit(benchmark::kMillisecond);

// gap-validate: 100 cases, files written and read back, 2 threads.
void BM_Validate100(benchmark::State& state) {
  fdsid::GapValidationOptions o;
  o.cases = 100;
  o.threads = 2;
  o.workdir = (std::filesystem::temp_directory_path() / "fdsid-bench-gap").string();
  for (auto _ : state) {
    const fdsid::GapValidation v = fdsid::validate_gap(o);
    benchmark::DoNotOptimize(v.accuracy);
  }
  std::filesystem::remove_all(o.workdir);
}
BENCHMARK(BM_Validate100)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
