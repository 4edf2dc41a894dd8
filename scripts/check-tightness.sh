#!/usr/bin/env bash
# The tightness of `fdsid check`'s measured tolerances (issue 13): for each
# case, fdsid's own double-precision identify-spectrum / identify-frf is the
# candidate and the 50-digit reference the oracle; tightness = tolerance /
# distance for each compared quantity (>= 1: the candidate agrees; the target
# is a tolerance within 100 x what a correct implementation reaches).
# usage: bash scripts/check-tightness.sh [path/to/fdsid]   (needs python3)
set -euo pipefail
fdsid=${1:-build/fdsid}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# One table row: the case, check's exit status, tolerance / distance per quantity of $tmp/k.json.
tightness_line() {
  python3 -c "
import json
q = json.load(open('$tmp/k.json'))['quantities']
t = ['%.3g' % (x['tolerance'] / x['distance']) if x['distance'] > 0 else 'inf' for x in q]
print('%-34s %-4s %s' % ('$1', '$2', ', '.join(t)))"
}
printf '%-34s %-4s %-28s\n' "case (kind n par F noise r method)" "exit" "tightness: G data, G dense, poles"
while read -r kind n par F rel r method; do
  [ -z "$kind" ] && continue
  python3 "$here/frf_case.py" "$kind" "$n" "$par" "$F" "$rel" 3 "$tmp/d.csv"
  domain=discrete; [ "$kind" = c ] && domain=continuous
  "$fdsid" identify-frf --frf "$tmp/d.csv" --domain "$domain" --method "$method" --order "$n" --r "$r" \
    --json "$tmp/c.json" > /dev/null
  set +e
  "$fdsid" check --model "$tmp/c.json" --frf "$tmp/d.csv" --json "$tmp/k.json" > /dev/null
  rc=$?
  set -e
  tightness_line "$kind $n $par $F $rel $r $method" "$rc"
done <<'CASES'
d 4 0.9 100 1e-2 8 bilinear
d 4 0.99 200 1e-2 8 bilinear
d 4 0.999 400 0 8 bilinear
d 8 0.95 200 1e-3 16 bilinear
d 8 0.99 300 0 20 bilinear
d 2 0.9999 500 0 4 bilinear
c 4 0.1 100 1e-2 8 bilinear
c 4 0.01 200 0 8 bilinear
c 6 0.001 300 0 12 bilinear
c 8 0.02 300 0 16 bilinear
c 6 0.05 200 1e-3 12 orthogonal
c 4 0.01 200 0 8 orthogonal
c 6 0.01 300 0 12 orthogonal
CASES

# Spectra (Akcay 2011): noise-free samples in 50 digits of the bundled systems
# and of a pole pair at radius 0.99, and the bundled noisy spectrum.
cat > "$tmp/r99.json" <<'EOF'
{"domain":"discrete","sample_time":1,"A":[[1.4004,-0.9801],[1,0]],"B":[[1],[0]],"C":[[0.3,0.2]],"D":[[1]]}
EOF
printf '\n%-34s %-4s %s\n' "spectrum case (model M)" "exit" "tightness: poles, spectrum, summand Markov, factor zeros, factor Markov"
root="$here/.."
while read -r model M order; do
  [ -z "$model" ] && continue
  if [ "$M" = file ]; then
    data="$root/$model"
  else
    model_path="$root/$model"
    [ "$model" = r99 ] && model_path="$tmp/r99.json"
    "$fdsid" sample-spectrum --model "$model_path" --M "$M" --precision high --out "$tmp/s.csv"
    data="$tmp/s.csv"
  fi
  "$fdsid" identify-spectrum --data "$data" --order "$order" --json "$tmp/c.json" > /dev/null
  set +e
  "$fdsid" check --model "$tmp/c.json" --data "$data" --json "$tmp/k.json" > /dev/null
  rc=$?
  set -e
  tightness_line "$(basename "$model") $M" "$rc"
done <<'CASES'
fixtures/systems/akcay2011.json 64 4
fixtures/systems/akcay2011.json 1000 4
r99 200 2
fixtures/systems/mimo2x2_example.json 64 3
data/akcay2011_M1000_eps1e-3.csv file 4
CASES

# The certified suite (fixtures/certified): fdsid as the conformance candidate;
# the tolerances are the stored ones (the suite's perturbed_models).
printf '\n%-40s %-8s %s\n' "certified case" "tier" "tightness per compared quantity"
"$fdsid" conformance --suite "$root/fixtures/certified" --candidate "$fdsid {fdsid_args} --json {out}" \
  --json "$tmp/conformance.json" > /dev/null || true
python3 -c "
import json
for c in json.load(open('$tmp/conformance.json'))['cases']:
    q = c.get('comparison', {}).get('quantities', [])
    t = ['%s %.3g' % (x['quantity'], x['tolerance'] / x['distance']) if x['distance'] > 0 else x['quantity'] + ' inf' for x in q]
    print('%-40s %-8s %s%s' % (c['case'], c['tier'], '' if c['pass'] else 'FAIL ', ', '.join(t)))"
