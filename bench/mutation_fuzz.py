#!/usr/bin/python3
"""Mutation fuzzing of the volume readers through the offline CLI: valid files with one to
four bytes changed (not random files), each read whole by `sheetmesh-pipeline convert`.

    /usr/bin/python3 bench/mutation_fuzz.py BUILD --format vdb --minutes 30 [--isolate]
    /usr/bin/python3 bench/mutation_fuzz.py BUILD --format all --minutes 30 --jobs 2

Formats: vdb, tiff, hdf5, nrrd, nifti, dicom, npy (seeds written here: by sheetmesh's own
writers and by the Python libraries labs use: pyopenvdb, h5py, nibabel, pydicom, numpy).

Each mutant is read with --isolate_readers=false unless --isolate: the reader itself in the
CLI's process, so that a library's fault is seen rather than contained. A finding is a run
that dies by a signal, ends with an exit other than 0 or 2 (a clear error about the input),
takes over --max_seconds (default 2) or peaks above --max_mib (default 1536) of resident
memory; each is kept in bench/out/fuzz/FORMAT/findings/ with what it did. The summary
line per format gives runs, exits by code, the slowest run and the largest peak.
"""
import argparse
import json
import os
import pathlib
import random
import shutil
import subprocess
import sys
import threading
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent
OUT = ROOT / "out" / "fuzz"
FORMATS = ["vdb", "tiff", "hdf5", "nrrd", "nifti", "dicom", "npy"]


def cli(build):
    return str(pathlib.Path(build) / "worker" / "pipeline" / "sheetmesh-pipeline")


def phantom(build, folder, dtype="uint8"):
    p = folder / f"sample_64x56x48_{ {'uint8': 'u8', 'uint16': 'u16', 'float32': 'f32'}[dtype]}.raw"
    if not p.exists():
        subprocess.run([cli(build), "phantom", "--preset=sample", "--dims=64x56x48",
                        f"--dtype={dtype}", "-o", str(p)], check=True, stdout=subprocess.DEVNULL)
    return p


