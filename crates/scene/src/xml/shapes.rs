//! Shape plugins `sphere`, `cube`, `rectangle`, `disk`, `cylinder`, `obj`, `ply`, `serialized`,
//! `shapegroup` and `instance`, with their BSDF,
//! interior/exterior media and area emitter.

use super::context::Builder;
use super::document::Element;
use super::document::{MeshScope, ScopeMesh};
use super::params::Params;
use super::transform::uniform_scale;
use super::{bsdfs, emitters, obj, ply, serialized, LoadError};
use crate::bsdf::Bsdf;
use crate::emitter::Emitter;
use crate::medium::MediumId;
use crate::shape::{cube_mesh, cylinder_mesh, rectangle_mesh, Geometry, Shape, TriangleMesh};
use glam::{Mat3, Mat4, Vec3};
use haze_core::Rgb;

/// Builds shape `el` and adds it (and its area emitter) to the scene.
///
/// Every shape takes `to_world` (identity) and `flip_normals` (false); one `<bsdf>` (nested or
/// `<ref>`; Mitsuba 3's default is `diffuse` with reflectance 0.5); media named `interior`
/// and `exterior` (nested `<medium name="interior">` or `<ref name="interior" id=".."/>`);
/// and one `<emitter type="area">` (nested, or declared at the top level with an id and
/// referenced).
pub(super) fn build<'a>(b: &mut Builder<'a>, el: &'a Element) -> Result<(), LoadError> {
    build_placed(b, el, None)
}

/// Mitsuba 3's instancing: a `shapegroup` (with an id) holds shapes and is not rendered itself;
/// each `instance` referring to it adds a copy of its shapes, each placed by the instance's
/// `to_world` after its own. haze copies the geometry (no instancing in the BVH). As in
/// Mitsuba 3, instanced shapes cannot emit, and groups do not nest.
fn instance<'a>(b: &mut Builder<'a>, p: &Params<'a>) -> Result<(), LoadError> {
    let to_world = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
    let groups = p.objects(&["shape"]);
    let group = match groups[..] {
        [one] => one,
        [] => return Err(p.element().error("an instance needs a <ref> to a shapegroup")),
        [_, second, ..] => return Err(second.site.error("an instance refers to one shapegroup")),
    };
    let gp = p.nested(group.target)?;
    if gp.ty() != "shapegroup" {
        return Err(group
            .site
            .error(format!("an instance refers to a shapegroup, not a '{}' shape", gp.ty())));
    }
    p.finish()?;
    let number = b.shapes.len();
    for member in gp.objects(&["shape"]) {
        build_placed(b, member.target, Some((to_world, number)))?;
    }
    gp.finish()
}

