//! The scene under construction ([`Builder`]), shared by the walk over the `<scene>` element
//! (`builder.rs`) and the plugin files that add objects to it (`shapes.rs`, `sensor.rs`).

use super::document::{Document, Element};
use super::params::{Ids, Params};
use super::{media, LoadError};
use crate::emitter::Emitter;
use crate::medium::{Medium, MediumId};
use crate::shape::Shape;
use std::collections::HashMap;

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
    /// An empty scene over `doc`, whose ids are `ids`.
    pub fn new(doc: &'a Document, ids: &'a Ids<'a>) -> Self {
        Builder {
            doc,
            ids,
            shapes: Vec::new(),
            media: Vec::new(),
            emitters: Vec::new(),
            media_by_element: HashMap::new(),
        }
    }

    pub fn params(&self, el: &'a Element) -> Result<Params<'a>, LoadError> {
        Params::new(el, self.ids, self.doc)
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
        let medium = media::build(&self.params(el)?, name, self.doc)?;
        let id = self.media.len() as MediumId;
        self.media.push(medium);
        self.media_by_element.insert(el.uid, id);
        Ok(id)
    }
}
