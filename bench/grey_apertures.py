#!/usr/bin/python3
"""Apertures from grey levels against the truth (issue 45).

Grey phantoms are made here with numpy: one tilted planar sheet (or a rough one) of a known
aperture across a 64³ rock with a band of void along x = 0 (the air around a core), drawn by
the share of each voxel it covers (8 sub-samples per axis), blurred by a Gaussian point
spread and given Gaussian noise at a contrast-to-noise ratio. Each volume is meshed three
ways by `sheetmesh-pipeline run --extract=false`:

- `--grey`: sheets found by their sheetness, apertures from missing attenuation, the
  levels measured from the histogram;
- `--grey --grey_levels=40,200`: the same with the levels given (a calibrated scan);
- `--threshold=otsu`: one global threshold, the apertures counted from voxels;
- the same Otsu run's voxel-count aperture is also what the grey run reports beside its own.

For each: the share of the sheet found (the mesh's area over the sheet's area in the box)
and the mean aperture against the truth (error in voxels and per cent), and the time.

Usage: /usr/bin/python3 bench/grey_apertures.py BUILD_DIR [--quick]
Writes bench/out/grey_apertures.md and prints it. With `--scale N`: the grey path's time and
peak memory against the binary path's on an N³ volume of one rough sheet (the binary path
on the same sheet thresholded), both `run --extract=false --r=7`. With `--paper`: the same
at the paper's scale — the paper phantom (`phantom --preset=paper`, 1012×1024×931, 6 rough
crossing sheets of mean aperture 5 and 120,598 specks) as the binary input, and as an 8-bit
grey scan (rock 200, sheets and specks 40, blurred by σ = 1, noise at CNR 10) made from it
slab by slab; both `run --r=7` (extraction on, as a user runs it).
"""
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy import ndimage

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def phantom(path, aperture, sigma, cnr, rough=0.0, n=64, rock=200.0, void=40.0, seed=1):
    """Writes a float32 volume; returns the sheet's area (voxels²) inside the rock."""
    normal = np.array([0.25, 0.35, 1.0])
    normal /= np.linalg.norm(normal)
    along = np.cross(normal, [0, 1, 0])
    along /= np.linalg.norm(along)
    across = np.cross(normal, along)
    centre = np.array([n / 2 + 3, n / 2, n / 2])
    k = 8
    sub = (np.arange(k) + 0.5) / k - 0.5
    z, y, x = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    vol = np.full((n, n, n), rock, dtype=np.float64)

    def offset(px, py, pz):
        q = np.stack([px - centre[0], py - centre[1], pz - centre[2]], -1)
        d = q @ normal
        if rough > 0:
            d = d - rough * np.sin(0.21 * (q @ along)) * np.cos(0.17 * (q @ across))
        return d

    centre_offset = offset(x, y, z)
    near = np.abs(centre_offset) <= aperture / 2 + 1.5
    idx = np.nonzero(near)
    share = np.zeros(len(idx[0]))
    for dz in sub:
        for dy in sub:
            for dx in sub:
                d = offset(idx[2] + dx, idx[1] + dy, idx[0] + dz)
                share += np.abs(d) <= aperture / 2
    share /= k ** 3
    vol[idx] = rock - (rock - void) * share
    vol[:, :, :6] = void
    vol = ndimage.gaussian_filter(vol, sigma, mode="nearest")
    rng = np.random.default_rng(seed)
    vol += rng.normal(0, (rock - void) / cnr, vol.shape)
    vol.astype("<f4").tofile(path)
    # The sheet's area in the rock: voxels whose centre lies within half a voxel of it.
    inside = (np.abs(centre_offset) <= 0.5) & (x >= 6)
    return float(inside.sum())


def mesh_aperture(vtu, field="aperture", power=1):
    """The area-weighted mean of the faces' `field` (to `power`) in a surface.vtu (spacing
    1: voxels). With power 3 and the aperture: the cubic law's mean transmissivity × 12."""
    import meshio
    m = meshio.read(vtu)
    tri = m.cells_dict["triangle"]
    p = m.points[tri]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    a = m.cell_data_dict[field]["triangle"]
    return float((area * a ** power).sum() / area.sum())


def run(cli, vol, out, extra):
    t0 = time.time()
    p = subprocess.run([cli, "run", vol, "--extract=false", "-o", out, "--output_previews=false"]
                       + extra, capture_output=True, text=True)
    dt = time.time() - t0
    if p.returncode != 0:
        return None, dt, p.stderr.strip().splitlines()[-1]
    return json.load(open(os.path.join(out, "report.json"))), dt, ""


