#!/usr/bin/env python3
"""The corpus check of issue 38: do public Mitsuba 3 scenes load and render in haze?

Fetches each repository of the pinned list CORPUS below at its pinned commit, renders every
scene file listed for it at low spp with haze, and writes a table: loads, renders, and the image
mean against Mitsuba 3's where a reference is at hand (the mitsuba-data test scenes'
`refs/NAME_ref_rgb.exr`, rendered by Mitsuba's own test suite) or Mitsuba renders the scene.
Not run by CI: it downloads about 400 MB and renders for tens of minutes.

    python3 scripts/corpus-check.py [--haze target/release/haze] [--spp 16] [--threads 1] [--out corpus.md]

The corpus (scene files only: the XML files these repositories ship whose root is a Mitsuba 3
`<scene>`, without include fragments; scenes that the tutorials and research code build as
Python dicts are not files and are not counted):
  mitsuba-data       mitsuba-renderer/mitsuba-data: Mitsuba 3's documentation, test, Cornell-box
                     and material-preview scenes (the commit Mitsuba 3.9.1 pins);
  mitsuba-tutorials  mitsuba-renderer/mitsuba-tutorials: the scenes/ folder of the tutorials;
  Mitsuba3ToF        dartmouth-risc-lab/Mitsuba3ToF: time-of-flight rendering (research code);
  mitransient        diegoroyo/mitransient: transient rendering (research code);
  revamp             poloclub/revamp: adversarial scene attacks (research code; its
                     scenes/teapot/scene_v0.6.xml is a Mitsuba 0.6 scene and
                     assets/scenes/ repeats scenes/adv_tex_bird, so neither is listed).

Environment:
  HAZE_CORPUS_DIR_<KEY>  an existing checkout of that repository at its pinned commit, KEY its
                    short name above in capitals with `-` as `_` (HAZE_CORPUS_DIR_MITSUBA_DATA,
                    HAZE_CORPUS_DIR_MITSUBA_TUTORIALS, HAZE_CORPUS_DIR_MITSUBA3TOF,
                    HAZE_CORPUS_DIR_MITRANSIENT, HAZE_CORPUS_DIR_REVAMP); else the script clones
                    it into .corpus/NAME beside the repository, with git. HAZE_CORPUS_DIR is
                    still read for mitsuba-data;
  HAZE_CORPUS_ONLY  a substring: only scenes whose `name/path` contains it;
  HAZE_CORPUS_MITSUBA  a Python with `mitsuba` (3.9.1): every scene is also loaded by Mitsuba 3
                    (variant scalar_rgb, else scalar_spectral_polarized, else llvm_ad_rgb; column
                    `Mitsuba 3 loads`), and scenes haze renders that have no reference are rendered
                    by it (scalar_rgb) at the same spp, for the mean column (slow: minutes per
                    large scene).
The image means need an EXR reader: the `haze` Python package or `mitsuba`, whichever imports
(else the mean column says "-").

A scene whose `<integrator>` haze does not have (`direct`, `ptracer`, ...) is rendered with
`--integrator volpath`, which replaces it (column `via`). Scenes that need `$name` parameters
get the defaults listed in their entry's defines (given to haze and to Mitsuba alike).
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# mitsuba-renderer/mitsuba-data's scene files (include fragments excluded).
MITSUBA_DATA_SCENES = """
docs/scenes/bsdf_blendbsdf.xml
docs/scenes/bsdf_bumpmap_with.xml
docs/scenes/bsdf_bumpmap_without.xml
docs/scenes/bsdf_conductor_aluminium.xml
docs/scenes/bsdf_conductor_gold.xml
docs/scenes/bsdf_dielectric_diamond.xml
docs/scenes/bsdf_dielectric_glass.xml
docs/scenes/bsdf_diffuse_plain.xml
docs/scenes/bsdf_diffuse_textured.xml
docs/scenes/bsdf_hair_blonde.xml
docs/scenes/bsdf_hair_brown.xml
docs/scenes/bsdf_mask_after.xml
docs/scenes/bsdf_mask_before.xml
docs/scenes/bsdf_measured_polarized_fakegold.xml
docs/scenes/bsdf_measured_polarized_fakegold_stokes.xml
docs/scenes/bsdf_measured_polarized_gold.xml
docs/scenes/bsdf_measured_polarized_gold_stokes.xml
docs/scenes/bsdf_normalmap_with.xml
docs/scenes/bsdf_normalmap_without.xml
docs/scenes/bsdf_plastic_default.xml
docs/scenes/bsdf_plastic_diffuse.xml
docs/scenes/bsdf_plastic_nopreserve.xml
docs/scenes/bsdf_plastic_preserve.xml
docs/scenes/bsdf_plastic_shiny.xml
docs/scenes/bsdf_polarizer_absorbing.xml
docs/scenes/bsdf_polarizer_aligned.xml
docs/scenes/bsdf_polarizer_middle.xml
docs/scenes/bsdf_pplastic.xml
docs/scenes/bsdf_pplastic_diffuse.xml
docs/scenes/bsdf_pplastic_diffuse_stokes.xml
docs/scenes/bsdf_pplastic_specular.xml
docs/scenes/bsdf_pplastic_specular_stokes.xml
docs/scenes/bsdf_roughconductor_anisotropic_aluminium.xml
docs/scenes/bsdf_roughconductor_copper.xml
docs/scenes/bsdf_roughconductor_textured_carbon.xml
docs/scenes/bsdf_roughdielectric_glass.xml
docs/scenes/bsdf_roughdielectric_rough.xml
docs/scenes/bsdf_roughdielectric_textured.xml
docs/scenes/bsdf_roughplastic_beckmann.xml
docs/scenes/bsdf_roughplastic_diffuse.xml
docs/scenes/bsdf_roughplastic_ggx.xml
docs/scenes/bsdf_roughplastic_nopreserve.xml
docs/scenes/bsdf_roughplastic_preserve.xml
docs/scenes/bsdf_thindielectric_glass.xml
docs/scenes/bsdf_twosided_cbox.xml
docs/scenes/bsdf_twosided_cbox_onesided.xml
docs/scenes/emitter_projector_constant.xml
docs/scenes/emitter_projector_textured.xml
docs/scenes/emitter_spot_no_texture.xml
docs/scenes/emitter_spot_texture.xml
docs/scenes/integrator_aov.xml
docs/scenes/integrator_depth_1.xml
docs/scenes/integrator_depth_2.xml
docs/scenes/integrator_depth_3.xml
docs/scenes/integrator_depth_inf.xml
docs/scenes/integrator_direct_both.xml
docs/scenes/integrator_direct_bsdf.xml
docs/scenes/integrator_direct_lum.xml
docs/scenes/integrator_stokes_cbox.xml
docs/scenes/medium_homogeneous_sss.xml
docs/scenes/medium_homogeneous_sss_textured.xml
docs/scenes/principled_blend_creation/scene.xml
docs/scenes/principled_blend_creation/scene_light.xml
docs/scenes/principled_blend_creation/scene_studio.xml
docs/scenes/principled_blend_creation/scene_thin.xml
docs/scenes/principled_blend_creation/scene_thin_light.xml
docs/scenes/sampler_independent_16spp.xml
docs/scenes/sampler_independent_25spp.xml
docs/scenes/sampler_ldsampler_16spp.xml
docs/scenes/sampler_multijitter_16spp.xml
docs/scenes/sampler_orthogonal_25spp.xml
docs/scenes/sampler_stratified_16spp.xml
docs/scenes/sensor_orthographic.xml
docs/scenes/sensor_orthographic_2.xml
docs/scenes/sensor_perspective.xml
docs/scenes/sensor_perspective_large_fov.xml
docs/scenes/sensor_thinlens.xml
docs/scenes/sensor_thinlens_small_aperture.xml
docs/scenes/shape_bsplinecurve_basic.xml
docs/scenes/shape_bsplinecurve_parameterization.xml
docs/scenes/shape_cylinder_onesided.xml
docs/scenes/shape_cylinder_twosided.xml
docs/scenes/shape_disk.xml
docs/scenes/shape_disk_parameterization.xml
docs/scenes/shape_linearcurve_basic.xml
docs/scenes/shape_linearcurve_parameterization.xml
docs/scenes/shape_ply_bunny.xml
docs/scenes/shape_ply_bunny_facet.xml
docs/scenes/shape_rectangle.xml
docs/scenes/shape_rectangle_parameterization.xml
docs/scenes/shape_sdfgrid.xml
docs/scenes/shape_sdfgrid_analytic.xml
docs/scenes/shape_sphere_basic.xml
docs/scenes/shape_sphere_light_analytic.xml
docs/scenes/shape_sphere_light_mesh.xml
docs/scenes/shape_sphere_parameterization.xml
docs/scenes/texture_checkerboard.xml
docs/scenes/texture_mesh_attribute_face.xml
docs/scenes/texture_mesh_attribute_vertex.xml
docs/scenes/variants_cbox_rgb.xml
docs/scenes/variants_cbox_spectral.xml
scenes/cbox/cbox-rgb.xml
scenes/cbox/cbox-spectral.xml
scenes/cbox/cbox.xml
scenes/hello.xml
scenes/matpreview/matpreview.xml
tests/scenes/bsdf_spheres/test_arealight_path.xml
tests/scenes/bsdf_spheres/test_bumpmap_path.xml
tests/scenes/bsdf_spheres/test_constant_path.xml
tests/scenes/bsdf_spheres/test_envmap_path.xml
tests/scenes/bsdf_spheres/test_normalmap_identity_roughconductor_path.xml
tests/scenes/bsdf_spheres/test_normalmap_path.xml
tests/scenes/bsdf_spheres/test_normalmap_roughconductor_path.xml
tests/scenes/bsdf_spheres/test_pointlight_path.xml
tests/scenes/bsdf_spheres/test_roughdielectric_path.xml
tests/scenes/bsdf_spheres/test_roughplastic_linear_path.xml
tests/scenes/bsdf_spheres/test_roughplastic_nonlinear_path.xml
tests/scenes/bsdf_spheres/test_textured_diffuse_path.xml
tests/scenes/bsdf_spheres/test_textured_roughconductor_path.xml
tests/scenes/bsdf_spheres/test_texturedprincipled1_path.xml
tests/scenes/bsdf_spheres/test_texturedprincipled2_path.xml
tests/scenes/bsdf_spheres/test_texturedprincipledthin_path.xml
tests/scenes/floating_sphere/test_directional_direct.xml
tests/scenes/infinite_mirrors/scene_path.xml
tests/scenes/instancing/test_instancing_path.xml
tests/scenes/mesh_attributes/test_mesh_attributes_1_face_direct.xml
tests/scenes/mesh_attributes/test_mesh_attributes_3_face_direct.xml
tests/scenes/mesh_attributes/test_mesh_attributes_3_vertex_direct.xml
tests/scenes/orthographic_sensor/test_orthographic_path.xml
tests/scenes/participating_media/test_hetero_sigmat_albedo_volpath.xml
tests/scenes/participating_media/test_hetero_sigmat_volpath.xml
tests/scenes/participating_media/test_hetero_spectral_sigmat_no_scattering_volpath.xml
tests/scenes/participating_media/test_hetero_spectral_sigmat_volpathmis.xml
tests/scenes/participating_media/test_homo_area_light_volpath.xml
tests/scenes/participating_media/test_homo_dielectric_envmap_volpath.xml
tests/scenes/participating_media/test_homo_emitter_inside_medium_volpath.xml
tests/scenes/participating_media/test_homo_null_envmap_volpath.xml
tests/scenes/participating_media/test_homo_obj_inside_medium_volpath.xml
tests/scenes/participating_media/test_homo_roughdielectric_spot_volpath.xml
tests/scenes/participating_media/test_homo_spectral_sigmat_volpathmis.xml
tests/scenes/participating_media/test_surf_area_light_volpath.xml
tests/scenes/projector/test_projector_constant_direct.xml
tests/scenes/projector/test_projector_textured_direct.xml
tests/scenes/spot_light/test_spot_direct.xml
tests/scenes/texture_interp/test_texture_interp_direct.xml
tests/scenes/various_emitters/test_various_emitters_ptracer.xml
tests/scenes/various_shapes/test_various_shapes_path.xml
""".split()

CORPUS = [
    dict(name="mitsuba-data", repo="mitsuba-renderer/mitsuba-data",
         # The data commit Mitsuba 3.9.1 pins (as scripts/fetch-peers.sh).
         commit="01100fa9b0b154492061a92404f26dcd7b784dbb",
         # `$name` parameters some documentation scenes use without a <default> (Mitsuba's
         # documentation build sets them); `--spp` decides the sample count anyway.
         defines=["spp=4"], scenes=MITSUBA_DATA_SCENES),
    dict(name="mitsuba-tutorials", repo="mitsuba-renderer/mitsuba-tutorials",
         commit="a8dbee7e81b1039a983770ce1042f2d78688d0ae", defines=[], scenes="""
