//! The scene file as an owned element tree: XML parsing, `<include>`, `<default>` and `$name`
//! substitution.
//!
//! Mitsuba 3 resolves these before it looks at any plugin, and so do we: after [`parse`], the
//! tree holds only plugin, parameter and transform elements, with every attribute value final.
//! Each element remembers its file and position so that later errors can say where.

use super::LoadError;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// The file an element was read from.
#[derive(Debug)]
pub(super) struct Source {
    /// The name used in messages.
    pub file: PathBuf,
    /// The file's own directory: the last place relative file names are looked up in.
    pub dir: PathBuf,
}

/// A parsed scene file with its includes spliced in.
#[derive(Debug)]
pub(super) struct Document {
    /// The `<scene>` element.
    pub root: Element,
    /// Where relative file names are looked up, in order: the main file's directory, then the
    /// `<path value=".."/>` directories (Mitsuba 3's file resolver).
    pub search_dirs: Vec<PathBuf>,
    /// Every file read or resolved so far besides the main file (includes, then meshes and
    /// images as the builder resolves them), for shipping a scene to other machines.
    pub files: RefCell<Vec<PathBuf>>,
    /// Bitmap textures already loaded, by element: a texture referenced from several places
    /// is read once and shared.
    pub bitmaps: RefCell<HashMap<usize, std::sync::Arc<crate::bitmap::Bitmap>>>,
    /// The mesh a `mesh_attribute` texture built now reads (the shape whose BSDF is being
    /// built).
    pub(crate) mesh_scope: RefCell<MeshScope>,
}

impl Document {
    /// Resolves a file name given in `el`. Mitsuba 3 resolves names, also in included files,
    /// against the main file's directory and the `<path>`s; we then also try the directory
    /// of the file `el` is in. A name found nowhere resolves to its first candidate, for the
    /// error message.
    pub fn resolve(&self, name: &str, el: &Element) -> PathBuf {
        let path = resolve_in(&self.search_dirs, name, el);
        self.files.borrow_mut().push(path.clone());
        path
    }
}

fn resolve_in(search_dirs: &[PathBuf], name: &str, el: &Element) -> PathBuf {
    let name = Path::new(name);
    if name.is_absolute() {
        return name.to_path_buf();
    }
    let mut candidates = search_dirs.iter().chain(std::iter::once(&el.source.dir)).map(|d| d.join(name));
    let first = candidates.next().unwrap_or_else(|| name.to_path_buf());
    if first.exists() {
        return first;
    }
    candidates.find(|c| c.exists()).unwrap_or(first)
}

/// One XML element after includes, defaults and substitution.
#[derive(Debug)]
pub(super) struct Element {
    /// Unique within one load; identifies an object instance (a medium referenced twice is
    /// built once).
    pub uid: usize,
    pub tag: String,
    attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
    pub source: Rc<Source>,
    /// 1-based position of the start tag.
    pub line: u32,
    pub column: u32,
}

impl Element {
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    pub fn required_attr(&self, name: &str) -> Result<&str, LoadError> {
        self.attr(name).ok_or_else(|| self.error(format!("missing required attribute '{name}'")))
    }

    /// Strictness: an attribute Mitsuba would not read is a mistake in the file.
    pub fn check_attrs(&self, allowed: &[&str]) -> Result<(), LoadError> {
        match self.attrs.iter().find(|(k, _)| !allowed.contains(&k.as_str())) {
            None => Ok(()),
            Some((k, _)) => {
                Err(self.error(format!("unexpected attribute '{k}' (allowed: {})", allowed.join(", "))))
            }
        }
    }

    /// The start tag with the attributes that identify the element, e.g. `<shape type="obj">`,
    /// `<float name="sigma_t">` or `<ref name="interior" id="fog">`.
    pub fn describe(&self) -> String {
        let mut s = format!("<{}", self.tag);
        for key in ["type", "name", "id"] {
            if let Some(v) = self.attr(key) {
                s.push_str(&format!(" {key}=\"{v}\""));
            }
        }
        s.push('>');
        s
    }

