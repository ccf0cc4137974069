//! `<transform>`: a sequence of `translate`, `rotate`, `scale`, `matrix` and `lookat`
//! operations, composed in order as in Mitsuba 3 (each new operation is applied after the
//! previous ones: `M = op * M`).

use super::document::Element;
use super::values::{parse_float, tokens, vector3};
use super::LoadError;
use glam::{Mat3, Mat4, Vec3, Vec4};

/// The matrix of a `<transform>` element.
pub(super) fn parse(el: &Element) -> Result<Mat4, LoadError> {
    let mut m = Mat4::IDENTITY;
    for op in &el.children {
        if let Some(child) = op.children.first() {
            return Err(child.error(format!("<{}> takes no children", op.tag)));
        }
        let t = match op.tag.as_str() {
            "translate" => {
                op.check_attrs(&["value", "x", "y", "z"])?;
                Mat4::from_translation(named_vector(op, 0.0)?)
            }
            "scale" => {
                op.check_attrs(&["value", "x", "y", "z"])?;
                Mat4::from_scale(named_vector(op, 1.0)?)
            }
            "rotate" => {
                op.check_attrs(&["angle", "value", "x", "y", "z"])?;
                let axis = named_vector(op, 0.0)?;
                let angle = op.required_attr("angle")?;
                let angle = parse_float(angle).map_err(|m| op.error(format!("in 'angle': {m}")))?;
                if !angle.is_finite() {
                    return Err(op.error(format!("'angle' must be a finite number, got {angle}")));
                }
                rotate(axis, angle).map_err(|m| op.error(m))?
            }
            "matrix" => {
                op.check_attrs(&["value"])?;
                matrix(op.required_attr("value")?).map_err(|m| op.error(m))?
            }
            "lookat" => {
                op.check_attrs(&["origin", "target", "up"])?;
                let origin = vector3(op, op.required_attr("origin")?)?;
                let target = vector3(op, op.required_attr("target")?)?;
                let up = vector3(op, op.required_attr("up")?)?;
                look_at(origin, target, up).map_err(|m| op.error(m))?
            }
            other => {
                return Err(op.error(format!(
                    "unknown transform operation <{other}> \
                     (supported: translate, rotate, scale, matrix, lookat)"
                )))
            }
        };
        m = t * m;
        if !m.is_finite() {
            return Err(op.error("the transform is not finite"));
        }
    }
    Ok(m)
}

/// A vector from `value` (one number for all three, or three) or from `x`, `y`, `z`, whose
/// missing components are `default` (0 for `translate` and `rotate`, 1 for `scale`).
fn named_vector(op: &Element, default: f32) -> Result<Vec3, LoadError> {
    if let Some(v) = op.attr("value") {
        if ["x", "y", "z"].iter().any(|k| op.attr(k).is_some()) {
            return Err(op.error("give either 'value' or 'x', 'y', 'z', not both"));
        }
        return vector3(op, v);
    }
    let mut v = Vec3::splat(default);
    for (i, k) in ["x", "y", "z"].iter().enumerate() {
        if let Some(s) = op.attr(k) {
            v[i] = parse_float(s).map_err(|m| op.error(format!("in '{k}': {m}")))?;
            if !v[i].is_finite() {
                return Err(op.error(format!("'{k}' must be a finite number, got '{s}'")));
            }
        }
    }
    Ok(v)
}

/// Right-handed rotation by `angle_deg` degrees about `axis` (any length but zero).
pub(super) fn rotate(axis: Vec3, angle_deg: f32) -> Result<Mat4, String> {
    if !axis.is_finite() {
        return Err(format!("the rotation axis ({}, {}, {}) is not finite", axis.x, axis.y, axis.z));
    }
    // Scaled first, so that a huge axis (whose squared length overflows) or a tiny one (whose
    // squared length underflows) still gives its direction.
    let largest = axis.abs().max_element();
    let axis =
        (axis / largest).try_normalize().filter(|_| largest > 0.0).ok_or("the rotation axis is zero")?;
    Ok(Mat4::from_axis_angle(axis, angle_deg.to_radians()))
}

/// A matrix from 16 numbers (4x4) or 9 numbers (3x3 linear part), row by row.
fn matrix(value: &str) -> Result<Mat4, String> {
    let v = tokens(value).iter().map(|s| parse_float(s)).collect::<Result<Vec<f32>, String>>()?;
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return Err(format!("the matrix holds a number that is not finite ({x})"));
    }
    match v.len() {
        16 if v[12..] != [0.0, 0.0, 0.0, 1.0] => Err(format!(
            "the bottom row of a 4x4 matrix must be 0 0 0 1 (haze takes affine transforms only), \
             got {} {} {} {}",
            v[12], v[13], v[14], v[15]
        )),
        16 => Ok(Mat4::from_cols_slice(&v).transpose()),
        9 => Ok(Mat4::from_mat3(Mat3::from_cols_slice(&v).transpose())),
        n => Err(format!("expected 16 (or 9) values, got {n}")),
    }
}