def convert(build, src, dst, fmt):
    subprocess.run([cli(build), "convert", str(src), "-o", str(dst), f"--out_format={fmt}"],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return dst


def sample_array(shape=(24, 28, 32), dtype=np.uint8):
    rng = np.random.default_rng(7)
    a = np.zeros(shape, dtype)
    a[:, 10:13, :] = 200
    a[5:20, :, 14:16] = 90
    a[rng.random(shape) < 0.01] = 50
    return a


def dicom_slice(path, pixels, signed, rescale):
    """One CT slice, explicit VR little endian, as a scanner's export writes it."""
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, meta.MediaStorageSOPInstanceUID
    ds.Modality, ds.Rows, ds.Columns = "CT", pixels.shape[0], pixels.shape[1]
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated = ds.BitsStored = 16
    ds.HighBit, ds.PixelRepresentation = 15, int(signed)
    ds.PixelSpacing, ds.SliceThickness = [0.3, 0.3], 0.3
    if rescale:
        ds.RescaleSlope, ds.RescaleIntercept = rescale
    ds.PixelData = pixels.tobytes()
    ds.save_as(str(path), write_like_original=False)


def seeds(build, fmt, folder):
    """Valid files of `fmt` in `folder`; returns their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    raw8, raw16, rawf = (phantom(build, folder, t) for t in ("uint8", "uint16", "float32"))
    if fmt == "vdb":
        out.append(convert(build, raw8, folder / "sm_u8.vdb", "vdb"))
        out.append(convert(build, rawf, folder / "sm_f32.vdb", "vdb"))
        import pyopenvdb as vdb
        a = sample_array(dtype=np.float32)
        g = vdb.FloatGrid()
        g.copyFromArray(a)
        g.name = "density"
        vdb.write(str(folder / "py_float.vdb"), grids=[g])
        b = vdb.BoolGrid()
        b.copyFromArray(a > 100)
        b.name = "mask"
        vdb.write(str(folder / "py_bool.vdb"), grids=[b])
        h = vdb.FloatGrid()
        h.copyFromArray(a)
        h.name = "half"
        h.saveFloatAsHalf = True
        inst = h.copy()
        inst.name = "instance"
        vdb.write(str(folder / "py_half.vdb"), grids=[h, inst])
        out += [folder / n for n in ("py_float.vdb", "py_bool.vdb", "py_half.vdb")]
    elif fmt == "tiff":
        out.append(convert(build, raw8, folder / "sm_u8.tif", "tiff"))
        out.append(convert(build, raw16, folder / "sm_u16.tif", "tiff"))
        from PIL import Image
        a = sample_array()
        frames = [Image.fromarray(a[z]) for z in range(a.shape[0])]
        frames[0].save(folder / "pil_lzw.tif", save_all=True, append_images=frames[1:],
                       compression="tiff_lzw")
        frames[0].save(folder / "pil_deflate.tif", save_all=True, append_images=frames[1:],
                       compression="tiff_adobe_deflate")
        out += [folder / "pil_lzw.tif", folder / "pil_deflate.tif"]
    elif fmt == "hdf5":
        out.append(convert(build, raw8, folder / "sm_u8.h5", "hdf5"))
        import h5py
        a = sample_array(dtype=np.uint16)
        with h5py.File(folder / "plain.h5", "w") as f:
            f.create_dataset("data", data=a)
        with h5py.File(folder / "gzip.h5", "w") as f:
            f.create_dataset("entry/data", data=a, chunks=(8, 8, 8), compression="gzip",
                             shuffle=True)
        out += [folder / "plain.h5", folder / "gzip.h5"]
    elif fmt == "nrrd":
        out.append(convert(build, raw8, folder / "sm_u8.nrrd", "nrrd"))
        out.append(convert(build, raw16, folder / "sm_gz.nrrd", "nrrd-gzip"))
    elif fmt == "nifti":
        import nibabel
        for name, dt in (("u8", np.uint8), ("i16", np.int16), ("f32", np.float32)):
            img = nibabel.Nifti1Image(sample_array(dtype=dt), np.diag([0.5, 0.5, 0.7, 1]))
            nibabel.save(img, str(folder / f"nib_{name}.nii"))
            out.append(folder / f"nib_{name}.nii")
    elif fmt == "dicom":
        a = sample_array(dtype=np.int16)
        dicom_slice(folder / "ct.dcm", a[3], signed=True, rescale=(2.0, -1024.0))
        dicom_slice(folder / "u16.dcm", a[5].astype(np.uint16), signed=False, rescale=None)
        out += [folder / "ct.dcm", folder / "u16.dcm"]
    elif fmt == "npy":
        for name, dt in (("u8", np.uint8), ("u16", np.uint16), ("f64", np.float64)):
            np.save(folder / f"np_{name}.npy", sample_array(dtype=dt))
            out.append(folder / f"np_{name}.npy")
        np.save(folder / "np_fortran.npy", np.asfortranarray(sample_array()))
        out.append(folder / "np_fortran.npy")
    return [pathlib.Path(p) for p in out]


def mutate(data, rng):
    d = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        i = rng.randrange(len(d))
        r = rng.random()
        if r < 0.4:
            d[i] = rng.randrange(256)
        elif r < 0.7:
            d[i] ^= 1 << rng.randrange(8)
        else:
            d[i] = rng.choice([0x00, 0x01, 0x7f, 0x80, 0xfe, 0xff])
    return bytes(d)


def run_one(build, path, isolate, timeout_s):
    """(exit or -signal or "timeout", seconds, peak MiB of the CLI's process, stderr's last line)."""
    out = pathlib.Path(path).parent / "read_back.raw"  # every voxel read, as a run reads them
    cmd = [cli(build), "convert", str(path), "-o", str(out), "--out_format=raw",
           f"--isolate_readers={'true' if isolate else 'false'}"]
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         env=dict(os.environ, SHEETMESH_NO_HUGE_PAGES="1"))
    timer = threading.Timer(timeout_s, p.kill)
    timer.start()
    err = p.stderr.read()
    _, status, usage = os.wait4(p.pid, 0)
    timer.cancel()
    p.returncode = os.waitstatus_to_exitcode(status)
    secs = time.perf_counter() - t0
    code = "timeout" if secs >= timeout_s and p.returncode < 0 else p.returncode
    return code, secs, usage.ru_maxrss / 1024, (err.decode(errors="replace").strip().splitlines()
                                                or [""])[-1]


def fuzz(build, fmt, minutes, isolate, max_seconds, max_mib, seed):
    folder = OUT / fmt
    shutil.rmtree(folder / "work", ignore_errors=True)
    (folder / "work").mkdir(parents=True)
    findings = folder / "findings"
    findings.mkdir(exist_ok=True)
    files = seeds(build, fmt, folder / "seeds")
    blobs = [(f, f.read_bytes()) for f in files]
    for f, _ in blobs:  # every seed reads cleanly
        code, secs, _, last = run_one(build, f, isolate, 60)
        if code != 0:
            raise SystemExit(f"seed {f} does not read: {code} {last}")
    rng = random.Random(seed)
    end = time.time() + minutes * 60
    runs, codes, slowest, peak, found = 0, {}, 0.0, 0.0, 0
    while time.time() < end:
        src, data = rng.choice(blobs)
        mutant = folder / "work" / src.name
        mutant.write_bytes(mutate(data, rng))
        code, secs, mib, last = run_one(build, mutant, isolate, max(10, 5 * max_seconds))
        runs += 1
        key = str(code) if not isinstance(code, int) or code >= 0 else f"signal {-code}"
        codes[key] = codes.get(key, 0) + 1
        slowest = max(slowest, secs)
        peak = max(peak, mib)
        bad = (code not in (0, 2)) or secs > max_seconds or mib > max_mib
        if bad:
            found += 1
            name = f"{src.stem}-{runs}{src.suffix}"
            shutil.copy(mutant, findings / name)
            (findings / (name + ".json")).write_text(json.dumps(
                {"exit": code, "seconds": round(secs, 3), "peak_mib": round(mib, 1),
                 "stderr": last}, indent=1))
    summary = {"format": fmt, "minutes": minutes, "isolated": isolate, "seeds": len(files),
               "runs": runs, "exits": codes, "slowest_s": round(slowest, 2),
               "largest_peak_mib": round(peak, 1), "findings": found}
    print(json.dumps(summary))
    return summary


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--format", default="vdb", help="one of %s, or all" % ", ".join(FORMATS))
    ap.add_argument("--minutes", type=float, default=1)
    ap.add_argument("--isolate", action="store_true", help="read in the CLI's child reader")
    ap.add_argument("--max_seconds", type=float, default=2)
    ap.add_argument("--max_mib", type=float, default=1536)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    formats = FORMATS if args.format == "all" else args.format.split(",")
    bad = 0
    for fmt in formats:
        s = fuzz(args.build, fmt, args.minutes, args.isolate, args.max_seconds, args.max_mib,
                 args.seed)
        bad += s["findings"]
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
