//! Upper bounds of a light cluster's contribution to a camera segment (`docs/theory.md` §7; the paper's
//! bound from the seed slides and a strictly conservative variant of ours).
//!
//! For a VRL cluster the sampled contribution of any of its VRLs is
//! `Phi f T_c(u) T_r(w) Theta / (h p(v))` (the estimator's `1/(w^2 p(u,v)) = Theta/(h p(v))`),
//! with `1/(h(v) p(v)) = (A_b - A_a)/sin(theta) = Int_VRL dv / h(v) <= L / min_v h(v)`,
//! `h(v)` the distance to the camera's **infinite line**. Hence:
//!
//! - **paper**: `B = Phi f_max T_r(h_min) Theta_max L_max / h_min`, `h_min` the distance from the
//!   cluster's box to the camera **segment** (Vibert et al. 2019).
//! - **conservative**: the same with `1/h_line`, `h_line <= h_min` the distance from the box to the
//!   camera's infinite line. Never below a sample (checked by a randomized test), while the paper's
//!   bound can be, when the box lies beyond the segment's ends near its line.
//!
//! Both use `Theta_max = min(pi, 2 atan(s / (2 h_min)))`: every point at distance `>= h_min`
//! from a segment of length `s` sees it under at most that angle (the points seeing it under a
//! larger angle lie inside the spindle through its endpoints, whose farthest point from the
//! segment is on the perpendicular bisector at `h_min`). [`ThetaBound::Pi`] gives the paper's
//! "pi when in doubt".
//!
//! For VPLs the estimate is `Phi f Tr Theta / h` (equiangular, `h` to the infinite line), so
//! `B_vpl = Phi f_max T_r(h_min) Theta_max / h` with the same two choices of `h`.

use super::{Aabb, Node};
use crate::vrl::Segment;
use haze_core::Rgb;

/// Which bound the cut uses (`--bound`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundKind {
    Paper,
    Conservative,
    /// Conservative, with `Int dv / h(v)` bounded through the VRLs' directions
    /// ([`inverse_distance_integral`]): grows like `log(1/h)` instead of `1/h` near the camera
    /// line. VPL clusters use the conservative bound.
    Tight,
}

/// How `Theta_max` is bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThetaBound {
    /// `min(pi, 2 atan(s / (2 h_min)))`.
    Exact,
    /// `pi`.
    Pi,
}

/// Everything about the camera segment and the media that the bound needs, per segment.
#[derive(Clone, Copy, Debug)]
pub struct BoundContext {
    pub seg: Segment,
    /// `sigma_s` on the camera side times the camera medium's phase maximum, per channel.
    pub camera_factor: Rgb,
    /// Largest `sigma_s` times phase maximum over the media that lights can be in, per channel.
    pub light_factor: Rgb,
    /// Smallest extinction along any connection (0 if a connection may cross vacuum), per channel.
    pub sigma_t_min: Rgb,
    pub kind: BoundKind,
    pub theta: ThetaBound,
    /// The camera medium's phase function ([`BoundKind::Tight`] bounds it over the directions
    /// from the segment to a node's box instead of taking its maximum).
    pub camera_phase: haze_core::Phase,
    /// The phase function every light medium shares, if they share one ([`BoundKind::Tight`]
    /// then bounds the light-side phase over the node's directions; `None`: its maximum).
    pub light_phase: Option<haze_core::Phase>,
}

impl BoundContext {
    /// Bound (max over channels) for a VRL cluster, from its box.
    pub fn vrl(&self, node: &Node) -> f32 {
        let (h_seg, h_line) = distances(&self.seg, &node.bounds);
        self.finish(node, h_seg, h_line, node.l_max)
    }

    /// Bound (max over channels) for a VPL cluster, from its box.
    pub fn vpl(&self, node: &Node) -> f32 {
        let (h_seg, h_line) = distances(&self.seg, &node.bounds);
        self.finish(node, h_seg, h_line, 1.0)
    }

