//! A plugin element's parameters and nested objects, read by type, with Mitsuba 3's "unused
//! parameter" check.
//!
//! A plugin reads what it needs through the typed getters ([`Params::float`],
//! [`Params::spectrum`], ...) and the nested objects it takes ([`Params::objects`]); then
//! [`Params::finish`] turns whatever was not read into an error, as Mitsuba 3 does for
//! unreferenced properties. Values are checked where they are read, and errors point at the
//! parameter's element.

use super::document::{Document, Element};
use super::plugins;
use super::transform;
use super::values::{parse_float, tokens, vector3};
use super::LoadError;
use glam::{Mat4, Vec3};
use haze_core::color::{spectrum_to_linear_srgb, SpectrumKind};
use haze_core::Rgb;
use std::cell::Cell;
use std::collections::HashMap;

/// Every element with an `id`, for `<ref id=".."/>`.
pub(super) type Ids<'a> = HashMap<&'a str, &'a Element>;

/// Tags of typed parameters.
pub(super) const VALUE_TAGS: &[&str] =
    &["float", "integer", "boolean", "string", "rgb", "spectrum", "point", "vector", "transform"];

/// Mitsuba 3 plugin kinds haze has no plugin of at all.
const UNSUPPORTED_KINDS: &[&str] = &["texture"];

/// A typed parameter, e.g. `<float name="radius" value="2"/>`.
struct Prop<'a> {
    el: &'a Element,
    name: &'a str,
    used: Cell<bool>,
}

/// A nested object (`<bsdf ..>` inside a shape) or a reference to one (`<ref id=".."/>`).
pub(super) struct Object<'a> {
    /// The element in this plugin: the nested object itself or the `<ref>`.
    pub site: &'a Element,
    /// The object's definition (for a `<ref>`, the element with that `id`).
    pub target: &'a Element,
    /// The `name` attribute at the site, e.g. `interior`.
    pub name: Option<&'a str>,
    used: Cell<bool>,
}

/// The parameters of one plugin element.
pub(super) struct Params<'a> {
    el: &'a Element,
    ty: &'a str,
    allowed: &'static [&'static str],
    ids: &'a Ids<'a>,
    doc: &'a Document,
    props: Vec<Prop<'a>>,
    objects: Vec<Object<'a>>,
}

impl<'a> Params<'a> {
    /// Collects the parameters of plugin element `el`; its tag is the plugin kind. Fails for
    /// unsupported types, unknown tags, malformed parameter elements, duplicate parameters and
    /// dangling references.
    pub fn new(el: &'a Element, ids: &'a Ids<'a>, doc: &'a Document) -> Result<Self, LoadError> {
        let kind = el.tag.as_str();
        el.check_attrs(&["type", "id", "name"])?;
        let ty = el.required_attr("type")?;
        let allowed = plugins::parameters(kind, ty).ok_or_else(|| {
            el.error(format!("unsupported {kind} type '{ty}' (supported: {})", plugins::types_of(kind)))
        })?;
        let mut params = Params { el, ty, allowed, ids, doc, props: Vec::new(), objects: Vec::new() };
        for child in &el.children {
            params.add_child(child)?;
        }
        Ok(params)
    }

    fn add_child(&mut self, child: &'a Element) -> Result<(), LoadError> {
        let tag = child.tag.as_str();
        if VALUE_TAGS.contains(&tag) {
            check_value_attrs(child)?;
            let name = child.required_attr("name")?;
            if let Some(first) = self.props.iter().find(|p| p.name == name) {
                return Err(
                    child.error(format!("parameter '{name}' is already given at line {}", first.el.line))
                );
            }
            self.props.push(Prop { el: child, name, used: Cell::new(false) });
        } else if tag == "ref" {
            child.check_attrs(&["id", "name"])?;
            let id = child.required_attr("id")?;
            let target = self
                .ids
                .get(id)
                .ok_or_else(|| child.error(format!("dangling reference: no object has id '{id}'")))?;
            self.push_object(child, target);
        } else if plugins::is_supported_kind(tag) {
            self.push_object(child, child);
        } else if UNSUPPORTED_KINDS.contains(&tag) {
            return Err(child.error(format!("unsupported: haze has no <{tag}> plugins")));
        } else {
            return Err(child.error(format!("unknown element <{tag}>")));
        }
        Ok(())
    }

