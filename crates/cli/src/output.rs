//! What `haze render` writes, checked before rendering (issue 16): `-o` names an `.exr` (the
//! image, with a PNG preview beside it) or a `.png` (the preview only, no EXR); any other
//! extension is refused rather than written in the wrong format. No output may be the scene
//! file or any file the scene reads (includes, meshes, images), nor another output
//! (`--variance-out` equal to `-o` replaced the image).

use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// What `-o` asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct Outputs {
    /// The EXR image, unless `-o` is a `.png`.
    pub exr: Option<PathBuf>,
    /// The sRGB preview.
    pub png: PathBuf,
}

fn extension(p: &Path) -> String {
    p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default()
}

/// The files `-o output` stands for.
pub fn plan(output: &Path) -> Result<Outputs> {
    match extension(output).as_str() {
        "exr" => Ok(Outputs { exr: Some(output.to_path_buf()), png: output.with_extension("png") }),
        "png" => Ok(Outputs { exr: None, png: output.to_path_buf() }),
        _ => bail!(
            "-o {}: haze writes .exr (with a .png preview beside it) or .png (the preview only); \
             give one of those extensions",
            output.display()
        ),
    }
}

/// `p` made absolute with symbolic links resolved, as far as it exists.
fn normalize(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let parent = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (parent.canonicalize(), p.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => p.to_path_buf(),
    }
}

/// Refuses outputs that would overwrite an input (the scene file, its includes, meshes,
/// images: `inputs`) or each other. `outputs` are every file the render will write, with the
/// option that names it.
pub fn check_distinct(outputs: &[(&str, PathBuf)], inputs: &[PathBuf]) -> Result<()> {
    let inputs: Vec<PathBuf> = inputs.iter().map(|p| normalize(p)).collect();
    let mut seen: Vec<(&str, PathBuf)> = Vec::new();
    for (option, path) in outputs {
        let n = normalize(path);
        if inputs.contains(&n) {
            bail!(
                "{option} {} would overwrite an input of the scene; choose another file name",
                path.display()
            );
        }
        if let Some((other, _)) = seen.iter().find(|(_, p)| *p == n) {
            bail!("{option} {} is also written by {other}; choose another file name", path.display());
        }
        seen.push((option, n));
    }
    Ok(())
}

/// The `-D NAME=VALUE` scene parameters.
pub fn parse_defines(define: &[String]) -> Result<Vec<(String, String)>> {
    define
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
            _ => bail!("-D expects NAME=VALUE, got '{d}'"),
        })
        .collect()
}

/// The EXR of one component beside `-o out` (`--components`): `out_single.exr`, ...
pub(crate) fn component_path(out: &Path, comp: haze_render::Component) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "haze".into());
    out.with_file_name(format!("{stem}_{}.exr", comp.name()))
}

/// Loads the scene and lists every file it read (the inputs no output may overwrite).
pub fn load_with_sources(path: &Path, define: &[String]) -> Result<(haze_scene::Scene, Vec<PathBuf>)> {
    let options = haze_scene::LoadOptions { defines: parse_defines(define)? };
    Ok(haze_scene::load_file_with_sources(path, &options)?)
}

/// Checks every file `haze render` will write (`-o output`, with `components` its per-component
/// EXRs, `--variance-out`, `--cut-image`) against the scene's inputs and each other, and
/// returns what `-o` stands for.
pub fn check_render_outputs(
    output: &Path,
    components: bool,
    variance_out: Option<&Path>,
    cut_image: Option<&Path>,
    inputs: &[PathBuf],
) -> Result<Outputs> {
    let plan = plan(output)?;
    let mut outputs: Vec<(&str, PathBuf)> = Vec::new();
    if let Some(exr) = &plan.exr {
        outputs.push(("-o", exr.clone()));
    }
    outputs.push((if plan.exr.is_some() { "the PNG preview of -o" } else { "-o" }, plan.png.clone()));
    if components {
        for comp in haze_render::Component::ALL {
            outputs.push(("--components", component_path(output, comp)));
        }
    }
    if let Some(v) = variance_out {
        if extension(v) != "exr" {
            bail!(
                "--variance-out {}: the variance is written as OpenEXR; give a .exr file name",
                v.display()
            );
        }
        outputs.push(("--variance-out", v.to_path_buf()));
    }
    if let Some(c) = cut_image {
        outputs.push(("--cut-image", c.to_path_buf()));
    }
    check_distinct(&outputs, inputs)?;
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions() {
        let p = plan(Path::new("a/x.exr")).unwrap();
        assert_eq!((p.exr.as_deref(), p.png.as_path()), (Some(Path::new("a/x.exr")), Path::new("a/x.png")));
        let p = plan(Path::new("x.PNG")).unwrap();
        assert_eq!((p.exr, p.png.as_path()), (None, Path::new("x.PNG")));
        for bad in ["x.jpg", "x.txt", "scene.xml", "x"] {
            assert!(plan(Path::new(bad)).unwrap_err().to_string().contains("give one of those"), "{bad}");
        }
    }

    #[test]
    fn inputs_and_outputs_are_distinct() {
        let dir = std::env::temp_dir().join(format!("haze-output-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("s.xml");
        std::fs::write(&scene, "<scene/>").unwrap();
        let inputs = vec![scene.clone()];
        // The same file through another spelling.
        let other = dir.join(".").join("s.xml");
        let e = check_distinct(&[("-o", other)], &inputs).unwrap_err().to_string();
        assert!(e.contains("would overwrite an input"), "{e}");
        let e = check_distinct(&[("-o", dir.join("x.exr")), ("--variance-out", dir.join("x.exr"))], &inputs)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--variance-out") && e.contains("also written by -o"), "{e}");
        check_distinct(&[("-o", dir.join("x.exr")), ("--variance-out", dir.join("v.exr"))], &inputs).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
