//! The options of `haze` against the engine's table (`haze_engine::options::OPTIONS`): every
//! option on `haze render --help` is the table's or listed here as the command line's own;
//! every option fed to every method is either used or rejected with a message naming both; bad
//! values are clear errors; the README's usage block names exactly the options of `--help`.

use haze_engine::options::{Scope, OPTIONS};
use haze_engine::MethodKind;
use std::collections::BTreeSet;
use std::process::Output;

mod common;

use common::{haze, repo, s, stderr, tmp};

/// Options of `haze render` that are not the engine's: where and how to write, threads, the
/// method itself, scene parameters. They apply to every method. `--cut-image` is the one
/// output that needs a lightcut method (tested below like the table's options).
const RENDER_OWN: &[&str] = &["output", "threads", "integrator", "variance-out", "exposure", "quiet", "help"];

fn help(command: &str) -> String {
    let o = haze(&[command, "--help"]);
    assert!(o.status.success(), "{command} --help: {}", stderr(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The long names (without `--`) and short letters of the options in a `--help` text.
fn help_options(text: &str) -> Vec<(String, Option<char>)> {
    let mut out = Vec::new();
    for line in text.lines() {
        let t = line.trim_start();
        if !t.starts_with('-') || line.len() - t.len() < 2 {
            continue;
        }
        let head = t.split("  ").next().unwrap_or_default();
        let mut long = None;
        let mut short = None;
        for word in head.split([',', ' ']).filter(|w| !w.is_empty()) {
            if let Some(l) = word.strip_prefix("--") {
                long = Some(l.to_string());
            } else if let Some(s) = word.strip_prefix('-') {
                if s.len() == 1 {
                    short = s.chars().next();
                }
            }
        }
        if long.is_some() || short.is_some() {
            out.push((long.unwrap_or_else(|| short.unwrap().to_string()), short));
        }
    }
    out
}

/// A render of the smoke room at 8x8 pixels and 1 spp with `method` and `extra` arguments.
/// Many-light methods trace 30 light paths (unless `extra` sets the light budget) to stay fast.
fn render(method: MethodKind, extra: &[&str]) -> Output {
    let scene = repo("scenes/bench-smoke-room.xml");
    let out = tmp(&format!("{method}.exr"));
    let mut args =
        vec!["render", s(&scene), "-o", s(&out), "-D", "res=8", "-D", "res_y=8", "-D", "spp=1", "--quiet"];
    args.extend(["--integrator", method.name()]);
    let budget_given = extra.iter().any(|a| *a == "--vrls" || *a == "--light-paths");
    if method != MethodKind::VolPath && !budget_given {
        args.extend(["--light-paths", "30"]);
    }
    args.extend(extra);
    haze(&args)
}

#[test]
fn every_render_option_is_the_engines_or_listed() {
    let table: BTreeSet<String> = OPTIONS.iter().map(|o| o.flag()[2..].to_string()).collect();
    for (long, _) in help_options(&help("render")) {
        let own = RENDER_OWN.contains(&long.as_str()) || long == "cut-image" || long == "D";
        assert!(
            table.contains(&long) || own,
            "--{long} is neither in the engine's table nor one of haze render's own options"
        );
    }
    let shown: BTreeSet<String> = help_options(&help("render")).into_iter().map(|(l, _)| l).collect();
    for flag in &table {
        assert!(shown.contains(flag), "--{flag} of the engine's table is not a haze render option");
    }
    // The --integrator help lists every method, from the engine's one list.
    let text = help("render");
    let integrator = text.split("--integrator").nth(1).unwrap().split("\n  -").next().unwrap();
    for m in MethodKind::ALL {
        assert!(integrator.contains(m.name()), "--integrator help lacks {m}: {integrator}");
    }
}

#[test]
fn every_option_with_every_method_is_used_or_rejected_naming_both() {
    for spec in OPTIONS {
        let flag = spec.flag();
        for method in MethodKind::ALL {
            // An option that needs another's value (`--epsilon` needs `--cut bound`) gets it.
            let requirement = spec.requires.filter(|_| spec.applies_to.contains(&method));
            let req_flag = requirement.map(|(name, _)| format!("--{}", name.replace('_', "-")));
            let mut extra: Vec<&str> = Vec::new();
            if let (Some(f), Some((_, value))) = (&req_flag, requirement) {
                extra.extend([f.as_str(), value]);
            }
            extra.push(flag.as_str());
            if spec.kind != haze_engine::options::Kind::Flag {
                extra.push(spec.example);
            }
            let o = render(method, &extra);
            let err = stderr(&o);
            let context = format!("{flag} {} with {method}", spec.example);
            if spec.applies_to.contains(&method) {
                assert!(o.status.success(), "{context}: failed\n{err}");
                if spec.scope == Scope::Method {
                    // The options in effect, as the engine resolved them, show the value.
                    let line = err.lines().find(|l| l.starts_with(&format!("{method}: "))).unwrap_or("");
                    let want = format!("{}={}", spec.name, spec.example);
                    assert!(line.split(' ').any(|w| w == want), "{context}: `{want}` not in use: {err}");
                }
                if spec.name == "spp" {
                    assert!(err.contains(&format!("at {} spp", spec.example)), "{context}: {err}");
                }
            } else {
                assert_eq!(o.status.code(), Some(1), "{context}: accepted\n{err}");
                assert!(err.contains(&flag) && err.contains(method.name()), "{context}: {err}");
                assert!(err.contains("does not apply to"), "{context}: {err}");
            }
        }
    }
    // --cut-image, the command line's one method-specific output.
    for method in MethodKind::ALL {
        let map = tmp(&format!("cuts-{method}.png"));
        let o = render(method, &["--cut-image", map.to_str().unwrap()]);
        if method.is_lightcuts() {
            assert!(o.status.success() && map.exists(), "--cut-image with {method}: {}", stderr(&o));
        } else {
            let err = stderr(&o);
            assert!(
                !o.status.success() && err.contains("--cut-image") && err.contains(method.name()),
                "{err}"
            );
        }
    }
}

/// `haze render` says when it picked spp per pass itself, and renders in passes of that many
/// samples: the engine's auto rule gives 64 (its clamp) for the lightcut methods at 8x8 pixels,
/// 1 for the others; a given value is used as given, without the line.
#[test]
fn render_prints_and_uses_the_auto_spp_per_pass() {
    for (method, spp_per_pass) in
        [(MethodKind::VrlLightcuts, 64), (MethodKind::VplLightcuts, 64), (MethodKind::Vrl, 1)]
    {
        let o = render(method, &["--spp", "128"]);
        let err = stderr(&o);
        assert!(o.status.success(), "{method}: {err}");
        let want = format!("{method}: spp per pass {spp_per_pass} (auto; --spp-per-pass sets it)");
        assert!(err.lines().any(|l| l == want), "`{want}` not in\n{err}");
        let passes = format!("({} passes,", 128 / spp_per_pass);
        assert!(err.contains("at 128 spp in") && err.contains(&passes), "{method}: {err}");
        let o = render(method, &["--spp", "128", "--spp-per-pass", "32"]);
        let err = stderr(&o);
        assert!(o.status.success() && !err.contains("(auto"), "{method}: {err}");
        assert!(err.contains("(4 passes,"), "{method}: {err}");
    }
    // `--help` gives the rule and where it comes from.
    let text = help("render");
    let spp_per_pass = text.split("--spp-per-pass").nth(1).unwrap().split("\n  -").next().unwrap();
    let flat = spp_per_pass.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(flat.contains("Default: auto: for vrl_lightcuts and vpl_lightcuts"), "{flat}");
    assert!(flat.contains("clamp(round(262144 / (width * height)), 1, 64)"), "{flat}");
    assert!(flat.contains("docs/lightcuts.md"), "{flat}");
}

#[test]
fn bad_values_are_clear_errors() {
    let lc = MethodKind::VrlLightcuts;
    for (extra, want) in [
        (vec!["--max-cut", "0"], "--max-cut must be a positive integer"),
        (vec!["--epsilon", "nan"], "--epsilon must be a number >= 0, got 'nan'"),
        (vec!["--bound", "foo"], "--bound must be 'paper', 'conservative' or 'tight', got 'foo'"),
        (vec!["--builder", "sah"], "--builder must be 'agglomerative' or 'median', got 'sah'"),
        (vec!["--vrls", "0"], "--vrls must be a positive integer"),
        (vec!["--vrls", "10", "--light-paths", "10"], "give either --vrls or --light-paths, not both"),
        (vec!["--spp", "1", "--time", "1"], "give either --spp or --time, not both"),
        (vec!["--spp-per-pass", "0"], "--spp-per-pass must be a positive integer"),
    ] {
        let o = render(lc, &extra);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(want), "{extra:?}: {err}");
    }
    let scene = repo("scenes/bench-smoke-room.xml");
    let s = scene.to_str().unwrap();
    for (args, want) in [
        (vec!["bench", s, "--spp", "0"], "--spp must be a positive integer"),
        (vec!["bench", s, "--integrator", "vrl", "--vrls", "0"], "--vrls must be a positive integer"),
        (vec!["bench", s, "--integrator", "volpath", "--vrls", "5"], "--vrls does not apply to volpath"),
        (vec!["bench", s, "--integrator", "lightcuts"], "cargo bench -p haze-lab"),
        (
            vec!["reference", s, "-o", "/nonexistent/x.exr", "--time", "nan"],
            "--time must be a positive number",
        ),
    ] {
        let o = haze(&args);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains(want), "{args:?}: {err}");
    }
}

/// The `haze SUBCOMMAND` lines of the README's "Using it" block, each with its continuation
/// lines, comments removed.
fn readme_usage() -> Vec<(String, String)> {
    let readme = std::fs::read_to_string(repo("README.md")).unwrap();
    let block = readme.split("## Using it").nth(1).expect("README has a 'Using it' section");
    let code = block.split("```sh").nth(1).unwrap().split("```").next().unwrap();
    let mut out: Vec<(String, String)> = Vec::new();
    for line in code.lines() {
        let line = line.split('#').next().unwrap_or_default();
        if let Some(rest) = line.strip_prefix("haze ") {
            let command = rest.split_whitespace().next().unwrap().to_string();
            out.push((command, rest.to_string()));
        } else if let Some(last) = out.last_mut() {
            last.1 += line;
        }
    }
    out
}

#[test]
fn readme_usage_names_exactly_the_options_of_help() {
    let usage = readme_usage();
    let commands: Vec<&str> = usage.iter().map(|(c, _)| c.as_str()).collect();
    assert_eq!(commands, ["render", "reference", "compare", "bench"]);
    for (command, text) in &usage {
        let words: BTreeSet<String> = text
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .filter(|w| {
                w.starts_with('-') && w.len() > 1 && !w[1..].starts_with(|c: char| c.is_ascii_digit())
            })
            .map(String::from)
            .collect();
        let options = help_options(&help(command));
        let mut known = BTreeSet::new();
        for (long, short) in &options {
            if long == "help" {
                continue;
            }
            let names: Vec<String> = [Some(format!("--{long}")), short.map(|s| format!("-{s}"))]
                .into_iter()
                .flatten()
                .filter(|n| n != "--D")
                .collect();
            assert!(
                names.iter().any(|n| words.contains(n)),
                "README's `haze {command}` usage lacks {} (from `haze {command} --help`)",
                names.join(" / ")
            );
            known.extend(names);
        }
        for w in &words {
            assert!(
                known.contains(w),
                "README's `haze {command}` usage has {w}, which `haze {command} --help` lacks"
            );
        }
    }
}

/// A value the README's `haze render` usage writes out for an option of the engine's table is
/// that option's default (`[--cut-size 1]`), and the first choice of a list (`[--cut
/// stochastic|bound]`) is the default when it has one; placeholders are capitals (`[--spp N]`).
#[test]
fn readme_usage_values_are_the_defaults() {
    use haze_engine::options::{find, Default};
    let usage = readme_usage();
    let render = &usage.iter().find(|(c, _)| c == "render").expect("render usage").1;
    let words: Vec<&str> = render.split_whitespace().map(|w| w.trim_matches(['[', ']'])).collect();
    let mut checked = 0;
    for pair in words.windows(2) {
        let (Some(flag), value) = (pair[0].strip_prefix("--"), pair[1]) else { continue };
        let Some(spec) = find(&flag.replace('-', "_")) else { continue };
        if value.starts_with('-') || value.chars().all(|c| c.is_ascii_uppercase()) {
            continue;
        }
        let shown = value.split('|').next().unwrap();
        match spec.default {
            Default::Value(d) => assert_eq!(
                shown, d,
                "README's `haze render` usage shows --{flag} {value}; the default is {d}"
            ),
            Default::Unset(_) if value.contains('|') => {}
            Default::Unset(what) => {
                panic!("README's `haze render` usage shows --{flag} {value}; it has no default ({what})")
            }
        }
        checked += 1;
    }
    assert!(checked >= 6, "only {checked} values checked in the render usage: {render}");
}

/// docs/python.md's `Scene.render(...)` signature names every option of the engine's table, in
/// the table's order (the Python signatures are checked against the table by
/// `python/tests/test_options.py`; this keeps the document with them).
#[test]
fn python_doc_signature_names_every_option() {
    let doc = std::fs::read_to_string(repo("docs/python.md")).unwrap();
    let start = doc.find("`Scene.render(").expect("docs/python.md has the Scene.render signature");
    let sig = &doc[start..start + doc[start..].find(")`").expect("signature ends")];
    let named: Vec<&str> = sig
        .split(['(', ','])
        .skip(1)
        .map(|p| p.split('=').next().unwrap().trim())
        .filter(|n| !n.is_empty() && *n != "*" && *n != "integrator")
        .collect();
    let table: Vec<&str> = OPTIONS.iter().map(|o| o.name).collect();
    assert_eq!(named, table, "docs/python.md's Scene.render signature against the engine's table");
}
