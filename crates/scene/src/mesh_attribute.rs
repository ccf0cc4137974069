//! Mesh attributes (Mitsuba 3's `vertex_*` and `face_*` arrays read from PLY files) and the
//! `mesh_attribute` texture that reads them at a hit.
//!
//! Mitsuba 3 keeps attributes on the mesh and its `mesh_attribute` texture asks the hit shape
//! for one by name (`Mesh::eval_attribute`: a vertex attribute blended with the hit's
//! barycentrics, a face attribute taken per face). haze binds the texture to the one mesh whose
//! BSDF holds it when the scene loads (`xml/shapes.rs`), so the texture carries the values
//! it reads, expanded per triangle: a lookup is one indexed read and no name is looked up while
//! rendering.

use glam::Vec2;
use haze_core::Rgb;

/// Where a texture is looked up: the surface coordinates `uv` of the hit, and for the
/// `mesh_attribute` texture the hit's triangle (`prim`, its index in its mesh) and barycentric
/// weights `bary = (b1, b2)` of its vertices 1 and 2 (vertex 0 weighs `1 - b1 - b2`).
///
/// A point made from a bare `uv` ([`From<Vec2>`]) names no triangle ([`TexPoint::NO_PRIM`]);
/// every texture but `mesh_attribute` reads only `uv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexPoint {
    pub uv: Vec2,
    pub prim: u32,
    pub bary: Vec2,
}

impl TexPoint {
    /// The `prim` of a point that is not on a triangle.
    pub const NO_PRIM: u32 = u32::MAX;
}

impl Default for TexPoint {
    fn default() -> Self {
        Vec2::ZERO.into()
    }
}

impl From<Vec2> for TexPoint {
    fn from(uv: Vec2) -> Self {
        TexPoint { uv, prim: Self::NO_PRIM, bary: Vec2::ZERO }
    }
}

/// One attribute of a mesh as the file gives it: `dim` numbers per vertex or per face
/// (Mitsuba 3 reads 1 to 4; its `mesh_attribute` evaluates 1 and 3).
#[derive(Clone, Debug, PartialEq)]
pub struct AttributeArray {
    /// `vertex_...` or `face_...`, as Mitsuba 3 names it.
    pub name: String,
    pub dim: usize,
    /// `dim` numbers per vertex (or per face), row after row.
    pub values: Vec<f32>,
}

impl AttributeArray {
    pub fn is_vertex(&self) -> bool {
        self.name.starts_with("vertex_")
    }

    /// Row `i` as an RGB value: three channels as they are, one channel as grey.
    fn rgb(&self, i: usize) -> Rgb {
        match self.dim {
            1 => Rgb::splat(self.values[i]),
            _ => Rgb::new(self.values[3 * i], self.values[3 * i + 1], self.values[3 * i + 2]),
        }
    }
}

/// A `mesh_attribute` texture bound to its mesh: the attribute's values at each triangle's
/// three corners (the same three for a face attribute), already multiplied by `scale`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    pub name: String,
    /// 1 (grey) or 3 (RGB) channels.
    pub dim: usize,
    corners: Vec<[Rgb; 3]>,
    /// Smallest and largest channel value over the corners, computed once at binding:
    /// [`Bsdf::is_black`](crate::bsdf::Bsdf::is_black) asks for it at every surface hit, and a
    /// scan of the corners there would cost a mesh's size per hit.
    range: (f32, f32),
}

