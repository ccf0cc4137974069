//! Mitsuba 3 XML scene loader (a strict subset; see `docs/mitsuba-compat.md`).
//!
//! Errors name the file, line, column and element, like Mitsuba 3's loader does.
//!
//! The loader runs in three steps, one file each:
//! 1. [`document`]: parse with `roxmltree` into an owned element tree, splicing in `<include>`d
//!    files, consuming `<default>`s and substituting `$name` in attribute values;
//! 2. [`params`]: for each plugin element, collect its typed parameters and nested objects
//!    (resolving `<ref id=".."/>`), so that each plugin reads what it needs and anything left
//!    over is an "unused parameter" error;
//! 3. [`builder`] and the per-family files ([`sensor`], [`integrator`], [`shapes`], [`bsdfs`],
//!    [`media`], [`emitters`]) translate each plugin into haze's scene types, validating values
//!    where they are read.
//!
//! The table of what is supported is [`supported_plugins`]; the parameter check uses it, and a
//! test keeps `docs/mitsuba-compat.md` in step with it.

mod bsdfs;
mod builder;
mod context;
mod document;
mod emitters;
mod integrator;
mod media;
mod obj;
mod params;
mod plugins;
mod ply;
mod sensor;
mod serialized;
mod shapes;
mod textures;
mod transform;
mod values;

pub use bsdfs::{ior_by_name, NAMED_IORS};
pub use plugins::supported_plugins;

use crate::scene::Scene;
use std::fmt;
use std::path::{Path, PathBuf};

/// Largest emitter value (radiance, intensity) and extinction coefficient haze accepts: far
/// above any physical scene, far below where products of them overflow f32 (`3.4e38`) and
/// every sample turns NaN.
pub(crate) const MAX_MAGNITUDE: f32 = 1e20;

/// Options that come from outside the file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `-D name=value` overrides for `<default name=".." value=".."/>` parameters.
    pub defines: Vec<(String, String)>,
}

/// A scene-loading error with its location.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadError {
    pub file: PathBuf,
    /// 1-based line and column; 0 when the error is not tied to a place in the file.
    pub line: u32,
    pub column: u32,
    /// The element, e.g. `<shape type="obj">` or `<float name="sigma_t">`.
    pub element: String,
    pub message: String,
}

impl LoadError {
    /// An error about the file as a whole (it cannot be read, ...), not tied to an element.
    pub(crate) fn whole_file(file: &Path, message: impl Into<String>) -> Self {
        LoadError {
            file: file.to_path_buf(),
            line: 0,
            column: 0,
            element: String::new(),
            message: message.into(),
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: ", self.file.display(), self.line, self.column)?;
        if !self.element.is_empty() {
            write!(f, "{}: ", one_line(&shorten_long_words(&self.element)))?;
        }
        f.write_str(&one_line(&shorten_long_words(&self.message)))
    }
}

/// Messages quote text from the file, which may span lines: shown on one line.
fn one_line(s: &str) -> std::borrow::Cow<'_, str> {
    if s.contains(['\n', '\r']) {
        s.split(['\n', '\r']).map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" ").into()
    } else {
        s.into()
    }
}

/// Longest run of non-blank characters a message shows whole.
const MAX_WORD_CHARS: usize = 120;

/// Shortens every run of non-blank characters longer than [`MAX_WORD_CHARS`] to its start and
/// its length: messages quote attribute values, which a broken or hostile file can make
/// megabytes long.
fn shorten_long_words(s: &str) -> std::borrow::Cow<'_, str> {
    if s.len() <= MAX_WORD_CHARS {
        return s.into();
    }
    let mut out = String::with_capacity(s.len().min(16 * MAX_WORD_CHARS));
    let mut shortened = false;
    for (i, word) in s.split(' ').enumerate() {
        if out.len() > 16 * MAX_WORD_CHARS {
            shortened = true;
            break;
        }
        if i > 0 {
            out.push(' ');
        }
        match word.char_indices().nth(MAX_WORD_CHARS) {
            Some((cut, _)) => {
                let keep = word.char_indices().nth(MAX_WORD_CHARS / 2).map_or(cut, |(i, _)| i);
                out.push_str(&word[..keep]);
                out.push_str(&format!("[... {} bytes in all]", word.len()));
                shortened = true;
            }
            None => out.push_str(word),
        }
    }
    // Many short words (a long list of numbers) are cut as a whole.
    if out.len() > 8 * MAX_WORD_CHARS {
        let keep = out.char_indices().nth(4 * MAX_WORD_CHARS).map_or(out.len(), |(i, _)| i);
        let total = s.len();
        out.truncate(keep);
        out.push_str(&format!("[... {total} bytes in all]"));
        shortened = true;
    }
    if shortened {
        out.into()
    } else {
        s.into()
    }
}

impl std::error::Error for LoadError {}

/// Loads a scene file. Relative paths in it (mesh files, includes) resolve against the file's
/// directory, as in Mitsuba 3.
pub fn load_file(path: &Path, options: &LoadOptions) -> Result<Scene, LoadError> {
    let xml = std::fs::read_to_string(path)
        .map_err(|e| LoadError::whole_file(path, format!("cannot read scene file: {e}")))?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    load_str(&xml, path, base_dir, options)
}

/// Loads a scene from a string; relative paths resolve against `base_dir`, and messages name
/// `file_name`.
pub fn load_str(
    xml: &str,
    file_name: &Path,
    base_dir: &Path,
    options: &LoadOptions,
) -> Result<Scene, LoadError> {
    load_str_with_sources(xml, file_name, base_dir, options).map(|(scene, _)| scene)
}

/// [`load_file`], also returning every file the scene read: `path` first, then its includes,
/// mesh files and images, each once, in the order they were first read. This is what another
/// machine needs to load the same scene (the Python package ships these files to Ray workers).
pub fn load_file_with_sources(
    path: &Path,
    options: &LoadOptions,
) -> Result<(Scene, Vec<PathBuf>), LoadError> {
    let xml = std::fs::read_to_string(path)
        .map_err(|e| LoadError::whole_file(path, format!("cannot read scene file: {e}")))?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    load_str_with_sources(&xml, path, base_dir, options)
}

fn load_str_with_sources(
    xml: &str,
    file_name: &Path,
    base_dir: &Path,
    options: &LoadOptions,
) -> Result<(Scene, Vec<PathBuf>), LoadError> {
    let doc = document::parse(xml, file_name, base_dir, &options.defines)?;
    let scene = builder::build(&doc, file_name)?;
    let mut files = vec![file_name.to_path_buf()];
    for f in doc.files.into_inner() {
        if !files.contains(&f) {
            files.push(f);
        }
    }
    Ok((scene, files))
}