    fn push_object(&mut self, site: &'a Element, target: &'a Element) {
        self.objects.push(Object { site, target, name: site.attr("name"), used: Cell::new(false) });
    }

    /// The plugin element.
    pub fn element(&self) -> &'a Element {
        self.el
    }

    /// The plugin type, e.g. `sphere`.
    pub fn ty(&self) -> &'a str {
        self.ty
    }

    /// Parameters of a nested object or referenced definition `el`.
    pub fn nested(&self, el: &'a Element) -> Result<Params<'a>, LoadError> {
        Params::new(el, self.ids, self.doc)
    }

    /// The document the plugin is in (file lookup, objects shared between references).
    pub fn doc(&self) -> &'a Document {
        self.doc
    }

    /// The parameter element called `name`, marked as read.
    pub fn raw(&self, name: &str) -> Option<&'a Element> {
        debug_assert!(
            self.allowed.contains(&name),
            "{} reads '{name}', which the plugin table does not list",
            self.el.describe()
        );
        let prop = self.props.iter().find(|p| p.name == name)?;
        prop.used.set(true);
        Some(prop.el)
    }

    /// An error about parameter `name`: at its element if given, else at the plugin.
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> LoadError {
        match self.props.iter().find(|p| p.name == name) {
            Some(p) => p.el.error(message),
            None => self.el.error(message),
        }
    }

    pub fn float_opt(&self, name: &str) -> Result<Option<f32>, LoadError> {
        self.raw(name).map(|el| float_value(el, name)).transpose()
    }

    /// A `<float>` (or `<integer>`) parameter; must be finite.
    pub fn float(&self, name: &str, default: f32) -> Result<f32, LoadError> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    /// An `<integer>` parameter.
    pub fn int(&self, name: &str, default: i32) -> Result<i32, LoadError> {
        let Some(el) = self.raw(name) else {
            return Ok(default);
        };
        expect_tag(el, name, &["integer"])?;
        let v = el.required_attr("value")?;
        v.trim().parse().map_err(|_| el.error(format!("cannot parse '{v}' as an integer")))
    }

    /// A `<boolean>` parameter (`true` or `false`, any case, as in Mitsuba 3).
    pub fn bool(&self, name: &str, default: bool) -> Result<bool, LoadError> {
        let Some(el) = self.raw(name) else {
            return Ok(default);
        };
        expect_tag(el, name, &["boolean"])?;
        let v = el.required_attr("value")?;
        match v.trim().to_ascii_lowercase().as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(el.error(format!("cannot parse '{v}' as a boolean (true or false)"))),
        }
    }

    /// A `<string>` parameter.
    pub fn string_opt(&self, name: &str) -> Result<Option<&'a str>, LoadError> {
        let Some(el) = self.raw(name) else {
            return Ok(None);
        };
        expect_tag(el, name, &["string"])?;
        el.required_attr("value").map(Some)
    }

    /// A spectrum-valued parameter: `<rgb>`, a constant `<spectrum>` or, as Mitsuba 3
    /// accepts, a `<float>`/`<integer>` (grey).
    ///
    /// A `<spectrum>` of wavelength:value pairs is converted as Mitsuba 3's RGB variants do
    /// ([`haze_core::color::spectrum_to_linear_srgb`]): as emission inside an `<emitter>`, as
    /// an unbounded quantity inside a `<medium>`, as a reflectance elsewhere.
    pub fn spectrum_opt(&self, name: &str) -> Result<Option<Rgb>, LoadError> {
        let kind = match self.el.tag.as_str() {
            "emitter" => SpectrumKind::Emission,
            "medium" | "volume" => SpectrumKind::Unbounded,
            _ => SpectrumKind::Reflectance,
        };
        self.spectrum_opt_as(name, kind)
    }

    /// [`Self::spectrum_opt`] converting a wavelength list as `kind`, for the parameters that
    /// are not reflectances although their plugin is a BSDF (a conductor's `eta` and `k`, which
    /// Mitsuba 3 does not clamp to [0, 1]).
    pub fn spectrum_opt_as(&self, name: &str, kind: SpectrumKind) -> Result<Option<Rgb>, LoadError> {
        self.raw(name).map(|el| spectrum_value(el, name, kind)).transpose()
    }

    pub fn spectrum(&self, name: &str, default: Rgb) -> Result<Rgb, LoadError> {
        Ok(self.spectrum_opt(name)?.unwrap_or(default))
    }

    /// A `<point>` (or `<vector>`) parameter.
    pub fn point_opt(&self, name: &str) -> Result<Option<Vec3>, LoadError> {
        let Some(el) = self.raw(name) else {
            return Ok(None);
        };
        expect_tag(el, name, &["point", "vector"])?;
        if let Some(v) = el.attr("value") {
            if ["x", "y", "z"].iter().any(|k| el.attr(k).is_some()) {
                return Err(el.error("give either 'value' or 'x', 'y', 'z', not both"));
            }
            return vector3(el, v).map(Some);
        }
        let mut p = Vec3::ZERO;
        for (i, k) in ["x", "y", "z"].iter().enumerate() {
            if let Some(v) = el.attr(k) {
                p[i] = parse_float(v).map_err(|m| el.error(format!("in '{k}': {m}")))?;
                if !p[i].is_finite() {
                    return Err(el.error(format!("'{k}' must be a finite number, got '{v}'")));
                }
            }
        }
        Ok(Some(p))
    }

    /// A `<transform>` parameter.
    pub fn transform_opt(&self, name: &str) -> Result<Option<Mat4>, LoadError> {
        let Some(el) = self.raw(name) else {
            return Ok(None);
        };
        expect_tag(el, name, &["transform"])?;
        transform::parse(el).map(Some)
    }

    /// The nested objects and references whose definition is one of `tags`, marked as read.
    pub fn objects(&self, tags: &[&str]) -> Vec<&Object<'a>> {
        self.objects
            .iter()
            .filter(|o| tags.contains(&o.target.tag.as_str()))
            .inspect(|o| o.used.set(true))
            .collect()
    }

    /// Fails on the first parameter or nested object the plugin did not read.
    pub fn finish(&self) -> Result<(), LoadError> {
        if let Some(p) = self.props.iter().find(|p| !p.used.get()) {
            let takes =
                if self.allowed.is_empty() { "no parameters".to_string() } else { self.allowed.join(", ") };
            return Err(p.el.error(format!(
                "unused parameter '{}': {} takes {takes}",
                p.name,
                self.el.describe()
            )));
        }
        if let Some(o) = self.objects.iter().find(|o| !o.used.get()) {
            let what = if o.site.tag == "ref" {
                format!("a reference to a <{}>", o.target.tag)
            } else {
                format!("a nested <{}>", o.target.tag)
            };
            return Err(o.site.error(format!("{} does not take {what}", self.el.describe())));
        }
        Ok(())
    }
}