scenes/cbox.xml
scenes/cbox_pol.xml
scenes/lego/scene.xml
scenes/polarizers.xml
scenes/shadow_art.xml
scenes/simple.xml
""".split()),
    dict(name="Mitsuba3ToF", repo="dartmouth-risc-lab/Mitsuba3ToF",
         commit="00f01ebd5b4ba99df3c77d60cd6ad6c09afc5919", defines=[], scenes="""
scenes/cornell-box/scene_v3_doppler.xml
scenes/cornell-box/scene_v3_transient.xml
scenes/cornell-box_volumetric/scene_v3.xml
scenes/cornell-box_volumetric/scene_v3_transient.xml
""".split()),
    dict(name="mitransient", repo="diegoroyo/mitransient",
         commit="618eae7c382fbb27f0ef2050412e917d64e1d44d", defines=[], scenes="""
examples/angulararea-emitter/scenes/angular_1light.xml
examples/angulararea-emitter/scenes/area_1light.xml
examples/diff-transient/cornell-box/cbox_volumetric.xml
examples/diff-transient/staircase/scene.xml
examples/polarization/cornell-box/cbox_polarized.xml
examples/polarization/cornell-box/cbox_polarized_steady.xml
examples/transient-nlos/nlos-z-room.xml
examples/transient-nlos/nlos-z-simple.xml
examples/transient-nlos/nlos_Z.xml
examples/transient/cornell-box/cbox_diffuse.xml
examples/transient/cornell-box/cbox_diffuse_freq.xml
examples/transient/cornell-box/cbox_mirror.xml
examples/transient/cornell-box/cbox_volumetric.xml
""".split()),
    dict(name="revamp", repo="poloclub/revamp",
         commit="efa3d751401d2baa8f5be273714c4683b6ab4d02", defines=[], scenes="""
