#!/usr/bin/env bash
# The tightness of `fdsid check`'s derived FRF tolerance (issue 13): for each
# case, fdsid's own double-precision identify-frf is the candidate and the
# 50-digit reference the oracle; tightness = tolerance / distance for each
# compared quantity (G on the data grid, G on a dense grid, the poles), of
# which the smallest is printed (>= 1: the candidate agrees; the target is a
# tolerance within 100 x what a correct implementation reaches).
# usage: bash scripts/check-tightness.sh [path/to/fdsid]   (needs python3)
set -euo pipefail
fdsid=${1:-build/fdsid}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
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
  python3 -c "
import json, sys
q = json.load(open('$tmp/k.json'))['quantities']
t = ['%.3g' % (x['tolerance'] / x['distance']) if x['distance'] > 0 else 'inf' for x in q]
print('%-34s %-4s %s' % ('$kind $n $par $F $rel $r $method', '$rc', ', '.join(t)))"
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
