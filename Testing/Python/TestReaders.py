"""The readers of mcvol-render's scene files (Documentation/scene-format.md,
`input`): NIfTI with its orientation (qform with a slice flip, oblique sform,
an sform flipped against the qform, 4-D, types, rescaling), plain TIFF
stacks, ImageJ and OME-TIFF hyperstacks, raw files, .vti/.mha/.nrrd,
several files as the channels of one image (resampled onto the first's grid
when asked); every reader error exits with status 2, names the key and the file on one line and
writes no image. Files are generated here; the NIfTI checks read the headers
and voxels with their own code, after the NIfTI-1 standard, so that a voxel's
value and world position are checked against the file, not against VTK.
With /usr/share/mricron/templates (Debian's mricron-data), also the ch2
template and the AAL atlas as two channels.

    TestReaders.py [--mcvol-render PROGRAM] [--work DIR]

Registered by Testing/Python/CMakeLists.txt (the build's package on PYTHONPATH).
"""

import argparse
import gzip
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkCommonMath import vtkMatrix4x4
from vtkmodules.vtkIOImage import vtkNIFTIImageWriter

from mcvolTesting import Checker, read_png_rgb

from mcvol.scenefile.errors import ErrorCollector, SceneError
from mcvol.scenefile.parse import parse_input
from mcvol.scenefile.readers import read_inputs

try:
    import tifffile
except ImportError:
    tifffile = None

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
MRICRON = "/usr/share/mricron/templates"


def rotation(axis, degrees):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    t = math.radians(degrees)
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * (k @ k)


def vtk_matrix(rot, offset):
    m = vtkMatrix4x4()
    for r in range(3):
        for c in range(3):
            m.SetElement(r, c, rot[r][c])
        m.SetElement(r, 3, offset[r])
    return m


def write_nifti(fn, values, spacing, qform=None, qfac=1, time=False):
    """values: (z, y, x) or (z, y, x, t); the qform (rotation, offset) maps
    VTK data coordinates (the writer's convention) to the world."""
    image = vtkImageData()
    nz, ny, nx = values.shape[:3]
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    ncomp = values.shape[3] if values.ndim == 4 else 1
    image.GetPointData().SetScalars(numpy_to_vtk(values.reshape(-1, ncomp) if ncomp > 1 else values.ravel(), deep=True))
    writer = vtkNIFTIImageWriter()
    writer.SetInputData(image)
    writer.SetFileName(fn)
    if qform is not None:
        writer.SetQFormMatrix(vtk_matrix(*qform))
        writer.SetQFac(qfac)
    if time:
        writer.SetTimeDimension(ncomp)
    writer.Write()


def nifti_bytes(fn):
    with (gzip.open if fn.endswith(".gz") else open)(fn, "rb") as f:
        return f.read()


def patch_nifti(fn, fields):
    """Overwrites header fields: {offset: (struct format, values)}."""
    data = bytearray(nifti_bytes(fn))
    for offset, (fmt, values) in fields.items():
        struct.pack_into("<" + fmt, data, offset, *values)
    with (gzip.open if fn.endswith(".gz") else open)(fn, "wb") as f:
        f.write(bytes(data))


def sform_fields(affine, code=2):
    """The sform of a 3x4 index -> world matrix (srow_x, srow_y, srow_z)."""
    return {254: ("h", [code]), 280: ("4f", affine[0]), 296: ("4f", affine[1]), 312: ("4f", affine[2])}


def nifti_reference(fn):
    """The file's index -> world matrix (NIfTI-1: method 3, the sform, when
    sform_code > 0, else method 2, the qform) and its voxels as
    (t, k, j, i), read here from the bytes."""
    b = nifti_bytes(fn)
    dims = struct.unpack_from("<8h", b, 40)
    datatype = struct.unpack_from("<h", b, 70)[0]
    pixdim = struct.unpack_from("<8f", b, 76)
    offset = int(struct.unpack_from("<f", b, 108)[0])
    qcode, scode = struct.unpack_from("<2h", b, 252)
    if scode > 0:
        affine = np.array([struct.unpack_from("<4f", b, 280 + 16 * r) for r in range(3)], float)
    else:
        qb, qc, qd, qx, qy, qz = struct.unpack_from("<6f", b, 256)
        qa = math.sqrt(max(0.0, 1.0 - qb * qb - qc * qc - qd * qd))
        rot = np.array([
            [qa * qa + qb * qb - qc * qc - qd * qd, 2 * (qb * qc - qa * qd), 2 * (qb * qd + qa * qc)],
            [2 * (qb * qc + qa * qd), qa * qa + qc * qc - qb * qb - qd * qd, 2 * (qc * qd - qa * qb)],
            [2 * (qb * qd - qa * qc), 2 * (qc * qd + qa * qb), qa * qa + qd * qd - qc * qc - qb * qb]])
        qfac = -1.0 if pixdim[0] < 0 else 1.0
        affine = np.hstack([rot @ np.diag([pixdim[1], pixdim[2], qfac * pixdim[3]]), [[qx], [qy], [qz]]])
    dtype = {4: "<i2", 16: "<f4", 2: "u1", 256: "i1", 8: "<i4", 768: "<u4"}[datatype]
    nx, ny, nz = dims[1:4]
    voxels = np.frombuffer(b, dtype, offset=offset).reshape(-1, nz, ny, nx)
    return affine, voxels


