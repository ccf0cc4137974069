"""Measure haze.distributed's speed-up with 1 vs 2 local Ray workers (docs/python.md).

    python python/examples/distributed_speedup.py [SCENE.xml] [--passes 8] [--threads-per-worker 1]

Each configuration runs in a fresh process with its own local cluster (ray.init(num_cpus=N)).
With --threads-per-worker 1 every worker renders on one thread (RAYON_NUM_THREADS=1), so N
workers use N cores; with 0 each worker uses all cores (the default).
"""

import argparse
import os
import pathlib
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve()
DEFAULT_SCENE = HERE.parents[2] / "tests" / "data" / "validation" / "scenes" / "hg-box.xml"


def one(scene, workers, passes, vrls):
    import ray

    from haze import distributed

    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    # Warm up: start the workers and load the scene in them.
    distributed.render(scene, spp=workers, passes_per_task=1, vrls=vrls, progress=False)
    start = time.monotonic()
    distributed.render(scene, spp=passes, passes_per_task=1, vrls=vrls, progress=False)
    secs = time.monotonic() - start
    print(f"{workers} {secs:.3f} {os.getloadavg()[0]:.2f}")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    p.add_argument("--passes", type=int, default=8)
    p.add_argument("--vrls", type=int, default=1000)
    p.add_argument("--threads-per-worker", type=int, default=1)
    p.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.one:
        one(args.scene, args.one, args.passes, args.vrls)
        return
    env = dict(os.environ)
    if args.threads_per_worker > 0:
        env["RAYON_NUM_THREADS"] = str(args.threads_per_worker)
    times = {}
    for workers in (1, 2):
        load_before = os.getloadavg()[0]
        out = subprocess.run(
            [sys.executable, __file__, args.scene, "--passes", str(args.passes), "--vrls", str(args.vrls),
             "--one", str(workers)],
            env=env, check=True, capture_output=True, text=True,
        ).stdout.split()
        times[workers] = float(out[1])
        print(f"{workers} worker(s): {times[workers]:.2f} s for {args.passes} passes "
              f"(1-min load average {load_before:.2f} before, {out[2]} after)")
    print(f"speed-up with 2 workers: {times[1] / times[2]:.2f}x")


if __name__ == "__main__":
    main()
