#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan) and runs each
# for the given number of seconds (default 60), two at a time, each on a copy of
# its seed corpus fixtures/fuzz/<target>/ (the seeds are never written).
# Prints every target's final libFuzzer stats; exits non-zero when any target
# found a crash, leak, sanitizer report or timeout.
#
#   scripts/fuzz.sh [seconds-per-target]
#   FDSID_FUZZ_BUILD_DIR=/tmp/build-fuzz scripts/fuzz.sh 3600   # other build dir
#   FDSID_FUZZ_JOBS=1 scripts/fuzz.sh                           # one target at a time
set -uo pipefail

SECONDS_PER_TARGET="${1:-60}"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${FDSID_FUZZ_BUILD_DIR:-$ROOT/build-fuzz}"
JOBS="${FDSID_FUZZ_JOBS:-2}"
TARGETS=(fuzz_spectrum_csv fuzz_frf_csv fuzz_records_csv fuzz_model_json fuzz_meta_json
         fuzz_identify_spectrum fuzz_identify_frf)

case "$SECONDS_PER_TARGET" in
  ''|*[!0-9]*) echo "usage: $0 [seconds-per-target]" >&2; exit 2 ;;
esac

start=$(date +%s)
echo "== configure and build $BUILD (clang, -fsanitize=fuzzer,address,undefined)"
# Ninja for a new build folder (scripts/test-all.sh says why); an existing one keeps its generator.
GENERATOR=()
[ -f "$BUILD/CMakeCache.txt" ] || GENERATOR=(-G Ninja)
CC="${CC:-clang}" CXX="${CXX:-clang++}" cmake -S "$ROOT" -B "$BUILD" "${GENERATOR[@]}" -DFDSID_FUZZ=ON \
  -DFDSID_BUILD_TESTS=OFF -DFDSID_BUILD_BENCH=OFF >/dev/null || { echo "configure failed" >&2; exit 2; }
cmake --build "$BUILD" -j"$JOBS" --target "${TARGETS[@]}" || { echo "build failed" >&2; exit 2; }
built=$(date +%s)

# Leaks are checked per input and at exit (the static FFTW plan cache of
# fast/src/spectrum_id.cpp destroys its plans at exit).
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:symbolize=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

run_target() {
  local t="$1"
  local corpus="$BUILD/fuzz-corpus/$t" artifacts="$BUILD/fuzz-artifacts/$t/" log="$BUILD/fuzz-logs/$t.log"
  mkdir -p "$corpus" "$artifacts"
  cp -n "$ROOT/fixtures/fuzz/$t/"* "$corpus/" 2>/dev/null
  chmod -R u+w "$corpus"
  local dict=()
  case "$t" in
    *_csv) dict=(-dict="$ROOT/fuzz/csv.dict") ;;
    *_json) dict=(-dict="$ROOT/fuzz/json.dict") ;;
  esac
  # Per-input time limit: 10 s for the parsers; 30 s for the identification
  # entry points, whose largest inputs (automatic order and an r scan up to
  # F = 64) take ~0.1 s in Release but 50-100 times longer under ASan + UBSan at -O1.
  local limit=10
  case "$t" in fuzz_identify_*) limit=30 ;; esac
  "$BUILD/fuzz/$t" "$corpus" "${dict[@]}" -max_total_time="$SECONDS_PER_TARGET" -timeout="$limit" \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts" >"$log" 2>&1
  echo $? >"$BUILD/fuzz-logs/$t.rc"
}

mkdir -p "$BUILD/fuzz-logs"
rm -f "$BUILD/fuzz-logs/"*.rc
touch "$BUILD/fuzz-logs/.start"
echo "== fuzzing ${#TARGETS[@]} targets, ${SECONDS_PER_TARGET}s each, $JOBS at a time (logs: $BUILD/fuzz-logs)"
for t in "${TARGETS[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n; done
  run_target "$t" &
done
wait

status=0
printf '%-24s %-6s %s\n' target status "final stats"
for t in "${TARGETS[@]}"; do
  rc=$(cat "$BUILD/fuzz-logs/$t.rc" 2>/dev/null || echo missing)
  log="$BUILD/fuzz-logs/$t.log"
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -1)
  [ -n "$done_line" ] || done_line=$(grep -E '^#[0-9]+' "$log" | tail -1)
  printf '%-24s %-6s %s\n' "$t" "$rc" "$done_line"
  if [ "$rc" != 0 ]; then
    status=1
    echo "  FINDING in $t (exit $rc); log $log:"
    grep -E 'ERROR: |runtime error|invariant violated|Test unit written|SUMMARY|terminate called|what\(\)' "$log" | head -8 | sed 's/^/    /'
    find "$BUILD/fuzz-artifacts/$t/" -type f -newer "$BUILD/fuzz-logs/.start" 2>/dev/null | sed 's|^|    artifact: |'
  fi
done
end=$(date +%s)
echo "== build $((built - start)) s, fuzzing $((end - built)) s, total $((end - start)) s"
[ "$status" = 0 ] && echo "== no findings" || echo "== FINDINGS: see above; reproduce with $BUILD/fuzz/<target> <artifact>"
exit "$status"
