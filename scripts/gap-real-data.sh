#!/usr/bin/env bash
# The gap diagnosis on the real measurements in ../shared/data (README "Real
# data"): a linear model identified by identify-frf from one record, diagnosed
# against another record of the same system. Not part of CI (the data live
# outside the repository). Usage: bash scripts/gap-real-data.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
D=../shared/data
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

echo "== cubic-feedback circuit (oddms): order-2 model from realisation R00, gap on R01"
C=$D/cubic-feedback-circuit-pxi
"$B/fdsid" identify-frf --data "$C/oddms_R00.csv" --meta "$C/oddms.meta.json" --order 2 --json "$T/cub.json" | head -1
"$B/fdsid" gap --model "$T/cub.json" --data "$C/oddms_R01.csv" --meta "$C/oddms.meta.json"
"$B/fdsid" validate --model "$T/cub.json" --data "$C/oddms_R01.csv" --meta "$C/oddms.meta.json" | head -1

echo "== silverbox (Schroeder multisine, 11 periods): order-2 model from block A, gap on block B"
S=$D/silverbox
"$B/fdsid" identify-frf --data "$S/Schroeder80mV_blockA_11periods.csv" --meta "$S/Schroeder80mV_blockA_11periods.meta.json" \
  --order 2 --json "$T/sb.json" | head -1
"$B/fdsid" gap --model "$T/sb.json" --data "$S/Schroeder80mV_blockB_11periods.csv" --meta "$S/Schroeder80mV_blockB_11periods.meta.json"
"$B/fdsid" validate --model "$T/sb.json" --data "$S/Schroeder80mV_blockB_11periods.csv" \
  --meta "$S/Schroeder80mV_blockB_11periods.meta.json" | head -1

echo "== F-16 GVT (full multisine, u = Voltage, y = Acceleration1, periods 2-9): order-16 continuous model from Level 1, gap on Level 7"
F=$D/f16-gvt
# The files as they are: columns by name, the first period (8192 rows: the
# benchmark note's transient) skipped.
sel=(--input Voltage --output Acceleration1 --skip-periods 1)
"$B/fdsid" identify-frf --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" "${sel[@]}" \
  --domain continuous --order 16 --json "$T/f16.json" | head -1
"$B/fdsid" gap --model "$T/f16.json" --data "$F/F16Data_FullMSine_Level7.csv" --meta "$F/F16Data_FullMSine.meta.json" "${sel[@]}"
echo "-- the same model on its own Level-1 record"
"$B/fdsid" gap --model "$T/f16.json" --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" \
  "${sel[@]}" | head -3
echo "-- its fit on Level 7 (MATLAB compare's NRMSE fit)"
"$B/fdsid" validate --model "$T/f16.json" --data "$F/F16Data_FullMSine_Level7.csv" \
  --meta "$F/F16Data_FullMSine.meta.json" "${sel[@]}" | head -1 || echo "exit status $?"

echo "== F-16 GVT, three outputs (Acceleration1-3): one order-16 model with three outputs from Level 1, gap on Level 7"
sel3=(--input Voltage --output Acceleration1 Acceleration2 Acceleration3 --skip-periods 1)
"$B/fdsid" identify-frf --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" "${sel3[@]}" \
  --domain continuous --order 16 --json "$T/f16m.json" | head -1
"$B/fdsid" gap --model "$T/f16m.json" --data "$F/F16Data_FullMSine_Level7.csv" --meta "$F/F16Data_FullMSine.meta.json" \
  "${sel3[@]}" | grep -v '^  '

echo "== cascaded tanks: one period only (expected: refused, exit 2)"
"$B/fdsid" gap --model "$T/cub.json" --data "$D/cascaded-tanks/dataBenchmark.csv" --input uEst --output yEst \
  --meta "$D/cascaded-tanks/dataBenchmark.meta.json" || echo "exit status $?"