    /// `Phi f_max T_r(h_min) Theta_max`.
    fn common(&self, node: &Node, h_seg: f32) -> Rgb {
        let theta = match self.theta {
            ThetaBound::Pi => std::f32::consts::PI,
            ThetaBound::Exact => (2.0 * (self.seg.len / (2.0 * h_seg)).atan()).min(std::f32::consts::PI),
        };
        node.flux_bound * self.light_factor * self.camera_factor * self.sigma_t_min.exp_neg(h_seg) * theta
    }
}

/// Distances from the box to the segment and to the segment's infinite line: the minimum over
/// `t` of the point-to-box distance of `o + t d`, a convex piecewise quadratic in `t`, minimised
/// exactly on each piece between the `t` where a coordinate crosses a slab boundary.
pub fn distances(seg: &Segment, b: &Aabb) -> (f32, f32) {
    (min_distance(seg, b, 0.0, seg.len), min_distance(seg, b, f32::NEG_INFINITY, f32::INFINITY))
}

fn min_distance(seg: &Segment, b: &Aabb, t0: f32, t1: f32) -> f32 {
    let o = seg.o.as_dvec3();
    let d = seg.d.as_dvec3();
    let (lo, hi) = (b.lo.as_dvec3(), b.hi.as_dvec3());
    // Breakpoints where o + t d crosses a slab plane, within [t0, t1].
    let mut ts = [0.0f64; 8];
    let mut n = 0;
    for a in 0..3 {
        if d[a] != 0.0 {
            for plane in [lo[a], hi[a]] {
                let t = (plane - o[a]) / d[a];
                if t > t0 as f64 && t < t1 as f64 {
                    ts[n] = t;
                    n += 1;
                }
            }
        }
    }
    let ts = &mut ts[..n];
    ts.sort_unstable_by(f64::total_cmp);
    // Minimise on each piece; on a piece every axis is below, inside or above its slab, so the
    // squared distance is sum_a (o_a + t d_a - c_a)^2 over the axes outside, c_a the violated bound.
    let dist2 = |t: f64| -> f64 {
        let p = o + d * t;
        let q = p.clamp(lo, hi);
        (p - q).length_squared()
    };
    let mut best = f64::INFINITY;
    let mut edges = [0.0f64; 10];
    let mut m = 0;
    let (a0, a1) = (t0 as f64, t1 as f64);
    edges[m] = a0;
    m += 1;
    for &t in ts.iter() {
        edges[m] = t;
        m += 1;
    }
    edges[m] = a1;
    m += 1;
    for w in edges[..m].windows(2) {
        let (l, r) = (w[0], w[1]);
        // A point inside the piece tells which axes are outside the box there.
        let mid = if l.is_finite() && r.is_finite() {
            0.5 * (l + r)
        } else if l.is_finite() {
            l + 1.0
        } else if r.is_finite() {
            r - 1.0
        } else {
            0.0
        };
        let p = o + d * mid;
        let (mut qa, mut qb) = (0.0f64, 0.0f64); // minimise qa t^2 + qb t + ...
        for a in 0..3 {
            let c = if p[a] < lo[a] {
                lo[a]
            } else if p[a] > hi[a] {
                hi[a]
            } else {
                continue;
            };
            qa += d[a] * d[a];
            qb += 2.0 * d[a] * (o[a] - c);
        }
        let t = if qa > 0.0 { (-qb / (2.0 * qa)).clamp(l, r) } else { mid.clamp(l, r) };
        for cand in [t, l, r] {
            if cand.is_finite() {
                best = best.min(dist2(cand));
            }
        }
    }
    best.sqrt() as f32
}

/// Clusters with at most this many lights are bounded with the distances to their lights
/// themselves rather than to their box (our refinement of the paper's bound: a box around a
/// few VRLs often touches the camera segment although none of the VRLs comes close to it).
pub const EXACT_DISTANCE_MAX_COUNT: u32 = 8;

