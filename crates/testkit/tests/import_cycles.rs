//! No file-level import cycles in `crates/*/src` (issue #14): a file that names an item of
//! another file of its crate by path (`crate::a::b`, `super::x`, `self::y`, in a `use` or
//! inline, brace groups included) depends on that file, and no chain of such dependencies may
//! come back to where it started. A module's declaration (`mod x;`) and a parent's relative
//! re-export of its children (`pub use child::X`) are the module tree, not imports. Inline
//! `#[cfg(test)] mod tests { ... }` blocks (at the end of a file) are left out. Negative
//! control: the check finds cycles planted in a synthetic crate.

use haze_testkit::data::repo_root;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A module path within its crate (`["xml", "params"]`; the crate root is empty).
type ModPath = Vec<String>;

/// The module path of the file `rel` (relative to `src/`, without `.rs`): `lib`, `main` and
/// `mod` name their directory's module.
fn module_of(rel: &str) -> ModPath {
    let mut parts: ModPath = rel.split('/').map(String::from).collect();
    if matches!(parts.last().map(String::as_str), Some("lib" | "main" | "mod")) {
        parts.pop();
    }
    parts
}

/// `src` without comments and without its inline test module.
fn code_of(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let mut rest = src;
    while let Some(i) = rest.find("/*") {
        out.push_str(&rest[..i]);
        rest = rest[i..].find("*/").map_or("", |j| &rest[i + j + 2..]);
    }
    out.push_str(rest);
    let mut code: String =
        out.lines().map(|l| l.split("//").next().unwrap_or_default()).collect::<Vec<_>>().join("\n");
    let mut from = 0;
    while let Some(i) = code[from..].find("#[cfg(test)]") {
        let at = from + i;
        let after = code[at + "#[cfg(test)]".len()..].trim_start();
        if after.starts_with("mod ") && after.split('{').next().is_some_and(|h| !h.contains(';')) {
            code.truncate(at);
            break;
        }
        from = at + 1;
    }
    code
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The identifiers of a path continuing at `s` (after `prefix::`): `a::b::c` gives one path, a
/// brace group `{a, b::c, d::{e, f}}` one per item. Each is given as its segments.
fn paths_at(s: &str) -> Vec<Vec<String>> {
    let s = s.trim_start();
    if let Some(inner) = s.strip_prefix('{') {
        let mut depth = 0;
        let mut items = Vec::new();
        let mut start = 0;
        for (i, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => {
                    items.push(&inner[start..i]);
                    break;
                }
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    items.push(&inner[start..i]);
                    start = i + 1;
                }
                _ => {}
            }
        }
        return items.into_iter().flat_map(paths_at).collect();
    }
    let ident: String = s.chars().take_while(|c| is_ident(*c)).collect();
    if ident.is_empty() {
        return vec![vec![]];
    }
    match s[ident.len()..].trim_start().strip_prefix("::") {
        Some(more) => {
            paths_at(more).into_iter().map(|p| std::iter::once(ident.clone()).chain(p).collect()).collect()
        }
        None => vec![vec![ident]],
    }
}

/// The files (module paths) that the file of module `m` names, among `modules`.
fn dependencies(m: &ModPath, code: &str, modules: &BTreeSet<ModPath>) -> BTreeSet<ModPath> {
    let mut out = BTreeSet::new();
    for prefix in ["crate::", "super::", "self::"] {
        for (i, _) in code.match_indices(prefix) {
            // Not the tail of another path (`super::super::x`, `a::self::b`) nor of a name.
            if code[..i].chars().next_back().is_some_and(|c| is_ident(c) || c == ':') {
                continue;
            }
            let base: ModPath = match prefix {
                "crate::" => vec![],
                "self::" => m.clone(),
                _ => m[..m.len().saturating_sub(1)].to_vec(),
            };
            for segs in paths_at(&code[i + prefix.len()..]) {
                let mut path = base.clone();
                for s in segs {
                    match s.as_str() {
                        "super" => {
                            path.pop();
                        }
                        "self" => {}
                        _ => path.push(s),
                    }
                }
                while !path.is_empty() && !modules.contains(&path) {
                    path.pop();
                }
                if modules.contains(&path) && path != *m {
                    out.insert(path);
                }
            }
        }
    }
    out
}

