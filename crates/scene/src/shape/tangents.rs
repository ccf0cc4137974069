//! The surface's parameterisation derivatives `dp/du` and `dp/dv` at a hit, which normal and
//! bump maps orient their tangent space by (Mitsuba 3's `SurfaceInteraction::dp_du`, `dp_dv`),
//! and the shading frame anisotropic BSDFs are evaluated in.

use super::Geometry;
use glam::{Vec2, Vec3};
use haze_core::{Frame, PI};

/// `(dp/du, dp/dv)` of `geometry` at the point `p` of primitive `prim`, `n` the geometric
/// normal there.
///
/// - Triangle with uvs (Mitsuba's `Mesh::compute_surface_interaction`): with
///   `dp_1 = p_1 - p_0`, `dp_2 = p_2 - p_0`, `duv_1 = uv_1 - uv_0`, `duv_2 = uv_2 - uv_0` and
///   `det = duv_1.x duv_2.y - duv_1.y duv_2.x`:
///   `dp/du = (duv_2.y dp_1 - duv_1.y dp_2) / det`, `dp/dv = (duv_1.x dp_2 - duv_2.x dp_1) / det`.
/// - Sphere, haze's mapping `u = atan2(n.z, n.x) / 2pi + 1/2`, `v = acos(n.y) / pi` of the
///   outward (or, flipped, inward) normal `n`, `r` negated when flipped:
///   `dp/du = 2 pi r (-n.z, 0, n.x)`, `dp/dv = pi r (n.y cos phi, -sin theta, n.y sin phi)`.
/// - Disk, haze's mapping `u = |q|`, `v = atan2(q.y, q.x) / 2pi + 1/2` of the local point `q`:
///   `dp/du = M (cos a, sin a, 0)`, `dp/dv = 2 pi |q| M (-sin a, cos a, 0)`, `M` = `to_world`.
///
/// Where the parameterisation is degenerate (a triangle without uvs or with collinear ones, a
/// sphere's pole, a disk's centre) an orthonormal frame around `n` instead, as Mitsuba's
/// `coordinate_system` fallback.
pub fn uv_tangents(geometry: &Geometry, prim: u32, p: Vec3, n: Vec3) -> (Vec3, Vec3) {
    let fallback = || {
        let f = Frame::from_normal(n);
        (f.s, f.t)
    };
    let (du, dv) = match geometry {
        Geometry::Mesh(m) => {
            let Some(uvs) = &m.uvs else { return fallback() };
            let idx = m.indices[prim as usize].map(|i| i as usize);
            let [p0, p1, p2] = idx.map(|i| m.positions[i]);
            let [uv0, uv1, uv2] = idx.map(|i| uvs[i]);
            let (dp1, dp2, duv1, duv2) = (p1 - p0, p2 - p0, uv1 - uv0, uv2 - uv0);
            let det = duv1.x * duv2.y - duv1.y * duv2.x;
            if det == 0.0 {
                return fallback();
            }
            let inv = 1.0 / det;
            ((dp1 * duv2.y - dp2 * duv1.y) * inv, (dp2 * duv1.x - dp1 * duv2.x) * inv)
        }
        Geometry::Sphere { center, radius, flip_normals } => {
            // The uv mapping reads the (flipped) normal: `p = c + r' d(u, v)`, `r' = -r` flipped.
            let radius = if *flip_normals { -*radius } else { *radius };
            let d = (p - *center) / radius;
            let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
            if sin_theta == 0.0 {
                return fallback();
            }
            let (cos_phi, sin_phi) = (d.x / sin_theta, d.z / sin_theta);
            (
                Vec3::new(-d.z, 0.0, d.x) * (2.0 * PI * radius),
                Vec3::new(d.y * cos_phi, -sin_theta, d.y * sin_phi) * (PI * radius),
            )
        }
        Geometry::Disk { to_world, .. } => {
            let q = to_world.inverse().transform_point3(p);
            let r = Vec2::new(q.x, q.y).length();
            if r == 0.0 {
                return fallback();
            }
            let (c, s) = (q.x / r, q.y / r);
            (
                to_world.transform_vector3(Vec3::new(c, s, 0.0)),
                to_world.transform_vector3(Vec3::new(-s, c, 0.0)) * (2.0 * PI * r),
            )
        }
    };
    if du.is_finite() && dv.is_finite() && du.length_squared() > 0.0 {
        (du, dv)
    } else {
        fallback()
    }
}