scenes/adv_tex_bird/adv_tex_bird.xml
scenes/adv_tex_bird/sphere.xml
scenes/banana_r1/banana_r1.xml
scenes/banner_06/scene.xml
scenes/bw/bw.xml
scenes/city/city.xml
scenes/city_stop_sign/city_stop_sign.xml
scenes/city_stop_sign/city_stop_sign_full.xml
scenes/cone_r1/cone_r1.xml
scenes/coords/coords_scene.xml
scenes/cube/cube.xml
scenes/cube_r1/cube_r1.xml
scenes/cube_r2/cube_r2.xml
scenes/cylinder_r1/cylinder_r1.xml
scenes/fog/fog.xml
scenes/forest_soldier/forest_soldier.xml
scenes/intersection_taxi/intersection_taxi.xml
scenes/mesa/mesa.xml
scenes/office/office.xml
scenes/patio/patio.xml
scenes/pyramid_r1/pyramid_r1.xml
scenes/soldier/soldier.xml
scenes/sphere_r1/sphere_r1.xml
scenes/street_sunset/street_sunset.xml
scenes/teapot/taxi_street/taxi_street.xml
scenes/teapot/teapot.xml
scenes/underwater/underwater.xml
scenes/volume_scene/volume_scene.xml
""".split()),
]


def env_key(name: str) -> str:
    return "HAZE_CORPUS_DIR_" + re.sub(r"[^A-Z0-9]", "_", name.upper())


def fetch(entry: dict, dest: Path) -> Path:
    if (dest / ".git").exists():
        return dest
    dest.mkdir(parents=True, exist_ok=True)
    run = lambda *a: subprocess.run(["git", "-C", str(dest), *a], check=True)
    run("init", "-q")
    run("remote", "add", "origin", f"https://github.com/{entry['repo']}")
    run("fetch", "-q", "--depth", "1", "origin", entry["commit"])
    run("checkout", "-q", "FETCH_HEAD")
    return dest


def checkout(entry: dict, root: Path) -> Path:
    local = os.environ.get(env_key(entry["name"]))
    if not local and entry["name"] == "mitsuba-data":
        local = os.environ.get("HAZE_CORPUS_DIR")
    return Path(local) if local else fetch(entry, root.parent / ".corpus" / entry["name"])


def exr_mean(path: Path):
    """The mean over pixels and RGB channels of an EXR, or None without a reader."""
    try:
        import haze  # noqa: F401
        import numpy as np

        return float(np.asarray(haze.read_exr(str(path)))[..., :3].mean())
    except Exception:
        pass
    try:
        import mitsuba as mi
        import numpy as np

        mi.set_variant("scalar_rgb")
        return float(np.asarray(mi.Bitmap(str(path)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32))[..., :3].mean())
    except Exception:
        return None


def reference(scene: Path):
    """Mitsuba's test reference of `scene`: `refs/STEM_ref_rgb.exr`, STEM the file name without
    its `_integrator` suffix."""
    stem = re.sub(r"_[a-z]+$", "", scene.stem)
    ref = scene.parent / "refs" / f"{stem}_ref_rgb.exr"
    return ref if ref.exists() else None


# argv: scene, spp (0: load only), NAME=VALUE defines. Tries the variants in turn (polarised
# plugins need a polarized variant, `direct_projective` and `prb` an AD one) and prints, each on a
# line of its own (Mitsuba's log shares stdout): `@@try VARIANT`, then `@@error VARIANT MESSAGE` or
# `@@loaded VARIANT`, then `@@mean X` (scalar_rgb only).
MITSUBA = """
import sys, mitsuba as mi, numpy as np
defines = dict(a.split("=", 1) for a in sys.argv[3:])
for variant in ["scalar_rgb", "scalar_spectral_polarized", "llvm_ad_rgb"]:
    print("\\n@@try", variant, flush=True)
    try:
        mi.set_variant(variant)
        scene = mi.load_file(sys.argv[1], **defines)
        break
    except Exception as e:
        print("\\n@@error", variant, " ".join(str(e).split())[-200:], flush=True)
