//! Walks the `<scene>` element and assembles the [`Scene`]: ids and references, the one
//! sensor and integrator, and the lists of shapes, media and emitters.

use super::document::{Document, Element};
use super::params::{Ids, Params, VALUE_TAGS};
use super::{bsdfs, emitters, integrator, media, plugins, sensor, shapes, textures, LoadError};
use crate::camera::Camera;
use crate::emitter::Emitter;
use crate::medium::{Medium, MediumId};
use crate::scene::{IntegratorSpec, Scene};
use crate::shape::Shape;
use std::collections::HashMap;
use std::path::Path;

/// The scene under construction. Plugins that create objects other plugins refer to (media,
/// area emitters) add them here.
pub(super) struct Builder<'a> {
    pub doc: &'a Document,
    pub ids: &'a Ids<'a>,
    pub shapes: Vec<Shape>,
    pub media: Vec<Medium>,
    pub emitters: Vec<Emitter>,
    /// Media already built, by element: a medium referenced from several shapes is one medium.
    media_by_element: HashMap<usize, MediumId>,
}

impl<'a> Builder<'a> {
    pub fn params(&self, el: &'a Element) -> Result<Params<'a>, LoadError> {
        Params::new(el, self.ids)
    }

    /// The medium defined by `el`, built on first use.
    pub fn medium(&mut self, el: &'a Element) -> Result<MediumId, LoadError> {
        if let Some(&id) = self.media_by_element.get(&el.uid) {
            return Ok(id);
        }
        let name = match el.attr("id") {
            Some(id) => id.to_string(),
            None => format!("medium{}", self.media.len()),
        };
        let medium = media::build(&self.params(el)?, name)?;
        let id = self.media.len() as MediumId;
        self.media.push(medium);
        self.media_by_element.insert(el.uid, id);
        Ok(id)
    }
}

/// Builds the scene from a parsed document; `file` names the scene in [`Scene::path`].
pub(super) fn build(doc: &Document, file: &Path) -> Result<Scene, LoadError> {
    let mut ids = Ids::new();
    collect_ids(&doc.root, &mut ids)?;
    let mut b = Builder {
        doc,
        ids: &ids,
        shapes: Vec::new(),
        media: Vec::new(),
        emitters: Vec::new(),
        media_by_element: HashMap::new(),
    };
    let mut camera: Option<(Camera, u32, &Element)> = None;
    let mut integrator: Option<(IntegratorSpec, &Element)> = None;
    for el in &doc.root.children {
        match el.tag.as_str() {
            "sensor" => {
                if let Some((_, _, first)) = camera {
                    return Err(el.error(format!(
                        "haze renders one sensor; another is defined at line {}",
                        first.line
                    )));
                }
                let (cam, spp) = sensor::build(&mut b, el)?;
                camera = Some((cam, spp, el));
            }
            "integrator" => {
                if let Some((_, first)) = integrator {
                    return Err(el.error(format!(
                        "only one <integrator> is allowed; another is defined at line {}",
                        first.line
                    )));
                }
                integrator = Some((integrator::build(&b.params(el)?)?, el));
            }
            "shape" => shapes::build(&mut b, el)?,
            "medium" => {
                b.medium(el)?;
            }
            "emitter" => {
                let p = b.params(el)?;
                if p.ty() == "area" {
                    return Err(el.error("an area emitter must be nested inside the <shape> that emits"));
                }
                let emitter = emitters::build(&p, b.doc)?;
                b.emitters.push(emitter);
            }
            // Defined at the top level to be referenced; built here too, so that their errors
            // show even if nothing refers to them.
            "bsdf" => {
                bsdfs::build(&b.params(el)?)?;
            }
            "phase" => {
                media::phase(&b.params(el)?)?;
            }
            "texture" => {
                textures::build(&b.params(el)?)?;
            }
            "film" | "sampler" | "rfilter" => {
                return Err(el.error(format!(
                    "<{}> must be nested inside {}",
                    el.tag,
                    if el.tag == "rfilter" { "<film>" } else { "<sensor>" }
                )))
            }
            "ref" => return Err(el.error("<ref> at the top level refers to nothing")),
            tag if plugins::is_supported_kind(tag) => {
                return Err(el.error(format!("<{tag}> cannot appear at the top level")))
            }
            tag if VALUE_TAGS.contains(&tag) => {
                return Err(el.error("a parameter must be inside the plugin element it belongs to"))
            }
            "volume" => return Err(el.error(format!("unsupported: haze has no <{}> plugins", el.tag))),
            tag => return Err(el.error(format!("unknown element <{tag}>"))),
        }
    }
    let Some((camera, spp, _)) = camera else {
        return Err(doc.root.error("the scene has no <sensor> (haze needs a perspective sensor)"));
    };
    let integrator = integrator.map(|(i, _)| i).unwrap_or_default();
    Ok(Scene::new(Some(file.to_path_buf()), camera, spp, integrator, b.shapes, b.media, b.emitters))
}

/// Every plugin element with an `id`, anywhere in the tree (Mitsuba 3 lets a `<ref>` name any
/// object defined anywhere in the file, also later in it).
fn collect_ids<'a>(el: &'a Element, ids: &mut Ids<'a>) -> Result<(), LoadError> {
    for child in &el.children {
        if child.tag != "ref" {
            if let Some(id) = child.attr("id") {
                if let Some(first) = ids.get(id) {
                    return Err(child.error(format!(
                        "duplicate id '{id}' (first defined at line {} of {})",
                        first.line,
                        first.source.file.display()
                    )));
                }
                ids.insert(id, child);
            }
        }
        collect_ids(child, ids)?;
    }
    Ok(())
}