def load(value, scene_dir):
    """A scene's "input" read in this process: (image, None) or (None, SceneError)."""
    try:
        return read_inputs(parse_input(value, scene_dir), ErrorCollector()), None
    except SceneError as e:
        return None, e


def values_of(image, name):
    array = image.GetPointData().GetArray(name)
    nx, ny, nz = image.GetDimensions()
    return vtk_to_numpy(array).reshape(nz, ny, nx, array.GetNumberOfComponents())


def direction(image):
    d = image.GetDirectionMatrix()
    return np.array([[d.GetElement(r, c) for c in range(3)] for r in range(3)])


def check_nifti(t, label, image, name, fn, rot=None):
    """Every voxel of the file lies at its world position (the file's
    matrix) in the image, with its value; the direction is a rotation (and
    `rot` when given), the spacing the matrix's column lengths."""
    affine, voxels = nifti_reference(fn)
    nt, nz, ny, nx = voxels.shape
    got = values_of(image, name)
    t.check(tuple(image.GetDimensions()) == (nx, ny, nz), "%s: dimensions %s" % (label, image.GetDimensions()))
    t.check(got.shape[3] == nt, "%s: %d components, expected %d" % (label, got.shape[3], nt))
    d = direction(image)
    t.check(np.allclose(d.T @ d, np.eye(3), atol=1e-5) and abs(np.linalg.det(d) - 1) < 1e-5,
            "%s: direction is not a rotation: %s" % (label, d.tolist()))
    if rot is not None:
        t.check(np.allclose(d, rot, atol=1e-5), "%s: direction %s, expected %s" % (label, d.round(4).tolist(),
                                                                                  np.round(rot, 4).tolist()))
    spacing = np.linalg.norm(affine[:, :3], axis=0)
    t.check(np.allclose(image.GetSpacing(), spacing, rtol=1e-5), "%s: spacing %s, expected %s" % (
        label, image.GetSpacing(), spacing))
    bad = 0
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                world = affine @ [i, j, k, 1.0]
                index = [0.0, 0.0, 0.0]
                image.TransformPhysicalPointToContinuousIndex(world, index)
                ijk = [int(round(v)) for v in index]
                if max(abs(a - b) for a, b in zip(index, ijk)) > 1e-3 or not (
                        0 <= ijk[0] < nx and 0 <= ijk[1] < ny and 0 <= ijk[2] < nz):
                    bad += 1
                    continue
                if not np.allclose(got[ijk[2], ijk[1], ijk[0], :], voxels[:, k, j, i], rtol=1e-6):
                    bad += 1
    t.check(bad == 0, "%s: %d of %d voxels not at their world position with their value" % (label, bad, nx * ny * nz))


def run(program, args):
    return subprocess.run([sys.executable, program] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, timeout=300)


def scene_file(work, name, value, channels):
    fn = os.path.join(work, name + ".json")
    with open(fn, "w") as f:
        json.dump({"input": value, "channels": channels, "samples_per_pixel": 4, "image_size": [32, 32],
                   "backend": "cpu"}, f)
    return fn


def channel(array=None, component=None, color=(1, 1, 1)):
    ch = {"color": [[0, 0, 0, 0], [1] + list(color)], "opacity": [[0, 0], [1, 0.8]], "normalized": True}
    if array is not None:
        ch["array"] = array
    if component is not None:
        ch["component"] = component
    return ch


def check_render(t, program, work, name, value, channels, expect_channels):
    out = os.path.join(work, name + ".png")
    if os.path.exists(out):
        os.remove(out)
    r = run(program, [scene_file(work, name, value, channels), "-o", out])
    if not t.check(r.returncode == 0, "%s: exit status %d: %s" % (name, r.returncode, r.stderr.strip())):
        return
    t.check("%d channel(s)" % expect_channels in r.stderr and r.stderr.count("\n") == 1,
            "%s: summary %r" % (name, r.stderr))
    image = read_png_rgb(out)
    t.check(image.shape == (32, 32, 3) and float(image.std()) > 2.0, "%s: blank or wrong size image" % name)


