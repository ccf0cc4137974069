#!/usr/bin/env bash
# Downloads the third-party peer scenes that the peer tests (crates/render/tests/peers/) read.
# They are files by others whose licences do not clearly allow us to redistribute them, so the
# repository holds only this script: it fetches each file from its pinned upstream commit,
# checks its SHA-256, rebuilds the two reduced scenes, and renders the two Mitsuba 3 references
# that are not upstream (those need Python with Mitsuba 3.9.1; see below).
#
#   bash scripts/fetch-peers.sh [DEST]
#
# DEST defaults to $HAZE_PEERS_DIR, else ../shared/peers beside the clone: the two places the
# tests look (haze_testkit::data::peers_dir). With another DEST, export HAZE_PEERS_DIR=DEST.
# Needs curl and sha256sum; python3 for the teapot scene. Sources (details in the peers'
# READMEs, docs/validation.md):
#   * mitsuba-renderer/mitsuba-data @ 01100fa9b0b154492061a92404f26dcd7b784dbb (the data commit
#     Mitsuba 3.9.1 pins): the homogeneous and heterogeneous participating-media render tests,
#     their references and museum.exr -> mitsuba3-media-tests/ (repository layout kept);
#   * dartmouth-risc-lab/Mitsuba3ToF @ a8967d0323328ee0640906551b4fc96d59a9227f:
#     scenes/cornell-box_volumetric/scene_v3.xml -> tof-cbox-volumetric/;
#   * mitsuba-renderer/mitsuba3 @ 27be2795b6de7a137f44986b48ac8136be01a4c7:
#     create_medium_scene() of src/phase/tests/test_trampoline.py, and mitsuba-data
#     @ 15f8cd170ed01b409f6841b6dadb53801fd7d790 (the submodule commit it pins):
#     common/meshes/teapot.ply -> mi3-phase-trampoline-teapot/.
# References: tof-cbox-volumetric/ref.exr (8192 spp) and mi3-phase-trampoline-teapot/ref.exr
# (262144 spp) are rendered from small.xml by tests/data/validation/mitsuba_ref.py (Mitsuba 3.9.1,
# variant llvm_ad_rgb; about 3 minutes on 2 cores). Set HAZE_MITSUBA_PYTHON to a Python that
# has `mitsuba` (default: python3); the LLVM variant may need
# DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so. Without Mitsuba the script still
# fetches everything else, and the two tests that need these references say they are skipped.
set -euo pipefail
repo_root="$(cd "$(dirname "$0")/.." && pwd)"
dest="${1:-${HAZE_PEERS_DIR:-$repo_root/../shared/peers}}"
mkdir -p "$dest"
dest="$(cd "$dest" && pwd)"
# (HAZE_PEERS_RAW_URL: another mirror of raw.githubusercontent.com, e.g. file:// for tests.)
raw="${HAZE_PEERS_RAW_URL:-https://raw.githubusercontent.com}"

# fetch URL OUT SHA256: download to OUT unless it is already there with the right checksum.
fetch() {
  local url=$1 out=$2 sum=$3
  if [ -f "$out" ] && echo "$sum  $out" | sha256sum --check --status; then
    return
  fi
  mkdir -p "$(dirname "$out")"
  curl --fail --location --silent --show-error --retry 3 -o "$out.part" "$url"
  if ! echo "$sum  $out.part" | sha256sum --check --status; then
    echo "fetch-peers: checksum mismatch for $url" >&2
    exit 1
  fi
  mv "$out.part" "$out"
}

# 1. Mitsuba 3's media render tests (mitsuba-data, byte for byte, same layout).
data_commit=01100fa9b0b154492061a92404f26dcd7b784dbb
echo "fetch-peers: mitsuba-data @ ${data_commit:0:8} -> $dest/mitsuba3-media-tests"
while read -r sum path; do
  fetch "$raw/mitsuba-renderer/mitsuba-data/$data_commit/$path" "$dest/mitsuba3-media-tests/$path" "$sum"
