//! The `vrl` and `vpl` integrators against `volpath`, component by component, on the
//! validation scenes (rendered small so the test takes seconds), and the normalisation of light
//! tracing. The comparison itself (renders split into passes, the per-pixel z-test and the
//! image-mean z from the per-pass spread) is in `compare_support`, shared with `sky_sun.rs`.

mod compare_support;

use compare_support::*;
use haze_manylight::integrators::{
    ManyLightSettings, PathTracedMedia, TestControls, VplIntegrator, VrlIntegrator,
};
use haze_render::{Component, VolPath};
use haze_scene::{load_file, LoadOptions, Scene};
use haze_testkit::data::validation_scene;
use haze_testkit::ztest::{pool_variance, z_test};

const W: u32 = 24;
const H: u32 = 18;

fn load_small(name: &str) -> Scene {
    load_small_path(&validation_scene(name))
}

fn load_small_path(path: &std::path::Path) -> Scene {
    let mut scene = load_file(path, &LoadOptions::default()).expect("scene loads");
    scene.camera.width = W;
    scene.camera.height = H;
    scene
}

#[test]
fn foggy_room_components_match_volpath() {
    check_against_volpath(&load_small("foggy-room"), "foggy-room ", 150, 96, false);
}

/// `hide_emitters` (Mitsuba 3's integrator parameter, kept by every method): the area light the
/// camera sees in `foggy-room` is hidden by the many-light methods as by volpath (what the camera
/// sees at no scattering event), every component against volpath with the same setting, the
/// light's glow through the fog and its light on the walls kept. Negative control: the lamp
/// shown by `vrl` against volpath's hidden one fails.
#[test]
fn hide_emitters_hides_what_the_camera_sees_directly() {
    let mut scene = load_small("foggy-room");
    scene.integrator.hide_emitters = true;
    let reference = check_against_volpath(&scene, "foggy-room, hide_emitters: ", 150, 48, true);
    assert!(reference.film.mean(Some(Component::Emitted)).iter().all(|&v| v == 0.0));
    let shown = load_small("foggy-room");
    let vrl = VrlIntegrator::exhaustive(&shown, settings(&shown, 150), 1).unwrap();
    let wrong = render_passes(&shown, &vrl, 48, 1, 1);
    let (r, mean_z) = compare(&wrong, &reference, Component::Emitted);
    println!("foggy-room, lamp shown against hidden, emitted: {r}; image-mean z = {mean_z:.2}");
    assert!(r.failed_fraction() > 0.01 || mean_z.abs() > 5.0, "a shown lamp went unnoticed");
}

#[test]
fn hg_box_components_match_volpath() {
    check_against_volpath(&load_small("hg-box"), "hg-box ", 150, 96, false);
}

/// Doubling the number of light paths per pass leaves the expected image unchanged: the image
/// means of the two agree within 4 standard errors (the normalisation divides by the paths).
#[test]
fn light_path_count_does_not_change_the_expected_image() {
    let scene = load_small("foggy-room");
    let a = render_passes(
        &scene,
        &VrlIntegrator::exhaustive(&scene, settings(&scene, 60), 3).unwrap(),
        256,
        1,
        3,
    );
    let mut b = render_passes(
        &scene,
        &VrlIntegrator::exhaustive(&scene, settings(&scene, 120), 4).unwrap(),
        256,
        1,
        4,
    );
    let (r, mean_z) = compare(&a, &b, Component::Multiple);
    println!("60 vs 120 paths per pass: {r}; image-mean z = {mean_z:.2}");
    assert!(mean_z.abs() < 4.0, "{r}; image-mean z = {mean_z:.2}");
    // The test must be able to fail: a 10% normalisation error is caught.
    b.film.scale(0.9);
    for m in &mut b.pass_means {
        for c in m.iter_mut() {
            for v in c.iter_mut() {
                *v *= 0.9;
            }
        }
    }
    let (_, mean_z) = compare(&a, &b, Component::Multiple);
    assert!(mean_z.abs() > 4.0, "a 10% normalisation error went unnoticed: image-mean z = {mean_z:.2}");
}

