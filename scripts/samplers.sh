#!/usr/bin/env bash
# Equal-time runs of docs/results.md "Samplers" (issue 38): every sampler with volpath and with
# vrl_lightcuts (its defaults), one thread, BUDGET seconds per method (vrl_lightcuts LC_BUDGET),
# seeds SEEDS, on the three
# bench scenes at 64x64 (against vrl_lightcuts references with 1000 VRLs, REF_TIME s, all cores,
# seed 1000003, as scripts/results.sh makes them) and the two validation scenes at 128x96
# (against their Mitsuba 3 references). Seeds outermost, then scenes, then the two methods; the
# samplers' order within a `haze compare` is rotated by one per seed, so that a change of the
# machine's load does not fall on the same sampler every time. The load average is logged before
# and after each compare. Tables: scripts/samplers-table.py $OUT.
#
#   scripts/samplers.sh                       # about 17 min, plus 3 x REF_TIME for the references
#   REUSE_REF=1 scripts/samplers.sh           # keep $OUT/ref/*.exr
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-target/samplers}
BUDGET=${BUDGET:-2}
# vrl_lightcuts renders passes of 64 spp at 64x64 (21 at 128x96), 5-10 in 2 s: a longer budget
# makes the last pass's overrun a smaller part of the time.
LC_BUDGET=${LC_BUDGET:-4}
SEEDS=${SEEDS:-"1 2 3"}
REF_TIME=${REF_TIME:-180}
METHODS=${METHODS:-"volpath vrl_lightcuts"}
SCENES=${SCENES:-"smoke-room fog-shadow spot-beam hg-box foggy-room"}
HAZE=${CARGO_TARGET_DIR:-target}/release/haze
SAMPLERS=(independent stratified multijitter orthogonal ldsampler)
BENCH="smoke-room fog-shadow spot-beam"
mkdir -p "$OUT/ref"
load() { cut -d' ' -f1-3 /proc/loadavg; }

for s in $BENCH; do
  ref=$OUT/ref/bench-$s.exr
  if [ "${REUSE_REF:-0}" = 1 ] && [ -f "$ref" ]; then continue; fi
  "$HAZE" render "scenes/bench-$s.xml" -D res=64 -D res_y=64 --integrator vrl_lightcuts --vrls 1000 \
    --time "$REF_TIME" --seed 1000003 -o "$ref" >&2
done

i=0
for seed in $SEEDS; do
  order=("${SAMPLERS[@]:$((i % 5))}" "${SAMPLERS[@]:0:$((i % 5))}")
  for s in $SCENES; do
    case $s in
      hg-box | foggy-room) scene=tests/data/validation/scenes/$s.xml ref=tests/data/validation/refs/$s.exr defines="" ;;
      *) scene=scenes/bench-$s.xml ref=$OUT/ref/bench-$s.exr defines="-D res=64 -D res_y=64" ;;
    esac
    mkdir -p "$OUT/$s"
    for m in $METHODS; do
      args=() budget=$BUDGET
      [ "$m" = volpath ] || budget=$LC_BUDGET
      for k in "${order[@]}"; do args+=(--method "$m,sampler=$k"); done
      load > "$OUT/$s/$m-$seed.load"
      echo "$s $m seed $seed: load $(load)" >&2
      # shellcheck disable=SC2086
      "$HAZE" compare "$scene" $defines --reference "$ref" --time "$budget" --threads 1 --seed "$seed" \
        "${args[@]}" -o "$OUT/$s/images-$m-$seed" > "$OUT/$s/$m-$seed.md" 2> "$OUT/$s/$m-$seed.log"
      load >> "$OUT/$s/$m-$seed.load"
      echo "$s $m seed $seed: done, load $(load)" >&2
    done
  done
  i=$((i + 1))
done