/// Mitsuba 3's `Transform4f::look_at`: camera at `origin` looking at `target`. Columns are
/// `(left, up', dir, origin)` with `dir = normalize(target - origin)`,
/// `left = normalize(cross(up, dir))`, `up' = cross(dir, left)`.
pub(super) fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Result<Mat4, String> {
    let dir = target - origin;
    if !dir.is_finite() {
        return Err("lookat: origin and target are too far apart (target - origin is not finite)".into());
    }
    let dir = dir.try_normalize().ok_or("lookat: origin and target are the same point")?;
    let left = up.cross(dir);
    if left.length() <= 1e-6 * up.length().max(f32::MIN_POSITIVE) {
        return Err(format!(
            "lookat: the up vector ({}, {}, {}) is parallel to the viewing direction",
            up.x, up.y, up.z
        ));
    }
    let left = left.normalize();
    let new_up = dir.cross(left);
    Ok(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        Vec4::new(origin.x, origin.y, origin.z, 1.0),
    ))
}

/// If the linear part of `m` is a rotation (or reflection) times a uniform scale `s`, returns
/// `s`. Columns must be orthogonal and of equal length to a relative `1e-3`, the tolerance
/// Mitsuba 3 uses for `has_scale`.
pub(super) fn uniform_scale(m: &Mat4) -> Option<f32> {
    let l = Mat3::from_mat4(*m);
    let c = [l.x_axis, l.y_axis, l.z_axis];
    let s2 = (c[0].length_squared() + c[1].length_squared() + c[2].length_squared()) / 3.0;
    if !(s2 > 0.0 && s2.is_finite()) {
        return None;
    }
    for i in 0..3 {
        for j in 0..3 {
            let expected = if i == j { s2 } else { 0.0 };
            if (c[i].dot(c[j]) - expected).abs() > 1e-3 * s2 {
                return None;
            }
        }
    }
    Some(s2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xml::document;
    use std::path::Path;

    fn transform(ops: &str) -> Result<Mat4, LoadError> {
        let xml = format!("<scene version=\"3.0.0\"><transform name=\"to_world\">{ops}</transform></scene>");
        let doc = document::parse(&xml, Path::new("t.xml"), Path::new("."), &[])?;
        parse(&doc.root.children[0])
    }

    fn close(a: Mat4, b: Mat4) -> bool {
        a.abs_diff_eq(b, 1e-5)
    }

    #[test]
    fn operations_compose_left_multiplied_in_order() {
        // scale, then rotate 90 deg about z, then translate: p -> T * R * S * p.
        let m = transform(r#"<scale value="2"/><rotate z="1" angle="90"/><translate x="1" y="2" z="3"/>"#)
            .unwrap();
        // Hand-computed: S = 2I, R maps x->y, y->-x; T adds (1,2,3).
        let expected = Mat4::from_cols_array_2d(&[
            [0.0, 2.0, 0.0, 0.0],
            [-2.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 2.0, 0.0],
            [1.0, 2.0, 3.0, 1.0],
        ]);
        assert!(close(m, expected), "{m:?}");
        let p = m.transform_point3(Vec3::X);
        assert!((p - Vec3::new(1.0, 4.0, 3.0)).length() < 1e-5);
    }

    #[test]
    fn components_default_to_0_for_translate_and_1_for_scale() {
        let t = transform(r#"<translate y="2"/>"#).unwrap();
        assert!(close(t, Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0))));
        let s = transform(r#"<scale x="3"/>"#).unwrap();
        assert!(close(s, Mat4::from_scale(Vec3::new(3.0, 1.0, 1.0))));
        let v = transform(r#"<translate value="1, 2, 3"/>"#).unwrap();
        assert!(close(v, Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))));
    }

    #[test]
    fn rotation_is_right_handed() {
        let r = transform(r#"<rotate x="1" angle="90"/>"#).unwrap();
        assert!((r.transform_vector3(Vec3::Y) - Vec3::Z).length() < 1e-6);
        let r = transform(r#"<rotate value="0, 1, 0" angle="90"/>"#).unwrap();
        assert!((r.transform_vector3(Vec3::Z) - Vec3::X).length() < 1e-6);
        assert!(transform(r#"<rotate angle="90"/>"#).is_err());
    }

    #[test]
    fn matrix_is_row_major() {
        let m = transform(r#"<matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>"#).unwrap();
        assert!(close(m, Mat4::from_translation(Vec3::new(5.0, 6.0, 7.0))));
        let m3 = transform(r#"<matrix value="0 -1 0  1 0 0  0 0 1"/>"#).unwrap();
        assert!((m3.transform_vector3(Vec3::X) - Vec3::Y).length() < 1e-6);
        assert!(transform(r#"<matrix value="1 2 3"/>"#).is_err());
    }

    #[test]
    fn lookat_orientation() {
        let m = look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y).unwrap();
        // Camera looks down -z, so its local +z (dir) is world -z; +y stays up; local +x (left)
        // is world -x (the viewer's left when looking down -z).
        assert!((m.transform_vector3(Vec3::Z) - Vec3::NEG_Z).length() < 1e-6);
        assert!((m.transform_vector3(Vec3::Y) - Vec3::Y).length() < 1e-6);
        assert!((m.transform_vector3(Vec3::X) - Vec3::NEG_X).length() < 1e-6);
        assert!((m.transform_point3(Vec3::ZERO) - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-6);
        assert!(look_at(Vec3::ZERO, Vec3::Y, Vec3::Y).is_err());
        assert!(look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y).is_err());
    }

    #[test]
    fn uniform_scale_detection() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_y(0.3),
            Vec3::ONE,
        );
        assert!((uniform_scale(&m).unwrap() - 2.0).abs() < 1e-5);
        assert_eq!(uniform_scale(&Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0))), None);
        assert_eq!(uniform_scale(&Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))), Some(1.0));
        assert_eq!(uniform_scale(&Mat4::from_scale(Vec3::ZERO)), None);
    }
}
