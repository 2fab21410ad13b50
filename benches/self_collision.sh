#!/usr/bin/env bash
# Self-collision's cost and result on every shipped preset, whole process:
# each preset run RUNS times with `weights.self` 0 and 1 back to back
# (interleaved), at `--level summary` with nothing saved. Prints CSV rows
# (`commit,benchmark,measure,value,unit,note`, as in benches/results/): the
# median steps/s of each, their ratio, and the worst crossing count and the
# frames with any crossing (the same in every run: the runs are
# deterministic).
#
#   benches/self_collision.sh [WEFT] [RUNS] [PRESET...] >> benches/results/MACHINE.csv
#
# WEFT defaults to the binary `cargo test` builds; RUNS to 5; the presets to
# every shipped one.
set -euo pipefail
cd "$(dirname "$0")/.."
weft="${1:-${CARGO_TARGET_DIR:-target}/debug/weft}"
runs="${2:-5}"
shift $(($# < 2 ? $# : 2))
commit="$(git rev-parse --short HEAD)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

figure() { # FILE KEY
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['figures'][sys.argv[2]])" "$1" "$2"
}
median() {
  python3 -c "import statistics,sys; print(statistics.median(float(x) for x in sys.argv[1:]))" "$@"
}

presets=("$@")
if [ ${#presets[@]} -eq 0 ]; then
  mapfile -t presets < <("$weft" presets | awk '{print $1}')
fi
for preset in "${presets[@]}"; do
  declare -a off=() on=()
  for ((k = 0; k < runs; k++)); do
    for w in 0 1; do
      "$weft" record "$preset" --level summary --set "solver.weights.self=$w" \
        --summary "$tmp/$w.json" >/dev/null 2>&1 || true
      sps="$(figure "$tmp/$w.json" steps_per_second)"
      if [ "$w" = 0 ]; then off+=("$sps"); else on+=("$sps"); fi
    done
  done
  m_off="$(median "${off[@]}")"
  m_on="$(median "${on[@]}")"
  note="whole process, --level summary, median of $runs interleaved"
  echo "$commit,preset $preset self 0,steps_per_second,$m_off,steps/s,$note"
  echo "$commit,preset $preset self 1,steps_per_second,$m_on,steps/s,$note"
  ratio="$(python3 -c "print(round($m_on / $m_off, 3))")"
  echo "$commit,preset $preset self 1 / self 0,speed,$ratio,ratio,$note"
  for w in 0 1; do
    "$weft" record "$preset" --level summary --set "solver.weights.self=$w" \
      --summary "$tmp/$w.json" >/dev/null 2>&1 || true
    echo "$commit,preset $preset self $w,max_crossings,$(figure "$tmp/$w.json" max_crossings),edges,worst frame"
    echo "$commit,preset $preset self $w,crossing_frames,$(figure "$tmp/$w.json" crossing_frames),frames,of $(figure "$tmp/$w.json" frames)"
  done
done