done <<'LIST'
8e38b990409aa8ce4a6ce96801acbebaebf1c3c99514fb0fac1b909ee3d357d9 common/textures/museum.exr
05c363af4e2e667b973ab0bf9807f4cea0ce7e21627bf1bc2b4c27b5435f5d5f tests/scenes/participating_media/include/preamble.xml
09adda7a63e9ee96af4ae1ab0070dd632201d713577e73216d782297672cb171 tests/scenes/participating_media/include/test-scene-base-no-bg.xml
b860a5985717ea47025669ab308fc2095426a9cbdca3da006a6d1f9c1c02f39d tests/scenes/participating_media/include/test-scene-base.xml
61db4b2de5a174066b2471f35eb24a20a144fb9fa346949a3c82f31662cc1135 tests/scenes/participating_media/meshes/angled_cube.obj
788af456eef6a5135093db134f889023d73c3e00ef2fe8fa5775c882618f4b45 tests/scenes/participating_media/meshes/background.obj
d99f82cc2f24e4c15b3d9e454377ad3d44921007f206740a2629059f52020cb6 tests/scenes/participating_media/meshes/sphere_base.obj
38bca2c2424020b2d85b69b14a77879c530f4799f7239f8c799206ee577ab01b tests/scenes/participating_media/meshes/sphere_tiny.obj
c2541b81d5899ba2edcf629713d11d9a61111b2a8e6b9fead03617d7f4edf3dc tests/scenes/participating_media/meshes/torus1.obj
e19aa1be7559886e3b104f4c21e042b51b8eecc6f5dd1e0304c453ec735e18d7 tests/scenes/participating_media/meshes/torus2.obj
23f3f914c53aa44e549f2de1008b8e7c15a2b1cb533cf1bc2fa9bf134e30b7be tests/scenes/participating_media/meshes/unit_cube_centered.obj
26b57a4dfe8204475c2ed40b67d718cc8ab8819b0d84cc11f452a0dae16af3d1 tests/scenes/participating_media/refs/test_hetero_sigmat_albedo_ref_rgb.exr
d5dcdf9d06485a5d196d1e186139d8372c070fcb5072f8e6f4863adde966bd88 tests/scenes/participating_media/refs/test_hetero_sigmat_albedo_ref_rgb_var.exr
2daf33b7eb036857b57bccfc44ee9f3d4e84e412c8072161e2791a2d9b0a2815 tests/scenes/participating_media/refs/test_hetero_sigmat_ref_rgb.exr
c34f9dca287b647aedf21d9c1eaa513f0dbffc62ffd892db7e70d0e3d75ebfcb tests/scenes/participating_media/refs/test_hetero_sigmat_ref_rgb_var.exr
4a673e3ca66d217aac8b3ea86410a54247b01d7c2183cde1de072e6a434bab74 tests/scenes/participating_media/refs/test_hetero_spectral_sigmat_no_scattering_ref_rgb.exr
888b25e43e7e7c3125c828bc58ad682b070363070bd775867eaf2546e625156b tests/scenes/participating_media/refs/test_hetero_spectral_sigmat_no_scattering_ref_rgb_var.exr
3c38a3995955602c6bf01ce9d5560d6baed351ced81a8511166e223e047e639b tests/scenes/participating_media/refs/test_hetero_spectral_sigmat_ref_rgb.exr
6810e57e33a4126ddce5ff7ec902a5f3f724948e1465397578df174b7cfa4145 tests/scenes/participating_media/refs/test_hetero_spectral_sigmat_ref_rgb_var.exr
a343884b7319c7f90ec74c8d10d1bdb89e7c2a8d106cb2189094c44a3af653ae tests/scenes/participating_media/refs/test_homo_area_light_ref_rgb.exr
500a45327f9f60fbfa330b295e6f777e613ffc30031d694ac668359a6cd0b665 tests/scenes/participating_media/refs/test_homo_area_light_ref_rgb_var.exr
2dafafa5ad443a2ca2fc34a46bc0ca8a26dbcf2a17e07de214e984517495add1 tests/scenes/participating_media/refs/test_homo_dielectric_envmap_ref_rgb.exr
8bf70c078dc5554a2829d48f1ee1178bab3878b5962eb0047c426662aba126ac tests/scenes/participating_media/refs/test_homo_dielectric_envmap_ref_rgb_var.exr
d372d1e1d3c254cb1b6cb810e15248126023ec0bf5036f8b24de5c52df66032e tests/scenes/participating_media/refs/test_homo_emitter_inside_medium_ref_rgb.exr
a93a749c485bf87f02c187cadd4d1234feb39cc734486b1570c7cd7b6cbba003 tests/scenes/participating_media/refs/test_homo_emitter_inside_medium_ref_rgb_var.exr
faa4d66737e213353f491cd04c837fc3d0027d6439042875cf06374adab93438 tests/scenes/participating_media/refs/test_homo_null_envmap_ref_rgb.exr
0e01956a552fe2fe7cf4f53ae5efe26e56c0036db30b77c655534946e57073b9 tests/scenes/participating_media/refs/test_homo_null_envmap_ref_rgb_var.exr
db2d5268d173fdad99702dc142f1f2564b3040e33d7a06bce77cd8805586aa10 tests/scenes/participating_media/refs/test_homo_obj_inside_medium_ref_rgb.exr
0ff23835b991db87080db45e66abf9d094343fc2e0760548387a031b32e9cfdb tests/scenes/participating_media/refs/test_homo_obj_inside_medium_ref_rgb_var.exr
9793cf0f037ac5911facb03714b30b54d9c0aee57fc93f501ac4c16ea6ed03e0 tests/scenes/participating_media/refs/test_homo_roughdielectric_spot_ref_rgb.exr
f28237f63395c22f561c30d6a85803d726102bb4b5b3b8963c4e613dd3334d6c tests/scenes/participating_media/refs/test_homo_roughdielectric_spot_ref_rgb_var.exr
6dacbf1e4c4ffbddcb145c24412bda8544a95d8d04c2f614276b1d3a9b7e252d tests/scenes/participating_media/refs/test_homo_spectral_sigmat_ref_rgb.exr
8d30410a7d4a9042365aa53b1017ac3bebac997f32fd16552a60cf0921fc7955 tests/scenes/participating_media/refs/test_homo_spectral_sigmat_ref_rgb_var.exr
89e5fa0bdd97d58b0af24ac1ad04a43b932c6ec5795fd33eeffb1e3479620789 tests/scenes/participating_media/refs/test_surf_area_light_ref_rgb.exr
7854c2820a3cedd6dc61c2c9824ef46d12398047c677cf9bd9484b27f0106eab tests/scenes/participating_media/refs/test_surf_area_light_ref_rgb_var.exr
cd00e1cd8968dd8f145bc4c95efe012944642fccb6dcf387bc20b8ad68a14097 tests/scenes/participating_media/test_hetero_sigmat_albedo_volpath.xml
b412aa608f25a9016c140dc6c6dd2b218c24cc3f75afcba10c9d7000b319e0ba tests/scenes/participating_media/test_hetero_sigmat_volpath.xml
f272015bf21a6fe4c180aae8566d452d8b816086df3ac07ae1776fe2ac359d53 tests/scenes/participating_media/test_hetero_spectral_sigmat_no_scattering_volpath.xml
a11554f7d9b4fadedb8ad9540cb3670b1005be03b11c13946f7c2a70e3c7d4cc tests/scenes/participating_media/test_hetero_spectral_sigmat_volpathmis.xml
a851a740d5d665b10cdfb2c76d3a86b883a2f2fbc7af705883d521a7b935f404 tests/scenes/participating_media/test_homo_area_light_volpath.xml
447deba0bc270d584e3b1114bcb6e5a69598898a21dac569dafd77ce550b8149 tests/scenes/participating_media/test_homo_dielectric_envmap_volpath.xml
eb2897a06f65d5afccb125f6b1b68ca14f9dcddf69c7935e3443f194cf51800a tests/scenes/participating_media/test_homo_emitter_inside_medium_volpath.xml
afcc527083d76c0cb12e3759fd08c815cab3f99ed1fd2fe9555f1f5395cbee21 tests/scenes/participating_media/test_homo_null_envmap_volpath.xml
04dbd08790f81d8cce46e5a37bca0cabbacb0f1f4690527f5f7164a64359c525 tests/scenes/participating_media/test_homo_obj_inside_medium_volpath.xml
760728f3d2da93f531ee205b1aeb262819f21834b4deed4fffa411fbb2463ce4 tests/scenes/participating_media/test_homo_roughdielectric_spot_volpath.xml
b6a24bbc08105305ce4e616432d68985a06358db93c7a266138aef75da88c44c tests/scenes/participating_media/test_homo_spectral_sigmat_volpathmis.xml
db4a1e011264e3ee3dc54d5b0108d2c718ce2ee376bb878189e698a8aa9c3459 tests/scenes/participating_media/test_surf_area_light_volpath.xml
2f1cc4f004688d95e219ea000f113c8d5f485cd8a2017c0fd5470a62a4e76e71 tests/scenes/participating_media/textures/albedo.vol
8fd2de4c0f03399e8076b87566087ccadbecf304b839345d7311fa1a4ef87b01 tests/scenes/participating_media/textures/sigmat.vol
LIST