def timed(cmd):
    """Wall seconds and peak resident MiB of a command (GNU time)."""
    p = subprocess.run(["/usr/bin/time", "-f", "%e %M"] + cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(p.stderr)
    wall, kib = p.stderr.strip().splitlines()[-1].split()
    return float(wall), int(kib) / 1024.0


def scale(cli, n):
    """The grey path against the binary one on an n³ volume of one sheet, aperture 1."""
    tmp = tempfile.mkdtemp(prefix="sheetmesh_grey_scale_")
    grey = os.path.join(tmp, "grey_%dx%dx%d_f32.raw" % (n, n, n))
    phantom(grey, 1.0, 1.0, 10, rough=1.5, n=n)
    binary = os.path.join(tmp, "binary_%dx%dx%d_u8.raw" % (n, n, n))
    (np.fromfile(grey, dtype="<f4") < 120).astype(np.uint8).tofile(binary)
    g = timed([cli, "run", grey, "--grey", "--extract=false", "--r=7", "-o", tmp + "/g"])
    b = timed([cli, "run", binary, "--labels=1", "--extract=false", "--r=7", "-o", tmp + "/b"])
    return "| %d³ | %.1f s, %.0f MiB | %.1f s, %.0f MiB | %.1f× time, %.1f× memory |" % (
        n, g[0], g[1], b[0], b[1], g[0] / b[0], g[1] / b[1])


def grey_paper(binary, grey, dims, halo=4, slab=64):
    """Writes `binary`'s grey scan to `grey` (uint8), slab by slab."""
    nx, ny, nz = dims
    src = np.memmap(binary, dtype=np.uint8, mode="r", shape=(nz, ny, nx))
    rng = np.random.default_rng(5)
    with open(grey, "wb") as out:
        for z0 in range(0, nz, slab):
            z1 = min(nz, z0 + slab)
            e0, e1 = max(0, z0 - halo), min(nz, z1 + halo)
            v = np.where(src[e0:e1] > 0, np.float32(40), np.float32(200))
            v = ndimage.gaussian_filter(v, 1.0, mode="nearest")[z0 - e0:z1 - e0]
            v += rng.normal(0, 16.0, v.shape).astype(np.float32)
            np.clip(np.rint(v), 0, 255).astype(np.uint8).tofile(out)


def paper(cli, out_dir):
    """The grey path against the binary one at the paper's scale."""
    dims = (1012, 1024, 931)
    os.makedirs(out_dir, exist_ok=True)
    binary = os.path.join(out_dir, "paper_1012x1024x931_u8.raw")
    if not os.path.exists(binary):
        subprocess.run([cli, "phantom", "--preset=paper", "-o", binary], check=True,
                       capture_output=True)
    grey = os.path.join(out_dir, "paper_grey_1012x1024x931_u8.raw")
    if not os.path.exists(grey):
        grey_paper(binary, grey, dims)
    start = time.monotonic()
    subprocess.run(["cat", grey], stdout=subprocess.DEVNULL, check=True)
    read = time.monotonic() - start
    g = timed([cli, "run", grey, "--grey", "--r=7", "-o", out_dir + "/g"])
    b = timed([cli, "run", binary, "--labels=255", "--r=7", "-o", out_dir + "/b"])
    rg = json.load(open(out_dir + "/g/report.json"))
    rb = json.load(open(out_dir + "/b/report.json"))
    print("read with cat: %.1f s" % read)
    print("grey: detected %d voxels on %d slabs (noise units from %d slices); triangles %d, similarity %.4f" % (
        rg["grey"]["sheetness"]["detected_voxels"], rg["grey"]["sheetness"]["slabs"],
        rg["grey"]["sheetness"]["noise_slices"], rg["surface"]["triangles"],
        rg["similarity"]["similarity"]))
    print("binary: triangles %d, similarity %.4f" % (rb["surface"]["triangles"],
                                                     rb["similarity"]["similarity"]))
    print("| volume | grey path | binary path | grey / binary |")
    print("|---|---|---|---|")
    print("| paper phantom 1012×1024×931 | %.1f s, %.0f MiB | %.1f s, %.0f MiB | %.1f× time, "
          "%.1f× memory |" % (g[0], g[1], b[0], b[1], g[0] / b[0], g[1] / b[1]))


def plot(rows, path):
    """Aperture error against the true aperture, one panel per noise level, a line per point
    spread: the grey levels (measured, given) against the voxel count."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    planar = [r for r in rows if r["rough"] == 0]
    cnrs = sorted({r["cnr"] for r in planar})
    fig, axes = plt.subplots(1, len(cnrs), figsize=(5 * len(cnrs), 4), squeeze=False)
    for ax, cnr in zip(axes[0], cnrs):
        for sigma, style in zip(sorted({r["sigma"] for r in planar}), ["-", "--", ":"]):
            sel = sorted([r for r in planar if r["cnr"] == cnr and r["sigma"] == sigma],
                         key=lambda r: r["aperture"])
            for key, field, colour, label in [("grey", "mean", "C0", "grey, levels measured"),
                                              ("given", "mean", "C1", "grey, levels given"),
                                              ("given", "counted", "C3", "voxel count")]:
                # A run whose levels were not found fell back to the voxel count: not drawn
                # as the grey levels' answer.
                pts = [(r["aperture"], 100 * (r[key][field] - r["aperture"]) / r["aperture"])
                       for r in sel if field in r[key]
                       and (field == "counted" or r[key].get("measured"))]
                if pts:
                    ax.plot(*zip(*pts), style, color=colour, marker="o",
                            label="%s, σ %g" % (label, sigma))
        ax.axhspan(-10, 10, color="0.9")
        ax.set_xscale("log")
        ax.set_xticks([0.2, 0.5, 1, 2, 4], ["0.2", "0.5", "1", "2", "4"])
        ax.set_yscale("symlog", linthresh=10)
        ax.set_xlabel("true aperture (voxels)")
        ax.set_ylabel("error of the mean aperture (%)")
        ax.set_title("contrast to noise %g" % cnr)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build-tests")
    cli = os.path.join(build, "worker", "pipeline", "sheetmesh-pipeline")
    if "--paper" in sys.argv:
        paper(cli, os.path.join(ROOT, "bench", "data"))
        return
    if "--scale" in sys.argv:
        n = int(sys.argv[sys.argv.index("--scale") + 1])
        print("| volume | grey path | binary path (the same sheet, thresholded) | grey / binary |")
        print("|---|---|---|---|")
        print(scale(cli, n))
        return
    quick = "--quick" in sys.argv
    apertures = [0.2, 0.5, 1, 2, 4]
    cases = [(a, s, c, 0.0) for a in apertures for s in ([1.0] if quick else [0.5, 1.5])
             for c in ([10] if quick else [5, 20])]
    cases += [(a, 1.0, 10, 1.5) for a in ([1] if quick else [0.5, 1, 2])]
    rows = []
    tmp = tempfile.mkdtemp(prefix="sheetmesh_grey_")
    for a, s, c, rough in cases:
        vol = os.path.join(tmp, "grey_64x64x64_f32.raw")
        area = phantom(vol, a, s, c, rough)
        row = {"aperture": a, "sigma": s, "cnr": c, "rough": rough}
        for name, extra in [("grey", ["--grey", "--r=5"]),
                            ("given", ["--grey", "--grey_levels=40,200", "--r=5"]),
                            ("otsu", ["--threshold=otsu", "--r=5",
                                      "--surface_representation=sheet"])]:
            rep, dt, err = run(cli, vol, os.path.join(tmp, name), extra)
            if rep is None:
                row[name] = {"error": err, "seconds": dt}
                continue
            found = rep["surface"]["area_voxels"] / area
            counted = mesh_aperture(os.path.join(tmp, name, "surface.vtu"))
            mean = counted
            if name != "otsu" and rep.get("grey", {}).get("measured"):
                mean = rep["grey"]["mean_aperture_voxels"]
                counted = rep["grey"]["counted_mean_aperture_voxels"]
            vtu = os.path.join(tmp, name, "surface.vtu")
            # The cubic law's transmissivity against the truth's: from the apertures the run
            # gives, and from the voxel count (the prisms' fitted heights) beside them.
            t_err = mesh_aperture(vtu, "aperture", 3) / a ** 3 - 1
            t_count = mesh_aperture(vtu, "thickness_voxels", 3) / a ** 3 - 1
            row[name] = {"found": found, "mean": mean, "counted": counted, "seconds": dt,
                         "transmissivity_error": t_err, "counted_transmissivity_error": t_count,
                         "measured": bool(rep.get("grey", {}).get("measured"))}
        rows.append(row)
        print(json.dumps(row), flush=True)
    lines = ["| aperture | σ | CNR | rough | grey: found | grey: mean (error) | grey: voxel count "
             "| grey, levels given: mean (error) | Otsu: found | Otsu: mean (error) "
             "| transmissivity error: grey / levels given / voxel count |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]

    def cell(r, key, a):
        if "error" in r:
            return "fails", "—"
        err = r[key] - a
        return ("%.2f" % r["found"],
                "%.2f (%+.2f, %+.0f%%)" % (r[key], err, 100 * err / a))
    for r in rows:
        g = r["grey"]
        o = r["otsu"]
        gf, gm = cell(g, "mean", r["aperture"])
        if "error" not in g and not g["measured"]:
            gm = "*voxel count, %.2f: %s*" % (g["mean"], "no void found")
        of, om = cell(o, "mean", r["aperture"])
        _, vm = cell(r["given"], "mean", r["aperture"])
        gc = "%.2f" % g["counted"] if "counted" in g else "—"

        def t(run, key):
            return "%+.0f%%" % (100 * run[key]) if key in run else "—"
        ts = "%s / %s / %s" % (t(g, "transmissivity_error"),
                               t(r["given"], "transmissivity_error"),
                               t(r["given"], "counted_transmissivity_error"))
        lines.append("| %g | %g | %g | %g | %s | %s | %s | %s | %s | %s | %s |" % (
            r["aperture"], r["sigma"], r["cnr"], r["rough"], gf, gm, gc, vm, of, om, ts))
    # Semi-real: the binary scans blurred into grey volumes (rock 200, sheets 40, σ = 1,
    # CNR 10, the levels given: they hold no void of their own); the truth is the binary
    # run's own aperture (its sheets' voxel thickness across them).
    shared = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
    semi = []
    for name, path, dims in [("DPM", "dpm_3fractures_100x100x100_u8.raw", (100, 100, 100)),
                             ("NETL", "netl_binary_fracture_small.tif", (200, 42, 100))]:
        full = os.path.join(shared, path)
        if not os.path.exists(full):
            print("semi-real %s: %s absent, skipped" % (name, full))
            continue
        if full.endswith(".tif"):
            raw = os.path.join(tmp, "%s_%dx%dx%d_u8.raw" % ((name.lower(),) + dims))
            subprocess.run([cli, "convert", full, "-o", raw, "--out_format=raw"], check=True,
                           capture_output=True)
            full = raw
        binary = np.fromfile(full, dtype=np.uint8).reshape(dims[::-1]) > 0
        vol = 200.0 - 160.0 * binary
        vol = ndimage.gaussian_filter(vol, 1.0, mode="nearest")
        vol += np.random.default_rng(3).normal(0, 16.0, vol.shape)
        gpath = os.path.join(tmp, "semi_%dx%dx%d_f32.raw" % dims)
        vol.astype("<f4").tofile(gpath)
        truth, _, _ = run(cli, full, os.path.join(tmp, "semi_binary"),
                          ["--labels=%d" % np.fromfile(full, dtype=np.uint8).max(), "--r=5",
                           "--surface_representation=sheet"])
        grey, dt, err = run(cli, gpath, os.path.join(tmp, "semi_grey"),
                            ["--grey", "--grey_levels=40,200", "--r=5"])
        t = mesh_aperture(os.path.join(tmp, "semi_binary", "surface.vtu"))
        if grey is None:
            semi.append("| %s | %.2f | fails: %s |" % (name, t, err))
            continue
        g = grey["grey"]["mean_aperture_voxels"]
        semi.append("| %s | %.2f | %.2f (%+.0f%%) | %.2f | %.3f | %.1f s |" % (
            name, t, g, 100 * (g - t) / t, grey["grey"]["counted_mean_aperture_voxels"],
            grey["similarity"]["similarity"], dt))
    if semi:
        lines += ["", "| semi-real | binary run's aperture | grey run's | grey run's voxel count "
                  "| similarity | time |", "|---|---|---|---|---|---|"] + semi
    text = "\n".join(lines)
    os.makedirs(os.path.join(ROOT, "bench", "out"), exist_ok=True)
    plot(rows, os.path.join(ROOT, "bench", "out", "grey_apertures.png"))
    open(os.path.join(ROOT, "bench", "out", "grey_apertures.md"), "w").write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