/// [`build`], for a shape placed by an instance: `(to_world, number)` is the instance's
/// transform, applied after the shape's own, and a number naming the copy.
fn build_placed<'a>(
    b: &mut Builder<'a>,
    el: &'a Element,
    placed: Option<(Mat4, usize)>,
) -> Result<(), LoadError> {
    let p = b.params(el)?;
    match (p.ty(), placed) {
        ("shapegroup", None) => {
            // Checked member by member where an instance places it.
            for o in p.objects(&["shape"]) {
                if o.target.attr("type").is_some_and(|t| t == "shapegroup" || t == "instance") {
                    return Err(o.site.error("shapegroups do not nest (as in Mitsuba 3)"));
                }
            }
            return p.finish();
        }
        ("instance", None) => return instance(b, &p),
        ("shapegroup" | "instance", Some(_)) => {
            return Err(el.error("shapegroups do not nest (as in Mitsuba 3)"));
        }
        _ => {}
    }
    let own = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
    let to_world = placed.map_or(own, |(outer, _)| outer * own);
    let flip_normals = p.bool("flip_normals", false)?;
    let mut attributes = Vec::new();
    let geometry = match p.ty() {
        "sphere" => sphere(&p, &to_world, flip_normals)?,
        "cube" => {
            require_invertible(&p, &to_world)?;
            Geometry::Mesh(cube_mesh(&to_world, flip_normals))
        }
        "rectangle" => {
            require_planar_rank(&p, &to_world)?;
            Geometry::Mesh(rectangle_mesh(&to_world, flip_normals))
        }
        "cylinder" => cylinder(&p, &to_world, flip_normals)?,
        "disk" => {
            require_planar_rank(&p, &to_world)?;
            Geometry::Disk { to_world, flip_normals }
        }
        _ => {
            let (mesh, attrs) = mesh_file(b, &p, &to_world, flip_normals)?;
            attributes = attrs;
            Geometry::Mesh(mesh)
        }
    };
    check_extent(&p, &geometry)?;
    // What a `mesh_attribute` texture in this shape's BSDF reads (`textures::mesh_attribute`).
    let mesh = match &geometry {
        Geometry::Mesh(m) => Some(ScopeMesh {
            kind: p.ty().to_string(),
            indices: if attributes.is_empty() { Vec::new() } else { m.indices.clone() },
            vertex_count: m.positions.len(),
            attributes,
        }),
        _ => None,
    };
    *b.doc.mesh_scope.borrow_mut() =
        MeshScope::Shape { shape: format!("{} at line {}", el.describe(), el.line), mesh };

    let mut bsdf: Option<Bsdf> = None;
    let mut interior: Option<MediumId> = None;
    let mut exterior: Option<MediumId> = None;
    let mut radiance: Option<crate::texture::Texture> = None;
    for o in p.objects(&["bsdf", "medium", "emitter"]) {
        let twice = |what: &str| o.site.error(format!("{} takes one {what}", el.describe()));
        match o.target.tag.as_str() {
            "bsdf" => {
                if let Some(name @ ("interior" | "exterior")) = o.name {
                    return Err(o.site.error(format!("'{name}' must be a medium, not a <bsdf>")));
                }
                if bsdf.is_some() {
                    return Err(twice("<bsdf>"));
                }
                bsdf = Some(bsdfs::build(&p.nested(o.target)?)?);
            }
            "medium" => {
                let slot = match o.name {
                    Some("interior") => &mut interior,
                    Some("exterior") => &mut exterior,
                    _ => {
                        return Err(o
                            .site
                            .error("a medium in a shape must be named \"interior\" or \"exterior\""))
                    }
                };
                if slot.is_some() {
                    return Err(twice("medium of each name"));
                }
                *slot = Some(b.medium(o.target)?);
            }
            _ => {
                if radiance.is_some() {
                    return Err(twice("<emitter>"));
                }
                if placed.is_some() {
                    return Err(o.site.error("a shape in a shapegroup cannot emit (as in Mitsuba 3)"));
                }
                let ep = p.nested(o.target)?;
                if ep.ty() != "area" {
                    return Err(o.target.error(format!(
                        "only an area emitter can be attached to a shape, not '{}'",
                        ep.ty()
                    )));
                }
                radiance = Some(emitters::area_radiance(&ep)?);
            }
        }
    }
    *b.doc.mesh_scope.borrow_mut() = MeshScope::Outside;
    p.finish()?;

    let shape_index = b.shapes.len() as u32;
    let emitter = radiance.map(|radiance| {
        b.emitters.push(Emitter::Area { shape: shape_index, radiance });
        (b.emitters.len() - 1) as u32
    });
    let filename = match p.ty() {
        "obj" | "ply" | "serialized" => p.string_opt("filename")?,
        _ => None,
    };
    let mut name = match (el.attr("id"), filename) {
        (Some(id), _) => id.to_string(),
        (None, Some(file)) => format!("{} \"{file}\"", p.ty()),
        (None, None) => p.ty().to_string(),
    };
    if let Some((_, number)) = placed {
        name.push_str(&format!(" (instance at shape {number})"));
    }
    b.shapes.push(Shape {
        name,
        geometry,
        bsdf: bsdf.unwrap_or_else(|| default_bsdf(emitter.is_some())),
        interior,
        exterior,
        emitter,
    });
    Ok(())
}

/// The BSDF of a shape that names none, as Mitsuba 3 (`Shape`'s constructor): a `diffuse` of
/// reflectance 0.5, or of reflectance 0 if the shape emits, so that a bare area light reflects
/// nothing (a grey one makes a quad light over a floor 5-8% brighter than Mitsuba's image).
fn default_bsdf(emits: bool) -> Bsdf {
    let reflectance = if emits { 0.0 } else { 0.5 };
    Bsdf::Diffuse { reflectance: Rgb::splat(reflectance).into() }
}

