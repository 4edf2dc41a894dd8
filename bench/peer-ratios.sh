#!/usr/bin/env bash
# Peer baseline: runs the Google Benchmark binaries (BM_IdentifyFrf of
# bench_frf, BM_Identify of bench_spectrum; 5 repetitions, the "min"
# aggregate) and the dense numpy implementation bench/numpy_baseline.py
# (median of 7 repetitions, BLAS threads 1) one after the other in the same
# run, and prints workload | fdsid ms | numpy ms | ratio (numpy / fdsid), plus
# the ratio of the numpy minimum to the fdsid minimum.
# Not part of CI. See bench/README.md, "Peer baseline (numpy)".
#
# Usage: bash bench/peer-ratios.sh [BUILD_DIR]      (default: build)
# Environment: PYTHON (an interpreter with numpy; default: python3 if it has
# numpy, else /usr/bin/python3), REPS (Google Benchmark repetitions, 5),
# NUMPY_REPS (7), KEEP (a folder to keep the raw JSON in).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="${1:-build}"
reps="${REPS:-5}"
numpy_reps="${NUMPY_REPS:-7}"

py="${PYTHON:-}"
if [[ -z "$py" ]]; then
  for c in python3 /usr/bin/python3; do
    if command -v "$c" >/dev/null 2>&1 && "$c" -c 'import numpy' 2>/dev/null; then py="$c"; break; fi
  done
fi
[[ -n "$py" ]] || { echo "peer-ratios: no python3 with numpy (apt-get install python3-numpy, or set PYTHON)" >&2; exit 1; }

for b in bench_frf bench_spectrum; do
  if [[ ! -x "$build/bench/$b" ]]; then
    echo "peer-ratios: $build/bench/$b missing, building it" >&2
    cmake --build "$build" --target "$b" -j2 >&2
  fi
done

tmp="${KEEP:-$(mktemp -d)}"
mkdir -p "$tmp"
[[ -n "${KEEP:-}" ]] || trap 'rm -rf "$tmp"' EXIT

echo "# $(date -u +%Y-%m-%dT%H:%MZ)  $(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1)," \
     "$(getconf _NPROCESSORS_ONLN) CPUs, numpy $("$py" -c 'import numpy; print(numpy.__version__)'), BLAS threads 1" >&2
echo "# bench_frf BM_IdentifyFrf ($reps repetitions) ..." >&2
"$build/bench/bench_frf" --benchmark_filter='^BM_IdentifyFrf/' --benchmark_repetitions="$reps" \
  --benchmark_report_aggregates_only=true --benchmark_format=json >"$tmp/frf.json"
echo "# bench_spectrum BM_Identify ($reps repetitions) ..." >&2
"$build/bench/bench_spectrum" --benchmark_filter='^BM_Identify/' --benchmark_repetitions="$reps" \
  --benchmark_report_aggregates_only=true --benchmark_format=json >"$tmp/spectrum.json"
echo "# numpy baseline ($numpy_reps repetitions) ..." >&2
# (the script pins these itself before importing numpy; set here as well, for
# the numpy run only, so that the C++ binaries above run as they normally do)
OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
  "$py" "$here/numpy_baseline.py" --reps "$numpy_reps" >"$tmp/numpy.jsonl"

"$py" - "$tmp" <<'EOF'
import json, sys, os
tmp = sys.argv[1]
scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
fdsid = {}
for f, prefix, name in (("frf.json", "BM_IdentifyFrf/", "frf/"), ("spectrum.json", "BM_Identify/", "spectrum/")):
    for b in json.load(open(os.path.join(tmp, f)))["benchmarks"]:
        if b.get("aggregate_name") != "min":
            continue
        run = b["run_name"]
        if not run.startswith(prefix):
            continue
        key = name + run[len(prefix):].replace("/real_time", "")
        fdsid[key] = b["real_time"] * scale[b["time_unit"]]
rows = [json.loads(l) for l in open(os.path.join(tmp, "numpy.jsonl")) if l.strip()]
print("| workload | fdsid ms | numpy ms | ratio | ratio (min/min) |")
print("|----------|---------:|---------:|------:|----------------:|")
for r in rows:
    w, n, nmin = r["workload"], r["seconds"] * 1e3, r["min_seconds"] * 1e3
    f = fdsid.get(w)
    if f is None:
        print("| %s | – | %.3g | – | – |" % (w, n))
    else:
        print("| %s | %.3g | %.3g | %.2f | %.2f |" % (w, f, n, n / f, nmin / f))
EOF