    pub fn error(&self, message: impl Into<String>) -> LoadError {
        LoadError {
            file: self.source.file.clone(),
            line: self.line,
            column: self.column,
            element: self.describe(),
            message: message.into(),
        }
    }
}

/// Parses `xml` into the `<scene>` element. `defines` (`-D name=value`) take precedence over
/// the file's `<default>`s.
pub(super) fn parse(
    xml: &str,
    file_name: &Path,
    base_dir: &Path,
    defines: &[(String, String)],
) -> Result<Document, LoadError> {
    let mut ctx = Context {
        params: defines.iter().cloned().collect(),
        next_uid: 0,
        include_stack: Vec::new(),
        search_dirs: vec![base_dir.to_path_buf()],
        files: Vec::new(),
    };
    let source = Rc::new(Source { file: file_name.to_path_buf(), dir: base_dir.to_path_buf() });
    let doc = parse_xml(xml, &source.file)?;
    let lines = LineIndex::new(xml);
    let root = doc.root_element();
    let mut scene = ctx.element_shell(&lines, root, &source)?;
    if scene.tag != "scene" {
        return Err(scene.error("the root element must be <scene>"));
    }
    check_version(&scene)?;
    ctx.fill(&lines, root, &source, true, 1, &mut scene)?;
    Ok(Document {
        root: scene,
        search_dirs: ctx.search_dirs,
        files: RefCell::new(ctx.files),
        bitmaps: RefCell::default(),
        mesh_scope: RefCell::default(),
    })
}

/// Mitsuba 3 reads files of format versions 2.x and 3.x (older ones it upgrades, which we do
/// not).
fn check_version(scene: &Element) -> Result<(), LoadError> {
    scene.check_attrs(&["version"])?;
    let version = scene.required_attr("version")?;
    let parts: Vec<Option<u32>> = version.split('.').map(|p| p.parse().ok()).collect();
    match parts.first() {
        Some(Some(2 | 3)) if parts.len() <= 3 && parts.iter().all(Option::is_some) => Ok(()),
        _ if parts.iter().all(Option::is_some) => {
            Err(scene
                .error(format!("unsupported scene version '{version}' (haze reads versions 2.x and 3.x)")))
        }
        _ => Err(scene.error(format!("malformed version '{version}' (expected e.g. \"3.0.0\")"))),
    }
}

fn parse_xml<'x>(xml: &'x str, file: &Path) -> Result<roxmltree::Document<'x>, LoadError> {
    roxmltree::Document::parse(xml).map_err(|e| {
        use roxmltree::Error as E;
        let (line, column, message) = match e {
            // roxmltree places these at 1:1; they are about where the text ends.
            E::UnexpectedEndOfStream | E::UnclosedRootNode => {
                let (line, column) = LineIndex::new(xml).position(xml.len());
                (line, column, format!("malformed XML: the file ends early ({e})"))
            }
            _ => (e.pos().row, e.pos().col, format!("malformed XML: {e}")),
        };
        LoadError { file: file.to_path_buf(), line, column, element: String::new(), message }
    })
}

/// Byte offsets of line starts, for 1-based (line, column) of any offset in `O(log n)`.
/// (`roxmltree::Document::text_pos_at` scans from the start of the text on every call, which
/// made loading quadratic in the number of elements.)
struct LineIndex<'x> {
    text: &'x str,
    starts: Vec<usize>,
    /// The last answer `(byte offset, line, 0-based column)`: elements are looked up in file
    /// order, so the column of the next one on the same (possibly very long) line is counted
    /// from there rather than from the start of the line.
    last: std::cell::Cell<(usize, usize, usize)>,
}

impl<'x> LineIndex<'x> {
    fn new(text: &'x str) -> Self {
        let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        LineIndex { text, starts, last: std::cell::Cell::new((0, 1, 0)) }
    }

