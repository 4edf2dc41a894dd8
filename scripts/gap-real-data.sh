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

echo "== silverbox (Schroeder multisine, 11 periods): order-2 model from block A, gap on block B"
S=$D/silverbox
"$B/fdsid" identify-frf --data "$S/Schroeder80mV_blockA_11periods.csv" --meta "$S/Schroeder80mV_blockA_11periods.meta.json" \
  --order 2 --json "$T/sb.json" | head -1
"$B/fdsid" gap --model "$T/sb.json" --data "$S/Schroeder80mV_blockB_11periods.csv" --meta "$S/Schroeder80mV_blockB_11periods.meta.json"

echo "== F-16 GVT (full multisine, u = Voltage, y = Acceleration1, periods 2-9): order-16 continuous model from Level 1, gap on Level 7"
F=$D/f16-gvt
for L in 1 7; do
  # drop the header and the first period (8192 rows: the benchmark note's transient)
  { echo "u,y"; awk -F, 'NR > 1 && NF > 2 && $2 != "" {print $2 "," $3}' "$F/F16Data_FullMSine_Level$L.csv" | tail -n +8193; } > "$T/f16_L$L.csv"
done
sed 's/"periods": *9/"periods": 8/' "$F/F16Data_FullMSine.meta.json" > "$T/f16.meta.json"
"$B/fdsid" identify-frf --data "$T/f16_L1.csv" --meta "$T/f16.meta.json" --domain continuous --order 16 --json "$T/f16.json" | head -1
"$B/fdsid" gap --model "$T/f16.json" --data "$T/f16_L7.csv" --meta "$T/f16.meta.json"
echo "-- the same model on its own Level-1 record"
"$B/fdsid" gap --model "$T/f16.json" --data "$T/f16_L1.csv" --meta "$T/f16.meta.json" | head -3

echo "== cascaded tanks: one period only (expected: refused, exit 2)"
{ echo "u,y"; awk -F, 'NR > 1 && $1 != "" {print $1 "," $3}' "$D/cascaded-tanks/dataBenchmark.csv"; } > "$T/ct.csv"
"$B/fdsid" gap --model "$T/cub.json" --data "$T/ct.csv" --meta "$D/cascaded-tanks/dataBenchmark.meta.json" || echo "exit status $?"