def check_error(t, program, work, name, value, expected, channels=None):
    """Exit status 2, one line naming the key and the expected text (the
    file), no traceback, no image."""
    out = os.path.join(work, name + ".png")
    if os.path.exists(out):
        os.remove(out)
    r = run(program, [scene_file(work, name, value, channels or [channel(component=0)]), "-o", out])
    lines = r.stderr.strip().split("\n")
    t.check(r.returncode == 2, "%s: exit status %d, expected 2 (%s)" % (name, r.returncode, r.stderr.strip()))
    t.check(len(lines) == 1 and all(e in lines[0] for e in expected),
            "%s: message %r should be one line containing %s" % (name, r.stderr, expected))
    t.check("Traceback" not in r.stderr, "%s: traceback printed" % name)
    t.check(not os.path.exists(out), "%s: an image was written" % name)


def test_nifti(t, work, program):
    rng = np.random.default_rng(1)
    nz, ny, nx = 5, 6, 7
    data = (np.arange(nx * ny * nz, dtype=np.int16) * 3 + 1).reshape(nz, ny, nx)
    spacing = (0.8, 1.1, 1.7)

    # The qform: an oblique rotation, qfac -1 (slices stored in reverse).
    rq = rotation([1, 2, 3], 25)
    fq = os.path.join(work, "oblique.nii.gz")
    write_nifti(fq, data, spacing, (rq, [10.0, -20.0, 30.0]), qfac=-1)
    b = nifti_bytes(fq)
    t.check(struct.unpack_from("<f", b, 76)[0] == -1.0 and struct.unpack_from("<2h", b, 252) == (1, 0),
            "oblique.nii.gz: written with qfac -1, a qform and no sform")
    image, err = load("oblique.nii.gz", work)
    if t.check(err is None, "oblique.nii.gz: %s" % (err and err.message)):
        t.check(image.GetPointData().GetScalars().GetName() == "oblique", "the scalars are named after the file")
        check_nifti(t, "qform, qfac -1", image, "oblique", fq, rq)

    # An sform (oblique, other rotation, with the spacing in it) wins over
    # the qform.
    rs = rotation([0, 1, 1], -40)
    fs = os.path.join(work, "sform.nii")
    write_nifti(fs, data, spacing, (rq, [0.0, 0.0, 0.0]))
    patch_nifti(fs, sform_fields(np.hstack([rs @ np.diag([1.5, 0.5, 2.0]), [[1], [2], [3]]])))
    image, err = load("sform.nii", work)
    if t.check(err is None, "sform.nii: %s" % (err and err.message)):
        check_nifti(t, "sform", image, "sform", fs, rs)

    # An sform flipped against the qform (vtkNIFTIImageReader warns
    # "SFormMatrix is flipped compared to QFormMatrix"): the slices are
    # reversed, the direction stays a rotation, no warning is printed.
    flip = np.diag([-1.0, 1.0, 1.0])
    fflip = os.path.join(work, "flipped.nii")
    write_nifti(fflip, data, spacing, (np.eye(3), [0.0, 0.0, 0.0]))
    patch_nifti(fflip, sform_fields(np.hstack([rs @ flip @ np.diag(spacing), [[5], [6], [7]]])))
    image, err = load("flipped.nii", work)
    if t.check(err is None, "flipped.nii: %s" % (err and err.message)):
        check_nifti(t, "sform flipped against the qform", image, "flipped", fflip, rs @ flip @ np.diag([1, 1, -1]))
    check_render(t, program, work, "render-flipped", "flipped.nii", [channel()], 1)

    # 4-D: the time points become the components (channels), in order.
    data4 = rng.random((nz, ny, nx, 3)).astype(np.float32)
    f4 = os.path.join(work, "bold.nii.gz")
    write_nifti(f4, data4, spacing, (rq, [1.0, 2.0, 3.0]), time=True)
    image, err = load("bold.nii.gz", work)
    if t.check(err is None, "bold.nii.gz: %s" % (err and err.message)):
        t.check(struct.unpack_from("<5h", nifti_bytes(f4), 40)[0] == 4, "bold.nii.gz: written as 4-D")
        check_nifti(t, "4-D", image, "bold", f4, rq)
    check_render(t, program, work, "render-4d", "bold.nii.gz",
                 [channel(component=c, color=[float(c == k) for k in range(3)]) for c in range(3)], 3)

    # Types the mapper does not read are converted without loss; the NIfTI
    # rescaling (scl_slope, scl_inter) is applied.
    for dt, kind, fill, expected in ((256, "i1", [-7, 100], "short"), (8, "<i4", [-70000, 16777216], "float"),
                                     (768, "<u4", [3, 4000000001], "double")):
        fn = os.path.join(work, "type%d.nii" % dt)
        values = np.resize(np.array(fill, dtype=kind), nx * ny * nz)
        write_nifti(fn, data, spacing)
        raw = bytearray(nifti_bytes(fn)[:352])
        struct.pack_into("<2h", raw, 70, dt, np.dtype(kind).itemsize * 8)
        with open(fn, "wb") as f:
            f.write(bytes(raw) + values.tobytes())
        image, err = load(os.path.basename(fn), work)
        if t.check(err is None, "%s: %s" % (fn, err and err.message)):
            array = image.GetPointData().GetScalars()
            t.check(array.GetDataTypeAsString() == expected and np.array_equal(vtk_to_numpy(array), values),
                    "NIfTI type %d: read as %s %s" % (dt, array.GetDataTypeAsString(), vtk_to_numpy(array)[:2]))
    fn = os.path.join(work, "scaled.nii")
    write_nifti(fn, data, spacing)
    patch_nifti(fn, {112: ("2f", [0.5, -3.0])})
    image, err = load("scaled.nii", work)
    if t.check(err is None, "scaled.nii: %s" % (err and err.message)):
        t.check(np.allclose(values_of(image, "scaled")[..., 0], data * 0.5 - 3.0), "scl_slope/scl_inter applied")


