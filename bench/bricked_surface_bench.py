#!/usr/bin/env python3
"""The SCVD and its dual triangles in bricks against the whole volume (issue 47).

Runs build/bench/sheetmesh-bricked-surface-bench, each run a process of its own:
  exact  - per preset and r: the whole volume's generators, then pass 2 in bricks of 64
           with the halo SurfaceHalo(r, t_max): the same faces?
  close  - per preset and r: both passes whole, both in bricks, the whole volume with
           another seed, and today's one-process surface (random stream, Lloyd until the
           energy settles): faces and the vertex-prism similarity, to see the bricks' change
           against a seed's.
  draw   - per preset and r, seeds 1-3: the local draw spaced (the default), drawn node by
           node (Bernoulli) and today's stream, whole volume: generators and similarity.
  scale  - one large phantom (--scale PRESET:N), whole and in bricks of --scale_brick:
           seconds and peak memory.

Usage: bench/bricked_surface_bench.py BUILD_DIR [--parts exact,close,draw,scale]
           [--dims 256] [--presets P,...] [--rs 4,7,12] [--brick 64]
           [--scale paper:1024] [--scale_brick 256]
Writes --json (bench/out/bricked_surface.json) and prints markdown tables.
"""
import argparse
import concurrent.futures
import statistics
import json
import os
import subprocess
import sys
import tempfile
import time

PRESETS = ["rough_network", "thick_slab", "grazing_sheet", "shallow_network", "vuggy_network",
           "rough_slab"]


def phantom(build, preset, n, folder):
    path = os.path.join(folder, f"{preset}_{n}x{n}x{n}_u8.raw")
    if not os.path.exists(path):
        subprocess.run([os.path.join(build, "worker/pipeline/sheetmesh-pipeline"), "phantom",
                        f"--preset={preset}", f"--dims={n}x{n}x{n}", "-o", path],
                       check=True, stdout=subprocess.DEVNULL)
    return path