/// The shading frame around the unit shading normal `ns` whose `s` axis is `dp_du` made
/// orthogonal to `ns` (Gram-Schmidt), `t = ns x s`: Mitsuba 3's
/// `SurfaceInteraction::initialize_sh_frame`, the frame in which its anisotropic roughness
/// `alpha_u` lies along `s`. Falls back to [`Frame::from_normal`] where `dp_du` is parallel to
/// `ns`.
pub fn tangent_frame(ns: Vec3, dp_du: Vec3) -> Frame {
    let s = (dp_du - ns * ns.dot(dp_du)).normalize_or_zero();
    if s == Vec3::ZERO {
        return Frame::from_normal(ns);
    }
    Frame { s, t: ns.cross(s), n: ns }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::TriangleMesh;
    use glam::Mat4;

    /// The anisotropic shading frame: orthonormal, right-handed (`s x t = n`, as
    /// `Frame::from_normal`'s), `s` along `dp/du` made orthogonal to the normal, and the
    /// normal's own frame where `dp/du` is parallel to it.
    #[test]
    fn tangent_frame_follows_dp_du() {
        let ns = Vec3::new(0.2, -0.3, 0.93).normalize();
        for dp_du in [Vec3::new(2.0, 0.1, 0.0), Vec3::new(-0.3, 4.0, 1.0), ns * 3.0] {
            let f = tangent_frame(ns, dp_du);
            for (a, b) in [(f.s, f.t), (f.t, f.n), (f.s, f.n)] {
                assert!(a.dot(b).abs() < 1e-6 && (a.length() - 1.0).abs() < 1e-6);
            }
            assert!((f.s.cross(f.t) - f.n).length() < 1e-6);
            let along = dp_du - ns * ns.dot(dp_du);
            if along.length() > 1e-3 {
                assert!((f.s - along.normalize()).length() < 1e-6, "{dp_du}");
            } else {
                assert_eq!(f, Frame::from_normal(ns));
            }
        }
        let g = Frame::from_normal(ns);
        assert!((g.s.cross(g.t) - g.n).length() < 1e-6, "Frame::from_normal is right-handed too");
    }

    /// The tangents are the finite differences of the position along `u` and `v`: on a
    /// triangle with skewed uvs, on a sphere through its uv mapping, on a scaled disk.
    #[test]
    fn tangents_are_derivatives_of_the_mapping() {
        let close =
            |a: Vec3, b: Vec3, tol: f32| assert!((a - b).length() <= tol * b.length().max(1.0), "{a} vs {b}");
        // Triangle: p(uv) is affine, so p(uv0 + e_u) - p(uv0) is dp/du exactly.
        let positions = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 3.0, 0.0)];
        let uvs = vec![Vec2::new(0.1, 0.2), Vec2::new(0.5, 0.3), Vec2::new(0.2, 0.9)];
        let m = TriangleMesh::new(positions.clone(), None, Some(uvs.clone()), vec![[0, 1, 2]], false);
        let (du, dv) = uv_tangents(&Geometry::Mesh(m), 0, positions[0], Vec3::Z);
        // Barycentrics of uv0 + e: solve uv0 + b1 duv1 + b2 duv2 = uv0 + e.
        let to_p = |e: Vec2| {
            let (d1, d2) = (uvs[1] - uvs[0], uvs[2] - uvs[0]);
            let det = d1.x * d2.y - d1.y * d2.x;
            let b1 = (e.x * d2.y - e.y * d2.x) / det;
            let b2 = (d1.x * e.y - d1.y * e.x) / det;
            (positions[1] - positions[0]) * b1 + (positions[2] - positions[0]) * b2
        };
        close(du, to_p(Vec2::X), 1e-5);
        close(dv, to_p(Vec2::Y), 1e-5);
        // Sphere.
        let (center, radius) = (Vec3::new(1.0, -2.0, 0.5), 1.7);
        let at = |u: f32, v: f32| {
            let (phi, theta) = ((u - 0.5) * 2.0 * PI, v * PI);
            center + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
        };
        let (u, v, h) = (0.3f32, 0.35f32, 1e-3f32);
        let sphere = Geometry::Sphere { center, radius, flip_normals: false };
        let (du, dv) = uv_tangents(&sphere, 0, at(u, v), (at(u, v) - center).normalize());
        close(du, (at(u + h, v) - at(u - h, v)) / (2.0 * h), 1e-3);
        close(dv, (at(u, v + h) - at(u, v - h)) / (2.0 * h), 1e-3);
        // Disk.
        let to_world =
            Mat4::from_translation(Vec3::new(0.0, 1.0, 2.0)) * Mat4::from_scale(Vec3::new(2.0, 0.5, 1.0));
        let at = |u: f32, v: f32| {
            let a = (v - 0.5) * 2.0 * PI;
            to_world.transform_point3(Vec3::new(u * a.cos(), u * a.sin(), 0.0))
        };
        let disk = Geometry::Disk { to_world, flip_normals: false };
        let (du, dv) = uv_tangents(&disk, 0, at(u, v), Vec3::Z);
        close(du, (at(u + h, v) - at(u - h, v)) / (2.0 * h), 1e-3);
        close(dv, (at(u, v + h) - at(u, v - h)) / (2.0 * h), 1e-3);
    }
}
