//! The component split of radiance (`--components`): every estimated path belongs to exactly one
//! component, so the components sum to the full image.

use haze_core::Rgb;

/// Path classes. A path's class depends on its scattering events only (null-surface crossings
/// are not events):
/// - `Emitted`: no scattering at all (an emitter seen directly, possibly through media).
/// - `Single`: exactly one medium scattering event and no surface scattering.
/// - `Multiple`: two or more medium events and no surface scattering.
/// - `Surface`: at least one non-null surface interaction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    Emitted = 0,
    Single = 1,
    Multiple = 2,
    Surface = 3,
}

impl Component {
    pub const ALL: [Component; 4] =
        [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];

    pub fn name(self) -> &'static str {
        match self {
            Component::Emitted => "emitted",
            Component::Single => "single",
            Component::Multiple => "multiple",
            Component::Surface => "surface",
        }
    }

    /// Class of a path with `medium_events` medium scatterings and `surface_events` non-null
    /// surface interactions.
    pub fn classify(medium_events: u32, surface_events: u32) -> Component {
        if surface_events > 0 {
            Component::Surface
        } else {
            match medium_events {
                0 => Component::Emitted,
                1 => Component::Single,
                _ => Component::Multiple,
            }
        }
    }
}

/// Radiance estimate of one camera sample, split by component.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathRadiance(pub [Rgb; 4]);

impl PathRadiance {
    #[inline]
    pub fn add(&mut self, c: Component, v: Rgb) {
        self.0[c as usize] += v;
    }
    pub fn total(&self) -> Rgb {
        self.0[0] + self.0[1] + self.0[2] + self.0[3]
    }
    pub fn get(&self, c: Component) -> Rgb {
        self.0[c as usize]
    }
}
