"""Read speed of each volume reader on a 512³ volume, against `cat` of the same bytes in the
same run, and the peak memory of the read.

For each format the script writes the same volume (three sheet planes in a box: uint8 0/255,
or int16 -500/1000 for the formats scans come in as int16), then runs
`sheetmesh-pipeline info FILE --json` (its `seconds.read_and_select` is the reader plus the
selection scan) and `cat FILE > /dev/null`, each after dropping nothing from the page cache
(both warm: the figure is the reader's cost over moving the bytes), best of --runs.

Usage: /usr/bin/python3 bench/readers_bench.py BUILD_DIR [--n 512] [--runs 3]"""

import argparse
import json
import os
import resource
import shutil
import subprocess
import tempfile
import time

import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("build")
ap.add_argument("--n", type=int, default=512)
ap.add_argument("--runs", type=int, default=3)
args = ap.parse_args()
CLI = os.path.join(args.build, "worker/pipeline/sheetmesh-pipeline")
n = args.n
tmp = tempfile.mkdtemp(prefix="sheetmesh_readbench_")

u8 = np.zeros((n, n, n), np.uint8)
for z in (n // 4, n // 2, 3 * n // 4):
    u8[z:z + 3] = 255
i16 = np.where(u8 > 0, -500, 1000).astype(np.int16)


def write_all():
    files = []
    p = os.path.join(tmp, f"v_{n}x{n}x{n}_u8.raw")
    u8.tofile(p)
    files.append(("raw uint8", p, []))
    p = os.path.join(tmp, "v_u8.npy")
    np.save(p, u8)
    files.append(("npy uint8", p, []))
    p = os.path.join(tmp, "v_i16.npy")
    np.save(p, i16)
    files.append(("npy int16→float32", p, ["--threshold=0"]))
    try:
        import h5py
        p = os.path.join(tmp, "v.h5")
        with h5py.File(p, "w") as f:
            f.create_dataset("plain", data=u8)
            f.create_dataset("gzip", data=u8, chunks=(16, 64, 64), compression="gzip")
        files.append(("hdf5 uint8 contiguous", p + ":/plain", []))
        files.append(("hdf5 uint8 chunked gzip", p + ":/gzip", []))
    except ImportError:
        print("h5py missing: HDF5 not measured")
    try:
        import nibabel as nib
        p = os.path.join(tmp, "v.nii")
        nib.save(nib.Nifti1Image(np.asfortranarray(i16.transpose(2, 1, 0)), np.eye(4)), p)
        files.append(("nifti int16→float32", p, ["--threshold=0"]))
    except ImportError:
        print("nibabel missing: NIfTI not measured")
    p = os.path.join(tmp, "v.mrc")
    h = np.zeros(256, "<i4")
    h[0:3] = [n, n, n]
    h[3] = 1
    h[7:10] = [n, n, n]
    h[16:19] = [1, 2, 3]
    hb = bytearray(h.tobytes())
    hb[208:214] = b"MAP DD"
    with open(p, "wb") as f:
        f.write(bytes(hb) + i16.tobytes())
    files.append(("mrc int16→float32", p, ["--threshold=0"]))
    return files


def best(fn):
    return min(fn() for _ in range(args.runs))


def cat_seconds(path):
    path = path.split(":/")[0]
    def run():
        t = time.perf_counter()
        subprocess.run(["cat", path], stdout=subprocess.DEVNULL, check=True)
        return time.perf_counter() - t
    return best(run)


def read_seconds(path, extra):
    peak = [0]
    def run():
        r = subprocess.run(["/usr/bin/time", "-f", "%M", CLI, "info", path, "--json"] + extra,
                           capture_output=True, text=True, check=True)
        peak[0] = max(peak[0], int(r.stderr.strip().split("\n")[-1]))
        return json.loads(r.stdout)["seconds"]["read_and_select"]
    return best(run), peak[0]


try:
    rows = []
    for name, path, extra in write_all():
        size = os.path.getsize(path.split(":/")[0])
        c = cat_seconds(path)
        r, rss = read_seconds(path, extra)
        rows.append((name, size, c, r, rss))
    print(f"| reader | file MB | cat s | read + select s | read / cat | peak RSS MB |")
    print("|---|---|---|---|---|---|")
    for name, size, c, r, rss in rows:
        print(f"| {name} | {size / 1e6:.0f} | {c:.3f} | {r:.3f} | {r / c:.1f} | {rss / 1024:.0f} |")
finally:
    shutil.rmtree(tmp, ignore_errors=True)
