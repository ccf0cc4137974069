//! Limits on what the command line may ask for, checked before anything large is allocated
//! (issue 16): time budgets that fit a `Duration`, thread counts, film size and light counts
//! against the memory available, and the share of NaN/infinite samples a render may discard.

use anyhow::{bail, Result};
use std::time::Duration;

/// A budget of `seconds` as a `Duration` (which panics on overflow when converted blindly):
/// positive, finite, at least a millisecond and at most a year.
pub fn seconds(option: &str, seconds: f64) -> Result<Duration> {
    const MIN: f64 = 1e-3;
    const MAX: f64 = 365.0 * 24.0 * 3600.0;
    if !(seconds.is_finite() && seconds > 0.0) {
        bail!("{option} must be a positive number of seconds, got {seconds}");
    }
    if seconds < MIN {
        bail!("{option} {seconds:e} is too small a budget: no pass would finish (give at least {MIN} s)");
    }
    if seconds > MAX {
        bail!("{option} {seconds:e} is more than a year; give at most {MAX} s");
    }
    Ok(Duration::from_secs_f64(seconds))
}

/// Most worker threads: 8 per core, at least 256. Far more threads than cores only makes the
/// workers spin (`--threads 100000` showed nothing for a minute).
pub fn max_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (8 * cores).max(256)
}

pub fn check_threads(threads: usize) -> Result<()> {
    let max = max_threads();
    if threads > max {
        bail!("--threads {threads} is more than haze runs on this machine (at most {max}: 8 per core, at least 256)");
    }
    Ok(())
}

/// Memory this process may use: `MemAvailable` from `/proc/meminfo` where there is one, else
/// a fixed 64 GiB.
pub fn available_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib.saturating_mul(1024))
        })
        .unwrap_or(64 << 30)
}

/// Bytes a render of `width x height` needs: the film (per pixel and layer, 6 f64 sums; 5
/// layers with components) and the f32 images written from it.
pub fn film_bytes(width: u32, height: u32, components: bool) -> u64 {
    let pixels = width as u64 * height as u64;
    let layers = if components { 5 } else { 1 };
    pixels.saturating_mul(layers * 6 * 8 + 3 * 4 * 2)
}

pub fn check_film(width: u32, height: u32, components: bool, available: u64) -> Result<()> {
    let need = film_bytes(width, height, components);
    if need > available {
        bail!(
            "the image is too large for memory: {width}x{height} pixels{} need {:.1} GiB, {:.1} GiB are available",
            if components { " with components" } else { "" },
            need as f64 / (1u64 << 30) as f64,
            available as f64 / (1u64 << 30) as f64
        );
    }
    Ok(())
}

/// Bytes per virtual light, counted generously (the light, its tree node, the light path
/// records it came from).
const BYTES_PER_LIGHT: u64 = 512;

/// `--vrls` / `--light-paths`: each asks for at least that many lights per pass.
pub fn check_lights(option: &str, count: u64, available: u64) -> Result<()> {
    let need = count.saturating_mul(BYTES_PER_LIGHT);
    if need > available {
        bail!(
            "{option} {count} would need about {:.1} GiB for the lights alone ({BYTES_PER_LIGHT} bytes each), \
             {:.1} GiB are available",
            need as f64 / (1u64 << 30) as f64,
            available as f64 / (1u64 << 30) as f64
        );
    }
    Ok(())
}

/// Largest share of NaN or infinite samples a render may drop and still write its image.
pub const MAX_INVALID_FRACTION: f64 = 1e-3;

/// A render whose samples came out NaN or infinite more than rarely is an error: the image
/// would be silently dark (every sample discarded gave a black image and exit code 0).
pub fn check_invalid_samples(
    integrator: &str,
    invalid: u64,
    total: u64,
    scene: &std::path::Path,
) -> Result<()> {
    if invalid as f64 > MAX_INVALID_FRACTION * total as f64 {
        bail!(
            "{}: the {integrator} integrator produced {invalid} NaN or infinite samples out of {total} ({:.1}%, \
             more than the {}% haze discards silently); nothing written. The scene's emitters, media or BSDFs \
             hold values the {integrator} estimates overflow on (extreme intensities, extinction, IORs or \
             roughness, or a degenerate emitter transform)",
            scene.display(),
            100.0 * invalid as f64 / total.max(1) as f64,
            100.0 * MAX_INVALID_FRACTION
        );
    }
    Ok(())
}

/// The memory checks of `haze render`: the film, and the lights `--vrls` or `--light-paths`
/// ask for (each light path gives at least one light).
pub fn check_render(options: &haze_engine::options::Options, scene: &haze_scene::Scene) -> Result<()> {
    use haze_manylight::integrators::LightBudget;
    let available = available_memory();
    check_film(scene.camera.width, scene.camera.height, options.components, available)?;
    match options.method.budget {
        LightBudget::Vrls(n) => check_lights("--vrls", n, available),
        LightBudget::Paths(n) => check_lights("--light-paths", n, available),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn time_budgets() {
        assert!(seconds("--time", 1e20).unwrap_err().to_string().contains("more than a year"));
        assert!(seconds("--time", 1e-300).unwrap_err().to_string().contains("too small a budget"));
        assert!(seconds("--time", f64::NAN).is_err());
        assert!(seconds("--time", -1.0).is_err());
        assert_eq!(seconds("--time", 2.5).unwrap(), Duration::from_millis(2500));
    }

    #[test]
    fn threads_films_and_lights() {
        assert!(check_threads(100_000).unwrap_err().to_string().contains("--threads 100000"));
        check_threads(4).unwrap();
        let gib = 1u64 << 30;
        let e = check_film(65536, 65536, false, 16 * gib).unwrap_err().to_string();
        assert!(e.contains("too large for memory") && e.contains("65536x65536"), "{e}");
        check_film(1920, 1080, true, 16 * gib).unwrap();
        let e = check_lights("--vrls", 10_000_000_000, 16 * gib).unwrap_err().to_string();
        assert!(e.contains("--vrls 10000000000"), "{e}");
        check_lights("--vrls", 1_000_000, 16 * gib).unwrap();
    }

    #[test]
    fn invalid_samples() {
        let scene = Path::new("s.xml");
        check_invalid_samples("vrl", 1, 10_000, scene).unwrap();
        let e = check_invalid_samples("vrl", 256, 256, scene).unwrap_err().to_string();
        assert!(e.contains("vrl integrator") && e.contains("256 NaN or infinite samples out of 256"), "{e}");
    }
}
