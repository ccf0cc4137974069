//! Every option of a render, once: its name, default, validation, help text and the methods it
//! applies to ([`OPTIONS`]). `haze render` makes its flags from this table, `haze compare` its
//! `KEY=VALUE` method options, the Python binding its keyword arguments; [`resolve`] checks and
//! applies what a front end was given.
//!
//! Adding an option is one entry of [`OPTIONS`] (with its field in [`Options`] or
//! [`MethodOptions`]): `haze render`, `haze compare`, `python -m haze.distributed` and the
//! binding take it from there. The Python signatures (python/haze) spell the options out for
//! editors and `help()`; `python/tests/test_options.py` fails until each has the new one, and
//! `crates/cli/tests/options.rs` until the README's usage block does.
//!
//! An option given for a method it does not apply to is an error naming the option and the
//! method, never silently ignored.

use anyhow::{anyhow, bail, Result};
use haze_core::{SamplerKind, SamplerSpec};
use haze_manylight::integrators::{BoundCut, Builder, LightBudget, PathTracedMedia, StochasticCut};
use haze_manylight::tree::bound::BoundKind;
use haze_render::progressive::RenderSettings;
use haze_scene::Scene;
use std::fmt;

/// The rendering methods, each once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MethodKind {
    /// The reference volumetric path tracer.
    VolPath,
    /// Virtual ray lights, brute force.
    Vrl,
    /// Virtual point lights, brute force.
    Vpl,
    /// Virtual ray lights through a light tree and per-segment cuts.
    VrlLightcuts,
    /// Virtual point lights through a light tree and per-segment cuts.
    VplLightcuts,
}

use MethodKind::*;

impl MethodKind {
    /// Every method, in the order help texts list them.
    pub const ALL: [MethodKind; 5] = [VolPath, Vrl, Vpl, VrlLightcuts, VplLightcuts];
    /// The many-light methods.
    pub const MANY_LIGHT: &'static [MethodKind] = &[Vrl, Vpl, VrlLightcuts, VplLightcuts];
    /// The lightcut methods.
    pub const LIGHTCUTS: &'static [MethodKind] = &[VrlLightcuts, VplLightcuts];

    pub const fn name(self) -> &'static str {
        match self {
            VolPath => "volpath",
            Vrl => "vrl",
            Vpl => "vpl",
            VrlLightcuts => "vrl_lightcuts",
            VplLightcuts => "vpl_lightcuts",
        }
    }

    /// The method called `name`; `volpathmis` (Mitsuba 3's name for volpath with spectral MIS,
    /// which haze's volpath always does) is volpath. (`path`, which is volpath only for scenes
    /// without media, is resolved by `methods::method_kind`, which sees the scene.)
    pub fn from_name(name: &str) -> Option<MethodKind> {
        if name == "volpathmis" {
            return Some(VolPath);
        }
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    pub fn is_lightcuts(self) -> bool {
        Self::LIGHTCUTS.contains(&self)
    }
}

impl fmt::Display for MethodKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `volpath, vrl, vpl, vrl_lightcuts, vpl_lightcuts`: for help texts and error messages.
pub fn method_names() -> String {
    names(&MethodKind::ALL)
}

/// `methods`' names, comma-separated.
pub fn names(methods: &[MethodKind]) -> String {
    methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")
}

/// What values an option takes (and how its text is checked).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// An integer from 1 to `max`; `_` separators and the suffixes `k` (x1000) and `M`
    /// (x1000000) are accepted (`100k`).
    Count { max: u64 },
    /// Any integer from 0 to 2^64 - 1.
    Integer,
    /// A finite number >= 0.
    NonNegative,
    /// A finite number > 0.
    Positive,
    /// A finite number > 0 or one of these words.
    PositiveOr(&'static [&'static str]),
    /// A time budget in seconds: at least a millisecond (no pass could finish in less) and at
    /// most a year (a `Duration` of 1e20 s does not exist).
    Seconds,
    /// One of these words.
    Choice(&'static [&'static str]),
    /// On or off (`true`/`false`); on the command line a flag without value.
    Flag,
}

/// A checked option value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Int(u64),
    Float(f64),
    Word(&'static str),
    Flag(bool),
}

impl Value {
    fn int(self) -> u64 {
        match self {
            Value::Int(n) => n,
            other => unreachable!("{other:?} is not an integer"),
        }
    }

    fn float(self) -> f64 {
        match self {
            Value::Float(x) => x,
            other => unreachable!("{other:?} is not a number"),
        }
    }

    fn word(self) -> &'static str {
        match self {
            Value::Word(w) => w,
            other => unreachable!("{other:?} is not a word"),
        }
    }

    fn flag(self) -> bool {
        match self {
            Value::Flag(b) => b,
            other => unreachable!("{other:?} is not a flag"),
        }
    }
}

/// A count with optional `_` separators and a `k` or `M` suffix.
pub fn parse_count(s: &str) -> Option<u64> {
    let s = s.trim().replace('_', "");
    let (digits, scale) = match s.as_bytes().last()? {
        b'k' => (&s[..s.len() - 1], 1_000),
        b'M' => (&s[..s.len() - 1], 1_000_000),
        _ => (&s[..], 1),
    };
    digits.parse::<u64>().ok()?.checked_mul(scale)
}

impl Kind {
    /// The value of `text`, or what a value must be (for "NAME must be ..., got 'TEXT'").
    pub fn parse(self, text: &str) -> Result<Value, String> {
        let t = text.trim();
        // Numbers are stored in f32 by the integrators: a value beyond its range is no number.
        let number = || t.parse::<f64>().ok().filter(|x| (*x as f32).is_finite());
        match self {
            Kind::Count { max } => {
                parse_count(t).filter(|n| (1..=max).contains(n)).map(Value::Int).ok_or_else(|| match max {
                    u64::MAX => "must be a positive integer (e.g. 10000, 100k, 1M)".to_string(),
                    _ => format!("must be a positive integer up to {max}"),
                })
            }
            Kind::Integer => t.parse().map(Value::Int).map_err(|_| "must be an integer >= 0".into()),
            Kind::NonNegative => {
                number().filter(|x| *x >= 0.0).map(Value::Float).ok_or_else(|| "must be a number >= 0".into())
            }
            Kind::Positive => number()
                .filter(|x| *x > 0.0)
                .map(Value::Float)
                .ok_or_else(|| "must be a positive number".into()),
            Kind::PositiveOr(words) => match words.iter().find(|w| **w == t) {
                Some(w) => Ok(Value::Word(w)),
                None => number()
                    .filter(|x| *x > 0.0)
                    .map(Value::Float)
                    .ok_or_else(|| format!("must be a positive number or {}", one_of(words))),
            },
            Kind::Seconds => {
                const MIN: f64 = 1e-3;
                const MAX: f64 = 365.0 * 24.0 * 3600.0;
                match t.parse::<f64>().ok().filter(|x| x.is_finite() && *x > 0.0) {
                    None => Err("must be a positive number of seconds".into()),
                    Some(x) if x < MIN => {
                        Err(format!("is too small a budget: no pass would finish (give at least {MIN} s)"))
                    }
                    Some(x) if x > MAX => Err(format!("is more than a year (give at most {MAX} s)")),
                    Some(x) => Ok(Value::Float(x)),
                }
            }
            Kind::Choice(words) => words
                .iter()
                .find(|w| **w == t)
                .map(|w| Value::Word(w))
                .ok_or_else(|| format!("must be {}", one_of(words))),
            Kind::Flag => match t.to_ascii_lowercase().as_str() {
                "true" => Ok(Value::Flag(true)),
                "false" => Ok(Value::Flag(false)),
                _ => Err("must be true or false".into()),
            },
        }
    }

