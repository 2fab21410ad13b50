#!/usr/bin/env bash
# `weft fit` on its two measured cases, with each optimiser: the
# level-of-detail fit (a 24 × 16 windy_flag at 8 substeps × 2 iterations to
# the 96 × 64 one at 8 × 10, 6 s, three keys, 64 runs) and the drape ladder
# (the Cusick tester's curvature for a drape coefficient of 0.45, 24 runs).
# Prints CSV rows (`commit,benchmark,measure,value,unit,note`, as in
# benches/results/): the start's and the fit's distance, the fitted drape
# coefficient, and the wall time (the first level-of-detail fit includes
# measuring the reference once; the second finds it cached).
#
#   benches/fit.sh [WEFT] >> benches/results/MACHINE.csv
#
# WEFT defaults to the binary `cargo test` builds.
set -euo pipefail
cd "$(dirname "$0")/.."
weft="$(realpath "${1:-${CARGO_TARGET_DIR:-target}/debug/weft}")"
commit="$(git rev-parse --short HEAD)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# The fine flag strains past windy_flag's [expect] bound (exit 1); its recording is whole.
"$weft" record windy_flag --set cloth.weft=96 --set cloth.warp=64 --set solver.substeps=8 \
  --set solver.iterations=10 --seconds 6 --level summary --log-every 2 --save "$tmp/fine.rrd" \
  2> /dev/null || [ -s "$tmp/fine.rrd" ]
lod=(windy_flag --set cloth.weft=24 --set cloth.warp=16 --set solver.substeps=8
  --vary solver.weights.curvature=0.01..0.9 --vary solver.damping=0.9..1
  --vary solver.weights.normality=0..1 --to "$tmp/fine.rrd" --seconds 6 --budget 64)
drape=(presets/cusick_drape.toml --vary solver.weights.curvature=0.5..0.95
  --target drape_coefficient=0.45 --budget 24)
# The table's `distance (weighted total)` row: start, fitted.
row() { grep "^  distance (weighted total)" "$1" | awk '{print $4, $5}'; }
for method in swarm nelder-mead; do
  for case in lod drape; do
    if [ "$case" = lod ]; then args=("${lod[@]}"); else args=("${drape[@]}"); fi
    out="$tmp/$case-$method"
    start=$(date +%s.%N)
    "$weft" fit "${args[@]}" --method "$method" --out "$out" > "$out.txt" 2> /dev/null
    wall=$(echo "$(date +%s.%N) - $start" | bc)
    read -r before after < <(row "$out.txt")
    echo "$commit,fit $case $method,start distance,$before,,"
    echo "$commit,fit $case $method,fitted distance,$after,,"
    echo "$commit,fit $case $method,wall,$wall,s,"
    if [ "$case" = drape ]; then
      echo "$commit,fit $case $method,fitted drape coefficient,$(grep '^  drape_coefficient' "$out.txt" | awk '{print $5}'),,target 0.45"
    fi
  done
done
# The level-of-detail fit again, its reference cached: the search alone.
mkdir -p "$tmp/lod-cached" && cp "$tmp/lod-swarm/reference.json" "$tmp/lod-cached/"
start=$(date +%s.%N)
"$weft" fit "${lod[@]}" --out "$tmp/lod-cached" > /dev/null 2>&1
echo "$commit,fit lod swarm,wall without the reference,$(echo "$(date +%s.%N) - $start" | bc),s,reference cached"
