//! Comments in `crates/` that cite a document section (`docs/theory.md §7.3`, `§3-4`,
//! `§2, §6`) or an equation of `docs/theory.md` (`(T7)`) point at something that exists: a
//! numbered heading of that document (`## 7. ...`, `### 7.3 ...`) or an equation tag at the end
//! of a line of `docs/theory.md`. A comment that names `docs/theory.md` must also say where in
//! it (a section or an equation), on its line or the next, and so must one that names a document
//! of [`BY_SECTION`] (a section), so that no comment cites a passage by a name the document may
//! lose (a session's narrative, "issue 17, fifth part").

use haze_testkit::data::repo_root;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Documents that comments must cite by section number (`docs/performance.md §3.1`).
const BY_SECTION: &[&str] = &["performance.md"];

/// What a document offers to cite: its numbered sections and its equation tags.
#[derive(Default)]
struct Targets {
    sections: BTreeSet<String>,
    equations: BTreeSet<String>,
}

/// The numbered headings (`## 4. Joint ...` -> `4`, `### 4.1 ...` -> `4.1`) and the equation
/// tags that end a line after two spaces (`... (T7)`) of a Markdown text.
fn targets(markdown: &str) -> Targets {
    let mut t = Targets::default();
    for line in markdown.lines() {
        if let Some(rest) = line.strip_prefix('#') {
            let number: String = rest
                .trim_start_matches('#')
                .trim_start()
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            let number = number.trim_end_matches('.');
            if !number.is_empty() {
                t.sections.insert(number.to_string());
            }
        }
        let trimmed = line.trim_end();
        if let Some(open) = trimmed.rfind("  (T") {
            let tag = trimmed[open..].trim_start();
            if equation_tag(tag) == Some(tag.len()) {
                t.equations.insert(tag.to_string());
            }
        }
    }
    t
}

/// The length of the equation tag `(T<digits>)` at the start of `s`, if there is one.
fn equation_tag(s: &str) -> Option<usize> {
    let digits = s.strip_prefix("(T")?.chars().take_while(char::is_ascii_digit).count();
    (digits > 0 && s[2 + digits..].starts_with(')')).then_some(digits + 3)
}

/// The section numbers cited right after a `§` (`7.3`, or both ends of a range `3-4`).
fn section_numbers(after: &str) -> Vec<String> {
    let first: String = after.chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
    let mut out = vec![first.trim_end_matches('.').to_string()];
    if let Some(rest) = after[first.len()..].strip_prefix('-') {
        let second: String = rest.chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
        if !second.is_empty() {
            out.push(second.trim_end_matches('.').to_string());
        }
    }
    out
}

/// The last `docs/NAME.md` (or `NAME.md`) named in `text`.
fn last_document(text: &str) -> Option<String> {
    let end = text.rfind(".md")?;
    let start =
        text[..end].rfind(|c: char| !(c.is_ascii_alphanumeric() || "-_/".contains(c))).map_or(0, |i| i + 1);
    let name = &text[start..end];
    let name = name.rsplit('/').next().unwrap_or(name);
    (!name.is_empty()).then(|| format!("{name}.md"))
}

/// Every broken citation in the comments (from `//` to the end of a line) of `sources` (path,
/// text), against `docs` (file name -> its targets); `theory` is the file whose equations
/// `(Tn)` are.
fn broken_citations(
    sources: &[(PathBuf, String)],
    docs: &BTreeMap<String, Targets>,
    theory: &str,
) -> Vec<String> {
    let mut errors = Vec::new();
    for (path, text) in sources {
        let comments: Vec<(usize, &str)> =
            text.lines().enumerate().filter_map(|(i, l)| l.find("//").map(|c| (i + 1, &l[c..]))).collect();
        for (k, &(line_no, line)) in comments.iter().enumerate() {
            let at = format!("{}:{line_no}", path.display());
            // The document a `§` refers to: named before it on this line or on the comment
            // lines just above (a citation may wrap).
            let context_before = |pos: usize| -> Option<String> {
                last_document(&line[..pos]).or_else(|| {
                    comments[k.saturating_sub(3)..k]
                        .iter()
                        .rev()
                        .filter(|&&(n, _)| line_no - n <= 3)
                        .find_map(|(_, l)| last_document(l))
                })
            };
            for (pos, _) in line.match_indices('§') {
                let Some(doc) = context_before(pos) else {
                    errors.push(format!("{at}: `§` without the document it refers to"));
                    continue;
                };
                let Some(targets) = docs.get(&doc) else {
                    errors.push(format!("{at}: cites {doc}, which is not in docs/"));
                    continue;
                };
                for number in section_numbers(&line[pos + '§'.len_utf8()..]) {
                    if !targets.sections.contains(&number) {
                        errors.push(format!("{at}: {doc} has no section {number:?}"));
                    }
                }
            }
            for (pos, _) in line.match_indices("(T") {
                if let Some(len) = equation_tag(&line[pos..]) {
                    let tag = &line[pos..pos + len];
                    if !docs.get(theory).is_some_and(|t| t.equations.contains(tag)) {
                        errors.push(format!("{at}: {theory} has no equation {tag}"));
                    }
                }
            }
            let next = comments.get(k + 1).filter(|&&(n, _)| n == line_no + 1).map_or("", |(_, l)| l);
            for doc in BY_SECTION.iter().filter(|d| line.contains(*d)) {
                if !line.contains('§') && !next.contains('§') {
                    errors.push(format!("{at}: names {doc} without a section (§N)"));
                }
            }
            if line.contains(theory) {
                let says_where = |l: &str| {
                    l.contains('§') || l.match_indices("(T").any(|(p, _)| equation_tag(&l[p..]).is_some())
                };
                if !says_where(line) && !says_where(next) {
                    errors.push(format!("{at}: names {theory} without a section (§N) or equation ((TN))"));
                }
            }
        }
    }
    errors
}