/// Allowed attributes of each typed-parameter element.
fn check_value_attrs(el: &Element) -> Result<(), LoadError> {
    match el.tag.as_str() {
        "transform" => el.check_attrs(&["name"]),
        "point" | "vector" => el.check_attrs(&["name", "value", "x", "y", "z"]),
        "spectrum" => el.check_attrs(&["name", "value", "filename"]),
        _ => el.check_attrs(&["name", "value"]),
    }?;
    if el.tag != "transform" {
        if let Some(child) = el.children.first() {
            return Err(child.error(format!("<{}> takes no children", el.tag)));
        }
    }
    Ok(())
}

fn expect_tag(el: &Element, name: &str, tags: &[&str]) -> Result<(), LoadError> {
    if tags.contains(&el.tag.as_str()) {
        return Ok(());
    }
    let expected: Vec<String> = tags.iter().map(|t| format!("<{t}>")).collect();
    Err(el.error(format!(
        "wrong type for parameter '{name}': expected {}, got <{}>",
        expected.join(" or "),
        el.tag
    )))
}

fn float_value(el: &Element, name: &str) -> Result<f32, LoadError> {
    expect_tag(el, name, &["float", "integer"])?;
    let v = el.required_attr("value")?;
    if el.tag == "integer" {
        // As Mitsuba 3: an <integer> holds an integer, not any number.
        let i: i64 = v.trim().parse().map_err(|_| el.error(format!("cannot parse '{v}' as an integer")))?;
        return Ok(i as f32);
    }
    let x = parse_float(v).map_err(|m| el.error(m))?;
    finite(el, name, x)
}