impl MeshAttribute {
    /// Binds attribute `attr` of a mesh with triangles `indices` (a face attribute has one row
    /// per triangle: polygon faces are split into triangles with their face's row). `None`
    /// unless the attribute has 1 or 3 channels and one row per vertex (`vertex_count`) or
    /// per triangle; the caller words the error.
    pub fn bind(
        attr: &AttributeArray,
        scale: f32,
        indices: &[[u32; 3]],
        vertex_count: usize,
    ) -> Option<Self> {
        if !matches!(attr.dim, 1 | 3) {
            return None;
        }
        let rows = attr.values.len() / attr.dim;
        let corners: Vec<[Rgb; 3]> = if attr.is_vertex() {
            if rows != vertex_count || indices.iter().flatten().any(|&i| i as usize >= rows) {
                return None;
            }
            indices.iter().map(|t| t.map(|i| attr.rgb(i as usize) * scale)).collect()
        } else {
            if rows != indices.len() {
                return None;
            }
            (0..rows).map(|f| [attr.rgb(f) * scale; 3]).collect()
        };
        let range = corners.iter().flatten().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), c: &Rgb| {
            (lo.min(c.min_component()), hi.max(c.max_component()))
        });
        Some(MeshAttribute { name: attr.name.clone(), dim: attr.dim, corners, range })
    }

    /// The value at `at`: `b0 c0 + b1 c1 + b2 c2` over the triangle's corners (Mitsuba 3's
    /// `interpolate_attribute`; a face attribute's corners are equal). Zero at a point not on
    /// one of the mesh's triangles (never the case for hits on the mesh the texture is bound to).
    pub fn eval(&self, at: TexPoint) -> Rgb {
        let Some([c0, c1, c2]) = self.corners.get(at.prim as usize) else { return Rgb::ZERO };
        let (b1, b2) = (at.bary.x, at.bary.y);
        *c0 * (1.0 - b1 - b2) + *c1 * b1 + *c2 * b2
    }

    /// The value as one number (Mitsuba 3's `eval_1`): a one-channel attribute's value; a
    /// three-channel one gives 0, as Mitsuba 3.9.1's `Mesh::eval_attribute_1` returns 0 for an
    /// attribute whose channel count is not 1.
    pub fn eval_1(&self, at: TexPoint) -> f32 {
        if self.dim == 1 {
            self.eval(at)[0]
        } else {
            0.0
        }
    }

    /// The mean over the corners (Mitsuba 3's `mesh_attribute` has no `mean`; this is what
    /// sampling weights that must not depend on the hit get).
    pub fn mean(&self) -> Rgb {
        let n = (3 * self.corners.len()).max(1) as f32;
        self.corners.iter().flatten().fold(Rgb::ZERO, |a, &c| a + c) * (1.0 / n)
    }

    /// Smallest and largest channel value anywhere (a blend of corners stays between them).
    pub fn range(&self) -> (f32, f32) {
        self.range
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn colours() -> AttributeArray {
        AttributeArray {
            name: "vertex_color".into(),
            dim: 3,
            values: vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5],
        }
    }

    #[test]
    fn vertex_attribute_blends_with_barycentrics() {
        // Triangle 1 uses vertices 3, 1, 2: corner 0 is grey 0.5.
        let a = MeshAttribute::bind(&colours(), 2.0, &[[0, 1, 2], [3, 1, 2]], 4).unwrap();
        let at = |prim, b1, b2| TexPoint { uv: Vec2::ZERO, prim, bary: Vec2::new(b1, b2) };
        let v = a.eval(at(0, 0.25, 0.5));
        assert!((v - Rgb::new(0.5, 0.5, 1.0)).map(f32::abs).max_component() < 1e-6, "{v:?}");
        let v = a.eval(at(1, 0.0, 0.0));
        assert_eq!(v, Rgb::splat(1.0), "corner 0 of triangle 1 is vertex 3, scaled by 2");
        assert_eq!(a.eval(Vec2::new(0.3, 0.3).into()), Rgb::ZERO, "no triangle");
        assert_eq!(a.eval_1(at(0, 0.2, 0.2)), 0.0, "three channels read as one give 0, as Mitsuba");
        assert_eq!(a.range(), (0.0, 2.0));
    }

    #[test]
    fn face_attribute_is_constant_per_face() {
        let w = AttributeArray { name: "face_weight".into(), dim: 1, values: vec![0.25, 0.75] };
        let a = MeshAttribute::bind(&w, 1.0, &[[0, 1, 2], [0, 2, 3]], 4).unwrap();
        for (b1, b2) in [(0.0, 0.0), (0.7, 0.1), (0.0, 1.0)] {
            let at = TexPoint { uv: Vec2::ZERO, prim: 1, bary: Vec2::new(b1, b2) };
            assert!((a.eval_1(at) - 0.75).abs() < 1e-6);
        }
        assert!((a.mean()[0] - 0.5).abs() < 1e-6);
    }

    #[test]
    fn binding_refuses_shapes_that_do_not_fit() {
        assert!(MeshAttribute::bind(&colours(), 1.0, &[[0, 1, 2]], 3).is_none(), "4 rows, 3 vertices");
        let two = AttributeArray { name: "vertex_uv2".into(), dim: 2, values: vec![0.0; 8] };
        assert!(MeshAttribute::bind(&two, 1.0, &[[0, 1, 2]], 4).is_none(), "2 channels");
        let faces = AttributeArray { name: "face_w".into(), dim: 1, values: vec![0.0; 3] };
        assert!(MeshAttribute::bind(&faces, 1.0, &[[0, 1, 2]], 3).is_none(), "3 rows, 1 face");
    }
}
