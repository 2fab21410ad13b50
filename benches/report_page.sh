#!/usr/bin/env bash
# The results page of a large sweep: a 10 × 10 × 10 grid of hanging_sheet
# (1,000 points of 2 frames, level off), its report.html's size, and the
# time headless Chromium takes to load it: the page's own measure (from
# navigation to the end of loading, `data-loaded-ms`) and the whole browser
# process beside one that loads an empty page, medians of 5.
# Prints CSV rows (`commit,benchmark,measure,value,unit,note`, as in
# benches/results/).
#
#   benches/report_page.sh [WEFT] >> benches/results/MACHINE.csv
#
# WEFT defaults to the binary `cargo test` builds.
set -euo pipefail
cd "$(dirname "$0")/.."
weft="$(realpath "${1:-${CARGO_TARGET_DIR:-target}/debug/weft}")"
commit="$(git rev-parse --short HEAD)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$weft" sweep hanging_sheet --set solver.weights.curvature=0.05..0.5:10 \
  --set solver.damping=0.9..0.99:10 --set solver.weights.normality=0.1..0.5:10 \
  --frames 2 --level off --yes --out "$tmp/big" > /dev/null 2>&1
page="$tmp/big/report.html"
chrome=(chromium --headless --no-sandbox --disable-gpu --dump-dom)
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
wall() { # the whole process, seconds
  local s; s=$(date +%s.%N); "${chrome[@]}" "$1" > "$tmp/dom" 2> /dev/null
  echo "$(date +%s.%N) - $s" | bc
}
loaded=$(for _ in 1 2 3 4 5; do
  "${chrome[@]}" "file://$page" 2> /dev/null | grep -o 'data-loaded-ms="[0-9]*"' | grep -o '[0-9]*'
done | median)
page_wall=$(for _ in 1 2 3 4 5; do wall "file://$page"; done | median)
blank_wall=$(for _ in 1 2 3 4 5; do wall about:blank; done | median)
echo "$commit,report page 1000 points,size,$(stat -c %s "$page"),bytes,"
echo "$commit,report page 1000 points,loaded,$loaded,ms,headless Chromium's performance.now() at load; median of 5"
echo "$commit,report page 1000 points,browser process,$page_wall,s,median of 5"
echo "$commit,report page 1000 points,browser process on about:blank,$blank_wall,s,median of 5"
