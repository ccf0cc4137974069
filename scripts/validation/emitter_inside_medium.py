#!/usr/bin/env python3
"""Single scattering from an area light just beyond a null medium boundary, computed from the
radiative transfer equation alone (no renderer's code), for docs/validation.md
(`homo_emitter_inside_medium`, issue 37).

The configuration (`emitter_beyond_null_boundary.xml` beside this file; the same scene is built in
code by `crates/render/tests/analytic.rs`): a homogeneous medium (sigma_t = 1, albedo 0.9,
isotropic phase) fills the cube [-1, 1]^3, whose boundary is a `null` surface, in vacuum. A square
area light [-0.5, 0.5]^2 at height z_l, radiance 1, emits downwards (-z). The radiance along the
ray x(u) = (-0.9 + u, 0, 0.9), u in [0, 1.9] (it leaves the cube at x = 1 into an empty vacuum),
scattered once, is

    L_1 = Int_0^1.9 sigma_s e^(-sigma_t u) Int_A f_p L_e T(x, y) cos_l / r^2 dA(y) du

with f_p = 1 / (4 pi), r = |y - x|, cos_l = (z_l - 0.9) / r (the light's normal is -z) and T the
transmittance over the part of x -> y inside the cube: when z_l > 1 the segment leaves the cube
through its top face (the cube is convex and both ends lie over [-1, 1]^2), after
r (1 - 0.9) / (z_l - 0.9); when z_l < 1 it stays inside. Beyond the boundary there is nothing to
attenuate.

Two independent evaluations: tensor Gauss-Legendre quadrature (u and both coordinates of the
light, printed at two orders to show convergence) and plain Monte Carlo (u and y uniform).

The script also gives what a renderer that loses every next-event sample of these points would
return: the share of L_1 that volpath's phase-function samples carry under the power heuristic,
w = p_phase^2 / (p_phase^2 + p_light^2), p_phase = 1 / (4 pi), p_light = r^2 / (A cos_l). That is
Mitsuba 3's value when its shadow rays block their own light sample (docs/validation.md: after a
null crossing its shadow ray continues from an origin offset along the boundary's normal with the
remaining length unchanged, so it ends past the light's plane when the light is within about
(1 + max|x_c|) RayEpsilon / ShadowEpsilon = 0.2 of the scattering point, measured along the
light's normal).

Run (numpy; --mitsuba also renders the XML with Mitsuba 3, `pip install mitsuba`, scalar_rgb):

    python3 scripts/validation/emitter_inside_medium.py [--mitsuba]

Not run by CI; the Rust tests `shadow_rays_through_a_null_boundary_reach_a_light_just_beyond_it`
and `single_scattering_across_a_null_boundary_matches_quadrature` check haze against the same
integral.
"""

import argparse
import os

import numpy as np

SIGMA_T = 1.0
ALBEDO = 0.9
X0, Z0 = -0.9, 0.9  # the ray's origin (y = 0), direction +x
U_MAX = 1.9  # where the ray leaves the cube (x = 1)
HALF = 0.5  # the light is [-HALF, HALF]^2
AREA = (2 * HALF) ** 2
L_E = 1.0
F_P = 1.0 / (4.0 * np.pi)


def integrand(u, a, b, z_light):
    """sigma_s T(u) f_p L_e T(x, y) cos_l / r^2 at x = x(u), y = (a, b, z_light); also the
    power-heuristic weight of volpath's phase-function sample of y."""
    h = z_light - Z0  # height of the light's plane over the ray
    dx = a - (X0 + u)
    r2 = dx * dx + b * b + h * h
    r = np.sqrt(r2)
    cos_l = h / r
    inside = r * (1.0 - Z0) / h if z_light > 1.0 else r  # path length inside the cube
    f = ALBEDO * SIGMA_T * np.exp(-SIGMA_T * u) * F_P * L_E * np.exp(-SIGMA_T * inside) * cos_l / r2
    p_light = r2 / (AREA * cos_l)
    w_phase = F_P**2 / (F_P**2 + p_light**2)
    return f, w_phase


def quadrature(z_light, n):
    """Tensor Gauss-Legendre with n nodes per dimension, u in [0, U_MAX], a and b in
    [-HALF, HALF]: (L_1, the phase-sample share of L_1)."""
    x, w = np.polynomial.legendre.leggauss(n)
    u = 0.5 * U_MAX * (x + 1.0)
    wu = 0.5 * U_MAX * w
    a = HALF * x
    wa = HALF * w
    total = 0.0
    share = 0.0
    for ui, wui in zip(u, wu):
        f, wp = integrand(ui, a[:, None], a[None, :], z_light)
        ww = wui * wa[:, None] * wa[None, :]
        total += np.sum(ww * f)
        share += np.sum(ww * f * wp)
    return total, share


def monte_carlo(z_light, n, seed):
    """Plain Monte Carlo over u and the light's area: (mean, standard error)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, U_MAX, n)
    a = rng.uniform(-HALF, HALF, n)
    b = rng.uniform(-HALF, HALF, n)
    f, _ = integrand(u, a, b, z_light)
    est = f * U_MAX * AREA
    return est.mean(), est.std(ddof=1) / np.sqrt(n)


def mitsuba(z_light, seeds, spp):
    """Mitsuba 3 (scalar_rgb) on the XML beside this file, max_depth 2 (single scattering):
    (mean, standard error) over the seeds."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    xml = os.path.join(os.path.dirname(os.path.abspath(__file__)), "emitter_beyond_null_boundary.xml")
    scene = mi.load_file(xml, z_light=repr(z_light), spp=str(spp), max_depth="2")
    vals = np.array([np.array(mi.render(scene, seed=s)).ravel()[0] for s in range(seeds)])
    return vals.mean(), vals.std(ddof=1) / np.sqrt(seeds)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mitsuba", action="store_true", help="also render with Mitsuba 3")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--spp", type=int, default=65536)
    args = ap.parse_args()
    # z_l = 1.01: the light 0.01 beyond the boundary, 0.11 over the ray (the case); 1.08 and
    # 1.12: 0.18 and 0.22 over the ray, either side of Mitsuba's 0.2; 1.3: 0.4 over the ray
    # (control: far enough); 0.99: inside the medium (control: no crossing).
    for z_light in (1.01, 1.08, 1.12, 1.3, 0.99):
        q1, s1 = quadrature(z_light, 96)
        q2, s2 = quadrature(z_light, 192)
        mc, mc_se = monte_carlo(z_light, 4_000_000, 1)
        line = (
            f"z_light {z_light}: quadrature {q2:.6f} (96 nodes: {q1:.6f}), "
            f"Monte Carlo {mc:.6f} +- {mc_se:.6f}, phase-sample share {s2:.6f}"
        )
        if args.mitsuba:
            m, m_se = mitsuba(z_light, args.seeds, args.spp)
            line += f", Mitsuba 3 {m:.6f} +- {m_se:.6f} (ratio to quadrature {m / q2:.4f})"
        print(line)


if __name__ == "__main__":
    main()
