#!/usr/bin/env bash
# Instruction counts of haze builds (docs/performance.md §1.3): one 1-thread render per build
# and workload under valgrind's callgrind, which counts the instructions executed exactly, so
# two builds compare without timing noise. Prints per workload each build's total count, its
# ratio to the first build's, and the functions whose counts changed most; says whether the
# images are identical.
#
#   scripts/icount.sh BASE_BIN OTHER_BIN... -- SCENE.xml:METHOD[:ARG,ARG...]...
#   scripts/icount.sh /tmp/haze-old target/release/haze -- scenes/bench-fog-shadow.xml:volpath:--spp,8
#
# Valgrind does not run AVX-512 code: build both sides with
# RUSTFLAGS="-C target-cpu=x86-64-v3" (cargo's native default on a Zen 4 or Xeon would use it).
# Callgrind runs about 50x slower than the render: keep workloads small (a few spp).
# An instruction count is not a time (a build with fewer instructions can run slower, §3.6),
# but a count that grows says the code does more work.
set -euo pipefail
command -v valgrind > /dev/null && command -v callgrind_annotate > /dev/null \
  || { echo "icount.sh: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
# shellcheck source=scripts/builds-args.sh
source "$(dirname "$0")/builds-args.sh"
parse_builds icount.sh "scripts/icount.sh BASE_BIN OTHER_BIN... -- SCENE:METHOD[:ARGS]..." "$@"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for spec in "${specs[@]}"; do
  parse_spec "$spec"
  for i in "${!bins[@]}"; do
    # shellcheck disable=SC2086
    valgrind --tool=callgrind --callgrind-out-file="$out/cg.$i" "${bins[$i]}" render "$scene" \
      --integrator "$method" $args --seed 1 --threads 1 -q -o "$out/image.$i.exr" > /dev/null 2> "$out/err.$i" \
      || { tail -5 "$out/err.$i" >&2; echo "icount.sh: ${bins[$i]} failed on $spec (an AVX-512 build? see the header)" >&2; exit 1; }
    callgrind_annotate --auto=no --threshold=100 "$out/cg.$i" > "$out/fn.$i" 2> /dev/null
  done
  python3 - "$out" "$spec" "${bins[@]}" <<'EOF'
import hashlib, re, sys
out, spec, bins = sys.argv[1], sys.argv[2], sys.argv[3:]
def counts(i):
    total, fns = 0, {}
    for line in open(f"{out}/fn.{i}"):
        m = re.match(r"\s*([\d,]+) \([ \d.]+%\)\s+(.*)", line)
        if not m:
            continue
        n, name = int(m.group(1).replace(",", "")), m.group(2)
        if name.startswith("PROGRAM TOTALS"):
            total = n
            continue
        name = re.sub(r"\s*\[[^\]]*\]$", "", name)
        name = name.split(":", 1)[1] if re.match(r"[^ ]*\.(rs|c|S|h):", name) else name
        fns[name] = fns.get(name, 0) + n
    return total, fns
res = [counts(i) for i in range(len(bins))]
digests = {hashlib.sha256(open(f"{out}/image.{i}.exr", "rb").read()).hexdigest() for i in range(len(bins))}
print(f"### {spec}  (images {'identical' if len(digests) == 1 else 'DIFFER'})")
print("| build | instructions | ratio to first |")
print("|---|---|---|")
for b, (t, _) in zip(bins, res):
    print(f"| {b} | {t:,} | {t / res[0][0]:.4f} |")
for b, (t, fns) in zip(bins[1:], res[1:]):
    base = res[0][1]
    diff = sorted(((fns.get(k, 0) - base.get(k, 0), k) for k in set(fns) | set(base)), key=lambda d: -abs(d[0]))
    print(f"\nlargest changes, {b} against {bins[0]}:")
    for d, k in diff[:6]:
        if d:
            print(f"  {d:+,}  {k[:100]}")
EOF
done
