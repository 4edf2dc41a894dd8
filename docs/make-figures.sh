#!/usr/bin/env bash
# Draws the figures of docs/failure-modes.md and saves each command's printed
# summary beside them, by running the fdsid commands the walkthrough cites.
# Run through the docs target (it builds fdsid first):
#
#   cmake -S . -B build && cmake --build build --target docs
#
# or by hand:  bash docs/make-figures.sh build/fdsid docs/figures
# Every run is seeded: the same binary draws the same figures.
set -euo pipefail
FDSID="$(realpath "${1:?usage: make-figures.sh FDSID OUTDIR}")"
OUT="${2:?usage: make-figures.sh FDSID OUTDIR}"
cd "$(dirname "$0")/.."
mkdir -p "$OUT"
OUT="$(realpath "$OUT")"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

step() { echo "docs: $*" >&2; }
expect_failure() {  # FILE COMMAND...: the walkthrough says COMMAND fails at step 6 (exit 2); output into FILE
  local file="$1" status=0
  shift
  "$@" > "$file" 2>&1 || status=$?
  echo "exit status $status" >> "$file"
  if [ "$status" -ne 2 ] || ! grep -q "step 6" "$file"; then
    echo "docs: expected a step-6 failure from: $*" >&2
    cat "$file" >&2
    exit 1
  fi
}

# 1. Van Overschee's matrix loses rank with M; Akcay's Y does not (Table 1).
step "reproduce table1"
"$FDSID" reproduce table1 --plot "$OUT/table1.png" > "$OUT/table1.txt"

# 2. On noisy data vo1997 fails at step 6; Algorithm 1 does not (Table 2).
step "reproduce table2"
"$FDSID" reproduce table2 --seed 1 --plot "$OUT/table2.png" > "$OUT/table2.txt"

# 3. The same noisy spectrum (eps = 1e-3, M = 1000) through both methods.
step "identify-spectrum (akcay2011 and vo1997) on data/akcay2011_M1000_eps1e-3.csv"
"$FDSID" identify-spectrum --data data/akcay2011_M1000_eps1e-3.csv --order auto \
  --plot "$OUT/identify_spectrum.png" > "$OUT/identify_spectrum.txt"
expect_failure "$OUT/vo1997_noisy.txt" \
  "$FDSID" identify-spectrum --data data/akcay2011_M1000_eps1e-3.csv --method vo1997 --order 4

# 4. Noise-free data. vo1997 is interpolatory while its matrix keeps rank 2n
#    in double precision (M = 128, sigma5 ~ 3e-6); at M = 512 sigma5 is at
#    rounding level and even noise-free data fail at step 6, where Akcay's Y
#    still has rank 2n.
step "noise-free samples, M = 128 and 512: vo1997 and akcay2011"
for M in 128 512; do
  "$FDSID" sample-spectrum --model fixtures/systems/akcay2011.json --M $M --out "$WORK/clean$M.csv"
done
"$FDSID" identify-spectrum --data "$WORK/clean128.csv" --method vo1997 --p 9 --r 8 --order 4 \
  --plot "$OUT/vo1997_M128.png" > "$OUT/vo1997_M128.txt"
expect_failure "$OUT/vo1997_M512.txt" \
  "$FDSID" identify-spectrum --data "$WORK/clean512.csv" --method vo1997 --p 9 --r 8 --order 4
"$FDSID" identify-spectrum --data "$WORK/clean512.csv" --p 9 --r 8 --order 4 \
  --plot "$OUT/akcay_M512.png" > "$OUT/akcay_M512.txt"

# 5. What the sample variance costs (Pintelon 2002 Fig. 1) and what model
#    errors do to it (Fig. 2); 2000 runs instead of the paper's 10^4.
step "reproduce fig1, fig2 (2000 runs each)"
"$FDSID" reproduce fig1 --runs 2000 --seed 1 --plot "$OUT/fig1.png" > "$OUT/fig1.txt"
"$FDSID" reproduce fig2 --runs 2000 --seed 1 --plot "$OUT/fig2.png" > "$OUT/fig2.txt"

# 6. Pintelon's Algorithm 1 on the bundled periodic records.
step "identify-frf on data/pintelon2002_P512_M8.csv"
"$FDSID" identify-frf --data data/pintelon2002_P512_M8.csv --meta data/pintelon2002_P512_M8.meta.json \
  --plot "$OUT/identify_frf.png" > "$OUT/identify_frf.txt"

# 7. Sim-to-real: the "real" plant has a resonance the simulation model lacks.
step "simulate-records + gap"
"$FDSID" simulate-records --model docs/examples/plant_with_mode.json --period 1024 --periods 8 \
  --noise-std 0.05 --seed 7 --out "$WORK/real.csv" --meta-out "$WORK/real.meta.json"
"$FDSID" gap --model fixtures/systems/pintelon2002.json --data "$WORK/real.csv" --meta "$WORK/real.meta.json" \
  --plot "$OUT/gap.png" > "$OUT/gap.txt"
# The scratch folder's name is random: keep it out of the saved summaries.
sed -i "s|$WORK/||g" "$OUT"/*.txt
step "figures in $OUT"
