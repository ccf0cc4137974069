#!/bin/sh
# Where a volpath render spends its time, by category (docs/performance.md §1.2).
#
#   scripts/profile.sh SCENE.xml [SPP] [HAZE]
#
# Needs `perf` (Debian: apt-get install linux-perf). Samples one thread (the categories are per
# CPU time, so the thread count does not matter) at 2 kHz with DWARF call graphs (the release
# profile keeps debug info), then charges each sample to the first frame, inlined frames
# included, that scripts/profile_categories.py recognises. For a flame graph instead, feed the
# same `perf script` output to inferno-collapse-perf | inferno-flamegraph (not committed).
set -eu
scene=$1
spp=${2:-64}
haze=${3:-target/release/haze}
data=$(mktemp /tmp/haze-perf.XXXXXX)
perf record -q -F 2000 --call-graph dwarf,16384 -o "$data" \
    "$haze" render -q --threads 1 --spp "$spp" -o /tmp/haze-profile.exr "$scene" >/dev/null 2>&1
perf script -i "$data" -F ip,sym --inline 2>/dev/null | python3 "$(dirname "$0")/profile_categories.py"
rm -f "$data"