/// The cycles of the dependency graph of one crate's files (`(module path, source)`), each as
/// the file modules along it, joined by `::`.
fn cycles(files: &[(ModPath, String)]) -> Vec<String> {
    let modules: BTreeSet<ModPath> = files.iter().map(|(m, _)| m.clone()).collect();
    let graph: BTreeMap<&ModPath, BTreeSet<ModPath>> =
        files.iter().map(|(m, src)| (m, dependencies(m, &code_of(src), &modules))).collect();
    let name = |m: &ModPath| if m.is_empty() { "<crate root>".to_string() } else { m.join("::") };
    let mut found = Vec::new();
    // Depth-first search; a back edge to a module on the stack closes a cycle.
    let mut state: BTreeMap<&ModPath, u8> = BTreeMap::new(); // 1: on the stack, 2: done
    fn visit<'a>(
        m: &'a ModPath,
        graph: &'a BTreeMap<&'a ModPath, BTreeSet<ModPath>>,
        state: &mut BTreeMap<&'a ModPath, u8>,
        stack: &mut Vec<&'a ModPath>,
        found: &mut Vec<Vec<&'a ModPath>>,
    ) {
        state.insert(m, 1);
        stack.push(m);
        for d in &graph[m] {
            match state.get(d) {
                Some(1) => {
                    let start = stack.iter().position(|s| *s == d).unwrap();
                    found.push(stack[start..].to_vec());
                }
                Some(_) => {}
                None => visit(graph.get_key_value(d).unwrap().0, graph, state, stack, found),
            }
        }
        stack.pop();
        state.insert(m, 2);
    }
    let mut raw = Vec::new();
    for m in graph.keys() {
        if !state.contains_key(m) {
            visit(m, &graph, &mut state, &mut Vec::new(), &mut raw);
        }
    }
    for c in raw {
        let mut names: Vec<String> = c.iter().map(|m| name(m)).collect();
        names.push(names[0].clone());
        found.push(names.join(" -> "));
    }
    found
}

fn rust_files(dir: &Path, root: &Path, out: &mut Vec<(ModPath, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, root, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let rel = p.strip_prefix(root).unwrap().with_extension("");
            let rel = rel.to_string_lossy().replace('\\', "/");
            out.push((module_of(&rel), std::fs::read_to_string(&p).unwrap()));
        }
    }
}

#[test]
fn no_file_level_import_cycles() {
    let crates = repo_root().join("crates");
    let mut all = Vec::new();
    let mut names: Vec<_> = std::fs::read_dir(&crates).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    let mut checked = 0;
    for krate in names {
        let src = krate.join("src");
        if !src.is_dir() {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&src, &src, &mut files);
        checked += files.len();
        let name = krate.file_name().unwrap().to_string_lossy().into_owned();
        all.extend(cycles(&files).into_iter().map(|c| format!("crates/{name}: {c}")));
    }
    assert!(checked > 50, "only {checked} files found under {}", crates.display());
    assert!(all.is_empty(), "file-level import cycles:\n{}", all.join("\n"));
}

#[test]
fn the_check_finds_planted_cycles() {
    let file = |path: &str, src: &str| (module_of(path), src.to_string());
    // Siblings through `crate::` and `super::` with a brace group.
    let c = cycles(&[
        file("lib", "pub mod a;\npub mod b;"),
        file("a", "use crate::b::{X, Y};"),
        file("b", "use super::{a::Z, c};\npub fn f() { let _ = super::a::g(); }"),
    ]);
    assert_eq!(c, ["a -> b -> a"]);
    // An inline path three files long, through a directory module.
    let c = cycles(&[
        file("lib", ""),
        file("x/mod", "pub fn f() -> crate::y::T { todo!() }"),
        file("x/inner", "use super::super::z;"),
        file("y", "// use crate::z; (a comment)\nfn g() { self::h(); crate::x::inner::k(); }"),
        file("z", "use crate::x;"),
    ]);
    assert_eq!(c.len(), 1, "{c:?}");
    assert!(c[0].contains("x -> y -> x::inner -> z -> x"), "{c:?}");
    // Not cycles: comments, a test module's imports, the module tree itself.
    let c = cycles(&[
        file("lib", "mod a;\nmod b;\npub use a::X;"),
        file("a", "/* crate::b */ use crate::b::Y;\n#[cfg(test)]\nmod tests {\n    use crate::a::X;\n}"),
        file("b", "// crate::a\npub struct Y;\n#[cfg(test)]\nmod tests {\n    use crate::a::X;\n}"),
    ]);
    assert!(c.is_empty(), "{c:?}");
}
