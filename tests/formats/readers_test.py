"""Round trips for the readers of the formats labs have: a volume written by Python in
each format (NumPy .npy, HDF5 chunked and compressed, NIfTI-1, MRC/CCP4, folders of PNG,
JPEG and DICOM slices) reads back voxel
for voxel through `sheetmesh-pipeline convert`, with its spacing and origin; bad files in
each are refused naming the file and the field.

Usage: readers_test.py PATH_TO_sheetmesh-pipeline
Writers missing from the machine (h5py, nibabel, PIL, pydicom) skip their part with a message."""

import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import warnings

import numpy as np

warnings.filterwarnings("ignore")
CLI = sys.argv[1]
tmp = tempfile.mkdtemp(prefix="sheetmesh_readers_")
failures, checked, skipped = [], [], []
rng = np.random.default_rng(7)


def info(path):
    # Every voxel selected: the test is of the reader, not of the phase.
    r = subprocess.run([CLI, "info", path, "--json", "--window=-1e300:1e300"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def read_back(path, dtype):
    """The volume as the pipeline reads it, as a (z, y, x) array."""
    out = os.path.join(tmp, "back.raw")
    r = subprocess.run([CLI, "convert", path, "-o", out, "--out_format=raw"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    j = info(path)
    nx, ny, nz = j["dims"]
    return np.fromfile(out, dtype=dtype).reshape(nz, ny, nx), j


def refused(path, *words):
    r = subprocess.run([CLI, "info", path], capture_output=True, text=True)
    assert r.returncode != 0, f"{path} was read"
    for w in (path,) + words:
        assert w in r.stderr, f"'{w}' not in: {r.stderr.strip()}"


def part(name, needs=None):
    def wrap(fn):
        if needs is not None:
            try:
                __import__(needs)
            except ImportError:
                skipped.append(name)
                print(f"SKIP {name}: /usr/bin/python3 has no {needs}")
                return fn
        try:
            fn()
            checked.append(name)
            print(f"ok   {name}")
        except AssertionError as e:
            failures.append(name)
            print(f"FAIL {name}: {e}")
        return fn
    return wrap


def volume(dtype, shape=(9, 10, 11)):
    if np.dtype(dtype).kind == "f":
        return rng.normal(size=shape).astype(dtype)
    info_ = np.iinfo(dtype)
    return rng.integers(info_.min, info_.max, size=shape, endpoint=True).astype(dtype)


@part("npy: every type, both orders, both byte orders, a 2D slice")
def _():
    for dt in ("u1", "u2", "f4", "i1", "i2", "i4", "u4", "f8", ">u2", ">i2"):
        a = volume(np.dtype(dt))
        p = os.path.join(tmp, "v.npy")
        np.save(p, a)
        kind = np.dtype(dt).newbyteorder("=")
        native = {"u1": "u1", "u2": "u2", "f4": "f4"}.get(kind.str[1:], "f4")
        b, j = read_back(p, native)
        assert b.shape == a.shape, (dt, b.shape)
        assert np.array_equal(b, a.astype(native)), dt
        if native == "f4" and kind.str[1:] != "f4":
            assert "→float32" in j["format"], j["format"]
    a = volume(np.uint8)
    p = os.path.join(tmp, "f.npy")
    np.save(p, np.asfortranarray(a.transpose(2, 1, 0)))  # (x, y, z) in Fortran order
    b, _ = read_back(p, "u1")
    assert np.array_equal(b, a), "fortran order"
    s = volume(np.uint16, (10, 11))
    np.save(p, s)
    b, j = read_back(p, "u2")
    assert j["dims"] == [11, 10, 1] and np.array_equal(b[0], s)


@part("npy: bad files refused naming the field")
def _():
    p = os.path.join(tmp, "bad.npy")
    open(p, "wb").write(b"not numpy at all")
    refused(p, "magic")
    np.save(p, np.zeros((4, 4, 4), dtype=complex))
    refused(p, "descr")
    np.save(p, np.zeros((2, 3, 4, 5), dtype=np.uint8))
    refused(p, "shape")
    np.save(p, np.zeros((40, 40, 40), dtype=np.uint16))
    data = open(p, "rb").read()
    open(p, "wb").write(data[:-100])
    refused(p, "truncated")


@part("hdf5: chunked and gzip-compressed datasets, element_size_um, picking the dataset",
      needs="h5py")
def _():
    import h5py
    p = os.path.join(tmp, "scan.h5")
    a16 = volume(np.uint16, (12, 13, 14))
    af = volume(np.float64, (12, 13, 14))
    with h5py.File(p, "w") as f:
        d = f.create_dataset("entry/data/data", data=a16, chunks=(4, 5, 6), compression="gzip",
                             shuffle=True)
        d.attrs["element_size_um"] = [3.0, 2.0, 1.5]  # z, y, x
        f.create_dataset("other/f64", data=af, chunks=True, compression="gzip")
        f.create_dataset("meta/name", data=np.string_("rock"))
    b, j = read_back(p + ":/entry/data/data", "u2")
    assert np.array_equal(b, a16)
    assert j["spacing"] == [1.5, 2.0, 3.0] and j["unit"] == "um", (j["spacing"], j["unit"])
    b, j = read_back(p + ":/other/f64", "f4")
    assert np.array_equal(b, af.astype("f4")) and "→float32" in j["format"]
    refused(p, "name the dataset", "/entry/data/data", "/other/f64")
    refused(p + ":/entry/missing", "no dataset /entry/missing", "/entry/data/data")
    refused(p + ":/meta/name", "rank 0")
    open(os.path.join(tmp, "fake.h5"), "w").write("not hdf5")
    refused(os.path.join(tmp, "fake.h5"), "not an HDF5 file")


@part("nifti: int16 with scaling, spacing and the sform's origin", needs="nibabel")
def _():
    import nibabel as nib
    a = volume(np.int16, (14, 13, 12)).transpose(2, 1, 0)  # nibabel is (x, y, z)
    aff = np.diag([0.5, 0.75, 2.0, 1.0])
    aff[:3, 3] = [10, -20, 30]
    img = nib.Nifti1Image(np.asfortranarray(a.transpose(2, 1, 0)), aff)
    img.header.set_xyzt_units("mm")
    p = os.path.join(tmp, "head.nii")
    nib.save(img, p)
    b, j = read_back(p, "f4")
    assert np.array_equal(b, a.astype("f4")), "nifti voxels"
    assert j["spacing"] == [0.5, 0.75, 2.0] and j["origin"] == [10.0, -20.0, 30.0], j
    assert j["unit"] == "mm"
    img = nib.Nifti1Image(np.asfortranarray(volume(np.int16, (5, 6, 7))), np.eye(4))
    nib.save(img, p)
    with open(p, "r+b") as f:  # scl_slope 2, scl_inter 1 in the header as written
        f.seek(112)
        f.write(struct.pack("<ff", 2.0, 1.0))
    b, j = read_back(p, "f4")
    back = nib.load(p)  # nibabel's own reading, scaling applied, is the known answer
    assert back.dataobj.slope == 2.0 and back.dataobj.inter == 1.0, "the header was not patched"
    assert np.allclose(b, back.get_fdata().transpose(2, 1, 0), rtol=1e-6), "scl_slope"
    nib.save(img, os.path.join(tmp, "g.nii.gz"))
    refused(os.path.join(tmp, "g.nii.gz"), "gunzip")
    data = open(p, "rb").read()
    open(p, "wb").write(data[:200])
    refused(p, "348")


def write_mrc(path, a, mode, cell, origin, nsymbt=0):
    nz, ny, nx = a.shape
    h = np.zeros(256, dtype="<i4")
    h[0:3] = [nx, ny, nz]
    h[3] = mode
    h[7:10] = [nx, ny, nz]
    hf = h.view("<f4")
    hf[10:13] = cell
    h[16:19] = [1, 2, 3]
    h[23] = nsymbt
    hf[49:52] = origin
    raw = bytearray(h.tobytes())
    raw[208:212] = b"MAP "
    raw[212:214] = b"\x44\x44"
    with open(path, "wb") as f:
        f.write(bytes(raw) + b"\0" * nsymbt + a.astype(a.dtype.newbyteorder("<")).tobytes())


@part("mrc: int8, int16, float32, uint16; cell spacing, origin, an extended header")
def _():
    p = os.path.join(tmp, "map.mrc")
    for mode, dt in ((0, np.int8), (1, np.int16), (2, np.float32), (6, np.uint16)):
        a = volume(dt, (6, 7, 8))
        write_mrc(p, a, mode, cell=(8 * 1.25, 7 * 1.5, 6 * 2.0), origin=(5, 6, 7), nsymbt=96)
        native = "u2" if dt == np.uint16 else "f4"
        b, j = read_back(p, native)
        assert np.array_equal(b, a.astype(native)), f"mode {mode} voxels"
        assert j["spacing"] == [1.25, 1.5, 2.0] and j["origin"] == [5.0, 6.0, 7.0], j
        assert j["unit"] == "angstrom"
    write_mrc(p, volume(np.float32, (2, 2, 2)), 4, (1, 1, 1), (0, 0, 0))
    refused(p, "MODE", "4")
    write_mrc(p, volume(np.float32, (20, 20, 20)), 2, (1, 1, 1), (0, 0, 0))
    open(p, "r+b").truncate(3000)
    refused(p, "truncated")


def slices_folder(name):
    d = os.path.join(tmp, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


@part("png: 8-bit, 16-bit, 1-bit, palette indices and grey RGB slices, ordered by number", "PIL")
def _():
    from PIL import Image
    for dt in (np.uint8, np.uint16):
        a = volume(dt, (12, 7, 9))
        d = slices_folder("png")
        for z in range(a.shape[0]):  # s1 ... s12: "s10" after "s9"
            Image.fromarray(a[z]).save(os.path.join(d, f"s{z + 1}.png"))
        b, j = read_back(d, a.dtype.str)
        assert np.array_equal(b, a), f"{dt.__name__} voxels"
        assert j["format"] == "png-folder" and j["dtype"] == np.dtype(dt).name, j
    # A mask saved as 1-bit reads as 0/255; a palette image as its indices; grey RGB as grey.
    mask = rng.integers(0, 2, size=(5, 6)).astype(bool)
    d = slices_folder("png1")
    Image.fromarray(mask).save(os.path.join(d, "m0.png"))
    b, _j = read_back(d, "u1")
    assert np.array_equal(b[0], mask.astype(np.uint8) * 255), "1-bit"
    labels = rng.integers(0, 4, size=(5, 6)).astype(np.uint8)
    pal = Image.fromarray(labels, mode="P")
    pal.putpalette([0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 255] + [0] * 756)
    pal.save(os.path.join(d, "m0.png"))
    b, _j = read_back(d, "u1")
    assert np.array_equal(b[0], labels), "palette indices"
    g = volume(np.uint8, (5, 6))
    Image.fromarray(np.stack([g, g, g], axis=-1)).save(os.path.join(d, "m0.png"))
    b, _j = read_back(d, "u1")
    assert np.array_equal(b[0], g), "grey RGB"
    rgb = np.stack([g, g, 255 - g], axis=-1)
    rgb[0, 0] = (1, 2, 3)
    Image.fromarray(rgb).save(os.path.join(d, "m0.png"))
    refused(d, "m0.png", "colour PNG", "(0,0)", "greyscale")
    # One file alone is a volume one slice deep.
    Image.fromarray(g).save(os.path.join(tmp, "one.png"))
    b, j = read_back(os.path.join(tmp, "one.png"), "u1")
    assert np.array_equal(b[0], g) and j["dims"] == [6, 5, 1], j


@part("png: cut short, not a PNG, slices of different sizes or types, mixed formats", "PIL")
def _():
    from PIL import Image
    d = slices_folder("pngbad")
    for z in range(3):
        Image.fromarray(volume(np.uint8, (40, 50))).save(os.path.join(d, f"{z}.png"))
    Image.fromarray(volume(np.uint8, (41, 50))).save(os.path.join(d, "3.png"))
    refused(d, "3.png", "0.png", "50x41", "50x40")
    Image.fromarray(volume(np.uint16, (40, 50))).save(os.path.join(d, "3.png"))
    refused(d, "3.png", "16-bit", "8-bit")
    os.remove(os.path.join(d, "3.png"))
    shutil.copy(os.path.join(d, "1.png"), os.path.join(d, "1.jpg"))
    refused(d, "mixes slice formats", "png", "jpeg", "input.format")
    os.remove(os.path.join(d, "1.jpg"))
    p = os.path.join(d, "1.png")
    data = open(p, "rb").read()
    open(p, "wb").write(data[: len(data) // 2])
    r = subprocess.run([CLI, "convert", d, "-o", os.path.join(tmp, "x.raw"), "--out_format=raw"],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "1.png" in r.stderr and "cut short" in r.stderr, r.stderr
    open(p, "wb").write(b"not a png at all")
    refused(d, "1.png", "not a readable PNG")


@part("jpeg: grey and colour slices read as libjpeg decodes them; cut short refused", "PIL")
def _():
    from PIL import Image
    d = slices_folder("jpeg")
    a = (volume(np.uint8, (4, 16, 24)) // 4 + 100).astype(np.uint8)
    expect = []
    for z in range(a.shape[0]):
        p = os.path.join(d, f"slice_{z:03d}.jpg")
        if z % 2:
            Image.fromarray(np.stack([a[z], a[z] // 2, 255 - a[z]], -1)).save(p, quality=90)
        else:
            Image.fromarray(a[z]).save(p, quality=90)
        im = Image.open(p)
        im.draft("L", im.size)  # libjpeg's own grey output, as the reader asks for
        expect.append(np.asarray(im.convert("L")))
    b, j = read_back(d, "u1")
    assert np.array_equal(b, np.stack(expect)), "voxels differ from libjpeg's decoding"
    assert j["format"] == "jpeg-folder" and j["dims"] == [24, 16, 4], j
    p = os.path.join(d, "slice_002.jpg")
    data = open(p, "rb").read()
    open(p, "wb").write(data[: len(data) * 2 // 3])
    r = subprocess.run([CLI, "convert", d, "-o", os.path.join(tmp, "x.raw"), "--out_format=raw"],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "slice_002.jpg" in r.stderr and "cut short" in r.stderr, r.stderr


def write_dicom(path, pixels, position, series, instance, slope=1.0, intercept=0.0,
                spacing=(0.5, 0.25), bits=16, signed=True):
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
    ct = "1.2.840.10008.5.1.4.1.1.2"
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = ct
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.SOPClassUID, ds.SOPInstanceUID = ct, meta.MediaStorageSOPInstanceUID
    ds.StudyInstanceUID, ds.SeriesInstanceUID = "1.2.3.4", series
    ds.Modality, ds.InstanceNumber = "CT", instance
    ds.Rows, ds.Columns = pixels.shape
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit = bits, bits, bits - 1
    ds.PixelRepresentation = 1 if signed else 0
    ds.PixelSpacing = list(spacing)
    ds.ImagePositionPatient = list(position)
    ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    ds.RescaleSlope, ds.RescaleIntercept = slope, intercept
    ds.PixelData = pixels.tobytes()
    ds.save_as(path, write_like_original=False)


@part("dicom: a CT series in shuffled files without extension, ordered by position, in HU",
      "pydicom")
def _():
    d = slices_folder("dicom")
    a = volume(np.int16, (6, 9, 11))
    order = rng.permutation(a.shape[0])
    for k, z in enumerate(order):  # names say nothing of z
        write_dicom(os.path.join(d, f"IM{k:04d}"), a[z], (10.0, 20.0, -5.0 + 0.8 * z),
                    "1.2.3.4.5", int(z) + 1, slope=2.0, intercept=-1024.0)
    open(os.path.join(d, "notes.txt"), "w").write("scanned on a Tuesday\n")
    b, j = read_back(d, "f4")
    assert np.array_equal(b, a.astype(np.float32) * 2 - 1024), "HU voxels"
    assert j["format"].startswith("dicom-series") and "float32" in j["format"], j
    assert np.allclose(j["spacing"], [0.25, 0.5, 0.8]) and j["unit"] == "mm", j
    assert np.allclose(j["origin"], [10.0, 20.0, -5.0]), j
    # Unsigned 16-bit without rescale stays uint16.
    u = volume(np.uint16, (3, 5, 4))
    d = slices_folder("dicom16")
    for z in range(3):
        write_dicom(os.path.join(d, f"{z}.dcm"), u[z], (0, 0, 2.0 * z), "9.9", z + 1,
                    signed=False)
    b, j = read_back(d, "u2")
    assert np.array_equal(b, u) and j["dtype"] == "uint16" and j["spacing"][2] == 2.0, j


@part("dicom: a missing slice, two series, a truncated file refused naming them", "pydicom")
def _():
    d = slices_folder("dicombad")
    for z in (0, 1, 2, 4):
        write_dicom(os.path.join(d, f"{z}.dcm"), volume(np.int16, (4, 4)), (0, 0, 1.0 * z),
                    "1.1", z + 1)
    refused(d, "2.dcm", "4.dcm", "missing")
    write_dicom(os.path.join(d, "4.dcm"), volume(np.int16, (4, 4)), (0, 0, 3.0), "2.2", 4)
    refused(d, "2 DICOM series", "1.1", "2.2")
    write_dicom(os.path.join(d, "4.dcm"), volume(np.int16, (40, 40)), (0, 0, 3.0), "1.1", 4)
    refused(d, "4.dcm", "40x40", "4x4")
    write_dicom(os.path.join(d, "4.dcm"), volume(np.int16, (4, 4)), (0, 0, 3.0), "1.1", 4)
    p = os.path.join(d, "4.dcm")
    data = open(p, "rb").read()
    open(p, "wb").write(data[:-20])
    r = subprocess.run([CLI, "convert", d, "-o", os.path.join(tmp, "x.raw"), "--out_format=raw"],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "4.dcm" in r.stderr, r.stderr


shutil.rmtree(tmp, ignore_errors=True)
print(f"{len(checked)} passed, {len(failures)} failed, {len(skipped)} skipped")
sys.exit(1 if failures else 0)
