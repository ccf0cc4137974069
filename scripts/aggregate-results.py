#!/usr/bin/env python3
"""Aggregates `haze compare` tables of several seeds into one table (scripts/results.sh).

Usage: aggregate-results.py SEED0.md SEED1.md ...

Each input is the markdown table `haze compare` prints (one run, one seed). The output table
gives, per method, the median RMSE over the seeds with its min-max, the median SMAPE, and the
RMSE ratio to volpath computed per seed (same seed, same run, same machine load), as its median
and min-max. Below it, the ratios the lightcut issue asks for, per seed: the best stochastic
cut against the best brute-force `vrl` and the best deterministic cut (`cut=bound`), "best"
meaning the lowest median RMSE within the family.
"""
import statistics
import sys


def read(path):
    rows = {}
    with open(path) as f:
        lines = [l.strip() for l in f if l.strip().startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    for line in lines[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        row = dict(zip(head, cells))
        rows[row["method"]] = row
    return rows


def family(method):
    name = method.split(":")[0].split(",")[0]
    if name in ("vrl_lightcuts", "vpl_lightcuts"):
        return name + (" (paper's cut)" if "cut=bound" in method else " (stochastic cut)")
    return name


def spread(values):
    return statistics.median(values), min(values), max(values)


def main(paths):
    seeds = [read(p) for p in paths]
    methods = list(seeds[0])
    rmse = {m: [float(s[m]["RMSE"]) for s in seeds] for m in methods}
    smape = {m: statistics.median(float(s[m]["SMAPE (%)"]) for s in seeds) for m in methods}
    passes = {m: statistics.median(int(s[m]["passes"]) for s in seeds) for m in methods}
    print(f"| method | lights | passes (median) | RMSE median ({len(seeds)} seeds; min-max) | SMAPE % | RMSE / volpath per seed (median; min-max) |")
    print("|---|---:|---:|---:|---:|---:|")
    for m in methods:
        med, lo, hi = spread(rmse[m])
        ratio = "-"
        if "volpath" in rmse and m != "volpath":
            r = spread([a / b for a, b in zip(rmse[m], rmse["volpath"])])
            ratio = f"{r[0]:.2f} ({r[1]:.2f}-{r[2]:.2f})"
        lights = seeds[0][m].get("lights", "-")
        print(f"| {m} | {lights} | {passes[m]:.0f} | {med:.4g} ({lo:.4g}-{hi:.4g}) | {smape[m]:.1f} | {ratio} |")
    best = {}
    for m in methods:
        f = family(m)
        if f not in best or statistics.median(rmse[m]) < statistics.median(rmse[best[f]]):
            best[f] = m
    stoch = best.get("vrl_lightcuts (stochastic cut)")
    print()
    if stoch:
        for other in ["vrl", "vrl_lightcuts (paper's cut)", "volpath"]:
            if other in best:
                r = spread([a / b for a, b in zip(rmse[stoch], rmse[best[other]])])
                print(f"- best stochastic cut (`{stoch}`) / best {other} (`{best[other]}`): RMSE ratio "
                      f"{r[0]:.2f} (per seed {r[1]:.2f}-{r[2]:.2f})")
    many = [m for m in methods if m != "volpath"]
    if many and "volpath" in rmse:
        m = min(many, key=lambda x: statistics.median(rmse[x]))
        r = spread([a / b for a, b in zip(rmse[m], rmse["volpath"])])
        print(f"- best many-light method (`{m}`) / volpath: {r[0]:.2f} (per seed {r[1]:.2f}-{r[2]:.2f})")


if __name__ == "__main__":
    main(sys.argv[1:])