/// `sphere`: `center` (origin) and `radius` (1), then `to_world`, which may rotate, translate
/// and scale uniformly (Mitsuba 3 forbids non-uniform scales and shears here too).
fn sphere(p: &Params, to_world: &Mat4, flip_normals: bool) -> Result<Geometry, LoadError> {
    let center = p.point_opt("center")?.unwrap_or(Vec3::ZERO);
    let radius = p.float("radius", 1.0)?;
    if radius <= 0.0 {
        return Err(p.error_at("radius", format!("'radius' must be > 0, got {radius}")));
    }
    let scale = uniform_scale(to_world).ok_or_else(|| {
        p.error_at("to_world", "a sphere's to_world may only rotate, translate and scale uniformly")
    })?;
    Ok(Geometry::Sphere { center: to_world.transform_point3(center), radius: radius * scale, flip_normals })
}

/// `cylinder`: `p0` (origin), `p1` (0, 0, 1), `radius` (1): Mitsuba 3's open tube around the
/// segment `p0 p1`, then `to_world`; tessellated ([`cylinder_mesh`]). The frame around the
/// axis, where `u = 0` lies, is Mitsuba's ([`axis_frame`]), so `uv` is Mitsuba's too.
fn cylinder(p: &Params, to_world: &Mat4, flip_normals: bool) -> Result<Geometry, LoadError> {
    let p0 = p.point_opt("p0")?.unwrap_or(Vec3::ZERO);
    let p1 = p.point_opt("p1")?.unwrap_or(Vec3::Z);
    let radius = p.float("radius", 1.0)?;
    if radius <= 0.0 {
        return Err(p.error_at("radius", format!("'radius' must be > 0, got {radius}")));
    }
    let axis = p1 - p0;
    let length = axis.length();
    if length.is_nan() || length <= 0.0 {
        return Err(p.error_at("p1", "'p0' and 'p1' must differ"));
    }
    let d = axis / length;
    let (x, y) = axis_frame(d);
    let local =
        Mat4::from_cols((x * radius).extend(0.0), (y * radius).extend(0.0), axis.extend(0.0), p0.extend(1.0));
    let placed = *to_world * local;
    require_invertible(p, &placed)?;
    Ok(Geometry::Mesh(cylinder_mesh(&placed, flip_normals)))
}

/// Two unit vectors completing the unit `n` to a right-handed orthonormal frame `(x, y, n)`:
/// Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1), Listing 3), with
/// the sign of `n.z` taken as `+1` at zero, as Mitsuba 3's `coordinate_system` (which places its
/// cylinder with it). Written out rather than taken from glam, whose `any_orthonormal_pair` is
/// the same today but promises no particular pair.
fn axis_frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// Geometry must lie within `MAX_COORDINATE` of the origin (the BVH cannot hold larger
/// coordinates, and f32 has no precision left for rays there) and be finite.
fn check_extent(p: &Params, geometry: &Geometry) -> Result<(), LoadError> {
    use crate::accel::MAX_COORDINATE;
    let largest = match geometry {
        Geometry::Mesh(m) => m.positions.iter().map(|v| v.abs().max_element()).fold(0.0f32, |a, b| {
            if b.is_nan() {
                f32::NAN
            } else {
                a.max(b)
            }
        }),
        Geometry::Sphere { center, radius, .. } => center.abs().max_element() + radius,
        Geometry::Disk { to_world, .. } => {
            let o = to_world.transform_point3(Vec3::ZERO);
            let r =
                to_world.transform_vector3(Vec3::X).length() + to_world.transform_vector3(Vec3::Y).length();
            o.abs().max_element() + r
        }
    };
    if largest.is_nan() || largest > MAX_COORDINATE {
        return Err(p.element().error(format!(
            "the shape reaches coordinates of {largest:e}; haze takes geometry within {MAX_COORDINATE:e} \
             of the origin (scale the scene down)"
        )));
    }
    Ok(())
}

fn require_invertible(p: &Params, to_world: &Mat4) -> Result<Mat3, LoadError> {
    let l = Mat3::from_mat4(*to_world);
    let d = l.as_dmat3();
    let lengths = [d.x_axis.length(), d.y_axis.length(), d.z_axis.length()];
    // Relative to the axes' lengths, so that a uniformly tiny (or huge) shape is not called
    // flat; in f64, as products of tiny or huge lengths under- or overflow f32.
    let volume = lengths.iter().product::<f64>();
    if volume.is_nan() || volume <= 0.0 || (d.determinant().abs() / volume) <= 1e-9 {
        return Err(p.error_at("to_world", "to_world is singular (flattens the shape)"));
    }
    let smallest = lengths.iter().copied().fold(f64::INFINITY, f64::min) as f32;
    if smallest < MIN_SCALE {
        return Err(p.error_at(
            "to_world",
            format!(
                "to_world scales the shape by {smallest:e}: too small for f32 ray tracing \
                 (haze takes scales of at least {MIN_SCALE:e}; scale the scene up)"
            ),
        ));
    }
    Ok(l)
}