    /// A short name of the kind, for the Python binding's table.
    pub fn label(self) -> &'static str {
        match self {
            Kind::Count { .. } => "count",
            Kind::Integer => "integer",
            Kind::NonNegative | Kind::Positive | Kind::Seconds => "number",
            Kind::PositiveOr(_) => "number or word",
            Kind::Choice(_) => "choice",
            Kind::Flag => "flag",
        }
    }
}

/// An option's default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Default {
    /// This value (checked like a given one).
    Value(&'static str),
    /// No value; the text says what happens instead (e.g. "off").
    Unset(&'static str),
}

/// Which part of a run an option sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scope {
    /// The whole render (sample budget, seed, passes): `haze compare` sets these for every
    /// method at once.
    Render,
    /// The method: `haze compare` takes these per method (`--method vrl_lightcuts,epsilon=0.01`).
    Method,
    /// How a method's samples are grouped into passes (`spp_per_pass`): its default depends on
    /// the method, so `haze compare` takes it per method (`--method vrl_lightcuts,spp_per_pass=16`)
    /// or for every method at once (`--spp-per-pass`); not a method option of
    /// [`Options::describe`] (the render prints it with the sample budget).
    Pass,
}

/// How a front end spells option names in messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spelling {
    /// `--max-cut` (the command line).
    Flag,
    /// `max_cut` (Python keywords, `haze compare` method options).
    Keyword,
}

/// The words of a choice quoted, in an error message: `'a', 'b' or 'c'`.
fn one_of(words: &[&str]) -> String {
    let quoted: Vec<String> = words.iter().map(|w| format!("'{w}'")).collect();
    match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => quoted.concat(),
    }
}

/// One option: everything every front end needs to know about it.
pub struct OptionSpec {
    /// snake_case; the command-line flag is `--` and the name with `-` for `_`.
    pub name: &'static str,
    pub kind: Kind,
    pub default: Default,
    /// One sentence or two, without the default or the methods (see [`OptionSpec::help_text`]).
    pub help: &'static str,
    pub applies_to: &'static [MethodKind],
    /// Options that cannot be given together with this one.
    pub conflicts_with: &'static [&'static str],
    /// `(option, value)`: this option applies only when that option has that value (e.g. the
    /// bound-cut options only with `cut=bound`); otherwise it is an error naming both.
    pub requires: Option<(&'static str, &'static str)>,
    pub scope: Scope,
    /// A valid value other than the default (for the tests that feed every option to every
    /// method).
    pub example: &'static str,
    set: fn(&mut Options, Value),
    /// The value in effect, `None` when unset.
    get: fn(&Options) -> Option<String>,
}

impl fmt::Debug for OptionSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "OptionSpec({})", self.name)
    }
}

impl PartialEq for OptionSpec {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl OptionSpec {
    /// `--max-cut`.
    pub fn flag(&self) -> String {
        format!("--{}", self.name.replace('_', "-"))
    }

    /// The name as `spelling` writes it.
    pub fn spelled(&self, spelling: Spelling) -> String {
        match spelling {
            Spelling::Flag => self.flag(),
            Spelling::Keyword => self.name.to_string(),
        }
    }

    pub fn applies_to_all(&self) -> bool {
        MethodKind::ALL.iter().all(|m| self.applies_to.contains(m))
    }

    /// The help text with the methods it applies to (when not all) and the default.
    pub fn help_text(&self) -> String {
        let mut s = String::new();
        if !self.applies_to_all() {
            s += &format!("[{}] ", names(self.applies_to));
        }
        s += self.help;
        match self.default {
            Default::Value(v) => s += &format!(" Default: {v}."),
            Default::Unset(what) => s += &format!(" Default: {what}."),
        }
        s
    }

    /// `text` checked as this option's value; the error names the option as `spelling` does.
    pub fn parse(&self, text: &str, spelling: Spelling) -> Result<Value> {
        self.kind
            .parse(text)
            .map_err(|what| anyhow!("{} {what}, got '{}'", self.spelled(spelling), text.trim()))
    }

