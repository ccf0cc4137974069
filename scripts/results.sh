#!/usr/bin/env bash
# Regenerates docs/results.md: equal-time `haze compare` runs, several seeds each, on
#   - the benchmark scenes (scenes/bench-*.xml) at RES x RES against long references rendered by
#     REF_METHOD (default the stochastic cut, `vrl_lightcuts` with 1000 VRLs: unbiased and z-tested
#     against volpath and Mitsuba 3 in CI, and far less noisy per second than volpath on these
#     scenes, whose volpath references' fireflies put a floor under every method's error;
#     REF_METHOD=volpath gives the old references),
#   - the validation scenes (tests/data/validation) against their Mitsuba 3 references,
#   - the benchmark scenes at 640x360 (WIDE_*), where light tracing amortises over more pixels;
#   - whole images with lit surfaces and glass (WHOLE_*): scenes/glass-beam.xml (320x240),
#     tests/data/glass-ball-room.xml (256x192) and scenes/cbox-fog.xml (512x512), against
#     REF_METHOD references (volpath cannot find the spot's caustic through the ball, so it cannot
#     be the reference there), with volpath's error split into bias and noise
#     (scripts/bias-noise.py, with $PYTHON if it has numpy and OpenEXR);
#   - the heterogeneous smoke plume (PLUME_*): scenes/smoke-plume.xml at PLUME_RES and each of
#     PLUME_DENSITIES, every method
#     against a volpath reference (volpath is the method to beat in heterogeneous media, and its
#     reference has no many-light method's correlated noise);
#   - sun and sky (SKY_*, issue 36): part sky, scenes/sun-shafts.xml (a directional sun through
#     windows into haze, a constant sky; SKY_RES) against a REF_METHOD reference; part cloud,
#     scenes/cloud.xml (a heterogeneous cumulus under sun and sky; CLOUD_RES) against a volpath
#     reference, as the plume, brute force with 100 lights (a pass of 1000 takes longer than the
#     budget);
#   - Mitsuba 3's media test scenes lit by an environment (PEERS_*, issue 36; part peers, needs the
#     peer data, $HAZE_PEERS_DIR or ../shared/peers, skipped with a line without it) against their
#     Mitsuba 3 references (about 32,000 spp), 48x48;
# scripts/aggregate-results.py turns the runs of one scene into one table: median RMSE over the
# seeds with its min-max, and RMSE ratios computed per seed (same run, same machine load).
# Methods: volpath; brute-force vrl at two light counts; the paper's deterministic cut
# (cut=bound) at two; the stochastic cut (the default) at two, with --light-samples 4, and
# vpl_lightcuts; on the validation scenes also the stochastic cut with path_traced_media=all.
# Camera samples per pass: 1 for volpath (it batches passes anyway), brute-force
# vrl and the bound cut (their cost per sample grows with the lights), the auto default for the
# stochastic cut (16 at 128x128, 1 at 640x360), whose pass's light tracing and build are shared
# by the pass's samples (docs/lightcuts.md, "Choosing the defaults"); the two groups run one
# after the other per seed. Raw tables and
# images go to $OUT (not committed); HTML reports of seed 0 to $OUT/<scene>/report*/.
#
# Budgets come from the environment:
#   scripts/results.sh                                  # the documented run (about 1.5 h)
#   REF_TIME=5 WIDE_REF_TIME=5 BUDGET=1 WIDE_BUDGET=1 SEEDS=0 scripts/results.sh   # a smoke test
# With REUSE_REF=1 an existing $OUT/<scene>/reference.exr is kept (e.g. rendered earlier with
# `nice`: a reference's quality does not depend on the load, an equal-time comparison's does).
# PARTS selects parts: "bench validation wide whole plume sky cloud peers" (default all eight). The document
# holds only the parts run: for one part alone, give DOC another file and copy its section.
set -euo pipefail
cd "$(dirname "$0")/.."
REF_TIME=${REF_TIME:-240}
WIDE_REF_TIME=${WIDE_REF_TIME:-420}
BUDGET=${BUDGET:-10}
WIDE_BUDGET=${WIDE_BUDGET:-20}
RES=${RES:-128}
SEEDS=${SEEDS:-"0 1 2"}
REF_METHOD=${REF_METHOD:-vrl_lightcuts}
OUT=${OUT:-target/results}
SCENES=${SCENES:-"smoke-room spot-beam fog-shadow"}
PARTS=${PARTS:-"bench validation wide whole plume sky cloud peers"}
WHOLE_REF_TIME=${WHOLE_REF_TIME:-300}
WHOLE_BUDGET=${WHOLE_BUDGET:-20}
PLUME_REF_TIME=${PLUME_REF_TIME:-240}
PLUME_BUDGET=${PLUME_BUDGET:-10}
PLUME_RES=${PLUME_RES:-"64 80"}
# Density scales of the plume (the scene's `density`, Mitsuba's `scale`): 8 is the dense smoke
# of the demo; the thinner ones show where the many-light methods stand against volpath.
PLUME_DENSITIES=${PLUME_DENSITIES:-"8 2 1"}
SKY_REF_TIME=${SKY_REF_TIME:-240}
SKY_BUDGET=${SKY_BUDGET:-15}
SKY_RES=${SKY_RES:-"320 180"}
CLOUD_RES=${CLOUD_RES:-"160 120"}
PEERS_BUDGET=${PEERS_BUDGET:-5}
PEERS_DIR=${HAZE_PEERS_DIR:-../shared/peers}/mitsuba3-media-tests/tests/scenes/participating_media
# The suite's scenes with a `constant` or `envmap` emitter (file stems).
PEERS_SCENES=${PEERS_SCENES:-"test_homo_dielectric_envmap_volpath test_homo_null_envmap_volpath
  test_homo_obj_inside_medium_volpath test_homo_spectral_sigmat_volpathmis test_homo_emitter_inside_medium_volpath
  test_surf_area_light_volpath test_hetero_sigmat_volpath test_hetero_sigmat_albedo_volpath
  test_hetero_spectral_sigmat_volpathmis"}
# Two groups per run, separated by "--": one sample per pass, then each method's auto samples per
# pass (haze render --help: about 262,144 camera samples per pass for the lightcut methods).
METHODS=(volpath vrl:1000 vrl:10000 vrl_lightcuts:10000,cut=bound vrl_lightcuts:100000,cut=bound --
  vrl_lightcuts:1000 vrl_lightcuts:1000,light_samples=4 vrl_lightcuts:10000 vpl_lightcuts:10000)
# The validation scenes add the stochastic cut with every medium path-traced (the camera path
# traced as volpath traces it, the virtual lights serving surfaces only): the dense hg-box is
# lost to volpath with the default gathering.
VALIDATION_METHODS=("${METHODS[@]}" vrl_lightcuts:1000,path_traced_media=all)
WIDE_METHODS=(volpath vrl:1000 -- vrl_lightcuts:1000 vrl_lightcuts:10000)
WHOLE_METHODS=(volpath vrl:1000 -- vrl_lightcuts:1000 vpl_lightcuts:10000)
PLUME_METHODS=(volpath vrl:1000 vpl:1000 -- vrl_lightcuts:1000 vrl_lightcuts:10000 vpl_lightcuts:10000
  vpl_lightcuts:10000,light_samples=4)
SKY_METHODS=(volpath vrl:1000 vpl:1000 -- vrl_lightcuts:1000 vrl_lightcuts:10000 vpl_lightcuts:10000)
PEERS_METHODS=(volpath -- vrl_lightcuts:1000 vrl_lightcuts:10000 vpl_lightcuts:10000)
CLOUD_METHODS=(volpath vrl:100 vpl:100 -- vrl_lightcuts:1000 vrl_lightcuts:10000 vpl_lightcuts:10000
  vpl_lightcuts:10000,light_samples=4)
cargo build --release -p haze-cli >&2
HAZE=${CARGO_TARGET_DIR:-target}/release/haze
DOC=${DOC:-docs/results.md}
PYTHON=${PYTHON:-python3}

# compare NAME SCENE REFERENCE BUDGET "DEFINES" METHOD... [-- METHOD...]: runs every seed into
# $OUT/NAME (the methods before "--" with one sample per pass, those after it with their auto
# samples per pass) and prints the aggregated table.
compare() {
  local name=$1 scene=$2 ref=$3 budget=$4 defines=$5
  shift 5
  local dir=$OUT/$name groups=() group="" tables=()
  for m in "$@"; do
    if [ "$m" = "--" ]; then groups+=("$group"); group=""; else group+=" --method $m"; fi
  done
  groups+=("$group")
  mkdir -p "$dir"
  for seed in $SEEDS; do
    : > "$dir/seed-$seed.md"
    local g=0
    for methods in "${groups[@]}"; do
      local spp=(--spp-per-pass 1) extra=()
      [ "$g" -gt 0 ] && spp=()
      if [ "$seed" = "$(echo $SEEDS | cut -d' ' -f1)" ]; then extra=(--report "$dir/report-$g"); fi
      # shellcheck disable=SC2086
      "$HAZE" compare "$scene" $defines --reference "$ref" --time "$budget" --seed "$seed" \
        "${spp[@]}" $methods -o "$dir/images-$seed" "${extra[@]}" > "$dir/seed-$seed-$g.md"
      # The first group's header, then every group's rows.
      if [ "$g" = 0 ]; then cat "$dir/seed-$seed-$g.md"; else tail -n +3 "$dir/seed-$seed-$g.md"; fi >> "$dir/seed-$seed.md"
      g=$((g + 1))
    done
    tables+=("$dir/seed-$seed.md")
  done
  python3 scripts/aggregate-results.py "${tables[@]}"
}

reference() { # reference SCENE OUT.exr SECONDS "DEFINES"
  if [ "${REUSE_REF:-0}" = 1 ] && [ -f "$2" ]; then
    echo "reusing $2" >&2
  else
    mkdir -p "$(dirname "$2")"
    if [ "$REF_METHOD" = volpath ]; then
      # shellcheck disable=SC2086
      "$HAZE" reference "$1" $4 --time "$3" --seed 1000003 -o "$2" >&2
    else
      # shellcheck disable=SC2086
      "$HAZE" render "$1" $4 --integrator "$REF_METHOD" --vrls 1000 --time "$3" --seed 1000003 -o "$2" >&2
    fi
  fi
}

load() { cut -d' ' -f1-3 /proc/loadavg; }

{
  echo "# Results: equal-time comparisons"
  echo
  echo "Regenerated from $(date -u '+%Y-%m-%d %H:%M') UTC with main \`$(git rev-parse --short HEAD)\`$(git diff --quiet HEAD -- crates || echo ' (crates modified)')"
  echo "($(nproc) cores, $(uname -m)) by"
  echo
  echo "\`\`\`sh"
  echo "PARTS=\"$PARTS\" SEEDS=\"$SEEDS\" REUSE_REF=${REUSE_REF:-0} REF_TIME=$REF_TIME BUDGET=$BUDGET \\"
  echo "  WIDE_REF_TIME=$WIDE_REF_TIME WIDE_BUDGET=$WIDE_BUDGET WHOLE_REF_TIME=$WHOLE_REF_TIME WHOLE_BUDGET=$WHOLE_BUDGET \\"
  echo "  PLUME_REF_TIME=$PLUME_REF_TIME PLUME_BUDGET=$PLUME_BUDGET SKY_REF_TIME=$SKY_REF_TIME SKY_BUDGET=$SKY_BUDGET \\"
  echo "  PEERS_BUDGET=$PEERS_BUDGET scripts/results.sh"
  echo "\`\`\`"
  echo
  echo "Do not edit the tables by hand. Each method renders for the"
  echo "budget in wall-clock seconds, light tracing and tree builds included (the stochastic cut with its auto samples per pass, the others 1), once per"
  echo "seed ($SEEDS); the tables give the median over the seeds and its min-max, and ratios taken per"
  echo "seed (the methods of one seed run one after the other, under about the same machine load)."
  echo "References (seed 1000003; each table names its own): benchmark scenes \`$REF_METHOD\` (1000 VRLs if a many-light method),"
  echo "$REF_TIME s at ${RES}x${RES}, $WIDE_REF_TIME s at 640x360, $WHOLE_REF_TIME s for whole images$( [ "${REUSE_REF:-0}" = 1 ] && echo ' (REUSE_REF=1: a reference already in '"$OUT"' is kept, with the time it had)');"
  echo "validation and peer scenes their Mitsuba 3 references (16384 spp). A reference's own noise adds to every method's"
  echo "MSE, so ratios near 1 are pulled towards 1."
  echo
  echo "Metrics (crates/render/src/metrics.rs): RMSE over pixels and channels; SMAPE ="
  echo "100 mean |a-r|/(|a|+|r|), entries where both are 0 skipped (range 0-100). The paper's numbers"
  echo "(Vibert et al. 2019) are in [theory.md](theory.md#10-the-papers-reported-numbers) §10."
} > "$DOC.tmp"

for part in $PARTS; do
  case $part in
    bench)
      for s in $SCENES; do
        ref=$OUT/$s/reference.exr
        reference "scenes/bench-$s.xml" "$ref" "$REF_TIME" "-D res=$RES -D res_y=$RES"
        start_load=$(load)
        table=$(compare "$s" "scenes/bench-$s.xml" "$ref" "$BUDGET" "-D res=$RES -D res_y=$RES" "${METHODS[@]}")
        printf '\n## bench-%s, %sx%s, %s s per method\n\n`scenes/bench-%s.xml`; load average %s at the start, %s at the end.\n\n%s\n' \
          "$s" "$RES" "$RES" "$BUDGET" "$s" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      done
      ;;
    validation)
      for s in hg-box foggy-room; do
        start_load=$(load)
        table=$(compare "validation-$s" "tests/data/validation/scenes/$s.xml" "tests/data/validation/refs/$s.exr" \
          "$BUDGET" "" "${VALIDATION_METHODS[@]}")
        printf '\n## %s (validation scene, 128x96), %s s per method\n\n`tests/data/validation/scenes/%s.xml`, Mitsuba 3 reference; load average %s at the start, %s at the end.\n\n%s\n' \
          "$s" "$BUDGET" "$s" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      done
      ;;
    wide)
      for s in $SCENES; do
        ref=$OUT/wide/$s/reference.exr
        reference "scenes/bench-$s.xml" "$ref" "$WIDE_REF_TIME" "-D res=640 -D res_y=360"
        start_load=$(load)
        table=$(compare "wide/$s" "scenes/bench-$s.xml" "$ref" "$WIDE_BUDGET" "-D res=640 -D res_y=360" "${WIDE_METHODS[@]}")
        printf '\n## bench-%s, 640x360, %s s per method\n\nLoad average %s at the start, %s at the end.\n\n%s\n' \
          "$s" "$WIDE_BUDGET" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      done
      ;;
    whole)
      for s in ${WHOLE_SCENES:-glass-beam glass-ball-room cbox-fog}; do
        case $s in
          glass-beam) scene=scenes/glass-beam.xml defines="" size=320x240 ;;
          glass-ball-room) scene=tests/data/glass-ball-room.xml defines="-D res=256 -D res_y=192" size=256x192 ;;
          cbox-fog) scene=scenes/cbox-fog.xml defines="" size=512x512 ;;
          *) echo "unknown whole-image scene '$s'" >&2; exit 1 ;;
        esac
        ref=$OUT/whole/$s/reference.exr
        reference "$scene" "$ref" "$WHOLE_REF_TIME" "$defines"
        start_load=$(load)
        table=$(compare "whole/$s" "$scene" "$ref" "$WHOLE_BUDGET" "$defines" "${WHOLE_METHODS[@]}")
        printf '\n## %s (whole image), %s, %s s per method\n\n`%s`, `%s` reference (%s s); load average %s at the start, %s at the end.\n\n%s\n' \
          "$s" "$size" "$WHOLE_BUDGET" "$scene" "$REF_METHOD" "$WHOLE_REF_TIME" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
        images=()
        for seed in $SEEDS; do images+=("$OUT/whole/$s/images-$seed/volpath.exr"); done
        if "$PYTHON" -c 'import numpy, OpenEXR' 2>/dev/null; then
          printf -- '- volpath against the reference (scripts/bias-noise.py): %s\n' \
            "$("$PYTHON" scripts/bias-noise.py "$ref" "${images[@]}")" >> "$DOC.tmp"
        else
          echo "- volpath's bias/noise split skipped: $PYTHON has no numpy and OpenEXR" >> "$DOC.tmp"
        fi
      done
      ;;
    plume)
      read -r pw ph <<< "$PLUME_RES"
      for density in $PLUME_DENSITIES; do
        defines="-D res=$pw -D res_y=$ph -D density=$density"
        ref=$OUT/plume-$density/reference.exr
        if [ "${REUSE_REF:-0}" = 1 ] && [ -f "$ref" ]; then
          echo "reusing $ref" >&2
        else
          mkdir -p "$(dirname "$ref")"
          # shellcheck disable=SC2086
          "$HAZE" reference scenes/smoke-plume.xml $defines --time "$PLUME_REF_TIME" --seed 1000003 -o "$ref" >&2
        fi
        start_load=$(load)
        table=$(compare "plume-$density/smoke-plume" scenes/smoke-plume.xml "$ref" "$PLUME_BUDGET" "$defines" "${PLUME_METHODS[@]}")
        printf '\n## smoke-plume (heterogeneous, density %s), %sx%s, %s s per method\n\n`scenes/smoke-plume.xml -D density=%s`, volpath reference (%s s); load average %s at the start, %s at the end.\n\n%s\n' \
          "$density" "$pw" "$ph" "$PLUME_BUDGET" "$density" "$PLUME_REF_TIME" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      done
      ;;
    sky)
      read -r sw sh <<< "$SKY_RES"
      defines="-D res=$sw -D res_y=$sh"
      ref=$OUT/sky/sun-shafts/reference.exr
      reference scenes/sun-shafts.xml "$ref" "$SKY_REF_TIME" "$defines"
      start_load=$(load)
      table=$(compare "sky/sun-shafts" scenes/sun-shafts.xml "$ref" "$SKY_BUDGET" "$defines" "${SKY_METHODS[@]}")
      printf '\n## sun-shafts (sun and sky through windows into haze), %sx%s, %s s per method\n\n`scenes/sun-shafts.xml`, `%s` reference (%s s); load average %s at the start, %s at the end.\n\n%s\n' \
        "$sw" "$sh" "$SKY_BUDGET" "$REF_METHOD" "$SKY_REF_TIME" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      ;;
    cloud)
      read -r cw ch <<< "$CLOUD_RES"
      defines="-D res=$cw -D res_y=$ch"
      ref=$OUT/sky/cloud/reference.exr
      if [ "${REUSE_REF:-0}" = 1 ] && [ -f "$ref" ]; then
        echo "reusing $ref" >&2
      else
        mkdir -p "$(dirname "$ref")"
        # shellcheck disable=SC2086
        "$HAZE" reference scenes/cloud.xml $defines --time "$SKY_REF_TIME" --seed 1000003 -o "$ref" >&2
      fi
      start_load=$(load)
      table=$(compare "sky/cloud" scenes/cloud.xml "$ref" "$SKY_BUDGET" "$defines" "${CLOUD_METHODS[@]}")
      printf '\n## cloud (heterogeneous cumulus under sun and sky), %sx%s, %s s per method\n\n`scenes/cloud.xml`, volpath reference (%s s); load average %s at the start, %s at the end.\n\n%s\n' \
        "$cw" "$ch" "$SKY_BUDGET" "$SKY_REF_TIME" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      ;;
    peers)
      if [ ! -d "$PEERS_DIR" ]; then
        echo "part peers skipped: no peer data at $PEERS_DIR" >&2
        continue
      fi
      for s in $PEERS_SCENES; do
        stem=${s%_*}
        start_load=$(load)
        table=$(compare "peers/$stem" "$PEERS_DIR/$s.xml" "$PEERS_DIR/refs/${stem}_ref_rgb.exr" "$PEERS_BUDGET" "" "${PEERS_METHODS[@]}")
        printf '\n## Mitsuba 3 %s (environment-lit, 48x48), %s s per method\n\nMitsuba 3 reference; load average %s at the start, %s at the end.\n\n%s\n' \
          "$stem" "$PEERS_BUDGET" "$start_load" "$(load)" "$table" >> "$DOC.tmp"
      done
      ;;
    *) echo "unknown part '$part' (bench, validation, wide, whole, plume, sky, cloud, peers)" >&2; exit 1 ;;
  esac
done

# The hand-written discussion (between the findings markers) survives regeneration: it is taken
# from the previous docs/results.md and put back under the header. Update it when numbers change.
if [ -f "$DOC" ] && grep -q '<!-- findings:begin -->' "$DOC"; then
  sed -n '/<!-- findings:begin -->/,/<!-- findings:end -->/p' "$DOC" > "$DOC.findings"
  { sed -n '1,/^## /{/^## /!p}' "$DOC.tmp"; cat "$DOC.findings"; echo; sed -n '/^## /,$p' "$DOC.tmp"; } > "$DOC.tmp2"
  mv "$DOC.tmp2" "$DOC.tmp"
  rm -f "$DOC.findings"
fi
mv "$DOC.tmp" "$DOC"
echo "wrote $DOC" >&2
