#!/usr/bin/python3
"""The permeability tensor through the whole workflow (issue 46), against known answers.

Volumes built here with numpy, voxels of 5 µm (`--unit=um --spacing=5,5,5`):
- `crossing slabs`: two slabs 4 voxels thick through a 96³ box, z = 46..49 and x = 46..49:
  K = k_m I + Σ a³/(12 L) (I − n nᵀ) with a = 20 µm, L = 480 µm;
- `tilted slab`: one slab 4 voxels thick (measured along its normal) through the box, tilted
  30° about y: in its plane k_m + a³/(12 L cos 30°), across it k_m, the least principal
  direction its normal;
and the real scans NETL and DPM (../shared/data; their voxel size taken as 5 µm).

and the phantom presets at 96³ (`phantom --preset=P --dims=96x96x96`: rough and shallow
networks, vugs, a grazing sheet, rough and thick slabs, the sample).

Each is run as a user would, `sheetmesh-pipeline run VOLUME --flow --r=R` (extraction on;
the surface's fitted apertures are what the flow sees), over r = 2, 4, 7, 10 and 15: the
tensor's diagonal against the answer, the principal direction's angle, the sheets' share of
the flux, the solver's iterations and its time against the volume mesh's. The image's
reference (r-independent but for the extraction's) runs once per volume, at r = 7; the
others skip it (`--permeability_image_reference=false`) and are compared with it. The
convergence plot (each axis's permeameter against r, over its value at r = 2) goes to
docs/images/permeability_convergence.png (`--replot` draws it again from
bench/out/permeability.md).

With `--paper`: the paper phantom (1012×1024×931) at r = 7, `--volume_mesh` against `--flow`
(the image's reference skipped: beyond a million voxels), wall time and peak memory (GNU
time) of each, the flow stage's own seconds against the volume mesh's.

Usage: /usr/bin/python3 bench/permeability.py [BUILD_DIR] [--paper] [--only=NAME,...] | --replot
(`--only` runs the volumes named: "crossing slabs", NETL, a preset, ...; the table it writes
then holds those alone).
Writes bench/out/permeability.md and prints it.
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
VOXEL_M = 5e-6
K_M = 1e-18


def slabs(path):
    v = np.zeros((96, 96, 96), dtype=np.uint8)  # (z, y, x)
    v[46:50, :, :] = 255
    v[:, :, 46:50] = 255
    v.tofile(path)
    a, l = 4 * VOXEL_M, 96 * VOXEL_M
    f = a ** 3 / (12 * l)
    return [K_M + f, K_M + 2 * f, K_M + f], None


def tilted(path):
    z, y, x = np.mgrid[0:96, 0:96, 0:96]
    t = math.radians(30)
    n = (math.sin(t), 0.0, math.cos(t))
    d = (x - 47.5) * n[0] + (z - 47.5) * n[2]
    ((np.abs(d) < 2) * 255).astype(np.uint8).tofile(path)
    a, l = 4 * VOXEL_M, 96 * VOXEL_M
    along = K_M + a ** 3 / (12 * l * math.cos(t))
    # In the frame of the fracture: along, along, k_m; the diagonal in x, y, z follows.
    nn = np.outer(n, n)
    k = K_M * np.eye(3) + (along - K_M) * (np.eye(3) - nn)
    return [k[0, 0], k[1, 1], k[2, 2]], n


PRESETS = ["rough_network", "shallow_network", "vuggy_network", "grazing_sheet", "rough_slab",
           "thick_slab", "sample"]
RADII = (2, 4, 7, 10, 15)
REFERENCE_R = 7


def run(cli, vol, out, r, extra):
    p = subprocess.run([cli, "run", vol, "--flow", "--unit=um", "--spacing=5,5,5",
                        "--r=%g" % r, "-o", out, "--output_previews=false",
                        "--output_formats=ply", "--output_volume_formats=vtu",
                        "--similarity_hausdorff=false"] + extra,
                       capture_output=True, text=True)
    if p.returncode != 0:
        return None, (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
    return json.load(open(os.path.join(out, "report.json"))), None


def timed(cmd):
    """Wall seconds and peak resident MiB of a command (GNU time)."""
    p = subprocess.run(["/usr/bin/time", "-f", "%e %M"] + cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(p.stderr[-2000:])
    wall, kib = p.stderr.strip().splitlines()[-1].split()
    return float(wall), int(kib) / 1024.0


def paper(cli, tmp):
    """--volume_mesh against --flow on the paper phantom: time and peak memory."""
    vol = os.path.join(tmp, "paper_1012x1024x931_u8.raw")
    subprocess.run([cli, "phantom", "--preset=paper", "-o", vol], check=True, capture_output=True)
    start = time.monotonic()
    subprocess.run(["cat", vol], stdout=subprocess.DEVNULL, check=True)
    read = time.monotonic() - start
    common = ["run", vol, "--labels=255", "--r=7", "--unit=um", "--spacing=5,5,5",
              "--output_previews=false", "--similarity_hausdorff=false"]
    v = timed([cli] + common + ["--volume_mesh", "-o", tmp + "/v"])
    f = timed([cli] + common + ["--flow", "-o", tmp + "/f"])
    rv = json.load(open(tmp + "/v/report.json"))
    rf = json.load(open(tmp + "/f/report.json"))
    lines = ["read with cat: %.1f s" % read,
             "| run | wall s | peak MiB | volume mesh s | flow s (mesh solve s) | tetrahedra | "
             "k_xx / k_yy / k_zz (darcy) | image reference |", "|---|---|---|---|---|---|---|---|"]
    for name, t, rep in (("--volume_mesh", v, rv), ("--flow", f, rf)):
        secs = rep["seconds"]
        fl = rep.get("flow", {})
        k = fl.get("permeability_darcy")
        lines.append("| %s | %.1f | %.0f | %.1f | %s | %d | %s | %s |" % (
            name, t[0], t[1], secs.get("volume", 0),
            "%.2f (%.2f)" % (secs.get("flow", 0), fl.get("seconds", 0)) if fl else "—",
            rep["volume_mesh"]["tetrahedra"],
            " / ".join("%.3g" % k[i][i] for i in range(3)) if k else "—",
            fl.get("image_reference", {}).get("skipped", "—")[:60] if fl else "—"))
    return lines


def plot(series, path):
    """The permeameters (the laboratory's measurement) against r per volume and axis, each
    over its value at the smallest r that ran."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), sharey=True)
    colours = plt.get_cmap("tab20").colors
    markers = "osD^v<>ph*X"
    for axis, ax in enumerate(axes):
        for i, (name, points) in enumerate(series.items()):
            points = [(r, k) for r, k in points if k is not None]
            if len(points) < 2:
                continue
            base = points[0][1][axis]
            ax.plot([r for r, _ in points], [k[axis] / base for _, k in points],
                    marker=markers[i % len(markers)], color=colours[(2 * i) % len(colours)],
                    label=name)
        ax.set_title("permeameter along %s" % "xyz"[axis])
        ax.set_xlabel("r (voxels)")
        ax.axhline(1, color="grey", lw=0.5)
        ax.set_yscale("log")
    axes[0].set_ylabel("k(r) / k(r = 2)")
    axes[2].legend(fontsize=7, loc="best")
    fig.suptitle("The permeameters as the surface coarsens (--flow, 5 µm voxels, r = 2 … 15)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def replot(md, path):
    """The plot again from a written table: the mesh / image column is the permeameter over
    one number per volume, so its ratio to the first r is the permeameter's."""
    series = {}
    for line in open(md):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 10 or not cells[1].replace(".", "").isdigit():
            continue
        try:
            ratios = [float(x) for x in cells[5].split(" / ")]
        except ValueError:
            continue
        series.setdefault(cells[0], []).append((float(cells[1]), ratios))
    plot({k: sorted(v) for k, v in series.items()}, path)


def main():
    if "--replot" in sys.argv:
        replot(os.path.join(ROOT, "bench", "out", "permeability.md"),
               os.path.join(ROOT, "docs", "images", "permeability_convergence.png"))
        return
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    build = args[0] if args else os.path.join(ROOT, "build-tests")
    cli = os.path.join(build, "worker", "pipeline", "sheetmesh-pipeline")
    tmp = tempfile.mkdtemp(prefix="sheetmesh_flow_")
    cases = []
    p = os.path.join(tmp, "slabs_96x96x96_u8.raw")
    cases.append(("crossing slabs", p, ["--labels=255"]) + slabs(p))
    p = os.path.join(tmp, "tilted_96x96x96_u8.raw")
    cases.append(("tilted slab", p, ["--labels=255"]) + tilted(p))
    for name, f in [("NETL", "netl_binary_fracture_small.tif"),
                    ("DPM", "dpm_3fractures_100x100x100_u8.raw")]:
        full = os.path.join(SHARED, f)
        if os.path.exists(full):
            cases.append((name, full, ["--labels=255"], None, None))
        else:
            print("%s: %s absent, skipped" % (name, full))
    only = [a.split("=", 1)[1].split(",") for a in sys.argv if a.startswith("--only=")]
    if only:
        cases = [c for c in cases if c[0] in only[0]]
    for preset in PRESETS:
        if only and preset not in only[0]:
            continue
        p = os.path.join(tmp, "%s_96x96x96_u8.raw" % preset)
        subprocess.run([cli, "phantom", "--preset=" + preset, "--dims=96x96x96", "-o", p],
                       check=True, capture_output=True)
        cases.append((preset, p, ["--labels=255"], None, None))
    lines = ["| volume | r | k_xx / k_yy / k_zz (darcy) | against the answer | least principal "
             "direction off the normal | permeameters: mesh / image (r = 7) per axis | sheets' "
             "share of the flux | tetrahedra | CG iterations | mesh solve s / volume mesh s |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    series = {}
    for name, vol, extra, answer, normal in cases:
        image = {}
        points = []
        for r in (REFERENCE_R,) + tuple(x for x in RADII if x != REFERENCE_R):
            skip = [] if r == REFERENCE_R else ["--permeability_image_reference=false"]
            rep, err = run(cli, vol, os.path.join(tmp, "%s_%g" % (name.replace(" ", "_"), r)), r,
                           extra + skip)
            if rep is None:
                lines.append("| %s | %g | fails: %s |" % (name, r, err))
                points.append((r, None))
                print(lines[-1], flush=True)
                continue
            k = rep["flow"]["permeability_m2"]
            diag = [k[i][i] for i in range(3)]
            points.append((r, rep["flow"]["permeameter_m2"]))
            darcy = " / ".join("%.3g" % (d / 9.869233e-13) for d in diag)
            against = "—"
            if answer:
                against = " / ".join("%+.1f%%" % (100 * (d - a) / a) for d, a in zip(diag, answer))
            angle = "—"
            if normal is not None:
                least = rep["flow"]["principal_directions"][2]
                c = abs(sum(u * v for u, v in zip(least, normal)))
                angle = "%.2f°" % math.degrees(math.acos(min(1.0, c)))
            share = " / ".join("%.2f" % s for s in rep["flow"]["fracture_share_of_flux"])
            if r == REFERENCE_R:
                image = rep["flow"].get("image_reference", {})
            if image.get("permeability_m2"):
                perm = rep["flow"]["permeameter_m2"]
                ratio = " / ".join("%.3f" % (perm[i] / image["permeability_m2"][i][i])
                                   for i in range(3))
            else:
                ratio = image.get("skipped", "—")[:50]
            secs = rep["seconds"]
            lines.append("| %s | %g | %s | %s | %s | %s | %s | %d | %s | %.2f / %.2f |" % (
                name, r, darcy, against, angle, ratio, share, rep["volume_mesh"]["tetrahedra"],
                "/".join(str(i) for i in rep["flow"]["iterations"]),
                rep["flow"]["seconds"], secs.get("volume", 0)))
            print(lines[-1], flush=True)
        if image.get("seconds"):
            lines.append("| %s | image reference | %.1f s, %d cells, CG %s |" % (
                name, image["seconds"], image["cells"], "/".join(map(str, image["iterations"]))))
        series[name] = sorted(points)
    plot(series, os.path.join(ROOT, "docs", "images", "permeability_convergence.png"))
    if "--paper" in sys.argv:
        lines += [""] + paper(cli, tmp)
    text = "\n".join(lines)
    os.makedirs(os.path.join(ROOT, "bench", "out"), exist_ok=True)
    open(os.path.join(ROOT, "bench", "out", "permeability.md"), "w").write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