def test_tiff(t, work, program):
    if tifffile is None:
        print("tifffile not installed: TIFF tests skipped")
        return
    rng = np.random.default_rng(2)
    nz, ny, nx = 4, 5, 6
    # A plain z-stack: vtkTIFFReader; page k is z = k, the file's row j is y = j.
    stack = rng.integers(0, 60000, (nz, ny, nx)).astype(np.uint16)
    tifffile.imwrite(os.path.join(work, "stack.tif"), stack, photometric="minisblack", metadata=None)
    image, err = load({"file": "stack.tif", "spacing": [0.5, 0.5, 2.0]}, work)
    if t.check(err is None, "stack.tif: %s" % (err and err.message)):
        t.check(np.array_equal(values_of(image, "stack")[..., 0], stack), "stack.tif: voxels")
        t.check(image.GetSpacing() == (0.5, 0.5, 2.0), "stack.tif: spacing %s" % (image.GetSpacing(),))

    # ImageJ hyperstack, Z C Y X: three channels, spacing from the
    # resolution tags and the ImageJ "spacing".
    hyper = rng.random((nz, 3, ny, nx)).astype(np.float32)
    tifffile.imwrite(os.path.join(work, "hyper.tif"), hyper, imagej=True, resolution=(1 / 0.4, 1 / 0.25),
                     metadata={"axes": "ZCYX", "spacing": 2.5, "unit": "um"})
    image, err = load("hyper.tif", work)
    if t.check(err is None, "hyper.tif: %s" % (err and err.message)):
        got = values_of(image, "hyper")
        t.check(got.shape == (nz, ny, nx, 3), "hyper.tif: shape %s" % (got.shape,))
        t.check(all(np.array_equal(got[..., c], hyper[:, c]) for c in range(3)), "hyper.tif: channels in order")
        t.check(np.allclose(image.GetSpacing(), (0.4, 0.25, 2.5)), "hyper.tif: spacing %s" % (image.GetSpacing(),))
    check_render(t, program, work, "render-hyper", "hyper.tif",
                 [channel(component=c, color=[float(c == k) for k in range(3)]) for c in range(3)], 3)

    # An ImageJ stack of one channel goes through tifffile as well.
    tifffile.imwrite(os.path.join(work, "ijstack.tif"), stack, imagej=True, metadata={"axes": "ZYX", "spacing": 3})
    image, err = load("ijstack.tif", work)
    if t.check(err is None, "ijstack.tif: %s" % (err and err.message)):
        t.check(np.array_equal(values_of(image, "ijstack")[..., 0], stack) and image.GetSpacing()[2] == 3.0,
                "ijstack.tif: voxels and z spacing")

    # OME-TIFF: channel names, physical sizes (z in nm, brought to µm).
    ome = rng.integers(0, 255, (nz, 2, ny, nx)).astype(np.uint8)
    tifffile.imwrite(os.path.join(work, "cells.ome.tif"), ome, ome=True, metadata={
        "axes": "ZCYX", "PhysicalSizeX": 0.2, "PhysicalSizeY": 0.3, "PhysicalSizeZ": 500, "PhysicalSizeZUnit": "nm",
        "Channel": {"Name": ["dapi", "gfp"]}})
    image, err = load("cells.ome.tif", work)
    if t.check(err is None, "cells.ome.tif: %s" % (err and err.message)):
        got = values_of(image, "cells")
        t.check(got.shape == (nz, ny, nx, 2) and np.array_equal(got[..., 1], ome[:, 1])
                and np.array_equal(got[..., 0], ome[:, 0]), "cells.ome.tif: channels %s" % (got.shape,))
        array = image.GetPointData().GetArray("cells")
        t.check([array.GetComponentName(c) for c in range(2)] == ["dapi", "gfp"], "cells.ome.tif: channel names")
        t.check(np.allclose(image.GetSpacing(), (0.2, 0.3, 0.5)), "cells.ome.tif: spacing %s" % (image.GetSpacing(),))
    check_render(t, program, work, "render-ome", "cells.ome.tif",
                 [channel(component="gfp", color=[0, 1, 0]), channel(component="dapi", color=[0, 0, 1])], 2)

    # OME-TIFF channel colours (OME-XML Color, signed 32-bit RGBA) are the
    # default channels' colours; a channel with a malformed one ("None",
    # "blue") keeps its default colour, with a warning.
    from mcvol.scenefile.assemble import DEFAULT_COLORS, default_channels

    tifffile.imwrite(os.path.join(work, "colors.ome.tif"), ome[:, [0, 1, 0, 1]], ome=True, metadata={
        "axes": "ZCYX", "PhysicalSizeX": 0.2, "PhysicalSizeY": 0.3, "PhysicalSizeZ": 0.5,
        "Channel": {"Name": ["dapi", "gfp", "none", "bad"],
                                    "Color": [65535, -16711681, None, "blue"]}})
    image, err = load("colors.ome.tif", work)
    if t.check(err is None, "colors.ome.tif: %s" % (err and err.message)):
        tops = [(c["component"], c["color"]["points"][-1][1:]) for c in default_channels(image)]
        t.check(tops == [(0, [0.0, 0.0, 1.0]), (1, [1.0, 0.0, 1.0]), (2, list(DEFAULT_COLORS[2])),
                         (3, list(DEFAULT_COLORS[3]))], "colors.ome.tif: default colours %s" % tops)
    image, err = load(["colors.ome.tif", "cells.ome.tif"], work)
    if t.check(err is None, "colors.ome.tif in a list: %s" % (err and err.message)):
        tops = [(c["array"], c["component"], c["color"]["points"][-1][1:]) for c in default_channels(image)]
        t.check(tops[:2] == [("colors", 0, [0.0, 0.0, 1.0]), ("colors", 1, [1.0, 0.0, 1.0])]
                and tops[4] == ("cells", 0, list(DEFAULT_COLORS[4])), "in a list: default colours %s" % tops)
    # mcvol-render's default channels: a blue-only file renders blue (the
    # first default colour is green), and the malformed colour is a warning.
    blue = np.zeros((nz, 2, ny, nx), np.uint8)
    blue[:, 0] = 200 * (rng.random((nz, ny, nx)) < 0.5)
    tifffile.imwrite(os.path.join(work, "blue.ome.tif"), blue, ome=True, metadata={
        "axes": "ZCYX", "Channel": {"Name": ["dapi", "bad"], "Color": [65535, "0xFF"]}})
    out = os.path.join(work, "blue.png")
    r = run(program, [os.path.join(work, "blue.ome.tif"), "-o", out, "--spp", "4", "--size", "32x32",
                      "--backend", "cpu"])
    if t.check(r.returncode == 0, "blue.ome.tif: exit status %d: %s" % (r.returncode, r.stderr.strip())):
        rgb = read_png_rgb(out).reshape(-1, 3).mean(axis=0)
        t.check(rgb[2] > 2.0 * rgb[1] and rgb[2] > 1.0, "blue.ome.tif renders in its file colour: mean rgb %s" % rgb)
        t.check("channel 1 (bad)" in r.stderr and "0xFF" in r.stderr and "Traceback" not in r.stderr,
                "blue.ome.tif: the malformed colour is a warning: %r" % r.stderr)