def measure(build, path, **flags):
    cmd = [os.path.join(build, "bench/sheetmesh-bricked-surface-bench"), path]
    cmd += [f"--{k}={v}" for k, v in flags.items()]
    start = time.monotonic()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    row = json.loads(out.strip().splitlines()[-1])
    row["wall_seconds"] = time.monotonic() - start
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build")
    ap.add_argument("--parts", default="exact,close,scale")
    ap.add_argument("--dims", type=int, default=256)
    ap.add_argument("--scale", default="paper:1024")
    ap.add_argument("--scale_brick", type=int, default=256)
    ap.add_argument("--presets", default=",".join(PRESETS), help="exact, close, draw: these presets")
    ap.add_argument("--rs", default="", help="close, draw: these r (default 4,7,12)")
    ap.add_argument("--brick", type=int, default=64, help="exact, close: the bricks' side")
    ap.add_argument("--json", default="bench/out/bricked_surface.json")
    args = ap.parse_args()
    parts = args.parts.split(",")
    presets = args.presets.split(",")
    rs = [float(r) for r in args.rs.split(",")] if args.rs else [4, 7, 12]
    results = {}
    with tempfile.TemporaryDirectory(prefix="bricked_surface_") as folder:
        if "exact" in parts:
            rows = []
            print("| preset | r | t̄ | t_max | halo | faces | bricks | same faces |")
            print("|---|---|---|---|---|---|---|---|")
            for preset in presets:
                path = phantom(args.build, preset, args.dims, folder)
                for r in [2, 4, 7, 10, 15]:
                    row = measure(args.build, path, mode="check", r=r, brick=args.brick)
                    row["preset"] = preset
                    rows.append(row)
                    print(f"| {preset} | {r} | {row['t']:.1f} | {row['t_max']:.0f} | "
                          f"{row['halo']} | {row['faces']} | {row['bricks']} | "
                          f"{'yes' if row['same_faces'] else 'no: -%d +%d, %d vertices' % (row['faces_missing'], row['faces_extra'], row['disagreeing_vertices'])} |",
                          flush=True)
            results["exact"] = rows
        if "close" in parts:
            rows = []
            print("\n| preset | r | faces whole / bricks / seed 2 / stream | similarity whole / "
                  "bricks / seed 2 / stream | bricks' change | seed's change |")
            print("|---|---|---|---|---|---|")
            for preset in presets:
                path = phantom(args.build, preset, args.dims, folder)
                for r in rs:
                    whole = measure(args.build, path, mode="whole", r=r)
                    t = dict(t=whole["t"], t_max=whole["t_max"])
                    bricked = measure(args.build, path, mode="bricked", r=r, brick=args.brick, **t)
                    other = measure(args.build, path, mode="whole", r=r, seed=2, **t)
                    stream = measure(args.build, path, mode="stream", r=r, **t)
                    rows.append(dict(preset=preset, r=r, whole=whole, bricked=bricked, seed2=other,
                                     stream=stream))
                    print(f"| {preset} | {r} | {whole['faces']} / {bricked['faces']} / "
                          f"{other['faces']} / {stream['faces']} | {whole['similarity']:.4f} / "
                          f"{bricked['similarity']:.4f} / {other['similarity']:.4f} / "
                          f"{stream['similarity']:.4f} | "
                          f"{bricked['similarity'] - whole['similarity']:+.4f}, "
                          f"{100 * (bricked['faces'] / whole['faces'] - 1):+.1f}% | "
                          f"{other['similarity'] - whole['similarity']:+.4f}, "
                          f"{100 * (other['faces'] / whole['faces'] - 1):+.1f}% |", flush=True)
            results["close"] = rows
        if "draw" in parts:
            rows = []
            print("\n| preset | r | generators spaced / Bernoulli / stream (mean ± sd) | "
                  "similarity spaced / Bernoulli / stream (mean) | spaced − stream | "
                  "Bernoulli − stream |")
            print("|---|---|---|---|---|---|")
            draws = [("spaced", dict(mode="whole", draw="spaced")),
                     ("bernoulli", dict(mode="whole", draw="bernoulli")),
                     ("stream", dict(mode="stream"))]
            with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
                for preset in presets:
                    path = phantom(args.build, preset, args.dims, folder)
                    for r in rs:
                        first = measure(args.build, path, mode="whole", r=r)
                        t = dict(t=first["t"], t_max=first["t_max"])
                        jobs = {(name, seed): pool.submit(measure, args.build, path, r=r, seed=seed,
                                                          **flags, **t)
                                for name, flags in draws for seed in (1, 2, 3)}
                        row = dict(preset=preset, r=r)
                        for name, _ in draws:
                            runs = [jobs[(name, seed)].result() for seed in (1, 2, 3)]
                            row[name] = dict(
                                generators=[x["generators"] for x in runs],
                                similarity=[x["similarity"] for x in runs])
                        rows.append(row)
                        g = {n: row[n]["generators"] for n, _ in draws}
                        m = {n: statistics.mean(row[n]["similarity"]) for n, _ in draws}
                        print(f"| {preset} | {r} | " + " / ".join(
                            f"{statistics.mean(g[n]):.0f} ± {statistics.stdev(g[n]):.1f}"
                            for n, _ in draws) + " | " +
                              " / ".join(f"{m[n]:.4f}" for n, _ in draws) +
                              f" | {m['spaced'] - m['stream']:+.4f} | "
                              f"{m['bernoulli'] - m['stream']:+.4f} |", flush=True)
            results["draw"] = rows
        if "scale" in parts:
            preset, n = args.scale.split(":")
            path = phantom(args.build, preset, int(n), folder)
            start = time.monotonic()
            subprocess.run(["cat", path], check=True, stdout=subprocess.DEVNULL)
            cat = time.monotonic() - start
            whole = measure(args.build, path, mode="whole", r=7)
            t = dict(t=whole["t"], t_max=whole["t_max"])
            bricked = measure(args.build, path, mode="bricked", r=7, brick=args.scale_brick, **t)
            results["scale"] = dict(preset=preset, n=int(n), cat_seconds=cat, whole=whole,
                                    bricked=bricked)
            print(f"\n{preset} {n}³ ({whole['voxels']} sheet voxels), r = 7, cat {cat:.1f} s")
            print("| run | bricks | halo | build s | peak MiB | largest crop voxels | faces | "
                  "similarity |")
            print("|---|---|---|---|---|---|---|---|")
            for name, row in [("whole", whole), ("bricked", bricked)]:
                print(f"| {name} | {row['bricks']} | {row['halo']} | {row['build_seconds']:.1f} | "
                      f"{row['peak_mib_after_build']:.0f} | {row['largest_crop_voxels']} | "
                      f"{row['faces']} | {row['similarity']:.4f} |")
    os.makedirs(os.path.dirname(args.json) or ".", exist_ok=True)
    with open(args.json, "w") as f:
        json.dump(results, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
