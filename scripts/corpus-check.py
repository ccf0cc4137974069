#!/usr/bin/env python3
"""The corpus check of issue 38: do public Mitsuba 3 scenes load and render in haze?

Fetches mitsuba-renderer/mitsuba-data at a pinned commit (Mitsuba 3's own documentation, test,
Cornell-box and material-preview scenes), renders every scene of the pinned list below at low
spp with haze, and writes a table: loads, renders, and the image mean against Mitsuba 3's where
a reference is at hand (the test scenes' `refs/NAME_ref_rgb.exr`, rendered by Mitsuba's own test
suite). Not run by CI: it downloads about 180 MB and renders for several minutes.

    python3 scripts/corpus-check.py [--haze target/release/haze] [--spp 16] [--threads 1] [--out corpus.md]

Environment:
  HAZE_CORPUS_DIR   an existing checkout of mitsuba-data at the pinned commit (else the script
                    clones it into .corpus/mitsuba-data beside the repository, with git);
  HAZE_CORPUS_ONLY  a substring: only scenes whose path contains it;
  HAZE_CORPUS_MITSUBA  a Python with `mitsuba` (3.9.1): scenes haze renders that have no
                    reference are also rendered by Mitsuba 3 (variant scalar_rgb, the same spp),
                    for the mean column (slow: minutes per large scene).
The image means need an EXR reader: the `haze` Python package or `mitsuba`, whichever imports
(else the mean column says "-").

A scene whose `<integrator>` haze does not have (`direct`, `ptracer`, ...) is rendered with
`--integrator volpath`, which replaces it (column `via`). Scenes that need `$name` parameters
get the defaults listed in DEFINES.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = "https://github.com/mitsuba-renderer/mitsuba-data"
# The data commit Mitsuba 3.9.1 pins (as scripts/fetch-peers.sh).
COMMIT = "01100fa9b0b154492061a92404f26dcd7b784dbb"
# `$name` parameters some documentation scenes use without a <default> (Mitsuba's documentation
# build sets them); `--spp` decides the sample count anyway.
DEFINES = ["spp=4"]

SCENES = """
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


def fetch(dest: Path) -> Path:
    if (dest / ".git").exists():
        return dest
    dest.mkdir(parents=True, exist_ok=True)
    run = lambda *a: subprocess.run(["git", "-C", str(dest), *a], check=True)
    run("init", "-q")
    run("remote", "add", "origin", REPO)
    run("fetch", "-q", "--depth", "1", "origin", COMMIT)
    run("checkout", "-q", "FETCH_HEAD")
    return dest


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


MITSUBA_RENDER = """
import sys, mitsuba as mi, numpy as np
mi.set_variant("scalar_rgb")
scene = mi.load_file(sys.argv[1], spp=int(sys.argv[2]))
img = np.asarray(mi.render(scene, spp=int(sys.argv[2])))
print(float(img[..., :3].mean()))
"""


def mitsuba_mean(python: str, scene: Path, spp: int, timeout: float):
    """The image mean Mitsuba 3 renders `scene` to, or None if it fails or times out."""
    try:
        p = subprocess.run([python, "-c", MITSUBA_RENDER, scene.name, str(spp)], cwd=scene.parent,
                           capture_output=True, text=True, timeout=timeout)
        return float(p.stdout.split()[-1]) if p.returncode == 0 else None
    except (subprocess.TimeoutExpired, ValueError, IndexError):
        return None


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
    data = Path(os.environ.get("HAZE_CORPUS_DIR") or fetch(root.parent / ".corpus" / "mitsuba-data"))
    only = os.environ.get("HAZE_CORPUS_ONLY", "")
    rows, blockers = [], {}
    tmp = Path(tempfile.mkdtemp(prefix="haze-corpus-"))
    for rel in [s for s in SCENES if only in s]:
        scene = data / rel
        out = tmp / (rel.replace("/", "_") + ".exr")
        base = [args.haze, "render", scene.name, "-o", str(out), "--spp", str(args.spp), "--threads", str(args.threads), "-q"]
        for d in DEFINES:
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
            mitsuba = os.environ.get("HAZE_CORPUS_MITSUBA")
            if ref_mean is None and mitsuba:
                ref_mean = mitsuba_mean(mitsuba, scene, args.spp, args.timeout)
        if not ok:
            key = classify(err)
            blockers.setdefault(key, []).append(rel)
        rows.append((rel, loads, ok, via, secs, mean, ref_mean, err))
        status = "renders" if ok else ("loads" if loads else "fails")
        print(f"{status:8} {rel} {via} {err}", file=sys.stderr)
    rendered = sum(r[2] for r in rows)
    loaded = sum(r[1] for r in rows)
    fmt = lambda x: "-" if x is None else f"{x:.5g}"
    lines = [
        f"# haze on Mitsuba 3's public scenes (mitsuba-data @ {COMMIT[:8]}, {args.spp} spp)",
        "",
        f"{rendered} of {len(rows)} scenes render; {loaded} load.",
        "",
        "| scene | loads | renders | via | seconds | mean | Mitsuba 3 mean (reference, or rendered at the same spp) | ratio | error |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for rel, loads, ok, via, secs, mean, ref_mean, err in rows:
        ratio = "-" if mean is None or not ref_mean else f"{mean / ref_mean:.3f}"
        lines.append(
            f"| {rel} | {'yes' if loads else 'no'} | {'yes' if ok else 'no'} | {via} | {secs:.1f} | {fmt(mean)} | {fmt(ref_mean)} | {ratio} | {err.replace('|', '/')} |"
        )
    lines += ["", "## What blocks the rest", "", "| blocker | scenes |", "|---|---|"]
    for key, scenes in sorted(blockers.items(), key=lambda kv: -len(kv[1])):
        lines.append(f"| {key.replace('|', '/')} | {len(scenes)} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"{rendered} of {len(rows)} render, {loaded} load; table in {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