impl BoundContext {
    /// Like [`Self::vrl`], but for a cluster of at most [`EXACT_DISTANCE_MAX_COUNT`] VRLs uses
    /// the smallest segment-to-segment and segment-to-line distances of its VRLs (still an
    /// upper bound of every sample: `w >= min_i dist(cam, VRL_i)` and
    /// `h(v) >= min_i dist(camera line, VRL_i)`).
    pub fn vrl_in_tree(&self, tree: &super::LightTree, node: &Node, vrls: &[crate::vrl::Vrl]) -> f32 {
        if node.count > EXACT_DISTANCE_MAX_COUNT {
            return self.vrl(node);
        }
        let (mut h_seg, mut h_line) = (f32::INFINITY, f32::INFINITY);
        for_each_light(tree, node, |i| {
            let s = &vrls[i as usize].seg;
            h_seg = h_seg.min(segment_segment_distance(&self.seg, s));
            h_line = h_line.min(line_segment_distance(&self.seg, s));
        });
        self.finish(node, h_seg, h_line, node.l_max)
    }

    /// Like [`Self::vpl`] with the VPLs' own distances for small clusters.
    pub fn vpl_in_tree(&self, tree: &super::LightTree, node: &Node, vpls: &[crate::vpl::Vpl]) -> f32 {
        if node.count > EXACT_DISTANCE_MAX_COUNT {
            return self.vpl(node);
        }
        let (mut h_seg, mut h_line) = (f32::INFINITY, f32::INFINITY);
        for_each_light(tree, node, |i| {
            let p = vpls[i as usize].p;
            h_seg = h_seg.min(point_segment_distance(&self.seg, p));
            h_line = h_line.min(point_line_distance(&self.seg, p));
        });
        self.finish(node, h_seg, h_line, 1.0)
    }

    /// `common * length / h`, with `h` the segment or line distance as `kind` says; `length` is
    /// `L_max` for VRLs and 1 for VPLs.
    fn finish(&self, node: &Node, h_seg: f32, h_line: f32, length: f32) -> f32 {
        let h = match self.kind {
            BoundKind::Paper => h_seg,
            BoundKind::Conservative | BoundKind::Tight => h_line,
        };
        if h <= 0.0 {
            return f32::INFINITY;
        }
        (self.common(node, h_seg) * (length / h)).max_component()
    }
}

/// Upper bound of `Int_0^L dv / h(v)` over a VRL of length at most `l` whose distance to the
/// camera's infinite line is `h(v)`, given `h(v) >= h` everywhere and `s` at most the sine of the
/// angle between the VRL and the camera line.
///
/// `h(v)^2 = h0^2 + s^2 (v - v0)^2` (the perpendicular part of the VRL's points grows linearly
/// with slope `s`), so `h(v) >= max(h, s |v - v0|)`. The integral of `1 / max(h, s |v - v0|)`
/// over an interval of length `l` is largest with the interval centred on `v0`:
/// `2 (h/s) / h + 2 Int_{h/s}^{l/2} dv / (s v) = (2/s) (1 + ln(l s / (2h)))` when `l s > 2h`,
/// else `l / h`. This is the sinh sampling's `1/(h p(v)) = (asinh(b/h0) - asinh(a/h0)) / s`
/// (`docs/theory.md` (T7)) bounded without knowing `h0`: logarithmic in `1/h`, where the paper's `L/h` is
/// linear. Non-increasing in `s` and `h`, non-decreasing in `l`.
pub fn inverse_distance_integral(l: f32, s: f32, h: f32) -> f32 {
    if h <= 0.0 {
        return f32::INFINITY;
    }
    let x = l * s / (2.0 * h);
    if x <= 1.0 {
        l / h
    } else {
        (2.0 / s) * (1.0 + x.ln())
    }
}

