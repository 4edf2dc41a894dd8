#!/usr/bin/env bash
# gap-validate with the effects injected into real measured noise (issue 17
# item 5; README "Blind validation", measured noise): each four consecutive
# measured periods give two noise periods (orthonormal contrasts across the
# periods, gap_cases.hpp), in which the system's periodic response and a
# linear drift of it cancel, and the noise keeps what the measurement had —
# its spectrum, its power varying from group to group, its bursts. Not part
# of CI (the data live outside the repository). Usage:
#   bash scripts/gap-validate-measured-noise.sh [BUILD_DIR] [CASES] [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
N=${2:-100}
S=${3:-1}
D=../shared/data

echo "== cubic-feedback circuit, full multisine R00-R07 (y; period 1 a transient, dropped): 8 x 3 noise periods (7 periods: 4 + 3), P 5000"
C=$D/cubic-feedback-circuit-pxi
"$B/fdsid" gap-validate --cases "$N" --seed "$S" --noise-meta "$C/fullms.meta.json" --noise-input u --noise-output y \
  --noise-skip-periods 1 $(for r in 0 1 2 3 4 5 6 7; do echo --noise-from "$C/fullms_R0$r.csv"; done) || true

echo "== silverbox, Schroeder blocks A and B (y; period 1 dropped): 2 x 4 noise periods (10 periods: 4 + 4, 2 unused), P 1024"
SB=$D/silverbox
"$B/fdsid" gap-validate --cases "$N" --seed "$S" --noise-meta "$SB/Schroeder80mV_blockA_11periods.meta.json" \
  --noise-input u --noise-output y --noise-skip-periods 1 \
  --noise-from "$SB/Schroeder80mV_blockA_11periods.csv" --noise-from "$SB/Schroeder80mV_blockB_11periods.csv" || true

echo "== F-16 GVT, full multisine Level 1 (Acceleration1; period 1 dropped): 4 noise periods (8 periods: 4 + 4), P 8192, M 4"
F=$D/f16-gvt
# Level 1 only (its own findings: README, "Measured noise"). At Level 7 the
# period-to-period differences are 20-50x Level 1's in 2-200 Hz and, by the
# data set's README, non-periodic nonlinear contributions (friction,
# clearance), not measurement noise; with them the effect-free cases' gap is
# 0.69-0.99, not about 1 (the mean over periods varies less than the periods'
# scatter says: they are not independent).
"$B/fdsid" gap-validate --cases "$N" --seed "$S" --noise-meta "$F/F16Data_FullMSine.meta.json" \
  --noise-input Voltage --noise-output Acceleration1 --noise-skip-periods 1 \
  --noise-from "$F/F16Data_FullMSine_Level1.csv" || true
