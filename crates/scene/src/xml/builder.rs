//! Walks the `<scene>` element and assembles the [`Scene`]: ids and references, the one
//! sensor and integrator, and the lists of shapes, media and emitters.

use super::context::Builder;
use super::document::MeshScope;
use super::document::{Document, Element};
use super::params::{Ids, VALUE_TAGS};
use super::{bsdfs, emitters, integrator, media, plugins, sensor, shapes, textures, LoadError};
use crate::camera::Camera;
use crate::scene::{IntegratorSpec, Scene};
use std::path::Path;

/// Builds the scene from a parsed document; `file` names the scene in [`Scene::path`].
pub(super) fn build(doc: &Document, file: &Path) -> Result<Scene, LoadError> {
    let mut ids = Ids::new();
    collect_ids(&doc.root, &mut ids)?;
    let mut b = Builder::new(doc, &ids);
    let mut camera: Option<(Camera, haze_core::SamplerSpec, &Element)> = None;
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
                let (cam, sampler) = sensor::build(&mut b, el)?;
                camera = Some((cam, sampler, el));
            }
            "integrator" => {
                if let Some((_, first)) = integrator {
                    return Err(el.error(format!(
                        "only one <integrator> is allowed; another is defined at line {}",
                        first.line
                    )));
                }
                integrator = Some((integrator::build(&b, el)?, el));
            }
            "shape" => shapes::build(&mut b, el)?,
            "medium" => {
                b.medium(el)?;
            }
            "emitter" => {
                let p = b.params(el)?;
                if p.ty() == "area" {
                    // Mitsuba 3 lets shapes refer to an area emitter declared at the top level
                    // with an id (`<ref id=".."/>` in the shape); each referring shape emits.
                    if el.attr("id").is_none() {
                        return Err(el.error(
                            "an area emitter must be nested inside the <shape> that emits \
                             (or declared with an id and referenced from it)",
                        ));
                    }
                    emitters::area_radiance(&p)?;
                    continue;
                }
                let emitter = emitters::build(&p, b.doc)?;
                b.emitters.push(emitter);
            }
            // Defined at the top level to be referenced; built here too, so that their errors
            // show even if nothing refers to them.
            "bsdf" => {
                *doc.mesh_scope.borrow_mut() = MeshScope::Declaration;
                bsdfs::build(&b.params(el)?)?;
                *doc.mesh_scope.borrow_mut() = MeshScope::Outside;
            }
            "phase" => {
                media::phase(&b.params(el)?)?;
            }
            "texture" => {
                *doc.mesh_scope.borrow_mut() = MeshScope::Declaration;
                textures::build(&b.params(el)?)?;
                *doc.mesh_scope.borrow_mut() = MeshScope::Outside;
            }
            "volume" => {
                media::volume(&b.params(el)?, "volume", (0.0, f32::INFINITY), b.doc)?;
            }
            // Declared at the top level to be referenced (Mitsuba 3 allows it): checked where
            // they are used.
            "film" | "sampler" | "rfilter" if el.attr("id").is_some() => {}
            "film" | "sampler" | "rfilter" => {
                return Err(el.error(format!(
                    "<{}> must be nested inside {} (or declared with an id and referenced)",
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
            tag => return Err(el.error(format!("unknown element <{tag}>"))),
        }
    }
    let Some((camera, sampler, _)) = camera else {
        return Err(doc
            .root
            .error("the scene has no <sensor> (haze needs one: perspective, thinlens or orthographic)"));
    };
    let integrator = integrator.map(|(i, _)| i).unwrap_or_default();
    let spp = sampler.sample_count();
    let mut scene =
        Scene::new(Some(file.to_path_buf()), camera, spp, integrator, b.shapes, b.media, b.emitters);
    scene.sampler = sampler;
    Ok(scene)
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