    /// The value in effect in `options`, as text (`None`: unset).
    pub fn value_in(&self, options: &Options) -> Option<String> {
        (self.get)(options)
    }
}

/// The error for an option given to a method it does not apply to (`what`: the option as the
/// front end spells it).
pub fn not_applicable(what: &str, method: MethodKind, applies_to: &[MethodKind]) -> anyhow::Error {
    anyhow!("{what} does not apply to {method} (only to {})", names(applies_to))
}

const ALL: &[MethodKind] = &MethodKind::ALL;

/// Every option, in the order help texts list them.
pub const OPTIONS: &[OptionSpec] = &[
    OptionSpec {
        name: "spp",
        kind: Kind::Count { max: u32::MAX as u64 },
        default: Default::Unset("the scene's sampler sample_count"),
        help: "Samples per pixel.",
        applies_to: ALL,
        conflicts_with: &["time"],
        requires: None,
        scope: Scope::Render,
        example: "2",
        set: |o, v| o.spp = Some(v.int() as u32),
        get: |o| o.spp.map(|n| n.to_string()),
    },
    OptionSpec {
        name: "time",
        kind: Kind::Seconds,
        default: Default::Unset("off (render spp samples)"),
        help: "Render for this many seconds instead of a sample count (whole passes: the last pass \
               started in time is finished).",
        applies_to: ALL,
        conflicts_with: &["spp"],
        requires: None,
        scope: Scope::Render,
        example: "0.2",
        set: |o, v| o.time = Some(v.float()),
        get: |o| o.time.map(|t| t.to_string()),
    },
    OptionSpec {
        name: "seed",
        kind: Kind::Integer,
        default: Default::Value("0"),
        help: "Seed of every random choice; the same seed gives the same image, whatever the \
               number of threads.",
        applies_to: ALL,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Render,
        example: "7",
        set: |o, v| o.seed = v.int(),
        get: |o| Some(o.seed.to_string()),
    },
    OptionSpec {
        name: "spp_per_pass",
        kind: Kind::Count { max: u32::MAX as u64 },
        default: Default::Unset(
            "auto: for vrl_lightcuts and vpl_lightcuts about 262144 camera samples per pass, \
             clamp(round(262144 / (width * height)), 1, 64): 16 at 128x128, where 16 beat 4 \
             and 1 at equal time (docs/lightcuts.md \"Choosing the defaults\"), and 1 at \
             640x360 and above; with an spp budget the largest divisor of spp up to that, so \
             passes are equal; 1 for the other methods (brute-force vrl and vpl cost per \
             sample grows with the light count, volpath batches passes)",
        ),
        help: "Samples per pixel in each progressive pass; the many-light methods trace one light \
               set per pass (and the lightcut methods build one tree) for all of them.",
        applies_to: ALL,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Pass,
        example: "2",
        set: |o, v| o.spp_per_pass = Some(v.int() as u32),
        get: |o| o.spp_per_pass.map(|n| n.to_string()),
    },
    OptionSpec {
        name: "components",
        kind: Kind::Flag,
        default: Default::Value("false"),
        help: "Also keep the components emitted, single, multiple and surface (they sum to the \
               image).",
        applies_to: ALL,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Render,
        example: "true",
        set: |o, v| o.components = v.flag(),
        get: |o| Some(o.components.to_string()),
    },
    OptionSpec {
        name: "vrls",
        kind: Kind::Count { max: u64::MAX },
        default: Default::Value("10000"),
        help: "Trace about this many virtual ray lights per pass (the light-path count is fixed \
               from a pilot run).",
        applies_to: MethodKind::MANY_LIGHT,
        conflicts_with: &["light_paths"],
        requires: None,
        scope: Scope::Method,
        example: "300",
        set: |o, v| o.method.budget = LightBudget::Vrls(v.int()),
        get: |o| match o.method.budget {
            LightBudget::Vrls(n) => Some(n.to_string()),
            LightBudget::Paths(_) => None,
        },
    },
    OptionSpec {
        name: "light_paths",
        kind: Kind::Count { max: u64::MAX },
        default: Default::Unset("set by vrls"),
        help: "Trace exactly this many light paths per pass (instead of vrls).",
        applies_to: MethodKind::MANY_LIGHT,
        conflicts_with: &["vrls"],
        requires: None,
        scope: Scope::Method,
        example: "40",
        set: |o, v| o.method.budget = LightBudget::Paths(v.int()),
        get: |o| match o.method.budget {
            LightBudget::Paths(n) => Some(n.to_string()),
            LightBudget::Vrls(_) => None,
        },
    },
    OptionSpec {
        name: "caustic_paths",
        kind: Kind::Integer,
        default: Default::Unset(
            "auto: one per pixel (of 0.25, 1 and 4 per pixel at 320x240, 1 gave the least \
             variance per time on glass-beam; docs/lightcuts.md \"Caustics seen directly\")",
        ),
        help: "Caustic paths per pass: light paths aimed at the glass (delta) surfaces and \
               connected to the camera, which render the caustics the camera sees directly \
               (light through glass into the haze or onto a wall); 0 leaves them to the camera \
               path, which cannot find those of point and spot lights (docs/theory.md 2.1).",
        applies_to: MethodKind::MANY_LIGHT,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Method,
        example: "20000",
        set: |o, v| o.method.caustic_paths = Some(v.int()),
        get: |o| o.method.caustic_paths.map(|n| n.to_string()),
    },
    OptionSpec {
        name: "vpl_clamp",
        kind: Kind::Positive,
        default: Default::Unset("off"),
        help: "Clamp the geometry term 1/w^2 at this value (biased).",
        applies_to: &[Vpl],
        conflicts_with: &[],
        requires: None,
        scope: Scope::Method,
        example: "10",
        set: |o, v| o.method.vpl_clamp = Some(v.float() as f32),
        get: |o| o.method.vpl_clamp.map(|c| c.to_string()),
    },
    OptionSpec {
        name: "clamp",
        kind: Kind::Positive,
        default: Default::Unset("off (unbiased)"),
        help: "Clamp the 1/d^2 of the connections to surface points and from surface VPLs at this \
               value: fewer fireflies near corners, a biased preview (docs/theory.md 2.1).",
        applies_to: &[Vrl, Vpl],
        conflicts_with: &["compensated_clamp"],
        requires: None,
        scope: Scope::Method,
        example: "10",
        set: |o, v| o.method.clamp = Some(v.float() as f32),
        get: |o| o.method.clamp.map(|c| c.to_string()),
    },
    OptionSpec {
        name: "compensated_clamp",
        kind: Kind::PositiveOr(&["auto", "off"]),
        default: Default::Value("auto"),
        help: "Clamp the 1/d^2 of surface VPL -> surface point connections at this value and \
               recover the clamped part with a BSDF-sampled path from the point (Kollig & Keller \
               2004): unbiased, fewer fireflies near corners, at the cost of a second gather \
               where surfaces are closer than 1/sqrt(value) (docs/theory.md 2.1). 'auto': \
               (6/R)^2, R the radius of the scene's bounding sphere (off where `clamp` is given); \
               'off': unclamped.",
        applies_to: MethodKind::MANY_LIGHT,
        conflicts_with: &["clamp"],
        requires: None,
        scope: Scope::Method,
        example: "25",
        set: |o, v| {
            o.method.compensated_clamp = match v {
                Value::Word("auto") => CompensatedClamp::Auto,
                Value::Word(_) => CompensatedClamp::Off,
                v => CompensatedClamp::At(v.float() as f32),
            }
        },
        get: |o| Some(o.method.compensated_clamp.to_string()),
    },
    OptionSpec {
        name: "path_traced_media",
        kind: Kind::Choice(&["heterogeneous", "all", "none"]),
        default: Default::Value("heterogeneous"),
        help: "Media in which the camera path is traced as volpath traces it (free flight, \
               next-event estimation, phase sampling) instead of gathering the virtual lights: \
               heterogeneous (where volpath won on every measured scene), all (every scattering \
               medium: the virtual lights then light surfaces only), or none (gather in every \
               medium). The virtual lights are traced in every medium either way \
               (docs/theory.md 2.1, \"Path-traced media\").",
        applies_to: MethodKind::MANY_LIGHT,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Method,
        example: "none",
        set: |o, v| {
            o.method.path_traced_media = match v.word() {
                "all" => PathTracedMedia::All,
                "none" => PathTracedMedia::None,
                _ => PathTracedMedia::Heterogeneous,
            }
        },
        get: |o| {
            Some(
                match o.method.path_traced_media {
                    PathTracedMedia::Heterogeneous => "heterogeneous",
                    PathTracedMedia::All => "all",
                    PathTracedMedia::None => "none",
                }
                .into(),
            )
        },
    },
    OptionSpec {
        name: "cut",
        kind: Kind::Choice(&["stochastic", "bound"]),
        default: Default::Value("stochastic"),
        help: "How each camera segment's cut is chosen: stochastic (bound-free: a cut of cut_size \
               nodes by importance, one light sampled in each; unbiased, a fixed cost per segment) \
               or bound (the paper's deterministic cut by upper bounds, with epsilon, max_cut and \
               bound; docs/lightcuts.md).",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Method,
        example: "bound",
        set: |o, v| {
            o.method.lightcuts.cut = if v.word() == "bound" { TreeCut::Bound } else { TreeCut::Stochastic }
        },
        get: |o| {
            Some(
                match o.method.lightcuts.cut {
                    TreeCut::Stochastic => "stochastic",
                    TreeCut::Bound => "bound",
                }
                .into(),
            )
        },
    },
    OptionSpec {
        name: "cut_size",
        kind: Kind::Count { max: 1 << 20 },
        default: Default::Value("1"),
        help: "Nodes in the stochastic cut: lights sampled per camera segment (the default is \
               measured: docs/lightcuts.md).",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: Some(("cut", "stochastic")),
        scope: Scope::Method,
        example: "2",
        set: |o, v| o.method.lightcuts.stochastic.settings.cut_size = v.int() as u32,
        get: |o| Some(o.method.lightcuts.stochastic.settings.cut_size.to_string()),
    },
    OptionSpec {
        name: "light_samples",
        kind: Kind::Count { max: 64 },
        default: Default::Value("1"),
        help: "Joint samples of each light the stochastic cut samples, averaged: pays in dense, \
               anisotropic media, where the joint sampling's own variance dominates (hg-box: 4), \
               not elsewhere (docs/lightcuts.md).",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: Some(("cut", "stochastic")),
        scope: Scope::Method,
        example: "4",
        set: |o, v| o.method.lightcuts.stochastic.settings.light_samples = v.int() as u32,
        get: |o| Some(o.method.lightcuts.stochastic.settings.light_samples.to_string()),
    },
    OptionSpec {
        name: "epsilon",
        kind: Kind::NonNegative,
        default: Default::Value("0.02"),
        help: "Refine a cut until every node's bound is at most epsilon times the cut's estimate \
               (largest RGB channel of each).",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: Some(("cut", "bound")),
        scope: Scope::Method,
        example: "0.05",
        set: |o, v| o.method.lightcuts.bound.cut.epsilon = v.float() as f32,
        get: |o| Some(o.method.lightcuts.bound.cut.epsilon.to_string()),
    },
    OptionSpec {
        name: "max_cut",
        kind: Kind::Count { max: u32::MAX as u64 },
        default: Default::Value("1000"),
        help: "Most nodes in a cut.",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: Some(("cut", "bound")),
        scope: Scope::Method,
        example: "50",
        set: |o, v| o.method.lightcuts.bound.cut.max_cut = v.int() as u32,
        get: |o| Some(o.method.lightcuts.bound.cut.max_cut.to_string()),
    },
    OptionSpec {
        name: "bound",
        kind: Kind::Choice(&["paper", "conservative", "tight"]),
        default: Default::Value("paper"),
        help: "Cluster bound: paper (Vibert et al. 2019), conservative, or tight (conservative, \
               with the VRL integral bounded through the VRLs' directions; docs/lightcuts.md).",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: Some(("cut", "bound")),
        scope: Scope::Method,
        example: "tight",
        set: |o, v| {
            o.method.lightcuts.bound.bound = match v.word() {
                "paper" => BoundKind::Paper,
                "conservative" => BoundKind::Conservative,
                _ => BoundKind::Tight,
            }
        },
        get: |o| {
            Some(
                match o.method.lightcuts.bound.bound {
                    BoundKind::Paper => "paper",
                    BoundKind::Conservative => "conservative",
                    BoundKind::Tight => "tight",
                }
                .into(),
            )
        },
    },
    OptionSpec {
        name: "builder",
        kind: Kind::Choice(&["agglomerative", "median"]),
        default: Default::Value("agglomerative"),
        help: "Light-tree builder: agglomerative (the paper's 3-step parallel build) or median \
               (median split).",
        applies_to: MethodKind::LIGHTCUTS,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Method,
        example: "median",
        set: |o, v| {
            let builder = if v.word() == "median" { Builder::MedianSplit } else { Builder::Agglomerative };
            o.method.lightcuts.stochastic.tree.builder = builder;
            o.method.lightcuts.bound.tree.builder = builder;
        },
        get: |o| {
            Some(
                match o.method.lightcuts.stochastic.tree.builder {
                    Builder::Agglomerative => "agglomerative",
                    Builder::MedianSplit => "median",
                }
                .into(),
            )
        },
    },
    OptionSpec {
        name: "sampler",
        kind: Kind::Choice(&SamplerKind::NAMES),
        default: Default::Unset("the scene's <sampler> type"),
        help: "Sample generator (Mitsuba 3's samplers), replacing the type of the scene's \
               <sampler>; the sample count is still --spp or the scene's sample_count, rounded \
               as Mitsuba 3 rounds it for the generator (stratified: up to a square; \
               multijitter: to ceil(n / floor(sqrt n)) * floor(sqrt n); orthogonal: to the \
               square of a prime; ldsampler: to a square power of two).",
        applies_to: ALL,
        conflicts_with: &[],
        requires: None,
        scope: Scope::Method,
        example: "ldsampler",
        set: |o, v| o.method.sampler = SamplerKind::from_name(v.word()),
        get: |o| o.method.sampler.map(|k| k.name().to_string()),
    },
];

/// The option called `name` (snake_case).
pub fn find(name: &str) -> Option<&'static OptionSpec> {
    OPTIONS.iter().find(|o| o.name == name)
}

