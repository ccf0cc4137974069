#!/usr/bin/env bash
# A/B runs of haze builds (docs/performance.md §1.3): alternated 1-thread renders of the same
# scene, seed and spp, the builds' order reversed every other round, timing each render's user
# CPU time; prints per build and workload the median time and the median of the per-round time
# ratios against the first build, with its quartiles.
#
#   scripts/ab.sh [-n ROUNDS] BASE_BIN OTHER_BIN... -- SCENE.xml:METHOD[:ARG,ARG...]...
#   scripts/ab.sh -n 10 /tmp/haze-old target/release/haze -- \
#       scenes/bench-fog-shadow.xml:volpath:--spp,256 \
#       scenes/bench-fog-shadow.xml:vrl_lightcuts:--spp,128,--vrls,2000
#
# Raw times go to $AB_LOG (default target/ab.log). Run on a quiet machine; a median over 10
# rounds resolves about +-3% on the 2-core development machine.
set -euo pipefail
rounds=10
if [ "${1:-}" = "-n" ]; then rounds=$2; shift 2; fi
# shellcheck source=scripts/builds-args.sh
source "$(dirname "$0")/builds-args.sh"
parse_builds ab.sh "scripts/ab.sh [-n ROUNDS] BASE_BIN OTHER_BIN... -- SCENE:METHOD[:ARGS]..." "$@"
log=${AB_LOG:-target/ab.log}
mkdir -p "$(dirname "$log")"
: > "$log"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for spec in "${specs[@]}"; do
  parse_spec "$spec"
  for round in $(seq "$rounds"); do
    order=("${bins[@]}")
    if [ $((round % 2)) = 0 ]; then
      order=(); for ((i = ${#bins[@]} - 1; i >= 0; i--)); do order+=("${bins[$i]}"); done
    fi
    for b in "${order[@]}"; do
      # shellcheck disable=SC2086
      /usr/bin/time -o "$out/time" -f "%U" "$b" render "$scene" --integrator "$method" $args \
        --seed 1 --threads 1 -q -o "$out/image.exr" > /dev/null 2> "$out/err" \
        || { cat "$out/err" >&2; echo "ab.sh: $b failed on $spec" >&2; exit 1; }
      printf '%s\t%s\t%s\t%s\t%s\n' "$spec" "$b" "$round" "$(cat "$out/time")" "$(sha256sum < "$out/image.exr" | cut -c1-16)" >> "$log"
    done
  done
done
python3 - "$log" "${bins[0]}" <<'EOF'
import collections, statistics, sys
log, base = sys.argv[1], sys.argv[2]
times = collections.defaultdict(dict)
images = collections.defaultdict(set)
for line in open(log):
    spec, b, rnd, t, digest = line.rstrip("\n").split("\t")
    times[(spec, rnd)][b] = float(t)
    images[spec].add(digest)
specs = list(dict.fromkeys(k[0] for k in times))
bins = list(dict.fromkeys(b for v in times.values() for b in v))
print("| workload | build | median user s | ratio to first (median, quartiles) | images |")
print("|---|---|---|---|---|")
for spec in specs:
    rounds = [v for (s, _), v in times.items() if s == spec]
    same = "identical" if len(images[spec]) == 1 else "DIFFER"
    for b in bins:
        med = statistics.median(r[b] for r in rounds)
        if b == base:
            ratio = "1"
        else:
            q = sorted(r[b] / r[base] for r in rounds)
            qs = statistics.quantiles(q, n=4) if len(q) > 1 else [q[0]] * 3
            ratio = f"{qs[1]:.3f} ({qs[0]:.3f}-{qs[2]:.3f})"
        print(f"| {spec} | {b} | {med:.3f} | {ratio} | {same} |")
EOF
