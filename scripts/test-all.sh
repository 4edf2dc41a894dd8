#!/usr/bin/env bash
# The whole test suite, as CI runs it: dependencies, Release build and every
# ctest label, then the coverage build with its 90 % line threshold on fast/ and
# reference/ (coverage/CMakeLists.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build
cmake --build build -j2
ctest --test-dir build --output-on-failure -j2
cmake -S . -B build-cov -DFDSID_COVERAGE=ON -DFDSID_BUILD_BENCH=OFF
cmake --build build-cov -j2
cmake --build build-cov --target coverage
