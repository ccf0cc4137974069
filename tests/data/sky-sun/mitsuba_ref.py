#!/usr/bin/env python3
"""Renders a Mitsuba 3 reference of one of the scenes in this directory (see README.md).

    python mitsuba_ref.py SCENE.xml OUT.exr SPP RES

Mitsuba 3's `scalar_rgb` variant (no LLVM needed), the scene's own integrator and filter, one
render of SPP samples per pixel at RES x RES (the scenes' `res` parameter), seed 0, written as a
linear RGB float32 EXR.
"""
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
scene_path, out, spp, res = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
scene = mi.load_file(scene_path, res=res, spp=str(spp))
image = mi.render(scene, spp=spp)
bitmap = mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
bitmap.write(out)
