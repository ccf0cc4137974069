"""Render a Mitsuba 3 reference of a scene here: python mitsuba_ref.py scenes/X.xml refs/X.exr 16384 (scalar_rgb, passes of 256 spp, seeds 0.., their mean)."""
import sys, time
import mitsuba as mi
mi.set_variant("scalar_rgb")
import numpy as np
scene_path, out, spp = sys.argv[1], sys.argv[2], int(sys.argv[3])
scene = mi.load_file(scene_path, spp=256)
t0 = time.time()
passes = max(1, spp // 256)
acc = None
for i in range(passes):
    a = np.array(mi.render(scene, spp=256, seed=i))
    acc = a if acc is None else acc + a
acc /= passes
mi.Bitmap(acc.astype(np.float32)).write(out)
print(f"{scene_path}: {spp} spp in {time.time()-t0:.1f} s, mean {acc.mean():.6f} -> {out}")