    /// Line and column (in characters, as roxmltree counts them) of byte offset `pos`.
    fn position(&self, pos: usize) -> (u32, u32) {
        let pos = pos.min(self.text.len());
        let line = self.starts.partition_point(|&s| s <= pos).max(1);
        let (last_pos, last_line, last_col) = self.last.get();
        let (from, col) = if last_line == line && last_pos <= pos {
            (last_pos, last_col)
        } else {
            (self.starts[line - 1], 0)
        };
        let column = col + self.text.get(from..pos).map_or(pos - from, |t| t.chars().count());
        self.last.set((pos, line, column));
        (u32::try_from(line).unwrap_or(u32::MAX), u32::try_from(column + 1).unwrap_or(u32::MAX))
    }
}

/// Elements nest at most this deep (Mitsuba scenes nest a handful of levels; very deep
/// nesting would exhaust the stack of the recursive loader).
pub(super) const MAX_NESTING_DEPTH: usize = 64;

/// A value may not grow beyond this many bytes through `$name` substitution (a chain of
/// `<default>`s, each repeating the previous one, grows exponentially).
pub(super) const MAX_SUBSTITUTED_LEN: usize = 1 << 20;

/// Includes nest at most this deep (a file including itself would recurse forever).
pub(super) const MAX_INCLUDE_DEPTH: usize = 16;

struct Context {
    /// Values for `$name`: `-D` defines and the `<default>`s seen so far. The first value
    /// of a name wins, as in Mitsuba 3: `-D` over `<default>`, and an earlier `<default>`
    /// over a later one (an included file's defaults do not override the includer's).
    params: HashMap<String, String>,
    next_uid: usize,
    include_stack: Vec<PathBuf>,
    search_dirs: Vec<PathBuf>,
    /// Included files, in the order they were read.
    files: Vec<PathBuf>,
}

impl Context {
    /// Converts `node` without its children, substituting `$name` in its attributes.
    fn element_shell(
        &mut self,
        lines: &LineIndex,
        node: roxmltree::Node,
        source: &Rc<Source>,
    ) -> Result<Element, LoadError> {
        let (line, column) = lines.position(node.range().start);
        let mut el = Element {
            uid: self.next_uid,
            tag: node.tag_name().name().to_string(),
            attrs: Vec::new(),
            children: Vec::new(),
            source: source.clone(),
            line,
            column,
        };
        self.next_uid += 1;
        // Attributes are first kept raw so that an error while substituting can still
        // describe the element.
        el.attrs = node.attributes().map(|a| (a.name().to_string(), a.value().to_string())).collect();
        for i in 0..el.attrs.len() {
            match substitute(&el.attrs[i].1, &self.params) {
                Ok(v) => el.attrs[i].1 = v,
                Err(msg) => {
                    let key = el.attrs[i].0.clone();
                    return Err(el.error(format!("in attribute '{key}': {msg}")));
                }
            }
        }
        Ok(el)
    }

    /// Converts the children of `node` and appends them to `parent`. At the top level
    /// (`top_level`), `<default>` elements are consumed.
    fn fill(
        &mut self,
        lines: &LineIndex,
        node: roxmltree::Node,
        source: &Rc<Source>,
        top_level: bool,
        depth: usize,
        parent: &mut Element,
    ) -> Result<(), LoadError> {
        for child in node.children() {
            if child.is_text() {
                let text = child.text().unwrap_or("").trim();
                if !text.is_empty() {
                    return Err(parent.error(format!("unexpected text '{text}'")));
                }
                continue;
            }
            if !child.is_element() {
                continue; // comments, processing instructions
            }
            let mut el = self.element_shell(lines, child, source)?;
            if depth >= MAX_NESTING_DEPTH {
                return Err(
                    el.error(format!("elements nest too deeply (the limit is {MAX_NESTING_DEPTH} levels)"))
                );
            }
            match el.tag.as_str() {
                "default" => {
                    if !top_level {
                        return Err(el.error("<default> must be a direct child of <scene>"));
                    }
                    self.add_default(&el)?;
                    if child.has_children() {
                        return Err(el.error("<default> takes no children"));
                    }
                }
                "include" => self.include(&el, top_level, depth, parent)?,
                "path" => {
                    if !top_level {
                        return Err(el.error("<path> must be a direct child of <scene>"));
                    }
                    el.check_attrs(&["value"])?;
                    let dir = resolve_in(&self.search_dirs[..1], el.required_attr("value")?, &el);
                    self.search_dirs.push(dir);
                }
                _ => {
                    self.fill(lines, child, source, false, depth + 1, &mut el)?;
                    parent.children.push(el);
                }
            }
        }
        Ok(())
    }