/// Smallest scale of a shape's `to_world` haze accepts: below it, ray offsets and f32
/// spacing are as large as the shape.
const MIN_SCALE: f32 = 1e-12;

/// A planar shape needs its local x and y axes to stay independent.
fn require_planar_rank(p: &Params, to_world: &Mat4) -> Result<(), LoadError> {
    let x = to_world.transform_vector3(Vec3::X);
    let y = to_world.transform_vector3(Vec3::Y);
    if x.cross(y).length() <= 1e-12 {
        return Err(p.error_at("to_world", "to_world flattens the shape to a line or a point"));
    }
    Ok(())
}

/// `obj`, `ply` and `serialized`: `filename` (required; relative to the scene file's directory),
/// `face_normals` (false: keep the file's vertex normals), `flip_tex_coords` (Mitsuba 3
/// defaults: true for OBJ, false for PLY; `serialized` has none), `shape_index` (`serialized`
/// only: which mesh of the file, 0). Positions go to world space with `to_world`,
/// normals with its inverse transpose.
fn mesh_file(
    b: &Builder,
    p: &Params,
    to_world: &Mat4,
    flip_normals: bool,
) -> Result<(TriangleMesh, Vec<crate::mesh_attribute::AttributeArray>), LoadError> {
    let filename =
        p.string_opt("filename")?.ok_or_else(|| p.element().error("missing parameter 'filename'"))?;
    let face_normals = p.bool("face_normals", false)?;
    let flip_tex_coords = p.ty() != "serialized" && p.bool("flip_tex_coords", p.ty() == "obj")?;
    let shape_index = match p.ty() {
        "serialized" => {
            let i = p.int("shape_index", 0)?;
            u32::try_from(i)
                .map_err(|_| p.error_at("shape_index", format!("'shape_index' must be >= 0, got {i}")))?
        }
        _ => 0,
    };
    let linear = require_invertible(p, to_world)?;
    let path = b.doc.resolve(filename, p.element());
    let load = |path: &std::path::Path| match p.ty() {
        "obj" => obj::load(path).map(|m| (m, Vec::new())),
        "ply" => ply::load(path),
        _ => serialized::load(path, shape_index).map(|m| (m, Vec::new())),
    };
    // The mesh parsers are third-party code; some index arithmetic in them can overflow (a
    // panic in debug builds) on hostile files. A bad file must be an error, never a crash.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load(&path)))
        .unwrap_or_else(|_| Err("the file is malformed (the parser gave up)".to_string()));
    let (mut mesh, attributes) = loaded
        .and_then(|(m, a)| check_mesh(&m).map(|()| (m, a)))
        .map_err(|e| p.element().error(format!("cannot load mesh file '{}': {e}", path.display())))?;

    for v in &mut mesh.positions {
        *v = to_world.transform_point3(*v);
    }
    mesh.normals = if face_normals { None } else { mesh.normals.take() };
    if let Some(normals) = mesh.normals.as_mut() {
        let normal_matrix = linear.inverse().transpose();
        for n in normals {
            *n = (normal_matrix * *n).normalize_or_zero();
        }
    }
    if flip_tex_coords {
        for uv in mesh.uvs.iter_mut().flatten() {
            uv.y = 1.0 - uv.y;
        }
    }
    mesh.flip_normals = flip_normals;
    Ok((mesh, attributes))
}

/// A mesh the renderer can use: triangles, in-range indices, finite positions, and attribute
/// arrays as long as the position array.
fn check_mesh(m: &TriangleMesh) -> Result<(), String> {
    if m.indices.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let n = m.positions.len();
    if let Some(t) = m.indices.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(format!(
            "a triangle ({}, {}, {}) refers to a vertex beyond the {n} vertices",
            t[0], t[1], t[2]
        ));
    }
    if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a non-finite position"));
    }
    let normals_ok = m.normals.as_ref().is_none_or(|v| v.len() == n);
    let uvs_ok = m.uvs.as_ref().is_none_or(|v| v.len() == n);
    if !(normals_ok && uvs_ok) {
        return Err("per-vertex attribute arrays differ in length from the positions".into());
    }
    Ok(())
}