/// The `cut` option: which tree cut the lightcut methods make.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TreeCut {
    /// [`StochasticCut`].
    #[default]
    Stochastic,
    /// [`BoundCut`].
    Bound,
}

/// The lightcut methods' options: the cut `cut` names, with both cuts' settings (each option
/// sets the cut it belongs to; `builder` both).
#[derive(Clone, Copy, Debug, Default)]
pub struct LightcutOptions {
    pub cut: TreeCut,
    /// `cut_size`, `light_samples`, `builder`.
    pub stochastic: StochasticCut,
    /// `epsilon`, `max_cut`, `bound`, `builder`.
    pub bound: BoundCut,
}

/// Options of the many-light methods (volpath has none). Front ends make them with
/// [`resolve`], which owns their defaults and checks.
#[derive(Clone, Debug)]
pub struct MethodOptions {
    pub budget: LightBudget,
    /// vpl only: clamp of the geometry term (biased).
    pub vpl_clamp: Option<f32>,
    /// vrl and vpl: clamp of the `1/d^2` of surface connections (biased).
    pub clamp: Option<f32>,
    /// Every many-light method: clamp of surface VPL -> surface point connections, the clamped
    /// part recovered by a compensation walk (unbiased).
    pub compensated_clamp: CompensatedClamp,
    pub lightcuts: LightcutOptions,
    /// Caustic paths per pass (`None`: one per pixel; 0: the camera continuation instead).
    pub caustic_paths: Option<u64>,
    /// The media the camera walk path-traces instead of gathering in.
    pub path_traced_media: PathTracedMedia,
    /// The sample generator's type (`None`: the scene's `<sampler>`'s).
    pub sampler: Option<SamplerKind>,
}