# 2. The volumetric Cornell box of Mitsuba3ToF; small.xml lowers only the <default> resolution
#    (256 -> 160) and spp (4096 -> 16).
tof_commit=a8967d0323328ee0640906551b4fc96d59a9227f
tof="$dest/tof-cbox-volumetric"
echo "fetch-peers: Mitsuba3ToF @ ${tof_commit:0:8} -> $tof"
fetch "$raw/dartmouth-risc-lab/Mitsuba3ToF/$tof_commit/scenes/cornell-box_volumetric/scene_v3.xml" \
  "$tof/scene_v3.xml" b0cd42e23cb857e988edbb3af7f9f1ffdb5eed23003d81e323e97da2a8a9baca
sed -e 's|<default name="spp" value="4096" />|<default name="spp" value="16" />|' \
    -e 's|<default name="resy" value="256" />|<default name="resy" value="160" />|' \
    -e 's|<default name="resx" value="256" />|<default name="resx" value="160" />|' \
    "$tof/scene_v3.xml" > "$tof/small.xml"
echo "b405f70589b21ae378bc8f11d8d2293d0fc881e509dba25e588255dbc1a030e2  $tof/small.xml" | sha256sum --check --quiet

# 3. The teapot of Mitsuba 3's phase-function trampoline test: the inline scene of
#    create_medium_scene(), dedented, with its defaults spp = 8 and phase_function = isotropic;
#    small.xml is the same file (32x32 at 8 spp is already small).
mi3_commit=27be2795b6de7a137f44986b48ac8136be01a4c7
teapot="$dest/mi3-phase-trampoline-teapot"
echo "fetch-peers: mitsuba3 @ ${mi3_commit:0:8} (test_trampoline.py) -> $teapot"
mkdir -p "$teapot"
curl --fail --location --silent --show-error --retry 3 -o "$teapot/test_trampoline.py.part" \
  "$raw/mitsuba-renderer/mitsuba3/$mi3_commit/src/phase/tests/test_trampoline.py"
