#!/usr/bin/env bash
# Installs fdsid's build and test dependencies from Debian 12 packages.
set -euo pipefail
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential cmake ninja-build pkg-config git \
  libeigen3-dev libfftw3-dev nlohmann-json3-dev libcli11-dev \
  libgtest-dev libbenchmark-dev librapidcheck-dev libboost-dev gcovr \
  libplplot-dev plplot-driver-cairo libceres-dev \
  clang libclang-rt-14-dev \
  bsdutils >/dev/null  # util-linux `script`: the pseudo-terminal of tests/cli_plot_test.cpp (essential, listed to say so)