else:
    sys.exit(0)
print("\\n@@loaded", variant, flush=True)
if int(sys.argv[2]) > 0 and variant == "scalar_rgb":
    img = np.asarray(mi.render(scene, spp=int(sys.argv[2])))
    print("\\n@@mean", float(img[..., :3].mean()), flush=True)
"""


def mitsuba(python: str, scene: Path, spp: int, defines, timeout: float):
    """(variant that loads or None, the variants' errors, image mean) of Mitsuba 3 on `scene`;
    the mean only with spp > 0 and scalar_rgb, None if the render fails or times out. Only the
    defines the scene file uses are passed: Mitsuba 3 refuses unused parameters. A variant whose
    process dies (llvm_ad_rgb with some system LLVMs) counts as not loading."""
    text = scene.read_text(errors="replace") if scene.exists() else ""
    defines = [d for d in defines if "$" + d.split("=", 1)[0] in text]
    died = ""
    try:
        p = subprocess.run([python, "-c", MITSUBA, scene.name, str(spp), *defines], cwd=scene.parent,
                           capture_output=True, text=True, timeout=timeout)
        out = p.stdout
        if p.returncode != 0:
            died = f"exit {p.returncode}"
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        died = f"timed out after {timeout:.0f} s"
    m = re.search(r"^@@loaded (\S+)$", out, re.M)
    variant = m.group(1) if m else None
    errs = [f"{v}: {msg}" for v, msg in re.findall(r"^@@error (\S+) (.*)$", out, re.M)]
    tried = re.findall(r"^@@try (\S+)$", out, re.M)
    if died and tried and not variant and not any(e.startswith(tried[-1] + ":") for e in errs):
        errs.append(f"{tried[-1]}: {died}")
    m = re.search(r"^@@mean (\S+)$", out, re.M)
    return variant, "" if variant else "; ".join(errs) or died or "?", float(m.group(1)) if m else None


def first_error(stderr: str) -> str:
    for line in stderr.splitlines():
        if line.startswith("error:"):
            return line[len("error:"):].strip()
    return stderr.strip().splitlines()[-1] if stderr.strip() else "?"


def classify(msg: str) -> str:
    m = re.search(r'unsupported (\w+) type \'([\w-]+)\'', msg)
    if m:
        return f"{m.group(1)} {m.group(2)}"
    m = re.search(r"unused parameter '(\w+)': (<\w+ type=\"\w+\")", msg)
    if m:
        return f"parameter {m.group(1)} of {m.group(2)}>"
    m = re.search(r"<(\w+) type=\"(\w+)\"[^:]*>: .*does not take (a \w+ <?\w+>?|a texture '\w+')", msg)
    if m:
        return f"{m.group(1)} {m.group(2)} with {m.group(3)}"
    return re.sub(r"^.*?: (<[^>]*>: )?", "", msg)[:100]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = Path(__file__).resolve().parent.parent
    ap.add_argument("--haze", default=str(root / "target/release/haze"))
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--threads", type=int, default=1, help="haze render --threads (1: a shared machine)")
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--out", default="corpus.md")
    args = ap.parse_args()
    only = os.environ.get("HAZE_CORPUS_ONLY", "")
    python = os.environ.get("HAZE_CORPUS_MITSUBA")
    rows, blockers = [], {}
    tmp = Path(tempfile.mkdtemp(prefix="haze-corpus-"))
    for entry in CORPUS:
        todo = [s for s in entry["scenes"] if only in f"{entry['name']}/{s}"]
        if not todo:
            continue
        data = checkout(entry, root)
        for rel in todo:
            name = f"{entry['name']}/{rel}"
            scene = data / rel
            out = tmp / (name.replace("/", "_") + ".exr")
            base = [args.haze, "render", scene.name, "-o", str(out), "--spp", str(args.spp), "--threads", str(args.threads), "-q"]
            for d in entry["defines"]:
                base += ["-D", d]
            via = ""
            t0 = time.time()
            try:
                p = subprocess.run(base, cwd=scene.parent, capture_output=True, text=True, timeout=args.timeout)
                if p.returncode != 0 and "unsupported integrator type" in p.stderr:
                    via = "--integrator volpath"
                    p = subprocess.run(base + ["--integrator", "volpath"], cwd=scene.parent, capture_output=True, text=True, timeout=args.timeout)
                ok, err = p.returncode == 0, ("" if p.returncode == 0 else first_error(p.stderr))
            except subprocess.TimeoutExpired:
                ok, err = False, f"timed out after {args.timeout:.0f} s"
            secs = time.time() - t0
            loads = ok or not re.search(r"\.xml:\d+:\d+: ", err)
            mean = ref_mean = None
            if ok:
                mean = exr_mean(out)
                ref = reference(scene)
                ref_mean = exr_mean(ref) if ref else None
            mi_loads, mi_err = None, ""
            if python:
                mi_spp = args.spp if ok and ref_mean is None else 0
                mi_loads, mi_err, mi_mean = mitsuba(python, scene, mi_spp, entry["defines"], args.timeout)
                if ref_mean is None:
                    ref_mean = mi_mean
            if not ok:
                blockers.setdefault(classify(err), []).append((entry["name"], rel, mi_loads))
            rows.append((entry["name"], rel, mi_loads, loads, ok, via, secs, mean, ref_mean, err, mi_err))
            status = "renders" if ok else ("loads" if loads else "fails")
            mi_status = "" if not python else (f"mi:{mi_loads}" if mi_loads else "mi:fails")
            print(f"{status:8} {mi_status:8} {name} {via} {err}", file=sys.stderr)
    yn = lambda b: "-" if b is None else ("yes" if b else "no")
    mi_yn = lambda v: "-" if not python else ("no" if not v else ("yes" if v == "scalar_rgb" else v))
    fmt = lambda x: "-" if x is None else f"{x:.5g}"
    cell = lambda s: s.replace("|", "/")
    count = lambda rs, i: sum(1 for r in rs if r[i])
    commit = {e["name"]: e["commit"] for e in CORPUS}
    rendered, loaded = count(rows, 4), count(rows, 3)
    lines = [
        f"# haze on public Mitsuba 3 scenes ({args.spp} spp)",
        "",
        f"{rendered} of {len(rows)} scene files render; {loaded} load."
        + (f" Mitsuba 3 loads {count(rows, 2)} (scalar_rgb, else a polarized or AD variant); haze renders"
           f" {sum(1 for r in rows if r[2] and r[4])} of those." if python else ""),
        "",
        "| repository | commit | scene files | Mitsuba 3 loads | haze loads | haze renders | haze renders, of those Mitsuba loads |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in dict.fromkeys(r[0] for r in rows):
        rs = [r for r in rows if r[0] == name]
        mi_n = str(count(rs, 2)) if python else "-"
        both = str(sum(1 for r in rs if r[2] and r[4])) if python else "-"
        lines.append(f"| {name} | {commit[name][:8]} | {len(rs)} | {mi_n} | {count(rs, 3)} | {count(rs, 4)} | {both} |")
    mi_n = str(count(rows, 2)) if python else "-"
    both = str(sum(1 for r in rows if r[2] and r[4])) if python else "-"
    lines.append(f"| total | | {len(rows)} | {mi_n} | {loaded} | {rendered} | {both} |")
    lines += [
        "",
        "| repository | scene | Mitsuba 3 loads (variant if not scalar_rgb) | loads | renders | via | seconds | mean | Mitsuba 3 mean (reference, or rendered at the same spp) | ratio | error | Mitsuba 3 error |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, rel, mi_loads, loads, ok, via, secs, mean, ref_mean, err, mi_err in rows:
        ratio = "-" if mean is None or not ref_mean else f"{mean / ref_mean:.3f}"
        lines.append(
            f"| {name} | {rel} | {mi_yn(mi_loads)} | {yn(loads)} | {yn(ok)} | {via} | {secs:.1f} | {fmt(mean)} | {fmt(ref_mean)} | {ratio} | {cell(err)} | {cell(mi_err)} |"
        )
    lines += ["", "## What blocks the rest", "",
              "| blocker | scenes | of them Mitsuba 3 loads | repositories |", "|---|---|---|---|"]
    for key, scenes in sorted(blockers.items(), key=lambda kv: -len(kv[1])):
        mi_n = str(sum(1 for s in scenes if s[2])) if python else "-"
        repos = ", ".join(f"{n} {sum(1 for s in scenes if s[0] == n)}" for n in dict.fromkeys(s[0] for s in scenes))
        lines.append(f"| {cell(key)} | {len(scenes)} | {mi_n} | {repos} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"{rendered} of {len(rows)} render, {loaded} load; table in {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
