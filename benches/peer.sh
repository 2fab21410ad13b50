#!/usr/bin/env bash
# weft against the peer XPBD solver (`rapier-cloth-core`), back to back in one
# benchmark binary: the `step` benchmarks at SIZE × SIZE (one substep × 10
# sweeps, a sheet pinned at two corners, benches/step.rs), built with the
# release profile. Prints CSV rows (`commit,benchmark,measure,value,unit,note`,
# as in benches/results/): each solver's steps/s (criterion's middle
# estimate) and weft's speed-up over the peer.
#
#   benches/peer.sh [SIZE] >> benches/results/MACHINE.csv
#
# SIZE is 32, 64 (the default), 128 or 256.
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-64}"
commit="$(git rev-parse --short HEAD)"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
cargo bench --no-default-features --bench step -- --noplot \
  "^step/(weft|rapier-cloth-core)/${size}\$" >"$log" 2>&1 || { cat "$log" >&2; exit 1; }
python3 - "$log" "$commit" "$size" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
commit, size = sys.argv[2], sys.argv[3]
units = {"ns": 1e-9, "µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0}
sps = {}
for name, mid, unit in re.findall(
    r"step/(weft|rapier-cloth-core)/\d+\s+time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]", text
):
    sps[name] = 1.0 / (float(mid) * units[unit])
if len(sps) != 2:
    sys.exit("peer.sh: criterion printed no time for both solvers:\n" + text)
note = f"criterion step, {size}x{size}, 1 substep x 10 sweeps, release"
for name, v in sps.items():
    print(f"{commit},step/{name}/{size},steps_per_second,{v:.1f},steps/s,{note}")
print(f"{commit},step/{size} weft over peer,ratio,{sps['weft'] / sps['rapier-cloth-core']:.2f},x,{note}")
PY