    fn add_default(&mut self, el: &Element) -> Result<(), LoadError> {
        el.check_attrs(&["name", "value"])?;
        let name = el.required_attr("name")?;
        let value = el.required_attr("value")?;
        if name.is_empty() || !name.chars().all(is_param_char) {
            return Err(el.error(format!("invalid parameter name '{name}' (use letters, digits and '_')")));
        }
        self.params.entry(name.to_string()).or_insert_with(|| value.to_string());
        Ok(())
    }

    /// `<include filename=".."/>`: a file whose root is `<scene>` contributes its children (at
    /// the top level its `<default>`s too); any other root element is inserted as it is.
    fn include(
        &mut self,
        el: &Element,
        top_level: bool,
        depth: usize,
        parent: &mut Element,
    ) -> Result<(), LoadError> {
        el.check_attrs(&["filename"])?;
        let name = el.required_attr("filename")?;
        let path = resolve_in(&self.search_dirs, name, el);
        if self.include_stack.contains(&path) {
            return Err(el.error(format!("'{}' is included recursively", path.display())));
        }
        if self.include_stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(el.error(format!(
                "include depth limit ({MAX_INCLUDE_DEPTH}) reached: cannot include '{}'",
                path.display()
            )));
        }
        let xml = std::fs::read_to_string(&path)
            .map_err(|e| el.error(format!("cannot read '{}': {e}", path.display())))?;
        self.files.push(path.clone());
        let source = Rc::new(Source {
            file: path.clone(),
            dir: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
        });
        let doc = parse_xml(&xml, &path)?;
        let lines = LineIndex::new(&xml);
        let root = doc.root_element();
        self.include_stack.push(path);
        let mut root_el = self.element_shell(&lines, root, &source)?;
        let result = if root_el.tag == "scene" {
            check_version(&root_el).and_then(|()| self.fill(&lines, root, &source, top_level, depth, parent))
        } else {
            self.fill(&lines, root, &source, false, depth + 1, &mut root_el).map(|()| {
                parent.children.push(root_el);
            })
        };
        self.include_stack.pop();
        result
    }
}