fn rust_sources(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
    for entry in std::fs::read_dir(dir).expect("readable source folder") {
        let path = entry.expect("folder entry").path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "target") {
                rust_sources(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).expect("source is UTF-8");
            out.push((path.strip_prefix(repo_root()).unwrap_or(&path).to_path_buf(), text));
        }
    }
}

#[test]
fn comments_cite_sections_and_equations_that_exist() {
    let root = repo_root();
    let mut docs = BTreeMap::new();
    for entry in std::fs::read_dir(root.join("docs")).expect("docs/") {
        let path = entry.expect("docs entry").path();
        if path.extension().is_some_and(|e| e == "md") {
            let name = path.file_name().expect("file name").to_string_lossy().into_owned();
            docs.insert(name, targets(&std::fs::read_to_string(&path).expect("readable doc")));
        }
    }
    let theory = &docs["theory.md"];
    assert!(
        theory.sections.len() >= 10 && theory.equations.len() >= 20,
        "theory.md parsed: {:?}",
        theory.sections
    );
    let mut sources = Vec::new();
    rust_sources(&root.join("crates"), &mut sources);
    // This file quotes broken citations on purpose (the negative control below).
    sources.retain(|(path, _)| !path.ends_with("testkit/tests/doc_references.rs"));
    assert!(sources.len() > 50, "found {} Rust files", sources.len());
    let cited = sources.iter().filter(|(_, t)| t.contains("theory.md")).count();
    assert!(cited >= 10, "only {cited} files cite docs/theory.md");
    let errors = broken_citations(&sources, &docs, "theory.md");
    assert!(errors.is_empty(), "broken citations:\n{}", errors.join("\n"));
}

/// The check must be able to fail: each kind of broken citation is caught, good ones pass.
#[test]
fn broken_citations_are_caught() {
    let doc = "# Title\n## 1. One\n### 1.2 Sub\n## 3. Three\n\n    a = b    (T1)\nsee (T9) in text\n";
    let docs = BTreeMap::from([("theory.md".to_string(), targets(doc))]);
    let check = |src: &str| broken_citations(&[(PathBuf::from("x.rs"), src.to_string())], &docs, "theory.md");
    let good = concat!(
        "//! (`docs/theory.md` §1.2, §3; (T1))\n",
        "// docs/theory.md §1-3\n",
        "// see `docs/theory.md`\n",
        "// (T1).\n",
        "fn f() {} // (`docs/theory.md` §3)\n",
    );
    assert_eq!(check(good), Vec::<String>::new());
    assert_eq!(
        check("fn f() {} // §1 of docs/theory.md"),
        vec!["x.rs:1: `§` without the document it refers to".to_string()]
    );
    assert!(check("// docs/theory.md §1.2").is_empty());
    assert_eq!(check("// `docs/theory.md` §2").len(), 1, "missing section");
    assert_eq!(check("// `docs/theory.md` §1-2").len(), 1, "missing end of a range");
    assert_eq!(check("// docs/theory.md §1.3").len(), 1, "missing subsection");
    assert_eq!(check("// (T9) of docs/theory.md").len(), 1, "(T9) is referred to, not defined");
    assert_eq!(check("// docs/other.md §1").len(), 1, "unknown document");
    assert_eq!(check("// docs/theory.md, VPL estimator").len(), 1, "no section named");
    assert_eq!(check("let x = \"§9\"; // not a comment line").len(), 0);
    assert_eq!(
        check("// docs/performance.md, \"issue 17, fifth part\""),
        vec!["x.rs:1: names performance.md without a section (§N)".to_string()]
    );
}
