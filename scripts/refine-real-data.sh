#!/usr/bin/env bash
# Maximum-likelihood refinement on the real measurements in ../shared/data
# (README "Maximum-likelihood refinement"): for each record, the subspace model
# and the refined one (identify-frf --refine ml), their V (Eq. 35) on the
# identification periods and the gap on held-out periods. Not part of CI (the
# data live outside the repository). Usage: bash scripts/refine-real-data.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
D=../shared/data
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# one ID ARGS... -- GAP_ARGS...: identify with and without --refine ml, then gap
one() {
  local id=() gap=()
  while [ "$1" != "--" ]; do id+=("$1"); shift; done
  shift
  gap=("$@")
  for refine in none ml; do
    "$B/fdsid" identify-frf "${id[@]}" --refine "$refine" --json "$T/m.json" > "$T/out.txt"
    python3 - "$T/m.json" "$refine" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
unstable = sum(1 for re, im in j["poles"] if (re >= 0 if j["domain"] == "continuous" else re * re + im * im >= 1))
r = j.get("refinement", {})
print(f"  {sys.argv[2]:4s}: V = {j['fit']['v_sub']:.4g} (expected {j['fit'].get('expected', float('nan')):.4g}), "
      f"unstable poles {unstable}" + (f", {r['iterations']} iterations, {r['termination']}" if r else ""))
PY
    "$B/fdsid" gap --model "$T/m.json" "${gap[@]}" | sed -n 's/^gap before \([^ ]*\).*/        held-out gap \1/p'
  done
}

echo "== F-16 GVT Level 1 (u = Voltage, y = Acceleration1): periods 2-5 identify, 6-9 held out, continuous time"
F=$D/f16-gvt
for order in 12 16 24; do
  echo " order $order"
  one --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" --input Voltage \
    --output Acceleration1 --skip-periods 1 --use-periods 4 --domain continuous --order $order -- \
    --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" --input Voltage \
    --output Acceleration1 --skip-periods 5
done

echo "== F-16 GVT Level 1 as above, discrete time in Algorithm 2's bases on the Tustin frequencies (narrow band)"
for method in bilinear orthogonal; do
  for order in 16 20; do
    echo " --method $method, order $order"
    one --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" --input Voltage \
      --output Acceleration1 --skip-periods 1 --use-periods 4 --method $method --order $order -- \
      --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" --input Voltage \
      --output Acceleration1 --skip-periods 5
  done
done

echo "== silverbox: order 2 from block A, held out: block B"
S=$D/silverbox
one --data "$S/Schroeder80mV_blockA_11periods.csv" --meta "$S/Schroeder80mV_blockA_11periods.meta.json" --order 2 -- \
  --data "$S/Schroeder80mV_blockB_11periods.csv" --meta "$S/Schroeder80mV_blockB_11periods.meta.json"
echo " errors-in-variables (--eiv: the measured input is noisy too)"
one --data "$S/Schroeder80mV_blockA_11periods.csv" --meta "$S/Schroeder80mV_blockA_11periods.meta.json" --order 2 --eiv -- \
  --data "$S/Schroeder80mV_blockB_11periods.csv" --meta "$S/Schroeder80mV_blockB_11periods.meta.json"

echo "== cubic-feedback circuit (oddms): order 2 from realisation R00, held out: R01"
C=$D/cubic-feedback-circuit-pxi
one --data "$C/oddms_R00.csv" --meta "$C/oddms.meta.json" --order 2 -- --data "$C/oddms_R01.csv" --meta "$C/oddms.meta.json"
echo " errors-in-variables (--eiv)"
one --data "$C/oddms_R00.csv" --meta "$C/oddms.meta.json" --order 2 --eiv -- --data "$C/oddms_R01.csv" --meta "$C/oddms.meta.json"

echo "== figure: F-16 order 20, discrete time, --method orthogonal, refined (docs/figures/f16_refined.png, 2-sigma bands)"
"$B/fdsid" identify-frf --data "$F/F16Data_FullMSine_Level1.csv" --meta "$F/F16Data_FullMSine.meta.json" --input Voltage \
  --output Acceleration1 --skip-periods 1 --use-periods 4 --method orthogonal --order 20 --refine ml \
  --plot docs/figures/f16_refined.png > docs/figures/f16_refined.txt