fn is_param_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Replaces every `$name` in `value` (`name` = the longest run of letters, digits and `_`).
fn substitute(value: &str, params: &HashMap<String, String>) -> Result<String, String> {
    if !value.contains('$') {
        return Ok(value.to_string());
    }
    let mut out = String::with_capacity(value.len());
    let mut rest = value;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let len = after.find(|c| !is_param_char(c)).unwrap_or(after.len());
        let name = &after[..len];
        if name.is_empty() {
            return Err("'$' must be followed by a parameter name".into());
        }
        match params.get(name) {
            Some(v) if out.len() + v.len() > MAX_SUBSTITUTED_LEN.max(value.len()) => {
                return Err(format!(
                    "substituting '${name}' makes the value longer than {MAX_SUBSTITUTED_LEN} bytes \
                     (<default> values that repeat each other grow exponentially)"
                ))
            }
            Some(v) => out.push_str(v),
            None => {
                return Err(format!(
                    "undefined parameter '${name}' (declare it with \
                     <default name=\"{name}\" value=\"..\"/> or define it with -D {name}=..)"
                ))
            }
        }
        rest = &after[len..];
    }
    out.push_str(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(pairs: &[(&str, &str)]) -> HashMap<String, String> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    fn load(xml: &str, defines: &[(&str, &str)]) -> Result<Element, LoadError> {
        let defines: Vec<(String, String)> =
            defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        parse(xml, Path::new("t.xml"), Path::new("."), &defines).map(|d| d.root)
    }

    #[test]
    fn substitution_takes_the_longest_name() {
        let p = params(&[("s", "1"), ("spp", "64")]);
        assert_eq!(substitute("$spp", &p).unwrap(), "64");
        assert_eq!(substitute("$s, $s", &p).unwrap(), "1, 1");
        assert_eq!(substitute("a$spp-b", &p).unwrap(), "a64-b");
        assert!(substitute("$nope", &p).unwrap_err().contains("'$nope'"));
        assert!(substitute("5$", &p).is_err());
    }

    #[test]
    fn defaults_apply_and_defines_override_them() {
        let xml = r#"<scene version="3.0.0">
            <default name="w" value="32"/>
            <film type="hdrfilm"><integer name="width" value="$w"/></film>
        </scene>"#;
        let width = |root: &Element| root.children[0].children[0].attr("value").unwrap().to_string();
        assert_eq!(width(&load(xml, &[]).unwrap()), "32");
        assert_eq!(width(&load(xml, &[("w", "8")]).unwrap()), "8");
    }

    #[test]
    fn use_before_default_is_an_error_and_the_first_default_wins() {
        let before = r#"<scene version="3.0.0">
            <film type="hdrfilm"><integer name="width" value="$w"/></film>
            <default name="w" value="32"/>
        </scene>"#;
        let e = load(before, &[]).unwrap_err();
        assert_eq!(e.line, 2);
        assert!(e.message.contains("'$w'"));
        let twice = r#"<scene version="3.0.0">
            <default name="w" value="32"/><default name="w" value="3"/>
            <film type="hdrfilm"><integer name="width" value="$w"/></film>
        </scene>"#;
        let root = load(twice, &[]).unwrap();
        assert_eq!(root.children[0].children[0].attr("value"), Some("32"));
    }

    #[test]
    fn versions() {
        for ok in ["3.0.0", "2.1.0", "3.5"] {
            assert!(load(&format!("<scene version=\"{ok}\"/>"), &[]).is_ok(), "{ok}");
        }
        for bad in ["0.6.0", "4.0.0", "x", "3..0"] {
            assert!(load(&format!("<scene version=\"{bad}\"/>"), &[]).is_err(), "{bad}");
        }
        assert!(load("<scene/>", &[]).unwrap_err().message.contains("'version'"));
    }

    #[test]
    fn positions_and_descriptions() {
        let root =
            load("<scene version=\"3.0.0\">\n  <shape type=\"obj\" id=\"a\"/>\n</scene>", &[]).unwrap();
        let shape = &root.children[0];
        assert_eq!((shape.line, shape.column), (2, 3));
        assert_eq!(shape.describe(), r#"<shape type="obj" id="a">"#);
    }

    #[test]
    fn malformed_xml_reports_its_position() {
        let e = load("<scene version=\"3.0.0\">\n<shape type=\"obj\">\n</scene>", &[]).unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.message.starts_with("malformed XML"));
    }
}

/// What a `mesh_attribute` texture being built reads from (`Document::mesh_scope`): it is bound
/// to the mesh whose BSDF holds it, so the loader says which shape that is while it builds the
/// shape's BSDF (`xml/shapes.rs`).
#[derive(Debug, Default)]
pub(crate) enum MeshScope {
    /// Not inside a shape's BSDF (an emitter's or a medium's texture): an error.
    #[default]
    Outside,
    /// A texture or BSDF declared at the top level, built only to check it.
    Declaration,
    /// The BSDF of a shape: `shape` describes it for messages (`<shape type="ply"> at line 7`).
    Shape { shape: String, mesh: Option<ScopeMesh> },
}

/// The mesh of the shape whose BSDF is being built: its attributes and what binding needs.
#[derive(Debug)]
pub(crate) struct ScopeMesh {
    /// `ply`, `obj`, ...: only PLY files carry attributes.
    pub kind: String,
    pub attributes: Vec<crate::mesh_attribute::AttributeArray>,
    pub indices: Vec<[u32; 3]>,
    pub vertex_count: usize,
}
