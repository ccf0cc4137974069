//! Images are bit-identical for any thread count and any grouping of passes into rounds
//! (`progressive::render` batches volpath's passes by wall time, which must change no bit).

use haze_core::{Ray, Sampler};
use haze_render::components::PathRadiance;
use haze_render::progressive::{render, RenderSettings};
use haze_render::{Integrator, VolPath};
use haze_scene::{load_file, LoadOptions, MediumId, Scene};
use std::sync::atomic::AtomicBool;

fn load(name: &str) -> Scene {
    let path = haze_testkit::data::validation_scene(name);
    let mut scene = load_file(&path, &LoadOptions::default()).expect("validation scene loads");
    // A smaller film: the property does not depend on the size.
    scene.camera.width = 32;
    scene.camera.height = 24;
    scene
}

/// volpath with one pass per round (as the many-light integrators run).
struct Unbatched(VolPath);

impl Integrator for Unbatched {
    type PassData = ();
    fn name(&self) -> &str {
        "volpath-unbatched"
    }
    fn begin_pass(&self, _scene: &Scene, _seed: u64, _pass: u32) {}
    fn radiance(
        &self,
        scene: &Scene,
        pass: &(),
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        self.0.radiance(scene, pass, ray, medium, sampler)
    }
}

fn image(scene: &Scene, threads: usize, batched: bool, spp_per_pass: u32) -> (Vec<f64>, u32) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let settings = RenderSettings { spp: 37, seed: 5, spp_per_pass, components: true, ..Default::default() };
    let v = VolPath::from_spec(&scene.integrator);
    let cancel = AtomicBool::new(false);
    let out = pool.install(|| {
        if batched {
            render(scene, &v, &settings, &cancel, |_| {})
        } else {
            render(scene, &Unbatched(v.clone()), &settings, &cancel, |_| {})
        }
    });
    assert_eq!(out.film.samples, 37);
    (out.film.data().to_vec(), out.passes)
}

#[test]
fn images_do_not_depend_on_threads_or_rounds() {
    for name in ["hg-box", "foggy-room"] {
        let scene = load(name);
        for spp_per_pass in [1, 4] {
            let (want, passes) = image(&scene, 1, false, spp_per_pass);
            assert_eq!(passes, 37u32.div_ceil(spp_per_pass));
            for (threads, batched) in [(1, true), (2, true), (3, true), (2, false)] {
                let (got, _) = image(&scene, threads, batched, spp_per_pass);
                assert!(got == want, "{name}: {threads} threads, batched {batched}, {spp_per_pass} spp/pass");
            }
        }
    }
}
