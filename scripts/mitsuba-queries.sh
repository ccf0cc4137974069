#!/bin/sh
# How many ray queries Mitsuba 3 (llvm_ad_rgb) makes per camera sample, and how full its 16-lane
# Embree packets are (docs/performance.md §1.4, §2.2).
#
#   scripts/mitsuba-queries.sh SCENE.xml [SPP] [PYTHON]
#
# Needs root, `perf` with uprobes, and a Python with `mitsuba` (DRJIT_LIBLLVM_PATH set for the
# LLVM variant). Puts uprobes on the entry of Mitsuba's `rtcIntersect16` and `rtcOccluded16`
# wrappers in its libembree3.so, recording the 16 ints of each call's `valid` mask (the first
# argument), renders the scene once at 48x48 (the peer scenes' `res`), and counts calls and
# active lanes. The render includes the kernel's compilation, which traces no rays.
set -eu
scene=$1
spp=${2:-64}
python=${3:-python3}
lib=$("$python" -c 'import mitsuba, os; print(os.path.join(os.path.dirname(mitsuba.__file__), "libembree3.so"))')
addr() { nm -D --defined-only "$lib" | awk -v s="$1" '$3 ~ s { print "0x" $1; exit }'; }
args=""
for i in $(seq 0 15); do args="$args v$i=+$((i * 4))(%di):s32"; done
perf probe -q -d 'probe_libembree3:*' 2>/dev/null || true
data=$(mktemp /tmp/mitsuba-queries.XXXXXX)
# The probes and the recording go away however the script ends.
trap 'perf probe -q -d "probe_libembree3:*" 2>/dev/null || true; rm -f "$data"' EXIT
perf probe -q -x "$lib" --add "isect16=$(addr 'rtcIntersect16EPKi') $args"
perf probe -q -x "$lib" --add "occl16=$(addr 'rtcOccluded16EPKi') $args"
perf record -q -e probe_libembree3:isect16 -e probe_libembree3:occl16 -o "$data" \
    "$python" -c "
import sys, mitsuba as mi, drjit as dr
mi.set_variant('llvm_ad_rgb')
scene = mi.load_file(sys.argv[1], spp=int(sys.argv[2]), res=48)
dr.eval(mi.render(scene, seed=0))
" "$scene" "$spp" >/dev/null 2>&1
perf script -i "$data" 2>/dev/null | python3 -c "
import re, sys
samples = 48 * 48 * int(sys.argv[1])
calls, lanes = {}, {}
for line in sys.stdin:
    m = re.search(r'probe_libembree3:(\w+):', line)
    if m:
        k = m.group(1)
        calls[k] = calls.get(k, 0) + 1
        lanes[k] = lanes.get(k, 0) + sum(v != '0' for v in re.findall(r'v\d+=(-?\d+)', line))
for k in ('isect16', 'occl16'):
    c, l = calls.get(k, 0), lanes.get(k, 0)
    print(f'{k}: {c} calls, {l} active lanes, {l / samples:.3f} per sample, {l / max(c, 1):.2f} lanes per call')
" "$spp"