impl BoundContext {
    /// The bound the cut uses for VRL node `index` (`node = tree.nodes[index]`): for
    /// [`BoundKind::Tight`], `Phi f_max T_r(h_seg) Theta_max Int dv/h(v)` with the integral
    /// bounded by [`inverse_distance_integral`] from the VRLs' own segment-to-line distances
    /// and angles (clusters of at most [`EXACT_DISTANCE_MAX_COUNT`]) or from the box-to-line
    /// distance, `L_max` and the node's cone of directions; otherwise [`Self::vrl_in_tree`].
    pub fn vrl_node(
        &self,
        tree: &super::LightTree,
        index: u32,
        vrls: &[crate::vrl::Vrl],
        cones: &[super::cone::LineCone],
        dir_cones: &[super::cone::DirCone],
    ) -> f32 {
        let node = &tree.nodes[index as usize];
        if self.kind != BoundKind::Tight {
            return self.vrl_in_tree(tree, node, vrls);
        }
        let dir_cone = &dir_cones[index as usize];
        if node.count > EXACT_DISTANCE_MAX_COUNT {
            return self.vrl_box_and_cone(node, &cones[index as usize], dir_cone);
        }
        let (h_seg, integral) = {
            let (mut h_seg, mut integral) = (f32::INFINITY, 0.0f32);
            for_each_light(tree, node, |i| {
                let v = &vrls[i as usize].seg;
                h_seg = h_seg.min(segment_segment_distance(&self.seg, v));
                let s = self.seg.d.cross(v.d).length();
                integral =
                    integral.max(inverse_distance_integral(v.len, s, line_segment_distance(&self.seg, v)));
            });
            (h_seg, integral)
        };
        if !integral.is_finite() {
            return f32::INFINITY;
        }
        let h_line = distances(&self.seg, &node.bounds).1;
        let phases = self.camera_phase_scale(node, h_line) * self.light_phase_scale(node, dir_cone);
        (self.common(node, h_seg) * integral * phases).max_component()
    }

    /// The tight bound of a VRL node from its box and its cone of directions:
    /// `Phi f T_r(h_seg) Theta_max I(L_max, s_min, h_line)` with [`inverse_distance_integral`],
    /// `s_min` from the cone and the camera phase bounded over the box
    /// ([`Self::camera_phase_scale`]).
    pub fn vrl_box_and_cone(
        &self,
        node: &Node,
        cone: &super::cone::LineCone,
        dir_cone: &super::cone::DirCone,
    ) -> f32 {
        let (h_seg, h_line) = distances(&self.seg, &node.bounds);
        let integral = inverse_distance_integral(node.l_max, cone.min_sine(self.seg.d), h_line);
        if !integral.is_finite() {
            return f32::INFINITY;
        }
        let phases = self.camera_phase_scale(node, h_line) * self.light_phase_scale(node, dir_cone);
        (self.common(node, h_seg) * integral * phases).max_component()
    }

    /// `max p_light / p_light max` over the node's VRL directions and the connections from its
    /// box to the camera segment (1 unless every light medium shares one HG phase). The light
    /// phase is evaluated at `cos = d_vrl . n`, `n = (y - x)/|y - x|` from the light point to the
    /// camera point (estimator's `phase.eval(vrl.d, n)`). With the box and the segment in balls
    /// `(c_b, r_b)` and `(c_s, r_s)` at distance `D > r_b + r_s`, every `y - x` lies in the ball
    /// `(c_s - c_b, r_b + r_s)`, so `n` is within `beta = asin((r_b + r_s)/D)` of
    /// `m = (c_s - c_b)/D`; `d_vrl` is within the cone's half-angle `alpha` of its axis, so the
    /// angle between them is at least `angle(axis, m) - alpha - beta` (at most that plus, for
    /// `g < 0`), and HG is monotone in `cos`.
    fn light_phase_scale(&self, node: &Node, cone: &super::cone::DirCone) -> f32 {
        let Some(phase @ haze_core::Phase::HenyeyGreenstein { g }) = self.light_phase else {
            return 1.0;
        };
        let (cb, rb) = (node.bounds.center(), 0.5 * node.bounds.diagonal());
        let rs = 0.5 * self.seg.len;
        let m = self.seg.at(rs) - cb;
        let dist = m.length();
        let r = (rb + rs) * (1.0 + 1e-4) + 1e-6;
        if dist <= r {
            return 1.0;
        }
        let beta = (r / dist).asin() + 1e-4;
        let phi = cone.axis.cross(m).length().atan2(cone.axis.dot(m));
        let cos = if g > 0.0 {
            (phi - cone.half_angle - beta).max(0.0).cos()
        } else {
            (phi + cone.half_angle + beta).min(std::f32::consts::PI).cos()
        };
        (haze_core::phase::hg(cos, g) / phase.max_value()).min(1.0)
    }

