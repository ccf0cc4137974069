#!/usr/bin/env python3
"""Where the time of a haze render goes, by category, from a `perf record --call-graph dwarf`
profile (see scripts/profile.sh).

Reads `perf script -F ip,sym --inline` on stdin. Each sample's stack is walked from the leaf
towards the root and charged to the first frame (inlined frames included) that matches a rule
below; libm, memcpy and other unmatched leaves are thus charged to their caller. BVH samples are
split by whether the query came from a shadow ray (`transmittance_to`) or a path ray.
"""
import re
import sys
from collections import Counter

# (category, regex on the frame's symbol), first match wins within a frame.
RULES = [
    ("BVH traversal", re.compile(r"obvhs::|accel::|watertight|Accel::|Scene::intersect|Scene::occluded")),
    ("RNG", re.compile(r"rand_pcg|rand_core|rng::Sampler|haze_core::rng")),
    ("film accumulation", re.compile(r"Film::add_sample|film::Film")),
    ("camera rays", re.compile(r"camera::|sample_film_position|PixelFilter")),
    ("medium sampling", re.compile(r"sample_free_flight|hero_channel")),
    ("transmittance (Beer-Lambert)", re.compile(r"beer_lambert|transmittance::transmittance")),
    ("emitter sampling / evaluation", re.compile(r"sample_emitter_direction|area_radiance|area_emitter_pdf|environment_emission|emitter|lights::|envmap")),
    ("shading (phase, BSDF, frames, MIS)", re.compile(r"phase::|bsdf::|Bsdf|frame::Frame|power_heuristic|texture::|offset_origin|medium_towards")),
    ("shadow-ray loop (transmittance_to)", re.compile(r"transmittance_to")),
    ("path loop (integrator radiance)", re.compile(r"Integrator>::radiance|::radiance")),
    ("render loop / per-pass", re.compile(r"progressive::render|begin_pass|passes::")),
    ("scheduling (rayon, kernel, idle)", re.compile(r"rayon|crossbeam|^ffffffff|\[kernel|futex|sched_yield|syscall|clone3|__GI___sched")),
]


def classify(frames):
    for sym in frames:
        for cat, rx in RULES:
            if rx.search(sym):
                if cat == "BVH traversal":
                    shadow = any("transmittance_to" in f for f in frames)
                    return "BVH traversal (shadow rays)" if shadow else "BVH traversal (path rays)"
                return cat
    return "other (start-up, loading, libm at top level)"


def main():
    counts = Counter()
    frames = []
    total = 0
    for line in sys.stdin:
        s = line.strip()
        if not s:
            if frames:
                counts[classify(frames)] += 1
                total += 1
            frames = []
            continue
        if line[0] not in " \t":
            continue  # sample header
        parts = s.split(None, 1)
        sym = parts[1] if len(parts) > 1 else ""
        if parts[0].startswith("ffffffff"):
            sym = "ffffffff " + sym
        frames.append(sym)
    if frames:
        counts[classify(frames)] += 1
        total += 1
    print(f"| category | share of samples ({total}) |")
    print("|---|---|")
    for cat, n in counts.most_common():
        print(f"| {cat} | {100.0 * n / total:.1f}% |")


if __name__ == "__main__":
    main()
