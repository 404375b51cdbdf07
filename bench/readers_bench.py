"""Read speed of each volume reader on a 512³ volume, against `cat` of the same bytes in the
same run, and the peak memory of the read.

For each format (and each folder-of-slices format: TIFF, PNG, JPEG, DICOM, `cat` of all
its files) the script writes the same volume (three sheet planes in a box: uint8 0/255,
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
    slice_folders(files)
    return files


def slice_folders(files):
    """A folder of one file per z slice in each slice format."""
    try:
        from PIL import Image
        for ext, kw in (("png", {}), ("jpg", {"quality": 95})):
            d = os.path.join(tmp, ext)
            os.makedirs(d)
            for z in range(n):
                Image.fromarray(u8[z]).save(os.path.join(d, f"s{z:04d}.{ext}"), **kw)
            files.append((f"{'PNG' if ext == 'png' else 'JPEG'} folder uint8", d, []))
    except ImportError:
        print("PIL missing: PNG/JPEG not measured")
    d = os.path.join(tmp, "tif")
    subprocess.run([CLI, "convert", os.path.join(tmp, f"v_{n}x{n}x{n}_u8.raw"), "-o", d,
                    "--out_format=tiff-folder"], check=True, capture_output=True)
    files.append(("TIFF folder uint8", d, []))
    try:
        import pydicom  # noqa: F401 (the writer below needs it)
        d = os.path.join(tmp, "dcm")
        os.makedirs(d)
        for z in range(n):
            write_dicom_slice(os.path.join(d, f"IM{z:04d}"), i16[z], z)
        # HU = stored - 1024: the sheets at -1524, the rock at -24.
        files.append(("DICOM series int16 rescaled→float32", d, ["--threshold=-1000"]))
    except ImportError:
        print("pydicom missing: DICOM not measured")


def write_dicom_slice(path, pixels, z):
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian
    ct = "1.2.840.10008.5.1.4.1.1.2"
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID, meta.MediaStorageSOPInstanceUID = ct, f"1.2.3.{z + 1}"
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.SOPClassUID, ds.SOPInstanceUID = ct, meta.MediaStorageSOPInstanceUID
    ds.SeriesInstanceUID, ds.InstanceNumber = "1.2.3", z + 1
    ds.Rows, ds.Columns = pixels.shape
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
    ds.PixelSpacing, ds.ImagePositionPatient = [1, 1], [0, 0, float(z)]
    ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    ds.RescaleSlope, ds.RescaleIntercept = 1, -1024
    ds.PixelData = pixels.tobytes()
    ds.save_as(path, write_like_original=False)


def best(fn):
    return min(fn() for _ in range(args.runs))


def paths_of(path):
    path = path.split(":/")[0]
    if os.path.isdir(path):
        return sorted(os.path.join(path, f) for f in os.listdir(path))
    return [path]


def cat_seconds(path):
    def run():
        t = time.perf_counter()
        subprocess.run(["cat"] + paths_of(path), stdout=subprocess.DEVNULL, check=True)
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
        size = sum(os.path.getsize(f) for f in paths_of(path))
        c = cat_seconds(path)
        r, rss = read_seconds(path, extra)
        rows.append((name, size, c, r, rss))
    # Voxel bytes as read (uint8 1, int16 2): a compressed stack's file says little.
    print(f"| reader | file MB | cat s | read + select s | read / cat | voxel MB/s | peak RSS MB |")
    print("|---|---|---|---|---|---|---|")
    for name, size, c, r, rss in rows:
        voxel_bytes = n ** 3 * (2 if "int16" in name else 1)
        print(f"| {name} | {size / 1e6:.1f} | {c:.3f} | {r:.3f} | {r / c:.1f} | "
              f"{voxel_bytes / 1e6 / r:.0f} | {rss / 1024:.0f} |")
finally:
    shutil.rmtree(tmp, ignore_errors=True)