def test_raw(t, work):
    nz, ny, nx = 3, 4, 5
    two = np.arange(nz * ny * nx * 2, dtype=np.uint16).reshape(nz, ny, nx, 2) * 7
    two.astype("<u2").tofile(os.path.join(work, "two.raw"))
    image, err = load({"raw": "two.raw", "dimensions": [nx, ny, nz], "type": "uint16", "components": 2,
                       "spacing": [1, 2, 3], "origin": [-1, -2, -3]}, work)
    if t.check(err is None, "two.raw: %s" % (err and err.message)):
        t.check(np.array_equal(values_of(image, "two"), two), "two.raw: interleaved components on their voxels")
        t.check(image.GetSpacing() == (1, 2, 3) and image.GetOrigin() == (-1, -2, -3), "two.raw: spacing, origin")
    big = np.linspace(-1, 1, nz * ny * nx).astype(np.float32).reshape(nz, ny, nx)
    big.astype(">f4").tofile(os.path.join(work, "big.raw"))
    image, err = load({"raw": "big.raw", "dimensions": [nx, ny, nz], "type": "float32", "endianness": "big"}, work)
    if t.check(err is None, "big.raw: %s" % (err and err.message)):
        t.check(np.array_equal(values_of(image, "big")[..., 0], big), "big.raw: big-endian floats")


