#!/usr/bin/env bash
# Whole process on every shipped preset: each run five times at
# `--level summary` with nothing saved, the median of `steps_per_second`
# from the summary (`RAYON_NUM_THREADS=1` holds a large cloth to one thread).
#
#   benches/presets.sh [WEFT]
#
# WEFT defaults to the binary `cargo test` builds.
set -euo pipefail
cd "$(dirname "$0")/.."
weft="${1:-${CARGO_TARGET_DIR:-target}/debug/weft}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
for p in $("$weft" presets | awk '{print $1}'); do
  for _ in 1 2 3 4 5; do
    "$weft" record "$p" --level summary --summary "$tmp/f.json" 2> /dev/null
    python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['figures']['steps_per_second'])" "$tmp/f.json"
  done | sort -n | sed -n 3p | sed "s/^/$p /"
done