/// The stochastic lightcut (`vrl_lightcuts`/`vpl_lightcuts`, default `--cut stochastic`)
/// against the brute-force `vrl`/`vpl` with the same light-path count, component `multiple`
/// (the virtual lights' part), for cut sizes 1 (the default), 4 and 16.
fn check_stochastic_against_brute_force(name: &str, paths: u64, passes: u32) {
    use haze_manylight::integrators::StochasticCut;
    use haze_manylight::tree::stochastic::StochasticSettings;
    let scene = load_small(name);
    let ml = settings(&scene, paths);
    let vrl =
        render_passes(&scene, &VrlIntegrator::exhaustive(&scene, ml.clone(), 21).unwrap(), passes, 1, 21);
    let vpl = render_passes(&scene, &VplIntegrator::exhaustive(&scene, ml, 22).unwrap(), passes, 1, 22);
    let mut failures = Vec::new();
    for cut_size in [1, 4, 16] {
        let lc = StochasticCut {
            settings: StochasticSettings { cut_size, ..Default::default() },
            ..Default::default()
        };
        let seed = 30 + cut_size as u64;
        let (a, b) = lightcut_renders(&scene, paths, passes, lc, [seed, seed]);
        for (method, f, reference) in [("vrl_lightcuts", &a, &vrl), ("vpl_lightcuts", &b, &vpl)] {
            let (r, mean_z) = compare(f, reference, Component::Multiple);
            judge(&mut failures, &format!("{name} {method} k = {cut_size}"), &r, mean_z, 0.01);
        }
    }
    assert!(failures.is_empty(), "{name}:\n{}", failures.join("\n"));
}

#[test]
fn foggy_room_stochastic_lightcuts_match_brute_force() {
    check_stochastic_against_brute_force("foggy-room", 150, 96);
}

#[test]
fn hg_box_stochastic_lightcuts_match_brute_force() {
    check_stochastic_against_brute_force("hg-box", 150, 96);
}

/// The whole image of the stochastic `vrl_lightcuts` and `vpl_lightcuts` (default cut size)
/// against the Mitsuba 3 reference of the validation scene at full resolution: the per-pixel
/// z-test with haze's variance over passes (the reference's 16384-spp noise added as in
/// haze-render's validation test) and the image-mean z from the per-pass spread.
fn check_stochastic_against_mitsuba(name: &str, paths: u64, passes: u32) {
    use haze_manylight::integrators::StochasticCut;
    use haze_render::image_io::RgbImage;
    let reference = RgbImage::read_exr(&haze_testkit::data::validation(&format!("refs/{name}.exr")))
        .expect("reference EXR");
    let scene = load_file(&validation_scene(name), &LoadOptions::default()).expect("validation scene loads");
    let (w, h) = (reference.width, reference.height);
    let (a, b) = lightcut_renders(&scene, paths, passes, StochasticCut::default(), [41, 42]);
    let mut failures = Vec::new();
    for (method, f) in [("vrl_lightcuts", &a), ("vpl_lightcuts", &b)] {
        let sample_var = pool_variance(&f.film.sample_variance(None), w, h, 3);
        let var_mean: Vec<f32> = sample_var.iter().map(|v| v / f.film.samples as f32).collect();
        let var_ref: Vec<f32> = sample_var.iter().map(|v| v / 16384.0).collect();
        let r = z_test(&f.film.mean(None), &var_mean, &reference.data, &var_ref, 0.01);
        let (mean, var) = f.mean_and_variance(None);
        let mean_z = (mean - r.reference_mean) / var.sqrt();
        judge(&mut failures, &format!("{name} {method} vs Mitsuba 3"), &r, mean_z, 0.005);
    }
    assert!(failures.is_empty(), "{name}:\n{}", failures.join("\n"));
}

#[test]
fn foggy_room_stochastic_lightcuts_match_mitsuba() {
    check_stochastic_against_mitsuba("foggy-room", 300, 64);
}

#[test]
fn hg_box_stochastic_lightcuts_match_mitsuba() {
    check_stochastic_against_mitsuba("hg-box", 300, 64);
}

/// The whole image of `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts` (camera chains through the glass ball, gathering at
/// surfaces, the continuation through delta chains: `docs/theory.md` §2.1) against `volpath`,
/// every component, on a small hazy room with grey walls, a glass ball and a small area light
/// (`tests/data/glass-ball-room.xml`, 16 x 12 pixels). Negative control: without the virtual
/// lights' light at gathering surface points (14% of `surface` here) the test fails. A 10% error
/// of one connection moves this image by about 1.5%, below what a test of seconds resolves
/// (the image mean's standard error is 3% of `surface` at 40 passes of 20 light paths): the
/// estimator tests against quadrature (`tests/surface_connections.rs`) catch those.
#[test]
fn glass_ball_room_whole_image_matches_volpath() {
    let mut scene = load_small_path(&haze_testkit::data::repo_root().join("tests/data/glass-ball-room.xml"));
    (scene.camera.width, scene.camera.height) = (16, 12);
    let (paths, passes) = (20, 40);
    let reference = check_against_volpath(&scene, "", paths, passes, true);
    let off = TestControls { gather_point_scale: 0.0, ..TestControls::default() };
    let wrong =
        VrlIntegrator::exhaustive(&scene, settings(&scene, paths), 1).unwrap().with_test_controls(off);
    let wrong = render_passes(&scene, &wrong, 2 * passes, 1, 1);
    let (r, mean_z) = compare(&wrong, &reference, Component::Surface);
    println!("vrl without the light at gathering points, surface: {r}; per-pass image-mean z = {mean_z:.2}");
    assert!(
        r.failed_fraction() > 0.01 || mean_z.abs() > 5.0,
        "the missing light at gathering points went unnoticed"
    );
}