python3 - "$teapot/test_trampoline.py.part" "$teapot/scene.xml" <<'PY'
import re, sys, textwrap
src = open(sys.argv[1], encoding="utf-8").read()
body = src[src.index("def create_medium_scene("):]
xml = re.search(r'f"""(.*?)"""', body, re.S).group(1)
xml = textwrap.dedent(xml).strip("\n").rstrip() + "\n"
xml = xml.replace("{spp}", "8").replace("{phase_function}", "isotropic")
open(sys.argv[2], "w", encoding="utf-8").write(xml)
PY
rm "$teapot/test_trampoline.py.part"
echo "a116824da7ea6ad9a7ef06d988cdfbb5de03849741687da46c4e094256df1093  $teapot/scene.xml" | sha256sum --check --quiet
cp "$teapot/scene.xml" "$teapot/small.xml"
fetch "$raw/mitsuba-renderer/mitsuba-data/15f8cd170ed01b409f6841b6dadb53801fd7d790/common/meshes/teapot.ply" \
  "$teapot/resources/data/common/meshes/teapot.ply" 948a9c1737d7a4d730f6150a54709f6e6490c113cca4b3f38ce9b230b24ae980

# 4. The two Mitsuba 3 references that are not upstream.
py="${HAZE_MITSUBA_PYTHON:-python3}"
if "$py" -c "import mitsuba, numpy" 2>/dev/null; then
  for spec in "$tof 8192" "$teapot 262144"; do
    set -- $spec
    if [ ! -f "$1/ref.exr" ]; then
      (cd "$1" && "$py" "$repo_root/tests/data/validation/mitsuba_ref.py" small.xml ref.exr "$2")
    fi
  done
else
  echo "fetch-peers: $py has no 'mitsuba' module: the references tof-cbox-volumetric/ref.exr and" \
    "mi3-phase-trampoline-teapot/ref.exr were not rendered (pip install mitsuba==3.9.1 numpy," \
    "then run this script again); their two tests will be skipped" >&2
fi

echo "fetch-peers: done; the peer tests read $dest"
if [ "$dest" != "$(cd "$repo_root/.." && pwd)/shared/peers" ]; then
  echo "fetch-peers: export HAZE_PEERS_DIR=$dest"
fi