    /// `max p_cam / p_cam max` over the connections from the camera segment to the node's box
    /// (1 for the isotropic phase). The camera phase is evaluated at `cos = d . (x - y) / |x - y|`
    /// (`y = o + u d` on the segment, `x` the light point; estimator's `phase.eval(n, -d)`).
    /// Writing `x - y = a d + p` with `p` perpendicular to `d`: `|p| >= h_line` (box to camera
    /// line) and `a` lies in `[min_box d.(x-o) - len, max_box d.(x-o)]`, so
    /// `cos <= a_max / sqrt(a_max^2 + h_line^2)` if `a_max > 0` (else `cos <= 0`) and
    /// `cos >= a_min / sqrt(a_min^2 + h_line^2)` if `a_min < 0` (else `cos >= 0`). HG is
    /// monotone in `cos` (increasing for `g > 0`), so it is bounded at that end.
    fn camera_phase_scale(&self, node: &Node, h_line: f32) -> f32 {
        let haze_core::Phase::HenyeyGreenstein { g } = self.camera_phase else {
            return 1.0;
        };
        let (d, o, b) = (self.seg.d, self.seg.o, &node.bounds);
        let proj = |pick_max: bool| -> f32 {
            (0..3)
                .map(|k| {
                    let (l, h) = (d[k] * b.lo[k], d[k] * b.hi[k]);
                    if pick_max {
                        l.max(h)
                    } else {
                        l.min(h)
                    }
                })
                .sum::<f32>()
                - d.dot(o)
        };
        let cos = if g > 0.0 {
            let a = proj(true);
            if a > 0.0 {
                a / (a * a + h_line * h_line).sqrt()
            } else {
                0.0
            }
        } else {
            let a = proj(false) - self.seg.len;
            if a < 0.0 {
                a / (a * a + h_line * h_line).sqrt()
            } else {
                0.0
            }
        };
        (haze_core::phase::hg(cos, g) / self.camera_phase.max_value()).min(1.0)
    }
}

/// Calls `f` with the light index of every leaf below `node`.
pub(crate) fn for_each_light(tree: &super::LightTree, node: &Node, mut f: impl FnMut(u32)) {
    let mut stack = [0u32; 64];
    let mut top = 0;
    if node.is_leaf() {
        f(node.rep);
        return;
    }
    stack[top] = node.left;
    stack[top + 1] = node.right;
    top += 2;
    while top > 0 {
        top -= 1;
        let n = &tree.nodes[stack[top] as usize];
        if n.is_leaf() {
            f(n.rep);
        } else if top + 2 <= stack.len() {
            stack[top] = n.left;
            stack[top + 1] = n.right;
            top += 2;
        }
    }
}