def test_several(t, work, program):
    nz, ny, nx = 5, 6, 7
    rng = np.random.default_rng(3)
    spacing = (0.8, 1.1, 1.7)
    rq = rotation([1, 2, 3], 25)
    offset = np.array([10.0, -20.0, 30.0])
    t1 = rng.integers(0, 1000, (nz, ny, nx)).astype(np.int16)
    labels = rng.integers(0, 5, (nz, ny, nx)).astype(np.uint8)
    write_nifti(os.path.join(work, "t1.nii.gz"), t1, spacing, (rq, offset), qfac=-1)
    write_nifti(os.path.join(work, "atlas.nii.gz"), labels, spacing, (rq, offset), qfac=-1)
    value = ["t1.nii.gz", "atlas.nii.gz"]
    image, err = load(value, work)
    if t.check(err is None, "t1 + atlas: %s" % (err and err.message)):
        pd = image.GetPointData()
        t.check([pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays())] == ["t1", "atlas"]
                and pd.GetScalars() is None, "t1 + atlas: arrays named after the files, no scalars")
        check_nifti(t, "t1 of two", image, "t1", os.path.join(work, "t1.nii.gz"), rq)
        check_nifti(t, "atlas of two", image, "atlas", os.path.join(work, "atlas.nii.gz"), rq)
    check_render(t, program, work, "render-two-files", value,
                 [channel("t1", color=[1, 1, 1]), channel("atlas", color=[1, 0, 0])], 2)

    # Different formats on one grid: NIfTI, raw, TIFF (their grids given).
    plain = rng.random((nz, ny, nx)).astype(np.float32)
    write_nifti(os.path.join(work, "plain.nii"), plain, spacing)
    labels.tofile(os.path.join(work, "labels.raw"))
    value = ["plain.nii", {"raw": "labels.raw", "dimensions": [nx, ny, nz], "type": "uint8", "spacing": list(spacing)}]
    if tifffile is not None:
        tifffile.imwrite(os.path.join(work, "mask.tif"), labels, photometric="minisblack", metadata=None)
        value.append({"file": "mask.tif", "name": "mask", "spacing": list(spacing)})
    image, err = load(value, work)
    if t.check(err is None, "NIfTI + raw + TIFF: %s" % (err and err.message)):
        t.check(np.array_equal(values_of(image, "plain")[..., 0], plain)
                and np.array_equal(values_of(image, "labels")[..., 0], labels)
                and (tifffile is None or np.array_equal(values_of(image, "mask")[..., 0], labels)),
                "NIfTI + raw + TIFF: voxels")

    # Resampling: the same voxels on a grid turned by 90 degrees in-plane
    # (index (ny-1-j, i, k), its own direction and origin) land back on
    # the first grid's voxels with "nearest".
    turn = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # columns -e1, e0, e2
    turned = np.ascontiguousarray(labels.transpose(0, 2, 1)[:, :, ::-1])
    write_nifti(os.path.join(work, "turned.nii.gz"), turned, (spacing[1], spacing[0], spacing[2]),
                (rq @ turn, offset + rq[:, 1] * spacing[1] * (ny - 1)))
    write_nifti(os.path.join(work, "ref.nii.gz"), t1, spacing, (rq, offset))
    image, err = load(["ref.nii.gz", "turned.nii.gz"], work)
    t.check(err is not None and err.key == "input[1]" and "does not match" in err.message,
            "a turned grid is not the first one's: %s" % (err and err.message))
    image, err = load(["ref.nii.gz", {"file": "turned.nii.gz", "resample": True}], work)
    if t.check(err is None, "resample turned: %s" % (err and err.message)):
        got = values_of(image, "turned")[..., 0]
        t.check(np.array_equal(got, labels), "resample (nearest for labels): %d of %d voxels differ"
                % (int((got != labels).sum()), labels.size))
    # Linear: a coarse grid of x + 2y + 3z (world) onto a fine one.
    coarse = np.fromfunction(lambda k, j, i: 2 * i + 4 * j + 6 * k, (4, 4, 4)).astype(np.float32)
    coarse.tofile(os.path.join(work, "coarse.raw"))
    np.zeros((8, 8, 8), np.float32).tofile(os.path.join(work, "fine.raw"))
    image, err = load([{"raw": "fine.raw", "dimensions": [8, 8, 8], "type": "float32"},
                       {"raw": "coarse.raw", "dimensions": [4, 4, 4], "type": "float32", "spacing": [2, 2, 2],
                        "resample": "linear"}], work)
    if t.check(err is None, "resample linear: %s" % (err and err.message)):
        got = values_of(image, "coarse")[..., 0]
        want = np.fromfunction(lambda k, j, i: i + 2 * j + 3 * k, (8, 8, 8))
        t.check(np.allclose(got[:7, :7, :7], want[:7, :7, :7], atol=1e-4), "resample linear: x + 2y + 3z")