impl MethodOptions {
    /// The sample generator of a render of `scene`: the scene's `<sampler>`, of type
    /// [`MethodOptions::sampler`] when given (with that type's default parameters if it
    /// differs), for `spp` samples (default: the scene's) rounded as Mitsuba 3 rounds them for
    /// the type. A time-budget render repeats rounds of this many samples.
    pub fn sampler_for(&self, scene: &Scene, spp: Option<u32>) -> SamplerSpec {
        let spec = match self.sampler {
            Some(kind) => scene.sampler.with_kind(kind),
            None => scene.sampler,
        };
        spec.with_sample_count(spp.unwrap_or(scene.spp))
    }
}

/// The `compensated_clamp` option: where the `1/d^2` of surface VPL -> surface point
/// connections is clamped, the clamped part recovered by the compensation walk
/// (`haze_manylight::gather`, docs/theory.md §2.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CompensatedClamp {
    /// Relative to the scene's size ([`haze_manylight::integrators::scene_compensated_clamp`]),
    /// off where the biased `clamp` is given (the two clamp the same connections).
    Auto,
    Off,
    /// At this `c` (`1/d^2` clamped below the distance `1/sqrt(c)`, in scene units).
    At(f32),
}

impl CompensatedClamp {
    /// The clamp `c` for a render of `scene` whose biased clamp is `clamp` (`None`: off).
    pub fn for_scene(self, scene: &Scene, clamp: Option<f32>) -> Option<f32> {
        match self {
            CompensatedClamp::Auto if clamp.is_none() => {
                Some(haze_manylight::integrators::scene_compensated_clamp(scene))
            }
            CompensatedClamp::At(c) => Some(c),
            CompensatedClamp::Auto | CompensatedClamp::Off => None,
        }
    }
}

impl fmt::Display for CompensatedClamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CompensatedClamp::Auto => f.write_str("auto"),
            CompensatedClamp::Off => f.write_str("off"),
            CompensatedClamp::At(c) => write!(f, "{c}"),
        }
    }
}

/// What every pass of a range shares (`crate::passes`).
#[derive(Clone, Copy, Debug)]
pub struct PassSettings {
    pub seed: u64,
    /// Samples per pixel in each pass (at least 1).
    pub spp_per_pass: u32,
    /// Keep the component split (emitted, single, multiple, surface).
    pub components: bool,
    /// The sample generator ([`Options::sampler_for`]).
    pub sampler: SamplerSpec,
}

/// Every setting of a render, as resolved from the table.
#[derive(Clone, Debug)]
pub struct Options {
    pub spp: Option<u32>,
    pub time: Option<f64>,
    pub seed: u64,
    /// `None`: auto, the method's default for the image size ([`auto_spp_per_pass`]).
    pub spp_per_pass: Option<u32>,
    pub components: bool,
    pub method: MethodOptions,
}

/// Camera samples per pass the lightcut methods aim at when `spp_per_pass` is auto. Measured at
/// 128x128 only (docs/lightcuts.md "Choosing the defaults"): 16 spp per pass (262,144 samples
/// sharing a pass's light set and tree) beat 4 and 1 at equal time, because tracing the lights
/// and building the tree is a fixed cost per pass that more samples amortise. Other sizes keep
/// the samples per pass, not the spp (an extrapolation, not measured): at 640x360 one sample
/// per pixel is already 230,400 samples, and more spp per pass would only coarsen the time
/// budget's granularity.
pub const LIGHTCUT_SAMPLES_PER_PASS: u64 = 262_144;

/// Most spp per pass auto picks (tiny images): a pass stays short enough for `--time`, Ctrl-C
/// and the progress bar, which act at pass ends.
pub const AUTO_SPP_PER_PASS_MAX: u32 = 64;

/// The rule behind `spp_per_pass`'s auto default, for every front end: for the lightcut
/// methods `clamp(round(LIGHTCUT_SAMPLES_PER_PASS / (width * height)), 1,
/// AUTO_SPP_PER_PASS_MAX)` (16 at 128x128, 1 at 640x360); 1 for the others, since brute-force
/// `vrl`/`vpl` cost per camera sample is proportional to the light count (nothing to amortise:
/// a 16-spp pass of 10k VRLs takes minutes) and volpath batches its passes anyway
/// (`passes_batchable`).
pub fn auto_spp_per_pass(method: MethodKind, width: u32, height: u32) -> u32 {
    if !method.is_lightcuts() {
        return 1;
    }
    let pixels = (width as u64 * height as u64).max(1);
    let spp = (LIGHTCUT_SAMPLES_PER_PASS as f64 / pixels as f64).round();
    spp.clamp(1.0, AUTO_SPP_PER_PASS_MAX as f64) as u32
}

impl Options {
    /// Every option at its default.
    pub fn defaults() -> Options {
        let mut o = Options {
            spp: None,
            time: None,
            seed: 0,
            spp_per_pass: None,
            components: false,
            // Placeholders: the table's defaults below set every field an option owns.
            method: MethodOptions {
                budget: LightBudget::Vrls(1),
                vpl_clamp: None,
                clamp: None,
                compensated_clamp: CompensatedClamp::Off,
                lightcuts: LightcutOptions::default(),
                caustic_paths: None,
                path_traced_media: PathTracedMedia::None,
                sampler: None,
            },
        };
        for spec in OPTIONS {
            if let Default::Value(text) = spec.default {
                let v = spec.kind.parse(text).unwrap_or_else(|e| panic!("default of {}: {e}", spec.name));
                (spec.set)(&mut o, v);
            }
        }
        o
    }

    /// The spp per pass of a render of `scene` with `method`: the given value, else auto:
    /// [`auto_spp_per_pass`] for the camera's image size, and with a sample budget (`spp`, default
    /// the scene's; not with `time`) the largest divisor of it not above that, so that the
    /// budget is whole passes of equal size (what a distributed render, `spp / spp_per_pass`
    /// passes, needs; 2 spp at 128x128 are one pass of 2). Every front end asks this.
    pub fn spp_per_pass_for(&self, method: MethodKind, scene: &Scene) -> u32 {
        if let Some(n) = self.spp_per_pass {
            return n;
        }
        let auto = auto_spp_per_pass(method, scene.camera.width, scene.camera.height);
        match (self.time, self.sampler_for(scene).sample_count()) {
            (None, spp) if spp > 0 => (1..=auto).rev().find(|d| spp % d == 0).unwrap_or(1),
            _ => auto,
        }
    }

    /// The sample generator of a render of `scene` ([`MethodOptions::sampler_for`] with `spp`).
    pub fn sampler_for(&self, scene: &Scene) -> SamplerSpec {
        self.method.sampler_for(scene, self.spp)
    }