fn finite(el: &Element, name: &str, x: f32) -> Result<f32, LoadError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(el.error(format!("'{name}' must be a finite number, got {x}")))
    }
}

fn spectrum_value(el: &Element, name: &str, kind: SpectrumKind) -> Result<Rgb, LoadError> {
    expect_tag(el, name, &["rgb", "spectrum", "float", "integer"])?;
    let rgb = match el.tag.as_str() {
        "rgb" => {
            let v = el.required_attr("value")?;
            let t = tokens(v);
            let c = t
                .iter()
                .map(|s| parse_float(s))
                .collect::<Result<Vec<f32>, String>>()
                .map_err(|m| el.error(m))?;
            match c[..] {
                [g] => Rgb::splat(g),
                [r, g, b] => Rgb::new(r, g, b),
                _ => return Err(el.error(format!("expected 1 or 3 values in '{v}', got {}", c.len()))),
            }
        }
        "spectrum" => {
            if el.attr("filename").is_some() {
                return Err(el.error(
                    "unsupported: spectra from files (use <rgb> or a constant <spectrum value=\"..\">)",
                ));
            }
            let v = el.required_attr("value")?;
            match tokens(v)[..] {
                [one] if !one.contains(':') => Rgb::splat(parse_float(one).map_err(|m| el.error(m))?),
                _ => wavelength_list(el, v, kind)?,
            }
        }
        _ => Rgb::splat(float_value(el, name)?),
    };
    for c in rgb.0 {
        finite(el, name, c)?;
    }
    Ok(rgb)
}

/// A `<spectrum value="400:0.1, 500:0.3, ...">` converted to linear sRGB. Wavelengths in nm,
/// strictly increasing, at least two pairs; values finite.
fn wavelength_list(el: &Element, v: &str, kind: SpectrumKind) -> Result<Rgb, LoadError> {
    let mut wavelengths = Vec::new();
    let mut values = Vec::new();
    for pair in tokens(v) {
        let Some((w, x)) = pair.split_once(':') else {
            return Err(el.error(format!("expected wavelength:value pairs in '{v}', got '{pair}'")));
        };
        let w = parse_float(w).map_err(|m| el.error(m))?;
        let x = parse_float(x).map_err(|m| el.error(m))?;
        if !w.is_finite() || !x.is_finite() {
            return Err(el.error(format!("non-finite number in '{pair}'")));
        }
        if wavelengths.last().is_some_and(|&last| w <= last) {
            return Err(el.error(format!(
                "wavelengths must increase strictly, got '{pair}' after {}",
                wavelengths.last().unwrap_or(&0.0)
            )));
        }
        wavelengths.push(w);
        values.push(x);
    }
    if wavelengths.len() < 2 {
        return Err(el.error(format!("a spectrum needs at least two wavelength:value pairs, got '{v}'")));
    }
    Ok(Rgb(spectrum_to_linear_srgb(&wavelengths, &values, kind)))
}