/// Distance between two segments (closest points by clamped parameters; Ericson 2004,
/// "Real-Time Collision Detection", 5.1.9), in f64.
pub fn segment_segment_distance(a: &Segment, b: &Segment) -> f32 {
    let (p, u, la) = (a.o.as_dvec3(), a.d.as_dvec3(), a.len as f64);
    let (q, v, lb) = (b.o.as_dvec3(), b.d.as_dvec3(), b.len as f64);
    let w0 = p - q;
    let (bb, d, e) = (u.dot(v), u.dot(w0), v.dot(w0));
    let denom = 1.0 - bb * bb;
    let mut s = if denom > 1e-12 { ((bb * e - d) / denom).clamp(0.0, la) } else { 0.0 };
    let mut t = e + s * bb;
    if t < 0.0 {
        t = 0.0;
        s = (-d).clamp(0.0, la);
    } else if t > lb {
        t = lb;
        s = (bb * lb - d).clamp(0.0, la);
    }
    (w0 + u * s - v * t).length() as f32
}

/// Distance from segment `b` to the infinite line through segment `a`.
pub fn line_segment_distance(a: &Segment, b: &Segment) -> f32 {
    let (p, u) = (a.o.as_dvec3(), a.d.as_dvec3());
    let (q, v, lb) = (b.o.as_dvec3(), b.d.as_dvec3(), b.len as f64);
    let w0 = q - p;
    let perp0 = w0 - u * w0.dot(u);
    let perp_d = v - u * v.dot(u);
    let pp = perp_d.length_squared();
    let t = if pp > 1e-24 { (-perp0.dot(perp_d) / pp).clamp(0.0, lb) } else { 0.0 };
    (perp0 + perp_d * t).length() as f32
}

pub fn point_segment_distance(a: &Segment, x: glam::Vec3) -> f32 {
    let t = (x - a.o).dot(a.d).clamp(0.0, a.len);
    (x - a.at(t)).length()
}

pub fn point_line_distance(a: &Segment, x: glam::Vec3) -> f32 {
    let w = x - a.o;
    (w - a.d * w.dot(a.d)).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use haze_core::Sampler;

    fn brute(seg: &Segment, b: &Aabb, t0: f32, t1: f32) -> f32 {
        let n = 20_000;
        (0..=n)
            .map(|i| {
                let t = t0 + (t1 - t0) * i as f32 / n as f32;
                let p = seg.at(t);
                (p - p.clamp(b.lo, b.hi)).length()
            })
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn segment_distances_match_dense_sampling() {
        let mut s = Sampler::from_seed(5);
        let mut r = || Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0 - 2.0;
        for _ in 0..300 {
            let a = Segment::from_points(r(), r());
            let b = Segment::from_points(r(), r());
            let n = 600;
            let mut best = f32::INFINITY;
            let mut best_line = f32::INFINITY;
            for i in 0..=n {
                let y = b.at(b.len * i as f32 / n as f32);
                best = best.min(point_segment_distance(&a, y));
                best_line = best_line.min(point_line_distance(&a, y));
            }
            let d = segment_segment_distance(&a, &b);
            assert!(d <= best + 1e-5 && d >= best - 2e-2 * (1.0 + b.len / n as f32 * 10.0), "{d} vs {best}");
            let dl = line_segment_distance(&a, &b);
            assert!(dl <= best_line + 1e-5 && dl >= best_line - 2e-2, "{dl} vs {best_line}");
            assert!(dl <= d + 1e-5);
        }
    }

    #[test]
    fn segment_box_distance_matches_dense_sampling() {
        let mut s = Sampler::from_seed(3);
        let mut r = || Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0 - 2.0;
        for _ in 0..500 {
            let b = Aabb::from_points(r(), r());
            let (o, e) = (r(), r());
            let seg = Segment::from_points(o, e);
            let (h_seg, h_line) = distances(&seg, &b);
            let bf = brute(&seg, &b, 0.0, seg.len);
            assert!(h_seg <= bf + 1e-5 && h_seg >= bf - 1e-3, "{h_seg} vs {bf}");
            let bf_line = brute(&seg, &b, -50.0, 50.0);
            assert!(h_line <= bf_line + 1e-4 && h_line <= h_seg + 1e-6, "{h_line} vs {bf_line}");
        }
    }
}
