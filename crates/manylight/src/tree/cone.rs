//! Cones of undirected directions: every VRL of a node lies along a line whose direction is
//! within `half_angle` of `axis` or of `-axis`. The tight VRL bound ([`super::bound`]) uses them
//! for the smallest sine of the angle between the camera ray and a VRL of the node.

use super::LightTree;
use glam::Vec3;
use std::f32::consts::FRAC_PI_2;

/// A cone of lines: axis (unit) and half-angle in radians, at most `pi/2` (all lines).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineCone {
    pub axis: Vec3,
    pub half_angle: f32,
}

/// Slack added at every merge against rounding in the angles (radians).
const ANGLE_SLACK: f32 = 1e-4;

impl LineCone {
    pub const ALL: LineCone = LineCone { axis: Vec3::Z, half_angle: FRAC_PI_2 };

    /// The cone of one line with unit direction `d`.
    pub fn line(d: Vec3) -> Self {
        LineCone { axis: d, half_angle: 0.0 }
    }

    /// Smallest cone holding both (the usual cone union, Shkurko et al. 2017 / Conty & Kulla
    /// 2018 "bounding cones", after flipping `b` to the side of `a`: lines have no sign).
    pub fn union(&self, b: &LineCone) -> LineCone {
        if self.half_angle >= FRAC_PI_2 || b.half_angle >= FRAC_PI_2 {
            return LineCone::ALL;
        }
        let bx = if self.axis.dot(b.axis) < 0.0 { -b.axis } else { b.axis };
        // atan2 of sine and cosine: acos loses ~1e-4 rad near 0 in f32.
        let theta = self.axis.cross(bx).length().atan2(self.axis.dot(bx));
        // Containment: the max keeps the cone closed under rounding of `theta`.
        if theta + b.half_angle <= self.half_angle + ANGLE_SLACK {
            return LineCone { axis: self.axis, half_angle: self.half_angle.max(theta + b.half_angle) };
        }
        if theta + self.half_angle <= b.half_angle + ANGLE_SLACK {
            return LineCone { axis: bx, half_angle: b.half_angle.max(theta + self.half_angle) };
        }
        let half = 0.5 * (theta + self.half_angle + b.half_angle) + ANGLE_SLACK;
        if half >= FRAC_PI_2 || theta < 1e-6 {
            return if half >= FRAC_PI_2 {
                LineCone::ALL
            } else {
                LineCone { axis: self.axis, half_angle: half }
            };
        }
        // Rotate `a`'s axis towards `b`'s by `half - a.half_angle` in their common plane.
        let rot = half - self.half_angle;
        let ortho = (bx - self.axis * self.axis.dot(bx)).normalize();
        let axis = (self.axis * rot.cos() + ortho * rot.sin()).normalize();
        LineCone { axis, half_angle: half }
    }

    /// Lower bound of `sin` of the angle between the line along unit `c` and any line of the cone:
    /// `sin(max(0, phi - half_angle))`, `phi = acos|c . axis|` the angle between the lines.
    pub fn min_sine(&self, c: Vec3) -> f32 {
        let phi = c.cross(self.axis).length().atan2(c.dot(self.axis).abs());
        (phi - self.half_angle).max(0.0).sin()
    }
}

/// The cone of every node of `tree`, given each light's direction. Children come before their
/// parent in `tree.nodes` (both builders append a node after its children), so one pass suffices.
pub fn node_cones(tree: &LightTree, direction: impl Fn(u32) -> Vec3) -> Vec<LineCone> {
    let mut cones = vec![LineCone::ALL; tree.nodes.len()];
    for (i, n) in tree.nodes.iter().enumerate() {
        cones[i] = if n.is_leaf() {
            LineCone::line(direction(n.rep))
        } else {
            debug_assert!((n.left as usize) < i && (n.right as usize) < i);
            cones[n.left as usize].union(&cones[n.right as usize])
        };
    }
    cones
}

/// A cone of directed directions (unit axis, half-angle in `[0, pi]`): the VRLs' propagation
/// directions below a node, for the light-side phase of the tight bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirCone {
    pub axis: Vec3,
    pub half_angle: f32,
}

impl DirCone {
    pub const ALL: DirCone = DirCone { axis: Vec3::Z, half_angle: std::f32::consts::PI };