def write_vtk_formats(work, name, values):
    """values (z, y, x) as name.vti, name.mha (uncompressed) and name.nrrd."""
    from vtkmodules.vtkIOImage import vtkMetaImageWriter
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    nz, ny, nx = values.shape
    image = vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(0.5, 0.5, 1.0)
    image.GetPointData().SetScalars(numpy_to_vtk(values.ravel(), deep=True))
    image.GetPointData().GetScalars().SetName("density")
    for writer, ext in ((vtkXMLImageDataWriter(), ".vti"), (vtkMetaImageWriter(), ".mha")):
        writer.SetInputData(image)
        writer.SetFileName(os.path.join(work, name + ext))
        if ext == ".mha":
            writer.SetCompression(False)
        writer.Write()
    with open(os.path.join(work, name + ".nrrd"), "wb") as f:
        f.write(("NRRD0004\ntype: short\ndimension: 3\nsizes: %d %d %d\nspacings: 0.5 0.5 1\nencoding: raw\n"
                 "endian: little\n\n" % (nx, ny, nz)).encode() + values.astype("<i2").tobytes())


def test_vtk_formats(t, work):
    values = np.random.default_rng(5).integers(0, 3000, (6, 7, 12)).astype(np.int16)  # x > 10: vtkNrrdReader reads a short first axis as components
    write_vtk_formats(work, "vol", values)
    image, err = load("vol.vti", work)
    if t.check(err is None, "vol.vti: %s" % (err and err.message)):
        t.check(image.GetPointData().GetScalars().GetName() == "density", "a single .vti keeps its array names")
    image, err = load(["vol.vti", {"file": "vol.mha", "name": "mha"}, {"file": "vol.nrrd", "name": "nrrd"}], work)
    if t.check(err is None, ".vti + .mha + .nrrd: %s" % (err and err.message)):
        t.check(all(np.array_equal(values_of(image, n)[..., 0], values) for n in ("vol", "mha", "nrrd")),
                ".vti, .mha, .nrrd: voxels")