    /// The progressive render's settings for `method`: `spp` samples (default: the scene's;
    /// rounded for the sampler, [`Options::sampler_for`]) or `time` seconds, in passes of
    /// [`Options::spp_per_pass_for`] samples.
    pub fn render_settings(&self, method: MethodKind, scene: &Scene) -> RenderSettings {
        let sampler = self.sampler_for(scene);
        RenderSettings {
            spp: if self.time.is_some() { 0 } else { sampler.sample_count() },
            time_limit: self.time.map(std::time::Duration::from_secs_f64),
            seed: self.seed,
            spp_per_pass: self.spp_per_pass_for(method, scene),
            components: self.components,
            first_pass: 0,
            sampler,
        }
    }

    /// The settings of `passes::render_passes` (which renders a pass range: no `spp` or `time`).
    pub fn pass_settings(&self, method: MethodKind, scene: &Scene) -> PassSettings {
        PassSettings {
            seed: self.seed,
            spp_per_pass: self.spp_per_pass_for(method, scene),
            components: self.components,
            sampler: self.sampler_for(scene),
        }
    }

    /// The method options in effect for `method`, e.g. `vrls=10000 epsilon=0.02 max_cut=1000
    /// bound=paper builder=agglomerative` (empty for volpath): what `haze render` prints.
    pub fn describe(&self, method: MethodKind) -> String {
        OPTIONS
            .iter()
            .filter(|s| s.scope == Scope::Method && s.applies_to.contains(&method))
            .filter(|s| {
                s.requires.is_none_or(|(name, want)| {
                    find(name).and_then(|o| o.value_in(self)).is_some_and(|have| have == want)
                })
            })
            .filter_map(|s| Some(format!("{}={}", s.name, (s.get)(self)?)))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// The options of a render with `method`: the table's defaults, then `given` (name, text) pairs
/// (snake_case names) applied in order. Unknown options, options that do not apply to `method`,
/// conflicting or repeated options and bad values are errors naming the option as `spelling`
/// writes it.
pub fn resolve(method: MethodKind, given: &[(&str, &str)], spelling: Spelling) -> Result<Options> {
    let mut options = Options::defaults();
    let mut seen: Vec<&OptionSpec> = Vec::new();
    for &(name, text) in given {
        let Some(spec) = find(name) else {
            let known: Vec<String> = OPTIONS.iter().map(|o| o.spelled(spelling)).collect();
            let shown = match spelling {
                Spelling::Flag => format!("--{}", name.replace('_', "-")),
                Spelling::Keyword => name.to_string(),
            };
            bail!("unknown option '{shown}' (available: {})", known.join(", "));
        };
        if seen.contains(&spec) {
            bail!("{} is given twice", spec.spelled(spelling));
        }
        if !spec.applies_to.contains(&method) {
            return Err(not_applicable(&spec.spelled(spelling), method, spec.applies_to));
        }
        if let Some(other) = seen.iter().find(|s| spec.conflicts_with.contains(&s.name)) {
            bail!("give either {} or {}, not both", other.spelled(spelling), spec.spelled(spelling));
        }
        let value = spec.parse(text, spelling)?;
        (spec.set)(&mut options, value);
        seen.push(spec);
    }
    for spec in &seen {
        if let Some((name, want)) = spec.requires {
            let other = find(name).expect("a requirement names an option of the table");
            let have = other.value_in(&options).unwrap_or_default();
            if have != want {
                bail!(
                    "{} does not apply to {method} with {} {have} (only with {} {want})",
                    spec.spelled(spelling),
                    other.spelled(spelling),
                    other.spelled(spelling)
                );
            }
        }
    }
    Ok(options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_manylight::tree::cut::CutSettings;

    /// `given` resolved for `method`, with the requirements (`cut=bound`, ...) of the given
    /// options added where `given` does not set them.
    fn ok(method: MethodKind, given: &[(&str, &str)]) -> Options {
        let mut all: Vec<(&str, &str)> = Vec::new();
        for (name, _) in given {
            if let Some(req) = find(name).and_then(|s| s.requires) {
                if !given.iter().any(|g| g.0 == req.0) && !all.contains(&req) {
                    all.push(req);
                }
            }
        }
        all.extend_from_slice(given);
        resolve(method, &all, Spelling::Keyword).unwrap_or_else(|e| panic!("{all:?}: {e}"))
    }

    /// The bound-cut options need `cut=bound`, `cut_size` needs the stochastic cut: otherwise
    /// an error naming the option, the method and the cut.
    #[test]
    fn cut_options_need_their_cut() {
        for (given, want) in [
            (
                vec![("epsilon", "0.1")],
                "epsilon does not apply to vrl_lightcuts with cut stochastic (only with cut bound)",
            ),
            (vec![("max_cut", "5")], "max_cut does not apply to vrl_lightcuts with cut stochastic"),
            (vec![("bound", "tight")], "bound does not apply to vrl_lightcuts with cut stochastic"),
            (
                vec![("cut", "bound"), ("cut_size", "4")],
                "cut_size does not apply to vrl_lightcuts with cut bound",
            ),
        ] {
            assert!(err(VrlLightcuts, &given, Spelling::Keyword).contains(want), "{given:?}");
        }
        let o = resolve(VplLightcuts, &[("cut_size", "3")], Spelling::Keyword).unwrap();
        assert_eq!(o.method.lightcuts.stochastic.settings.cut_size, 3);
        assert_eq!(
            o.describe(VplLightcuts),
            "vrls=10000 compensated_clamp=auto path_traced_media=heterogeneous cut=stochastic cut_size=3 light_samples=1 \
             builder=agglomerative"
        );
    }

    fn err(method: MethodKind, given: &[(&str, &str)], spelling: Spelling) -> String {
        match resolve(method, given, spelling) {
            Ok(_) => panic!("{given:?} with {method} should fail"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn the_table_is_consistent() {
        for (i, spec) in OPTIONS.iter().enumerate() {
            assert!(spec.name.chars().all(|c| c.is_ascii_lowercase() || c == '_'), "{}", spec.name);
            assert!(OPTIONS[..i].iter().all(|o| o.name != spec.name), "{} twice", spec.name);
            assert!(!spec.applies_to.is_empty(), "{}", spec.name);
            if spec.scope != Scope::Method {
                assert!(spec.applies_to_all(), "{} sets the whole render", spec.name);
            }
            for c in spec.conflicts_with {
                let other = find(c).unwrap_or_else(|| panic!("{} conflicts with unknown {c}", spec.name));
                assert!(other.conflicts_with.contains(&spec.name), "{c} / {}: not symmetric", spec.name);
            }
            if let Default::Value(d) = spec.default {
                assert!(spec.kind.parse(d).is_ok(), "default of {}", spec.name);
                assert_ne!(spec.kind.parse(spec.example), spec.kind.parse(d), "example of {}", spec.name);
            }
            let example = spec.kind.parse(spec.example).unwrap_or_else(|e| panic!("{}: {e}", spec.name));
            // The example reaches the options: `get` shows it back.
            let method = spec.applies_to[0];
            let o = ok(method, &[(spec.name, spec.example)]);
            let shown = spec.value_in(&o).unwrap_or_else(|| panic!("{} unset", spec.name));
            assert_eq!(spec.kind.parse(&shown), Ok(example), "{}", spec.name);
        }
    }

    #[test]
    fn defaults_are_the_integrators_own() {
        let o = Options::defaults();
        assert_eq!(o.method.budget, LightBudget::Vrls(10_000));
        let (stochastic, bound) = (StochasticCut::default(), BoundCut::default());
        let CutSettings { epsilon, max_cut } = bound.cut;
        let lc = &o.method.lightcuts;
        assert_eq!((lc.bound.cut.epsilon, lc.bound.cut.max_cut), (epsilon, max_cut));
        assert_eq!((lc.bound.bound, lc.bound.tree.builder), (bound.bound, bound.tree.builder));
        assert_eq!(lc.stochastic.tree.builder, stochastic.tree.builder);
        assert_eq!((o.spp, o.time, o.seed, o.spp_per_pass, o.components), (None, None, 0, None, false));
        assert_eq!(o.method.vpl_clamp, None);
        assert_eq!((lc.cut, lc.stochastic.settings), (TreeCut::Stochastic, stochastic.settings));
        // Giving a default explicitly changes nothing (beside the option's requirement).
        for spec in OPTIONS {
            if let Default::Value(d) = spec.default {
                let given = ok(spec.applies_to[0], &[(spec.name, d)]);
                let base = match spec.requires {
                    Some(req) => ok(spec.applies_to[0], &[req]),
                    None => o.clone(),
                };
                assert_eq!(format!("{given:?}"), format!("{base:?}"), "{}", spec.name);
            }
        }
    }

    #[test]
    fn values_are_checked() {
        let o =
            ok(VrlLightcuts, &[("vrls", "100k"), ("epsilon", "0.1"), ("max_cut", "7"), ("bound", "tight")]);
        assert_eq!(o.method.budget, LightBudget::Vrls(100_000));
        assert_eq!((o.method.lightcuts.bound.cut.epsilon, o.method.lightcuts.bound.cut.max_cut), (0.1, 7));
        assert_eq!(o.method.lightcuts.bound.bound, BoundKind::Tight);
        // Every word of a choice is a value of its own.
        for spec in OPTIONS {
            if let Kind::Choice(words) = spec.kind {
                let shown: Vec<_> = words
                    .iter()
                    .map(|w| spec.value_in(&ok(spec.applies_to[0], &[(spec.name, w)])).unwrap())
                    .collect();
                assert_eq!(shown, *words, "{}", spec.name);
            }
        }
        assert_eq!(ok(Vpl, &[("light_paths", "7")]).method.budget, LightBudget::Paths(7));
        let flag = Spelling::Flag;
        for (given, want) in [
            (vec![("max_cut", "0")], "--max-cut must be a positive integer up to 4294967295, got '0'"),
            (vec![("epsilon", "nan")], "--epsilon must be a number >= 0, got 'nan'"),
            (vec![("epsilon", "-1")], "--epsilon must be a number >= 0, got '-1'"),
            (vec![("epsilon", "1e39")], "--epsilon must be a number >= 0"),
            (vec![("bound", "foo")], "--bound must be 'paper', 'conservative' or 'tight', got 'foo'"),
            (vec![("builder", "sah")], "--builder must be 'agglomerative' or 'median', got 'sah'"),
            (vec![("vrls", "0")], "--vrls must be a positive integer"),
            (vec![("vrls", "1"), ("light_paths", "2")], "give either --vrls or --light-paths, not both"),
            (vec![("epsilon", "1"), ("epsilon", "2")], "--epsilon is given twice"),
            (vec![("alpha", "1")], "unknown option '--alpha'"),
        ] {
            let e = err(VrlLightcuts, &given, flag);
            assert!(e.contains(want), "{given:?}: {e}");
        }
        assert!(err(Vrl, &[("spp", "1"), ("time", "1")], flag).contains("give either --spp or --time"));
        assert!(err(Vrl, &[("time", "inf")], flag).contains("--time must be a positive number"));
        assert!(err(Vrl, &[("components", "maybe")], Spelling::Keyword).contains("components must be true"));
    }

    #[test]
    fn options_of_other_methods_are_errors_naming_both() {
        for spec in OPTIONS {
            for method in MethodKind::ALL {
                let mut given: Vec<(&str, &str)> =
                    spec.requires.into_iter().filter(|_| spec.applies_to.contains(&method)).collect();
                given.push((spec.name, spec.example));
                let r = resolve(method, &given, Spelling::Flag);
                let default_meets = |(name, want): (&str, &'static str)| {
                    find(name).is_some_and(move |o| o.default == Default::Value(want))
                };
                if spec.applies_to.contains(&method) && spec.requires.is_some_and(|r| !default_meets(r)) {
                    // Without its requirement the option is an error naming it and the method.
                    let e = resolve(method, &given[1..], Spelling::Flag).err().map(|e| e.to_string());
                    let named =
                        e.as_deref().is_some_and(|e| e.contains(&spec.flag()) && e.contains(method.name()));
                    assert!(named, "{} with {method} but not {:?}: {e:?}", spec.name, spec.requires);
                }
                if spec.applies_to.contains(&method) {
                    assert!(r.is_ok(), "{} with {method}: {:?}", spec.name, r.err());
                } else {
                    let e = r.err().unwrap().to_string();
                    assert!(e.contains(&spec.flag()) && e.contains(method.name()), "{e}");
                }
            }
        }
        let e = err(VplLightcuts, &[("vpl_clamp", "1")], Spelling::Keyword);
        assert_eq!(e, "vpl_clamp does not apply to vpl_lightcuts (only to vpl)");
    }

    #[test]
    fn describe_shows_the_method_options_in_effect() {
        assert_eq!(Options::defaults().describe(VolPath), "");
        assert_eq!(
            Options::defaults().describe(Vpl),
            "vrls=10000 compensated_clamp=auto path_traced_media=heterogeneous"
        );
        assert_eq!(
            ok(VrlLightcuts, &[("light_paths", "5"), ("max_cut", "9")]).describe(VrlLightcuts),
            "light_paths=5 compensated_clamp=auto path_traced_media=heterogeneous cut=bound epsilon=0.02 max_cut=9 bound=paper \
             builder=agglomerative"
        );
    }

    /// `compensated_clamp`: `auto` by default, `(6/R)^2` for the scene's bounding radius `R`
    /// (the same image for a scene scaled by any factor), off where the biased `clamp` is
    /// given; `off` and a value as given; other words refused with what the option takes.
    #[test]
    fn compensated_clamp_is_scene_relative_by_default() {
        let (small, large) = (box_scene(1.0), box_scene(1000.0));
        let r = small.bounding_sphere().radius;
        let c = |given: &[(&str, &str)], scene: &Scene| {
            let o = resolve(Vrl, given, Spelling::Keyword).unwrap();
            o.method.compensated_clamp.for_scene(scene, o.method.clamp)
        };
        let auto = c(&[], &small).expect("on by default");
        let divisor = haze_manylight::integrators::COMPENSATED_CLAMP_DIVISOR;
        assert!((auto - divisor * divisor / (r * r)).abs() <= 1e-5 * auto, "{auto} for R {r}");
        // The help text states the rule with the divisor the code uses.
        let help = OPTIONS.iter().find(|o| o.name == "compensated_clamp").unwrap().help;
        assert!(help.contains(&format!("({divisor}/R)^2")), "{help}");
        let scaled = c(&[], &large).unwrap();
        assert!((scaled * 1e6 / auto - 1.0).abs() < 1e-4, "{scaled} is not {auto} / 1000^2");
        assert_eq!(c(&[("compensated_clamp", "auto")], &small), Some(auto));
        assert_eq!(c(&[("compensated_clamp", "off")], &small), None);
        assert_eq!(c(&[("compensated_clamp", "2.5")], &large), Some(2.5));
        assert_eq!(c(&[("clamp", "10")], &small), None);
        for bad in ["0", "-1", "nan", "on", "Auto"] {
            assert_eq!(
                err(Vrl, &[("compensated_clamp", bad)], Spelling::Flag),
                format!("--compensated-clamp must be a positive number or 'auto' or 'off', got '{bad}'")
            );
        }
    }

    /// A scene whose geometry is a cube of half-size `size` (bounding radius `size * sqrt 3`).
    fn box_scene(size: f32) -> Scene {
        let xml = format!(
            r#"<scene version="3.0.0"><sensor type="perspective"/>
               <shape type="cube"><transform name="to_world"><scale value="{size}"/></transform></shape>
               </scene>"#
        );
        let p = std::path::Path::new("t.xml");
        haze_scene::load_str(&xml, p, std::path::Path::new("."), &haze_scene::LoadOptions::default()).unwrap()
    }

    /// A scene rendering `width` x `height` pixels.
    fn scene(width: u32, height: u32) -> Scene {
        let xml = format!(
            r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
               <integer name="width" value="{width}"/><integer name="height" value="{height}"/>
               </film></sensor></scene>"#
        );
        let p = std::path::Path::new("t.xml");
        haze_scene::load_str(&xml, p, std::path::Path::new("."), &haze_scene::LoadOptions::default()).unwrap()
    }

    /// Auto spp per pass: about 262,144 camera samples per pass for the lightcut methods, 1 for
    /// the others; a given value wins, for every method and size.
    #[test]
    fn spp_per_pass_is_auto_per_method_and_image_size() {
        let (small, wide) = (scene(128, 128), scene(640, 360));
        let auto = ok(Vrl, &[("spp", "1024")]);
        let timed = ok(Vrl, &[("time", "1")]);
        for m in MethodKind::ALL {
            assert_eq!(timed.spp_per_pass_for(m, &small), if m.is_lightcuts() { 16 } else { 1 });
            let want = if m.is_lightcuts() { 16 } else { 1 };
            assert_eq!(auto.spp_per_pass_for(m, &small), want, "{m} at 128x128");
            assert_eq!(auto.spp_per_pass_for(m, &wide), 1, "{m} at 640x360");
            assert_eq!(auto.render_settings(m, &small).spp_per_pass, want, "{m}");
            assert_eq!(auto.pass_settings(m, &small).spp_per_pass, want, "{m}");
            let given = ok(m, &[("spp_per_pass", "3")]);
            assert_eq!((given.spp_per_pass_for(m, &small), given.spp_per_pass_for(m, &wide)), (3, 3));
            assert_eq!(given.render_settings(m, &small).spp_per_pass, 3);
        }
        // A sample budget is whole passes: the largest divisor of spp up to the rule's value
        // (the scene's spp, Mitsuba's default 4, without a given one).
        for (spp, want) in [("100", 10), ("2", 2), ("17", 1), ("48", 16)] {
            assert_eq!(ok(Vrl, &[("spp", spp)]).spp_per_pass_for(VrlLightcuts, &small), want, "{spp}");
        }
        assert_eq!(Options::defaults().spp_per_pass_for(VplLightcuts, &small), small.spp.min(16));
        // Rounded, then clamped to 1 ..= 64.
        assert_eq!(auto_spp_per_pass(VplLightcuts, 256, 128), 8);
        assert_eq!(auto_spp_per_pass(VrlLightcuts, 100, 100), 26);
        assert_eq!(auto_spp_per_pass(VrlLightcuts, 32, 24), 64);
        assert_eq!(auto_spp_per_pass(VrlLightcuts, 1920, 1080), 1);
        assert_eq!(auto_spp_per_pass(Vrl, 1, 1), 1);
        // Explicit values are still checked.
        assert!(
            err(VrlLightcuts, &[("spp_per_pass", "0")], Spelling::Flag).contains("--spp-per-pass must be")
        );
    }

    /// `--sampler` replaces the scene's sampler type for every method; the sample count is the
    /// given spp or the scene's, rounded for the type (render and pass settings alike); an
    /// unknown name lists the valid ones.
    #[test]
    fn sampler_overrides_the_scenes_and_rounds_the_spp() {
        let small = scene(16, 16);
        assert_eq!(small.sampler.kind, SamplerKind::Independent);
        for m in MethodKind::ALL {
            let o = ok(m, &[("sampler", "stratified"), ("spp", "10")]);
            let r = o.render_settings(m, &small);
            assert_eq!(
                (r.sampler.kind, r.sampler.sample_count(), r.spp),
                (SamplerKind::Stratified, 16, 16),
                "{m}"
            );
            assert_eq!(o.pass_settings(m, &small).sampler, r.sampler);
            assert_eq!(
                o.describe(m).split(' ').find(|w| w.starts_with("sampler=")),
                Some("sampler=stratified")
            );
            // Without spp: the scene's 4 rounded (ldsampler: 4, orthogonal: 4).
            let o = ok(m, &[("sampler", "ldsampler")]);
            assert_eq!(o.render_settings(m, &small).spp, 4);
            // A time budget renders rounds of the scene's count.
            let o = ok(m, &[("sampler", "multijitter"), ("time", "1")]);
            assert_eq!((o.render_settings(m, &small).spp, o.sampler_for(&small).sample_count()), (0, 4));
            assert_eq!(Options::defaults().render_settings(m, &small).sampler, SamplerSpec::independent(4));
        }
        let e = err(VolPath, &[("sampler", "sobol")], Spelling::Flag);
        assert!(
            e.contains("--sampler must be 'independent', 'stratified', 'multijitter', 'orthogonal' or 'ldsampler', got 'sobol'"),
            "{e}"
        );
    }

    #[test]
    fn method_names_are_listed_once() {
        assert_eq!(method_names(), "volpath, vrl, vpl, vrl_lightcuts, vpl_lightcuts");
        for m in MethodKind::ALL {
            assert_eq!(MethodKind::from_name(m.name()), Some(m));
        }
        assert_eq!(MethodKind::from_name("volpathmis"), Some(VolPath));
        assert_eq!(MethodKind::from_name("bdpt"), None);
    }
}
