#!/usr/bin/env bash
# The whole test suite, as CI runs it: dependencies, Release build and every
# ctest label; then one build with coverage AND AddressSanitizer +
# UndefinedBehaviorSanitizer (-fno-sanitize-recover=all) that runs the quick
# suite (every test but the label `slow` ones: Monte Carlo and 50-digit runs
# that take minutes there, and `docs`) and checks the 90 % line threshold on
# fast/ and reference/ (LeakSanitizer suppressions for fontconfig and libltdl
# only: coverage/lsan.supp)
# (coverage/CMakeLists.txt); then every libFuzzer target for 60 s
# (scripts/fuzz.sh; clang, ASan + UBSan), failing on any finding.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build
cmake --build build -j2
ctest --test-dir build --output-on-failure -j2
cmake -S . -B build-cov -DFDSID_COVERAGE=ON -DFDSID_SANITIZE=ON -DFDSID_BUILD_BENCH=OFF
cmake --build build-cov -j2
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  LSAN_OPTIONS=suppressions=$PWD/coverage/lsan.supp:print_suppressions=0 \
  cmake --build build-cov --target coverage
bash scripts/fuzz.sh 60