def test_errors(t, work, program):
    rng = np.random.default_rng(4)
    data = rng.integers(0, 1000, (20, 30, 40)).astype(np.int16)
    write_nifti(os.path.join(work, "good.nii"), data, (1, 1, 1))
    write_nifti(os.path.join(work, "good.nii.gz"), data, (1, 1, 1))
    write_nifti(os.path.join(work, "other.nii"), data[:, :, :20], (1, 1, 2))
    with open(os.path.join(work, "good.nii"), "rb") as f:
        good = f.read()
    with open(os.path.join(work, "cut.nii"), "wb") as f:
        f.write(good[: len(good) - 1000])
    with open(os.path.join(work, "good.nii.gz"), "rb") as f:
        gz = f.read()
    with open(os.path.join(work, "cut.nii.gz"), "wb") as f:
        f.write(gz[: len(gz) // 2])
    header = bytearray(good)
    struct.pack_into("<2h", header, 70, 1536, 128)  # FLOAT128: VTK's reader would crash
    with open(os.path.join(work, "f128.nii"), "wb") as f:
        f.write(bytes(header) + bytes(len(good) * 8))
    np.zeros(999, np.uint8).tofile(os.path.join(work, "short.raw"))
    with open(os.path.join(work, "junk.tif"), "wb") as f:
        f.write(b"not a TIFF at all" * 10)
    write_vtk_formats(work, "cut", data)
    for ext, keep in ((".mha", 4000), (".nrrd", 9000)):
        with open(os.path.join(work, "cut" + ext), "rb") as f:
            head = f.read(keep)
        with open(os.path.join(work, "cut" + ext), "wb") as f:
            f.write(head)
    with open(os.path.join(work, "junk.vti"), "w") as f:
        f.write('<VTKFile type="ImageData">')
    w = lambda name: os.path.join(work, name)  # noqa: E731
    cases = [
        ("missing", ["good.nii", "nowhere.nii.gz"], ["input[1]:", "file not found", w("nowhere.nii.gz")]),
        ("truncated-nii", "cut.nii", ["input:", w("cut.nii"), "truncated", "%d bytes" % (len(good) - 1000),
                                      "needs %d" % len(good)]),
        ("truncated-gz", ["good.nii", {"file": "cut.nii.gz", "name": "cut"}], ["input[1].file:", w("cut.nii.gz")]),
        ("truncated-raw", {"raw": "short.raw", "dimensions": [10, 10, 10], "type": "uint8"},
         ["input.raw:", w("short.raw"), "999 bytes", "expects 1000"]),
        ("grids", ["good.nii", "other.nii"], ["input[1]:", w("good.nii"), w("other.nii"), "40x30x20", "20x30x20",
                                              "spacing 1 1 2"]),
        ("unsupported-type", "f128.nii", ["input:", w("f128.nii"), "FLOAT128"]),
        ("not-tiff", "junk.tif", ["input:", w("junk.tif")]),
        ("truncated-mha", "cut.mha", ["input:", w("cut.mha"), "truncated", "4000 bytes"]),
        ("truncated-nrrd", "cut.nrrd", ["input:", w("cut.nrrd")]),
        ("bad-vti", "junk.vti", ["input:", w("junk.vti")]),
        ("raw-type", {"raw": "short.raw", "dimensions": [10, 10, 10], "type": "int8"}, ["input.type:", "int8"]),
        ("same-name", ["good.nii", "good.nii.gz"], ["input[1]:", w("good.nii"), w("good.nii.gz"), "'good'"]),
        ("no-array", ["good.nii", {"file": "good.nii.gz", "name": "g2"}], ["channels[0]:", "give \"array\"", "g2"]),
        ("resample-first", [{"file": "good.nii", "resample": True}], ["input[0].resample:"]),
    ]
    if tifffile is not None:
        tifffile.imwrite(w("cut.tif"), data.astype(np.uint16), photometric="minisblack", metadata=None)
        with open(w("cut.tif"), "rb") as f:
            tif = f.read()
        with open(w("cut.tif"), "wb") as f:
            f.write(tif[: len(tif) * 3 // 4])
        cases.append(("truncated-tiff", "cut.tif", ["input:", w("cut.tif")]))
        tifffile.imwrite(w("cut-ij.tif"), data[:, None].astype(np.uint8), imagej=True, metadata={"axes": "ZCYX"})
        with open(w("cut-ij.tif"), "rb") as f:
            tif = f.read()
        with open(w("cut-ij.tif"), "wb") as f:
            f.write(tif[: len(tif) // 2])
        cases.append(("truncated-imagej", ["good.nii", "cut-ij.tif"], ["input[1]:", w("cut-ij.tif")]))
    for name, value, expected in cases:
        check_error(t, program, work, name, value, expected, [channel()] if name == "no-array" else None)


def test_mricron(t, work, program):
    ch2, aal = os.path.join(MRICRON, "ch2.nii.gz"), os.path.join(MRICRON, "aal.nii.gz")
    if not (os.path.isfile(ch2) and os.path.isfile(aal)):
        print("%s: no ch2.nii.gz and aal.nii.gz (mricron-data): skipped" % MRICRON)
        return
    image, err = load([ch2, aal], work)
    if t.check(err is None, "ch2 + aal: %s" % (err and err.message)):
        t.check(image.GetDimensions() == (181, 217, 181), "ch2 + aal: dimensions %s" % (image.GetDimensions(),))
        pd = image.GetPointData()
        t.check(pd.GetArray("ch2") is not None and pd.GetArray("aal") is not None, "ch2 + aal: both arrays")
    check_render(t, program, work, "render-ch2-aal", [ch2, aal],
                 [channel("ch2", color=[1, 1, 1]), channel("aal", color=[1, 0.5, 0])], 2)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mcvol-render", default=os.path.join(SOURCE, "Tools", "mcvol-render.py"))
    p.add_argument("--work", default=None)
    args = p.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="TestReaders-")
    os.makedirs(work, exist_ok=True)
    t = Checker()
    test_nifti(t, work, args.mcvol_render)
    test_tiff(t, work, args.mcvol_render)
    test_raw(t, work)
    test_vtk_formats(t, work)
    test_several(t, work, args.mcvol_render)
    test_errors(t, work, args.mcvol_render)
    test_mricron(t, work, args.mcvol_render)
    t.finish()


if __name__ == "__main__":
    main()