/// The caustic paths (`haze_manylight::splat`: light aimed at the glass and connected to the
/// camera) against the camera continuation they replace (`caustic_paths = 0`), component
/// `surface`, on a hazy room with a glass ball under a large lamp
/// (`tests/data/caustic-room.xml`, 16 x 12 pixels), with the box filter and with Mitsuba's
/// Gaussian (the splat's filter weights). Both strategies are unbiased for the caustics seen
/// directly and everything else is shared: with the same seeds the two renders draw the same
/// light and camera paths and differ only in how those caustics are estimated, so the paired
/// per-pass difference of the image means isolates them (its z-score within 5), besides the
/// per-pixel z-test. Negative control: splats 20% too bright fail the paired test.
#[test]
fn caustic_paths_match_the_camera_continuation() {
    use haze_scene::camera::PixelFilter;
    let mut scene = load_small_path(&haze_testkit::data::repo_root().join("tests/data/caustic-room.xml"));
    (scene.camera.width, scene.camera.height) = (16, 12);
    let (paths, passes) = (20, 48);
    let with = |scene: &Scene, caustic_paths: u64| ManyLightSettings {
        caustic_paths: Some(caustic_paths),
        ..settings(scene, paths)
    };
    let mut failures = Vec::new();
    for filter in [PixelFilter::Box, PixelFilter::MITSUBA_DEFAULT] {
        scene.camera.filter = filter;
        let continuation = render_passes(
            &scene,
            &VrlIntegrator::exhaustive(&scene, with(&scene, 0), 1).unwrap(),
            passes,
            16,
            1,
        );
        let splatting = VrlIntegrator::exhaustive(&scene, with(&scene, 2000), 1).unwrap();
        let splats = render_passes(&scene, &splatting, passes, 16, 1);
        let (r, _) = compare(&splats, &continuation, Component::Surface);
        let z = paired_z(&splats, &continuation, Component::Surface);
        judge(&mut failures, &format!("{filter:?}: caustic paths vs continuation (paired z)"), &r, z, 0.01);
        if filter == PixelFilter::Box {
            let brighter = TestControls { caustic_scale: 1.2, ..TestControls::default() };
            let splatting = VrlIntegrator::exhaustive(&scene, with(&scene, 2000), 1)
                .unwrap()
                .with_test_controls(brighter);
            let wrong = render_passes(&scene, &splatting, passes, 16, 1);
            let z = paired_z(&wrong, &continuation, Component::Surface);
            println!("caustic splats x 1.2: paired image-mean z = {z:.2}");
            assert!(z.abs() > 5.0, "20% too bright caustic splats went unnoticed: paired z = {z:.2}");
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The camera walk's split at its first glass vertex (both lobes followed, `gather.rs`
/// `ChainEnd::Split`) against the unsplit walk (one lobe by its Fresnel probability), every
/// component by the paired per-pass image-mean z (same seeds), on the glass-ball room seen
/// through a narrow lens so that the ball in dense haze fills most of the view (continuations
/// from the haze in front of the ball, the split's prefix, take part). Negative control: branches
/// weighted 50% too much fail (the camera paths part at the glass, so the paired difference
/// keeps their noise: 10% moves it by about 2 standard errors). (A wrong weight of the continuations from the prefix alone, which
/// only make paths through the ball into the haze in front of it, moves this image too little
/// to be caught in seconds.)
#[test]
fn split_at_the_first_glass_vertex_matches_the_unsplit_walk() {
    let mut scene = load_small_path(&haze_testkit::data::repo_root().join("tests/data/glass-ball-room.xml"));
    (scene.camera.width, scene.camera.height) = (12, 9);
    scene.camera.fov_x_deg = 20.0;
    let (paths, passes) = (20, 48);
    let with_split = |split: Option<f32>, seed: u64| {
        let controls = TestControls { split, ..TestControls::default() };
        let i = VrlIntegrator::exhaustive(&scene, settings(&scene, paths), seed)
            .unwrap()
            .with_test_controls(controls);
        render_passes(&scene, &i, passes, 4, seed)
    };
    // Same seeds: the passes' light paths are the same, the camera paths part at the glass.
    let unsplit = with_split(None, 1);
    let split = with_split(Some(1.0), 1);
    let mut failures = Vec::new();
    for comp in Component::ALL {
        let z = paired_z(&split, &unsplit, comp);
        println!("split vs unsplit {}: paired image-mean z = {z:.2}", comp.name());
        if z.abs() > 5.0 {
            failures.push(format!("split vs unsplit {}: paired z = {z:.2}", comp.name()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Branches weighted 50% too much.
    let heavy = with_split(Some(1.5), 1);
    let mean_z = paired_z(&heavy, &unsplit, Component::Surface);
    println!("split branches weighted x 1.5, surface: paired image-mean z = {mean_z:.2}");
    assert!(mean_z.abs() > 5.0, "split branches weighted 50% too much went unnoticed");
}

/// `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts` against `volpath`, every component, on the peer scene
/// `tof-cbox-volumetric/small.xml` (a Cornell box of diffuse walls with two boxes of dense
/// media behind null boundaries) at 16 x 16 pixels, with `max_depth` lifted so that the depth
/// limits of the two kinds of paths do not differ. Skipped (one line) without the peer data.
#[test]
fn peer_cbox_whole_image_matches_volpath() {
    let Some(dir) = haze_testkit::data::peers_or_skip() else { return };
    let options = LoadOptions { defines: vec![("max_depth".into(), "-1".into())] };
    let mut scene =
        load_file(&dir.join("tof-cbox-volumetric/small.xml"), &options).expect("peer scene loads");
    (scene.camera.width, scene.camera.height) = (16, 16);
    check_against_volpath(&scene, "cbox ", 20, 40, true);
}

/// `scenes/glass-beam.xml` (a spot light through a glass ball, a ceiling lamp, lit walls) renders
/// with every integrator without a non-finite sample, with every component non-negative and
/// the surface component present (walls lit).
#[test]
fn glass_beam_renders_with_every_integrator_without_nan() {
    use haze_manylight::integrators::{LightcutsIntegrator, StochasticCut, Vpls, Vrls};
    let mut scene = load_small_path(&haze_testkit::data::repo_root().join("scenes/glass-beam.xml"));
    (scene.camera.width, scene.camera.height) = (16, 12);
    let (ml, lc) = (settings(&scene, 20), StochasticCut::default());
    let films = [
        render_passes(&scene, &VolPath::from_spec(&scene.integrator), 1, 4, 1).film,
        render_passes(&scene, &VrlIntegrator::exhaustive(&scene, ml.clone(), 1).unwrap(), 4, 1, 1).film,
        render_passes(&scene, &VplIntegrator::exhaustive(&scene, ml.clone(), 1).unwrap(), 4, 1, 1).film,
        render_passes(&scene, &LightcutsIntegrator::<Vrls>::new(&scene, ml.clone(), lc, 1).unwrap(), 4, 1, 1)
            .film,
        render_passes(&scene, &LightcutsIntegrator::<Vpls>::new(&scene, ml, lc, 1).unwrap(), 4, 1, 1).film,
    ];
    for f in &films {
        for comp in Component::ALL {
            assert!(f.mean(Some(comp)).iter().all(|v| v.is_finite() && *v >= 0.0), "{}", comp.name());
        }
        assert!(f.image_mean(Some(Component::Surface)).iter().all(|v| *v > 0.0));
    }
}

/// A smoke grid of `N^3` cells: a lumpy blob (density falling off from a centre, modulated
/// per cell), strongly varying from cell to cell so that a lookup half a cell off changes the
/// image; three channels (chromatic extinction) when `rgb`.
fn smoke_grid(rgb: bool) -> haze_scene::volume::Grid {
    const N: u32 = 6;
    let channels = if rgb { 3 } else { 1 };
    haze_scene::volume::Grid::from_fn([N; 3], channels, (glam::Vec3::ZERO, glam::Vec3::ONE), |x, y, z, c| {
        let p = (glam::Vec3::new(x as f32, y as f32, z as f32) + 0.5) / N as f32 - 0.5;
        let blob = (1.0 - p.length() / 0.55).max(0.0);
        let lumps = ((x * 7 + y * 3 + z * 5) % 4) as f32 / 3.0;
        blob * (0.3 + 1.7 * lumps) * [1.0, 0.7, 0.45][c as usize]
    })
}

/// One of the two heterogeneous test scenes, in a fresh temporary directory: `room` is a
/// closed room of diffuse walls filled with smoke (the camera and a point light inside, the
/// walls lit through the smoke); otherwise a chromatic smoke puff behind a null cube, lit by a
/// spot light from the side, the camera in vacuum, a floor below. `offset` shifts the grid by
/// that many cells along x (the negative control's perturbed density lookup).
fn smoke_scene(room: bool, offset: f32) -> Scene {
    let dir =
        std::env::temp_dir().join(format!("haze-manylight-smoke-{}-{room}-{offset}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("smoke.vol"), smoke_grid(!room).to_vol_bytes()).unwrap();
    let size = 1.2f32;
    let shift = offset * size / 6.0;
    let medium = format!(
        r#"<medium id="smoke" type="heterogeneous"><float name="scale" value="{scale}"/>
             <volume name="sigma_t" type="gridvolume"><string name="filename" value="smoke.vol"/>
               <transform name="to_world"><scale value="{size}"/><translate x="{tx}" y="{ty}" z="-0.6"/></transform></volume>
             <rgb name="albedo" value="0.9, 0.8, 0.7"/>
             <phase type="hg"><float name="g" value="0.3"/></phase></medium>"#,
        scale = if room { 3.0 } else { 4.0 },
        tx = -0.6 + shift,
        ty = if room { 0.3 } else { -0.6 },
    );
    let xml = if room {
        format!(
            r#"<scene version="3.0.0">
            <integrator type="volpath"><integer name="max_depth" value="-1"/></integrator>
            {medium}
            <sensor type="perspective"><float name="fov" value="70"/>
              <transform name="to_world"><lookat origin="0, 1, 1.8" target="0, 0.9, 0" up="0, 1, 0"/></transform>
              <ref id="smoke"/>
              <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
            <shape type="cube"><boolean name="flip_normals" value="true"/>
              <transform name="to_world"><scale x="1.5" y="1.2" z="2"/><translate y="1.2"/></transform>
              <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.55, 0.5"/></bsdf>
              <ref name="exterior" id="smoke"/></shape>
            <emitter type="point"><point name="position" x="0.5" y="2.1" z="-0.9"/><rgb name="intensity" value="4, 4, 4"/></emitter>
            </scene>"#
        )
    } else {
        format!(
            r#"<scene version="3.0.0">
            <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
            {medium}
            <sensor type="perspective"><float name="fov" value="40"/>
              <transform name="to_world"><lookat origin="0.3, 0.6, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
              <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
            <shape type="cube"><bsdf type="null"/><ref name="interior" id="smoke"/>
              <transform name="to_world"><scale value="0.75"/></transform></shape>
            <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/><translate y="-0.9"/></transform>
              <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
            <emitter type="spot"><transform name="to_world"><lookat origin="-2.5, 1.5, 0.5" target="0, 0, 0" up="0, 1, 0"/></transform>
              <rgb name="intensity" value="40, 40, 40"/><float name="cutoff_angle" value="25"/></emitter>
            </scene>"#
        )
    };
    let scene = haze_scene::load_str(&xml, &dir.join("smoke.xml"), &dir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_dir_all(&dir).ok();
    assert!(scene.media.iter().all(|m| !m.is_homogeneous()));
    scene
}

/// `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts` in a heterogeneous medium against
/// `volpath` (delta and ratio tracking), every component, on the two smoke scenes
/// (`docs/theory.md` §12.5: light paths by delta tracking, VRLs carrying their transmittance,
/// every transmittance of the estimators by ratio tracking). Negative control: the many-light
/// image of the smoke with its density looked up half a cell off fails the same test.
fn check_smoke(room: bool) {
    let label = if room { "smoke room " } else { "smoke puff " };
    let scene = smoke_scene(room, 0.0);
    let (paths, passes) = (20, 48);
    let reference = check_against_volpath(&scene, label, paths, passes, true);
    let perturbed = smoke_scene(room, 0.5);
    let vrl = VrlIntegrator::exhaustive(&perturbed, settings(&perturbed, paths), 1).unwrap();
    let wrong = render_passes(&perturbed, &vrl, 4 * passes, 1, 1);
    let caught = caught_in_any_component(&wrong, &reference, &format!("{label}vrl, density half a cell off"));
    assert!(caught, "{label}: the density lookup half a cell off went unnoticed");
}

#[test]
fn smoke_room_heterogeneous_matches_volpath() {
    check_smoke(true);
}

#[test]
fn smoke_puff_heterogeneous_matches_volpath() {
    check_smoke(false);
}

/// The hand-off to volpath's walk in heterogeneous media (`path_traced_media`, its default,
/// `docs/theory.md` §2.1 "Path-traced media"): `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts`
/// against `volpath`, every component, on the smoke puff (the camera in vacuum, the smoke behind
/// a null cube, a floor lit through it: gathering on the floor, the hand-off inside the cube's
/// grid). Negative control: the hand-off with the smoke's density looked up half a cell off.
#[test]
fn path_traced_media_match_volpath_in_smoke() {
    let scene = smoke_scene(false, 0.0);
    let ml = ManyLightSettings { path_traced_media: PathTracedMedia::Heterogeneous, ..settings(&scene, 20) };
    let reference = volpath_reference(&scene);
    check_methods_with(&scene, &reference, "smoke puff, path-traced: ", &ml, 48, true);
    let perturbed = smoke_scene(false, 0.5);
    let vrl = VrlIntegrator::exhaustive(&perturbed, ml.clone(), 1).unwrap();
    let wrong = render_passes(&perturbed, &vrl, 192, 1, 1);
    let caught = caught_in_any_component(&wrong, &reference, "path-traced, density half a cell off");
    assert!(caught, "path-traced smoke: the density lookup half a cell off went unnoticed");
}

/// The hand-off in every medium (`path_traced_media = all`) on the hazy room with a glass ball
/// under a large lamp (`tests/data/caustic-room.xml`, 16 x 12): the camera starts in the haze, so
/// volpath's walk makes every path but the caustics seen directly, which the caustic paths
/// splat; the hand-off must leave to them exactly the area-emitter hits behind a delta chain
/// from a directly seen vertex (`HandOff`), or those caustics count twice or never. Against
/// `volpath`, every component, all four methods. Negative control: splats 20% too bright (a
/// fifth of the caustics that a wrong hand-off would double) fail the same test.
#[test]
fn path_traced_media_leave_the_caustics_seen_directly_to_the_caustic_paths() {
    let mut scene = load_small_path(&haze_testkit::data::repo_root().join("tests/data/caustic-room.xml"));
    (scene.camera.width, scene.camera.height) = (16, 12);
    let ml = ManyLightSettings { path_traced_media: PathTracedMedia::All, ..settings(&scene, 20) };
    let reference = volpath_reference(&scene);
    check_methods_with(&scene, &reference, "caustic room, path-traced: ", &ml, 48, true);
    let brighter = TestControls { caustic_scale: 1.2, ..TestControls::default() };
    let vrl = VrlIntegrator::exhaustive(&scene, ml.clone(), 1).unwrap().with_test_controls(brighter);
    let wrong = render_passes(&scene, &vrl, 48, 16, 1);
    let (r, mean_z) = compare(&wrong, &reference, Component::Surface);
    println!("path-traced, caustic splats x 1.2, surface: {r}; image-mean z = {mean_z:.2}");
    assert!(
        r.failed_fraction() > 0.01 || mean_z.abs() > 5.0,
        "path-traced caustic room: splats 20% too bright went unnoticed"
    );
}

/// The caustic paths in a heterogeneous medium (their beams and splatted points with
/// ratio-tracked transmittances and `sigma_s(x)`, `docs/theory.md` §12.5) against the camera
/// continuation through the same smoke (ratio tracking along the camera walk), by the paired
/// test of [`caustic_paths_match_the_camera_continuation`] on `tests/data/caustic-room.xml`
/// with its haze replaced by a lumpy smoke grid over the room (box filter). Negative control:
/// splats 20% too bright fail the paired test.
#[test]
fn caustic_paths_match_the_camera_continuation_in_smoke() {
    let dir = std::env::temp_dir().join(format!("haze-manylight-caustic-smoke-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("smoke.vol"), smoke_grid(false).to_vol_bytes()).unwrap();
    let path = haze_testkit::data::repo_root().join("tests/data/caustic-room.xml");
    let xml = std::fs::read_to_string(&path).unwrap();
    let (a, b) = (xml.find("<medium").unwrap(), xml.find("</medium>").unwrap() + "</medium>".len());
    // The room is [-1.5, 1.5] x [0, 2.4] x [-1.5, 1.5]; the grid fills it.
    let smoke = r#"<medium type="heterogeneous" id="haze"><float name="scale" value="0.6"/>
        <volume name="sigma_t" type="gridvolume"><string name="filename" value="smoke.vol"/>
          <transform name="to_world"><scale x="3" y="2.4" z="3"/><translate x="-1.5" z="-1.5"/></transform></volume>
        <rgb name="albedo" value="0.9, 0.9, 0.9"/><phase type="hg"><float name="g" value="0.2"/></phase></medium>"#;
    let xml = format!("{}{smoke}{}", &xml[..a], &xml[b..]);
    let mut scene = haze_scene::load_str(&xml, &dir.join("caustic-smoke.xml"), &dir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_dir_all(&dir).ok();
    assert!(!scene.media[0].is_homogeneous());
    (scene.camera.width, scene.camera.height) = (16, 12);
    let (paths, passes) = (20, 32);
    let with = |caustic_paths: u64| ManyLightSettings {
        caustic_paths: Some(caustic_paths),
        ..settings(&scene, paths)
    };
    let continuation =
        render_passes(&scene, &VrlIntegrator::exhaustive(&scene, with(0), 1).unwrap(), passes, 16, 1);
    let splatting = VrlIntegrator::exhaustive(&scene, with(2000), 1).unwrap();
    let splats = render_passes(&scene, &splatting, passes, 16, 1);
    let (r, _) = compare(&splats, &continuation, Component::Surface);
    let z = paired_z(&splats, &continuation, Component::Surface);
    let mut failures = Vec::new();
    judge(&mut failures, "smoke: caustic paths vs continuation (paired z)", &r, z, 0.01);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let brighter = TestControls { caustic_scale: 1.2, ..TestControls::default() };
    let splatting = VrlIntegrator::exhaustive(&scene, with(2000), 1).unwrap().with_test_controls(brighter);
    let wrong = render_passes(&scene, &splatting, passes, 16, 1);
    let z = paired_z(&wrong, &continuation, Component::Surface);
    println!("smoke: caustic splats x 1.2: paired image-mean z = {z:.2}");
    assert!(z.abs() > 5.0, "20% too bright caustic splats in smoke went unnoticed: paired z = {z:.2}");
}

/// The paper's bound cut (`--cut bound`) in heterogeneous media (`docs/theory.md` §12.5, "The
/// bound cut"), on the smoke room: with `epsilon = 0` it evaluates every light, so it equals
/// brute-force `vrl`/`vpl` with the same seeds pixel for pixel (the heterogeneous estimators'
/// numbers are keyed by light, so the cut changes nothing but the order of the sum); with the
/// default `epsilon` it agrees with them by the per-pixel z-test on `multiple`.
#[test]
fn smoke_bound_cut_matches_brute_force() {
    use haze_manylight::integrators::BoundCut;
    use haze_manylight::tree::cut::CutSettings;
    let scene = smoke_scene(true, 0.0);
    let paths = 20;
    let ml = settings(&scene, paths);
    let exhaustive = BoundCut { cut: CutSettings { epsilon: 0.0, max_cut: u32::MAX }, ..Default::default() };
    let (a, b) = lightcut_renders(&scene, paths, 2, exhaustive, [9, 9]);
    let vrl = render_passes(&scene, &VrlIntegrator::exhaustive(&scene, ml.clone(), 9).unwrap(), 2, 1, 9);
    let vpl = render_passes(&scene, &VplIntegrator::exhaustive(&scene, ml.clone(), 9).unwrap(), 2, 1, 9);
    for (what, x, y) in [("vrl", &a, &vrl), ("vpl", &b, &vpl)] {
        let (mx, my) = (x.film.mean(Some(Component::Multiple)), y.film.mean(Some(Component::Multiple)));
        let worst = mx
            .iter()
            .zip(&my)
            .fold(0.0f32, |w, (p, q)| w.max((p - q).abs() / (p.abs().max(q.abs()) + 1e-12)));
        println!("smoke room, exhaustive bound cut vs {what}: largest relative difference {worst:e}");
        assert!(worst < 1e-4, "{what}: exhaustive bound cut differs from brute force by {worst}");
        assert!(mx.iter().any(|v| *v > 0.0));
    }
    let (paths, passes) = (60, 48);
    let ml = settings(&scene, paths);
    let (a, b) = lightcut_renders(&scene, paths, passes, BoundCut::default(), [11, 12]);
    let vrl =
        render_passes(&scene, &VrlIntegrator::exhaustive(&scene, ml.clone(), 13).unwrap(), passes, 1, 13);
    let vpl = render_passes(&scene, &VplIntegrator::exhaustive(&scene, ml, 14).unwrap(), passes, 1, 14);
    let mut failures = Vec::new();
    for (what, x, y) in
        [("vrl_lightcuts --cut bound vs vrl", &a, &vrl), ("vpl_lightcuts --cut bound vs vpl", &b, &vpl)]
    {
        let (r, mean_z) = compare(x, y, Component::Multiple);
        judge(&mut failures, &format!("smoke room, {what}, multiple"), &r, mean_z, 0.01);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The compensated clamp (`compensated_clamp`, `crate::gather`'s `Walk::compensate_from`,
/// Kollig & Keller 2004) changes the noise, not the expected image: `vrl` with the `1/d^2` of
/// surface VPL -> surface point connections clamped at `c = 1` (every VPL closer than 1 m in a
/// room of 3 x 2.4 x 4 m) and the clamped part recovered by the BSDF-sampled walk agrees with `vrl`
/// unclamped, in the `surface` component that both put it in. The control: the same clamp
/// without the compensation (the biased `clamp`) must be told apart.
#[test]
fn compensated_clamp_keeps_the_expected_image() {
    let mut scene = load_small_path(&haze_testkit::data::repo_root().join("tests/data/glass-ball-room.xml"));
    (scene.camera.width, scene.camera.height) = (16, 12);
    let c = 1.0;
    let plain = render_passes(
        &scene,
        &VrlIntegrator::exhaustive(&scene, settings(&scene, 60), 3).unwrap(),
        192,
        1,
        3,
    );
    let ml = ManyLightSettings { compensated_clamp: Some(c), ..settings(&scene, 60) };
    let compensated = render_passes(&scene, &VrlIntegrator::exhaustive(&scene, ml, 4).unwrap(), 192, 1, 4);
    let (r, mean_z) = compare(&compensated, &plain, Component::Surface);
    println!("compensated clamp vs unclamped, surface: {r}; image-mean z = {mean_z:.2}");
    let mut failures = Vec::new();
    judge(&mut failures, "compensated clamp, surface", &r, mean_z, 0.01);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let mut biased = VrlIntegrator::exhaustive(&scene, settings(&scene, 60), 4).unwrap();
    biased.clamps.surface = Some(c);
    let biased = render_passes(&scene, &biased, 192, 1, 4);
    let (r, mean_z) = compare(&biased, &plain, Component::Surface);
    println!("clamp without compensation vs unclamped, surface: {r}; image-mean z = {mean_z:.2}");
    let mut failures = Vec::new();
    judge(&mut failures, "uncompensated clamp, surface", &r, mean_z, 0.01);
    assert!(!failures.is_empty(), "the clamp's bias went unnoticed: {r}; image-mean z = {mean_z:.2}");
}

/// A fog-filled rough-glass ball (`roughdielectric`, `alpha` 0.3) on a dark diffuse floor under a
/// blue sky and a small area light, `albedo` the fog's.
fn rough_glass_scene(albedo: f32) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
        <medium id="fog" type="homogeneous"><rgb name="sigma_t" value="1.5, 1, 0.5"/><rgb name="albedo" value="{albedo}"/>
          <phase type="hg"><float name="g" value="0.4"/></phase></medium>
        <sensor type="perspective"><float name="fov" value="30"/>
          <transform name="to_world"><lookat origin="0, 0.8, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
          <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
        <shape type="sphere"><float name="radius" value="0.8"/>
          <bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.3"/></bsdf>
          <ref name="interior" id="fog"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/><translate y="-0.8"/></transform>
          <bsdf type="diffuse"><rgb name="reflectance" value="0.05"/></bsdf></shape>
        <shape type="sphere"><point name="center" x="-1.2" y="1.6" z="-0.6"/><float name="radius" value="0.3"/>
          <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
        <emitter type="constant"><rgb name="radiance" value="0.5, 0.6, 0.8"/></emitter>
        </scene>"#
    );
    haze_scene::load_str(
        &xml,
        std::path::Path::new("rough-glass.xml"),
        std::path::Path::new("."),
        &LoadOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Every many-light method passes rough interfaces instead of gathering at them
/// (`docs/theory.md` §2.1, "Rough interfaces": next-event estimation there, a BSDF sample, the
/// chain gathering beyond, the emitters it hits before a delta vertex left out): against
/// `volpath`, every component, on a fog-filled rough-glass ball lit by a sky (light that
/// reaches the fog only through the glass; the sky's light paths aimed at the ball, (T38b)) and
/// a small area light (lighting the glass directly and the fog through it). Control: the fog's
/// albedo 0.6 instead of 0.9 in the many-light render (a third less light scattered once in the
/// ball) fails the same test.
#[test]
fn rough_glass_ball_matches_volpath() {
    let scene = rough_glass_scene(0.9);
    let (paths, passes) = (100, 200);
    let reference = check_against_volpath(&scene, "rough glass ", paths, passes, true);
    let dimmer = rough_glass_scene(0.6);
    let vrl = VrlIntegrator::exhaustive(&dimmer, settings(&dimmer, paths), 1).unwrap();
    let wrong = render_passes(&dimmer, &vrl, passes, 1, 1);
    let caught = caught_in_any_component(&wrong, &reference, "rough glass, vrl with albedo 0.6");
    assert!(caught, "an 11% dimmer fog in the rough-glass ball went unnoticed");
}
