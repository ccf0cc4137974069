//! volpath in a heterogeneous medium against the same medium as a homogeneous one (issue 15),
//! without the peer data: a `.vol` grid of constant chromatic density renders, by delta
//! tracking and ratio tracking, the image the homogeneous medium gives by Beer-Lambert, also
//! with majorants raised per channel so that most tentative collisions are null. Per-pixel
//! z-test with the image-mean gate; negative control: 10% more density must fail.

use haze_core::Rgb;
use haze_render::progressive::RenderOutput;
use haze_render::{render_volpath, RenderSettings};
use haze_scene::hetero::Heterogeneous;
use haze_scene::volume::Grid;
use haze_scene::{load_str, LoadOptions, MediumKind, Scene};
use haze_testkit::ztest::z_test;
use std::path::Path;
use std::sync::Arc;

const SIGMA_T: [f32; 3] = [1.5, 0.8, 0.4];

fn scene(medium: &str, dir: &Path) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="volpath"><integer name="max_depth" value="12"/></integrator>
        <sensor type="perspective"><float name="fov" value="45"/>
          <transform name="to_world"><lookat origin="0.3, 0.8, 5" target="0, -0.2, 0" up="0, 1, 0"/></transform>
          <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
        <emitter type="point"><point name="position" value="1, 3, 1"/><rgb name="intensity" value="12, 10, 8"/></emitter>
        <emitter type="constant"><rgb name="radiance" value="0.2, 0.25, 0.3"/></emitter>
        {medium}
        <shape type="cube"><bsdf type="null"/><ref name="interior" id="m"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-1.3"/></transform>
          <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
        </scene>"#
    );
    load_str(&xml, &dir.join("scene.xml"), dir, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

const PHASE: &str = r#"<phase type="hg"><float name="g" value="0.4"/></phase>"#;

fn homogeneous(dir: &Path) -> Scene {
    let [r, g, b] = SIGMA_T;
    scene(
        &format!(
            r#"<medium id="m" type="homogeneous"><rgb name="sigma_t" value="{r}, {g}, {b}"/>
               <rgb name="albedo" value="0.8, 0.6, 0.9"/>{PHASE}</medium>"#
        ),
        dir,
    )
}

/// The grid medium over exactly the cube `[-1, 1]^3`, density times `density_factor`, its
/// majorants times `majorant_factor` per channel.
fn heterogeneous(dir: &Path, density_factor: f32, majorant_factor: Rgb) -> Scene {
    let data: Vec<f32> = (0..8).flat_map(|_| SIGMA_T.map(|s| s * density_factor / 2.0)).collect();
    let grid = Grid { res: [2, 2, 2], channels: 3, data, bbox: (glam::Vec3::ZERO, glam::Vec3::ONE) };
    std::fs::write(dir.join("density.vol"), grid.to_vol_bytes()).unwrap();
    let mut s = scene(
        &format!(
            r#"<medium id="m" type="heterogeneous"><float name="scale" value="2"/>
               <volume name="sigma_t" type="gridvolume"><string name="filename" value="density.vol"/>
                 <transform name="to_world"><scale value="2"/><translate value="-1 -1 -1"/></transform></volume>
               <rgb name="albedo" value="0.8, 0.6, 0.9"/>{PHASE}</medium>"#
        ),
        dir,
    );
    for m in &mut s.media {
        let h = m.as_grid().cloned().expect("heterogeneous");
        let mut majorants = h.majorants.clone();
        for c in &mut majorants.cells {
            *c *= majorant_factor;
        }
        m.kind = MediumKind::Grid(Arc::new(Heterogeneous { majorants, ..h }));
    }
    s
}

fn render(scene: &Scene, seed: u64) -> (RenderOutput, u32) {
    let spp = 384;
    let out = render_volpath(scene, &RenderSettings { spp, seed, spp_per_pass: 32, ..Default::default() });
    assert_eq!(out.invalid_samples, 0);
    (out, spp)
}

fn compare(a: &Scene, b: &Scene) -> haze_testkit::ztest::ZTestReport {
    let ((ra, na), (rb, nb)) = (render(a, 1), render(b, 2));
    let va: Vec<f32> = ra.film.sample_variance(None).iter().map(|v| v / na as f32).collect();
    let vb: Vec<f32> = rb.film.sample_variance(None).iter().map(|v| v / nb as f32).collect();
    z_test(&ra.film.mean(None), &va, &rb.film.mean(None), &vb, 0.01)
}

fn dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("haze-hetero-render-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn constant_grid_renders_the_homogeneous_image() {
    let d = dir("same");
    let reference = homogeneous(&d);
    for majorant_factor in [Rgb::ONE, Rgb::new(2.5, 1.5, 4.0)] {
        let report = compare(&heterogeneous(&d, 1.0, majorant_factor), &reference);
        println!("majorants x {majorant_factor}: {report}");
        assert!(report.passed(0.0025, 5.0), "majorants x {majorant_factor}: {report}");
    }
    let report = compare(&heterogeneous(&d, 1.1, Rgb::new(2.5, 1.5, 4.0)), &reference);
    println!("density x 1.1: {report}");
    assert!(!report.passed(0.0025, 5.0), "10% more density went unnoticed: {report}");
    std::fs::remove_dir_all(&d).ok();
}
