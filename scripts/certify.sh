#!/usr/bin/env bash
# Regenerates the certified reference suite fixtures/certified/ (its README.md).
#
#   bash scripts/certify.sh [BUILD] [--data]
#
# BUILD (default build) holds the normal fdsid (50-digit reference). The script
# builds a second fdsid whose reference computes in 100 digits
# (build-certify100/, -DFDSID_REFERENCE_DIGITS=100), runs every case of
# fixtures/certified/cases.json in both precisions and writes each case's
# certified values with the significant digits the two share
# (fixtures/certified/<case>.json). --data first rewrites the data files from
# their recipes below (deterministic: fixed seeds; the committed files are the
# certified inputs, so only do this when the recipes change).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
fdsid=$build/fdsid
suite=fixtures/certified
[ -x "$fdsid" ] || { echo "certify.sh: $fdsid not built (cmake --build $build --target fdsid)" >&2; exit 2; }

if [ "${2:-}" = "--data" ]; then
  d=$suite/data s=$suite/systems
  # Akcay (2011) spectra: noise-free samples of the systems, and Section 4 noise.
  "$fdsid" sample-spectrum --model $s/akcay2011.json --M 64 --out $d/akcay2011_M64.csv
  "$fdsid" sample-spectrum --model $s/akcay2011.json --M 16 --out $d/akcay2011_M16.csv
  "$fdsid" sample-spectrum --model $s/mimo2x2_example.json --M 32 --out $d/mimo2x2_M32.csv
  "$fdsid" sample-spectrum --model $s/akcay2011.json --M 256 --epsilon 0.003 --seed 11 --out $d/akcay2011_M256_eps0.003.csv
  "$fdsid" sample-spectrum --model $s/radius099.json --M 256 --out $d/radius099_M256.csv
  "$fdsid" sample-spectrum --model $s/radius09999.json --M 2048 --out $d/radius09999_M2048.csv
  "$fdsid" sample-spectrum --model $s/clustered.json --M 512 --out $d/clustered_M512.csv
  "$fdsid" sample-spectrum --model $s/near_cancellation.json --M 256 --out $d/near_cancellation_M256.csv
  # Pintelon (2002) FRF samples: the data of fixtures/golden/frf_*.json (closed
  # formulas, fixtures/README.md) as G = Y/U and G_var = sigma^2/|U|^2 in double.
  for g in pintelon2002_F40_r8_discrete pintelon2002_F40_r8_discrete_noisy continuous4_F50_r8_bilinear \
           continuous4_F50_r8_bilinear_noisy; do
    python3 - fixtures/golden/frf_$g.json $d/frf_${g/_r8/}.csv <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))["data"]
with open(sys.argv[2], "w") as f:
    f.write("omega,G_re,G_im,G_var\n")
    for w, u, y, v in zip(d["omega"], d["U"], d["Y"], d["variance"]):
        U = complex(float(u[0]), float(u[1])); Y = complex(float(y[0]), float(y[1]))
        G = Y / U
        f.write("%s,%r,%r,%r\n" % (w, G.real, G.imag, float(v) / abs(U) ** 2))
PY
  done
  # Periodic records: the bundled experiment, and one with input noise (errors-in-variables)
  # whose 32 lines 1, 5, ..., 125 reach both modes of Eq. (36).
  cp data/pintelon2002_P512_M8.csv $d/pintelon2002_P512_M8.csv
  cp data/pintelon2002_P512_M8.meta.json $d/pintelon2002_P512_M8.meta.json
  "$fdsid" simulate-records --model fixtures/systems/pintelon2002.json --period 256 --periods 8 \
    --lines $(seq -s' ' 1 4 125) --noise-std 0.02 --input-noise-std 0.01 --seed 5 --out $d/pintelon2002_P256_M8_eiv.csv \
    --meta-out $d/pintelon2002_P256_M8_eiv.meta.json
fi

second=build-certify100
cmake -S . -B $second -DCMAKE_BUILD_TYPE=Release -DFDSID_BUILD_TESTS=OFF -DFDSID_BUILD_BENCH=OFF \
  -DFDSID_REFERENCE_DIGITS=100 > /dev/null
cmake --build $second -j2 --target fdsid
raw=$(mktemp -d)
trap 'rm -rf "$raw"' EXIT
echo "== 100 digits"
$second/fdsid certify --suite $suite --raw-out "$raw"
echo "== 50 digits, certified digits against the 100-digit values"
"$fdsid" certify --suite $suite --against "$raw"