    /// The usual cone union (as [`LineCone::union`] without the sign flip).
    pub fn union(&self, b: &DirCone) -> DirCone {
        use std::f32::consts::PI;
        if self.half_angle >= PI || b.half_angle >= PI {
            return DirCone::ALL;
        }
        let theta = self.axis.cross(b.axis).length().atan2(self.axis.dot(b.axis));
        // Containment: the max keeps the cone closed under rounding of `theta`.
        if theta + b.half_angle <= self.half_angle + ANGLE_SLACK {
            return DirCone { axis: self.axis, half_angle: self.half_angle.max(theta + b.half_angle) };
        }
        if theta + self.half_angle <= b.half_angle + ANGLE_SLACK {
            return DirCone { axis: b.axis, half_angle: b.half_angle.max(theta + self.half_angle) };
        }
        let half = 0.5 * (theta + self.half_angle + b.half_angle) + ANGLE_SLACK;
        if half >= PI {
            return DirCone::ALL;
        }
        let ortho = b.axis - self.axis * self.axis.dot(b.axis);
        if ortho.length_squared() < 1e-12 {
            // Opposite axes (theta = pi): no unique plane; every direction is within `half`.
            return DirCone::ALL;
        }
        let rot = half - self.half_angle;
        let axis = (self.axis * rot.cos() + ortho.normalize() * rot.sin()).normalize();
        DirCone { axis, half_angle: half }
    }
}

/// [`node_cones`] for directed cones.
pub fn node_dir_cones(tree: &LightTree, direction: impl Fn(u32) -> Vec3) -> Vec<DirCone> {
    let mut cones = vec![DirCone::ALL; tree.nodes.len()];
    for (i, n) in tree.nodes.iter().enumerate() {
        cones[i] = if n.is_leaf() {
            DirCone { axis: direction(n.rep), half_angle: 0.0 }
        } else {
            cones[n.left as usize].union(&cones[n.right as usize])
        };
    }
    cones
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::sampling::sample_uniform_sphere;
    use haze_core::Sampler;

    /// 2000 pairs of random cones, each the repeated union of 1 to 4 unit vectors within
    /// `max_spread` of a random axis (each negated at random if `flip`), and the union of the
    /// pair: `check(union, the vectors of both, sampler)`.
    fn for_random_unions<C>(
        seed: u64,
        max_spread: f32,
        flip: bool,
        single: impl Fn(Vec3) -> C,
        union: impl Fn(&C, &C) -> C,
        mut check: impl FnMut(&C, &[Vec3], &mut Sampler),
    ) {
        let mut s = Sampler::from_seed(seed);
        let make = |s: &mut Sampler, members: &mut Vec<Vec3>| -> C {
            let a = sample_uniform_sphere(s.next_2d());
            let spread = s.next_1d() * max_spread;
            let k = 1 + (s.next_1d() * 4.0) as usize;
            let start = members.len();
            for _ in 0..k {
                let d = (a + sample_uniform_sphere(s.next_2d()) * spread).normalize();
                members.push(if flip && s.next_1d() < 0.5 { -d } else { d });
            }
            members[start + 1..].iter().fold(single(members[start]), |c, &d| union(&c, &single(d)))
        };
        let mut members = Vec::new();
        for _ in 0..2000 {
            members.clear();
            let a = make(&mut s, &mut members);
            let b = make(&mut s, &mut members);
            check(&union(&a, &b), &members, &mut s);
        }
    }

    /// The union holds both cones' lines, and `min_sine` bounds the sine towards each of them.
    #[test]
    fn line_union_contains_both_cones() {
        for_random_unions(4, 0.8, true, LineCone::line, LineCone::union, |u, lines, s| {
            for l in lines {
                let angle = l.cross(u.axis).length().atan2(l.dot(u.axis).abs());
                assert!(angle <= u.half_angle + 1e-5, "line at {angle} outside cone {u:?}");
                let c = sample_uniform_sphere(s.next_2d());
                assert!(u.min_sine(c) <= c.cross(*l).length() + 1e-5);
            }
        });
    }

    /// The union holds both cones' directions.
    #[test]
    fn dir_union_contains_both_cones() {
        let single = |d| DirCone { axis: d, half_angle: 0.0 };
        for_random_unions(8, 1.5, false, single, DirCone::union, |u, ds, _| {
            for d in ds {
                let angle = d.cross(u.axis).length().atan2(d.dot(u.axis));
                assert!(angle <= u.half_angle + 1e-5, "direction at {angle} outside cone {u:?}");
            }
        });
    }
}
