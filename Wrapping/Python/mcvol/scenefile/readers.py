# SPDX-License-Identifier: BSD-3-Clause
"""The scene's input files (parse.parse_input) -> one vtkImageData.

Each format is read by VTK's own reader where one does the job:

    .vti               vtkXMLImageDataReader
    .mha .mhd          vtkMetaImageReader
    .nrrd .nhdr        vtkNrrdReader
    .nii .nii.gz       vtkNIFTIImageReader, its sform (else qform) put into
                       the image's origin and direction matrix
    .tif .tiff         vtkTIFFReader for plain z-stacks; OME-TIFF files and
                       ImageJ hyperstacks with tifffile (python3-tifffile),
                       since vtkTIFFReader reads their channels as slices
    raw                vtkImageReader2, the header given in the scene
    .zarr (a folder)   mcvol.omezarr (OME-NGFF 0.4): one array per channel,
                       the level that fits the memory budget

Several files (a list "input") become the point arrays of one image, each
file's point scalars named after it; their grids must match, unless a file
asks to be resampled onto the first one's grid.

Every failure is a SceneError naming the input's key and the file. VTK's
readers report errors to observers (errors.ErrorCollector) rather than
raising; other VTK objects print theirs to the output window, caught here
while a reader runs (update). Some readers do not notice a problem at all (a
truncated TIFF or MetaImage reads as zeros) or crash on it (a NIfTI of type
FLOAT128): the checks before each reader catch those.

VTK is imported inside the functions.
"""

import logging
import os
import struct
import sys
import tempfile

from .errors import RenderError, SceneError
from .schema import SUPPORTED_TYPES

# Two grids match when their dimensions are equal, their spacings agree to
# this relative tolerance, their direction matrices entry by entry to
# DIRECTION_TOLERANCE, and their origins to ORIGIN_TOLERANCE times the
# smallest spacing (NIfTI stores its matrices as float32).
SPACING_TOLERANCE = 1e-4
DIRECTION_TOLERANCE = 1e-4
ORIGIN_TOLERANCE = 1e-3

# NIfTI data types that vtkNIFTIImageReader reads (it crashes on FLOAT128
# and COMPLEX256 and cannot read BINARY).
NIFTI_TYPES = {
    2: "UINT8", 4: "INT16", 8: "INT32", 16: "FLOAT32", 32: "COMPLEX64", 64: "FLOAT64", 128: "RGB24", 256: "INT8",
    512: "UINT16", 768: "UINT32", 1024: "INT64", 1280: "UINT64", 1792: "COMPLEX128", 2304: "RGBA32",
}
NIFTI_UNSUPPORTED = {1: "BINARY", 1536: "FLOAT128", 2048: "COMPLEX256"}
RAW_SIZES = {"uint8": 1, "int16": 2, "uint16": 2, "float32": 4, "float64": 8}
META_SIZES = {"MET_UCHAR": 1, "MET_CHAR": 1, "MET_SHORT": 2, "MET_USHORT": 2, "MET_INT": 4, "MET_UINT": 4,
              "MET_LONG_LONG": 8, "MET_ULONG_LONG": 8, "MET_FLOAT": 4, "MET_DOUBLE": 8}
# Lengths in micrometres, to bring OME-TIFF physical sizes to one unit.
LENGTH_UNITS = {"pm": 1e-6, "nm": 1e-3, "µm": 1.0, "um": 1.0, "micron": 1.0, "mm": 1e3, "cm": 1e4, "m": 1e6}


def one_line(text):
    """A message on one line, without tifffile's "<tifffile.TiffPages @8> "."""
    text = " ".join(str(text).split())
    return text.split("> ", 1)[1] if text.startswith("<tifffile.") and "> " in text else text


def captured_error(text):
    """The first error in what VTK printed to its output window (and a
    truncated file's "File operation failed" warning), on one line."""
    for block in text.split("\n\n"):
        head, _, body = block.strip().partition("\n")
        if head.startswith("ERROR:") or "File operation failed" in body:
            body = one_line(body)
            who, sep, rest = body.partition("): ")
            return rest if sep and who.startswith("vtk") and " (" in who else body
    return None


def update(reader, key, filename, errors):
    """Runs a VTK reader; its first error becomes a SceneError. The reader's
    errors come to its observers (errors.watch); what other VTK objects print
    meanwhile (an XML parser's error, vtkImageReader's warning about a short
    read) is caught in a vtkStringOutputWindow, with VTK's logger silenced."""
    from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

    start = len(errors.messages)
    errors.watch(reader)
    # The executive only repeats that the reader failed, in many lines; the
    # readers' warnings are about what is handled here (a NIfTI's "SFormMatrix
    # is flipped compared to QFormMatrix"). Observed, neither is printed.
    reader.GetExecutive().AddObserver("ErrorEvent", lambda *args: None)
    reader.AddObserver("WarningEvent", lambda *args: None)
    window, verbosity = vtkOutputWindow.GetInstance(), vtkLogger.GetCurrentVerbosityCutoff()
    capture = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(capture)
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    # Some readers' libraries (MetaIO) print straight to the standard error:
    # kept from the terminal, and their last line said if the read fails.
    printed = tempfile.TemporaryFile()
    saved = os.dup(2)
    sys.stderr.flush()
    os.dup2(printed.fileno(), 2)
    try:
        reader.Update()
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        vtkOutputWindow.SetInstance(window)
        vtkLogger.SetStderrVerbosity(verbosity)
    printed.seek(0)
    stderr_lines = [one_line(x) for x in printed.read(65536).decode("utf-8", "replace").splitlines() if x.strip()]
    printed.close()
    image = reader.GetOutput()
    message = one_line(errors.messages[start]) if len(errors.messages) > start else captured_error(capture.GetOutput())
    if message:
        raise SceneError(key, "cannot read '%s': %s" % (filename, message))
    if image is None or image.GetNumberOfPoints() == 0:
        raise SceneError(key, "cannot read image data from '%s'%s" % (
            filename, ": " + stderr_lines[-1] if stderr_lines else ""))
    return image


NRRD_TYPES = {
    "signed char", "int8", "int8_t", "uchar", "unsigned char", "uint8", "uint8_t", "short", "short int",
    "signed short", "signed short int", "int16", "int16_t", "ushort", "unsigned short", "unsigned short int",
    "uint16", "uint16_t", "int", "signed int", "int32", "int32_t", "uint", "unsigned int", "uint32", "uint32_t",
    "longlong", "long long", "long long int", "signed long long", "signed long long int", "int64", "int64_t",
    "ulonglong", "unsigned long long", "unsigned long long int", "uint64", "uint64_t", "float", "double",
}
NRRD_ENCODINGS = {"raw", "txt", "text", "ascii", "hex", "gz", "gzip", "bz2", "bzip2"}


def check_nrrd_header(entry):
    """The NRRD header, checked field by field before vtkNrrdReader sees it:
    that reader crashes on a "sizes" that is not numbers, and never returns
    from a header whose last line runs into the end of the file."""
    fn, key = entry["file"], entry["file_key"]
    try:
        with open(fn, "rb") as f:
            head = f.read(65536)
            rest = f.read(1)
    except OSError as e:
        raise SceneError(key, "cannot read '%s': %s" % (fn, one_line(e)))
    text = head.replace(b"\r\n", b"\n")
    ended = b"\n\n" in text
    if not ended and (rest or not text.endswith(b"\n")):
        raise SceneError(key, "'%s' ends inside its NRRD header (a header ends with a blank line before the data)"
                         % fn)
    lines = text.split(b"\n\n", 1)[0].split(b"\n")

    def bad(what):
        return SceneError(key, "'%s' is not a valid NRRD file: %s" % (fn, what))

    if not lines[0].startswith(b"NRRD000") or lines[0][7:] not in (b"1", b"2", b"3", b"4", b"5"):
        raise bad("no NRRD000N magic line")
    fields = {}
    for raw in lines[1:]:
        if not raw or raw.startswith(b"#"):
            continue
        line = raw.decode("latin-1")
        k, sep, v = line.partition(": ")
        if not sep:
            k, sep, v = line.partition(":=")
            if not sep:
                raise bad("header line '%s' is neither 'field: value' nor 'key:=value'" % one_line(line)[:60])
            continue
        fields[k.strip().lower()] = v.strip()

    def integers(name, count=None, lo=0):
        try:
            values = [int(x) for x in fields[name].split()]
        except ValueError:
            values = None
        if values is None or (count is not None and len(values) != count) or any(x < lo for x in values):
            raise bad("\"%s: %s\" is not %s whole number(s) >= %d" % (
                name, fields[name][:60], count if count is not None else "some", lo))
        return values

    for required in ("type", "dimension", "sizes", "encoding"):
        if required not in fields:
            raise bad("no \"%s\" field" % required)
    (dimension,) = integers("dimension", 1, lo=1)
    if dimension > 16:
        raise bad("dimension %d (at most 16)" % dimension)
    integers("sizes", dimension, lo=1)
    if fields["type"].lower() not in NRRD_TYPES:
        raise bad("type '%s' is not a NRRD type" % fields["type"][:40])
    if fields["encoding"].lower() not in NRRD_ENCODINGS:
        raise bad("encoding '%s' is not a NRRD encoding" % fields["encoding"][:40])
    if "endian" in fields and fields["endian"].lower() not in ("little", "big"):
        raise bad("endian '%s' is neither little nor big" % fields["endian"][:40])
    for name in ("line skip", "lineskip"):
        if name in fields:
            integers(name, 1, lo=0)
    for name in ("byte skip", "byteskip"):
        if name in fields:
            integers(name, 1, lo=-1)
    for name in ("spacings", "thicknesses", "axis mins", "axismins", "axis maxs", "axismaxs"):
        if name in fields:
            values = fields[name].split()
            try:
                [float(x) for x in values]
            except ValueError:
                values = None
            if values is None or len(values) != dimension:
                raise bad("\"%s: %s\" is not %d numbers" % (name, fields[name][:60], dimension))


def check_meta_size(entry):
    """A MetaImage's uncompressed data must all be there (MetaIO only prints
    "data not read completely", and VTK's reader goes on)."""
    fn, key = entry["file"], entry["file_key"]
    fields, header = {}, 0
    try:
        with open(fn, "rb") as f:
            for line in f:
                header += len(line)
                k, sep, v = line.decode("latin-1").partition("=")
                if sep:
                    fields[k.strip()] = v.strip()
                if k.strip() == "ElementDataFile" or header > 65536:
                    break
    except OSError as e:
        raise SceneError(key, "cannot read '%s': %s" % (fn, one_line(e)))
    size = META_SIZES.get(fields.get("ElementType"))
    data = fields.get("ElementDataFile", "")
    try:
        skip = int(fields.get("HeaderSize", "0"))
        nbytes = size * int(fields.get("ElementNumberOfChannels", "1"))
        for n in fields["DimSize"].split():
            nbytes *= int(n)
    except (KeyError, TypeError, ValueError):
        return  # left to the reader
    if (fields.get("CompressedData", "False").lower() == "true" or not data or data == "LIST" or "%" in data
            or " " in data or skip < 0):
        return  # compressed, a list of files, or data at the end of a header: left to the reader
    if data == "LOCAL":
        path, need = fn, header + nbytes
    else:
        path = data if os.path.isabs(data) else os.path.join(os.path.dirname(fn), data)
        need = skip + nbytes
        if os.path.isdir(path):
            raise SceneError(key, "'%s' names its data file '%s', which is a folder" % (fn, path))
        if not os.path.isfile(path):
            raise SceneError(key, "'%s' names its data file '%s', which does not exist" % (fn, path))
    if os.path.getsize(path) < need:
        raise SceneError(key, "'%s' is truncated: %d bytes, its header needs %d" % (path, os.path.getsize(path), need))


def numpy_array(array):
    """A vtkDataArray as a numpy array of shape (tuples, components)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(array).reshape(array.GetNumberOfTuples(), array.GetNumberOfComponents())


def replace_array(image, old, values):
    """Puts numpy `values` in the place of point array `old`: same name,
    component names and role (the point scalars stay the scalars)."""
    from vtkmodules.util.numpy_support import numpy_to_vtk

    ncomp = old.GetNumberOfComponents()
    new = numpy_to_vtk(values.reshape(-1, ncomp) if ncomp > 1 else values.reshape(-1), deep=True)
    new.SetName(old.GetName())
    for c in range(ncomp):
        if old.GetComponentName(c):
            new.SetComponentName(c, old.GetComponentName(c))
    pd = image.GetPointData()
    if pd.GetScalars() is old:
        pd.SetScalars(new)
    else:
        pd.AddArray(new)
    return new


def point_arrays(image):
    pd = image.GetPointData()
    return [pd.GetArray(k) for k in range(pd.GetNumberOfArrays()) if pd.GetArray(k) is not None]


def convert_types(image):
    """Integer arrays of types the mapper does not read, converted without
    loss: 8-bit signed to int16; wider integers to float32 when every value
    fits its 24-bit mantissa, else to float64."""
    import numpy

    from vtkmodules.util.vtkConstants import VTK_BIT

    for array in point_arrays(image):
        if array.GetDataTypeAsString() in SUPPORTED_TYPES or array.GetDataType() == VTK_BIT:
            continue
        values = numpy_array(array)
        if values.dtype.itemsize == 1:
            values = values.astype(numpy.int16)
        else:
            big = values.size and max(abs(int(values.min())), abs(int(values.max()))) > (1 << 24)
            values = values.astype(numpy.float64 if big else numpy.float32)
        replace_array(image, array, values)


def name_scalars(image, name):
    scalars = image.GetPointData().GetScalars()
    if scalars is not None:
        scalars.SetName(name)


def read_vtk_format(entry, errors):
    """.vti, .mha/.mhd, .nrrd/.nhdr: the file as VTK reads it."""
    fmt, fn = entry["format"], entry["file"]
    if fmt == "vti":
        from vtkmodules.vtkIOXML import vtkXMLImageDataReader

        reader = vtkXMLImageDataReader()
    elif fmt == "meta":
        from vtkmodules.vtkIOImage import vtkMetaImageReader

        reader = vtkMetaImageReader()
    else:
        from vtkmodules.vtkIOImage import vtkNrrdReader

        reader = vtkNrrdReader()
    reader.SetFileName(fn)
    if not reader.CanReadFile(fn):
        raise SceneError(entry["file_key"], "cannot read '%s' as %s" % (fn, os.path.splitext(fn)[1].lower()))
    if fmt == "meta":
        check_meta_size(entry)
    elif fmt == "nrrd":
        check_nrrd_header(entry)
    return update(reader, entry["file_key"], fn, errors)


def nifti_header(entry):
    """(datatype, voxel bytes, data offset) from the NIfTI-1 or NIfTI-2
    header, read here: VTK's reader crashes on some types, and does not say
    how much of an uncompressed file is missing."""
    import gzip
    import zlib

    fn, key = entry["file"], entry["file_key"]
    try:
        with (gzip.open if fn.lower().endswith(".gz") else open)(fn, "rb") as f:
            head = f.read(540)
    except (OSError, EOFError, zlib.error) as e:
        raise SceneError(key, "cannot read '%s': %s" % (fn, one_line(e)))
    for order in "<>":
        size = struct.unpack(order + "i", head[:4])[0] if len(head) >= 4 else 0
        if size == 348 and len(head) >= 348:
            dims = struct.unpack_from(order + "8h", head, 40)
            datatype, bitpix = struct.unpack_from(order + "2h", head, 70)
            offset = struct.unpack_from(order + "f", head, 108)[0]
            offset = int(offset) if 0 <= offset < 1e12 else 0  # NaN or garbage: left to the reader
        elif size == 540 and len(head) >= 540:
            datatype, bitpix = struct.unpack_from(order + "2h", head, 12)
            dims = struct.unpack_from(order + "8q", head, 16)
            offset = struct.unpack_from(order + "q", head, 168)[0]
        else:
            continue
        if datatype not in NIFTI_TYPES:
            raise SceneError(key, "'%s' has NIfTI data type %s, which is not supported (supported: %s)" % (
                fn, NIFTI_UNSUPPORTED.get(datatype, datatype), ", ".join(NIFTI_TYPES.values())))
        voxels = 1
        for n in dims[1 : max(1, min(dims[0], 7)) + 1]:
            voxels *= max(n, 1)
        return datatype, voxels * bitpix // 8, offset
    raise SceneError(key, "'%s' is not a NIfTI file (no NIfTI-1 or NIfTI-2 header)" % fn)


def nifti_frame(reader, key, fn):
    """(3x3 matrix M, M with its columns normalised, translation t, column
    lengths) of the reader's sform, or else its qform: VTK data coordinates
    (origin + spacing * index) -> world = M x + t."""
    import numpy

    candidates = [m for m in (reader.GetSFormMatrix(), reader.GetQFormMatrix()) if m is not None]
    for m in candidates:
        full = numpy.array([[m.GetElement(r, c) for c in range(4)] for r in range(3)])
        scale = numpy.linalg.norm(full[:, :3], axis=0)
        if not numpy.all(scale > 0):
            continue
        direction = full[:, :3] / scale
        # A sheared sform is no rotation and spacing: take the qform then.
        if numpy.abs(direction.T @ direction - numpy.eye(3)).max() < 1e-3:
            return full[:, :3], direction, full[:, 3], scale
    if candidates:
        raise SceneError(key, "'%s': neither its sform nor its qform is a rotation and a spacing (sheared or "
                              "singular), which an image's direction matrix cannot hold" % fn)
    return numpy.eye(3), numpy.eye(3), numpy.zeros(3), numpy.ones(3)


def read_nifti(entry, errors):
    """NIfTI: time points and vector components become components; the
    orientation goes into the origin and direction matrix, so that world
    coordinates are the file's (RAS) world coordinates."""
    import numpy

    from vtkmodules.vtkIOImage import vtkNIFTIImageReader

    fn, key = entry["file"], entry["file_key"]
    _, nbytes, offset = nifti_header(entry)
    if not fn.lower().endswith(".gz") and os.path.getsize(fn) < offset + nbytes:
        raise SceneError(key, "'%s' is truncated: %d bytes, its header needs %d (%d of header, %d of voxels)"
                         % (fn, os.path.getsize(fn), offset + nbytes, offset, nbytes))
    reader = vtkNIFTIImageReader()
    reader.SetFileName(fn)
    reader.TimeAsVectorOn()
    if not reader.CanReadFile(fn):
        raise SceneError(key, "'%s' is not a NIfTI file" % fn)
    image = update(reader, key, fn, errors)
    scalars = image.GetPointData().GetScalars()
    slope, intercept = reader.GetRescaleSlope(), reader.GetRescaleIntercept()
    if slope != 0.0 and (slope != 1.0 or intercept != 0.0):  # scl_slope 0: no scaling
        values = numpy_array(scalars)
        kind = numpy.float64 if values.dtype == numpy.float64 else numpy.float32
        replace_array(image, scalars, values.astype(kind) * kind(slope) + kind(intercept))

    matrix, direction, translation, scale = nifti_frame(reader, key, fn)
    spacing = numpy.array(image.GetSpacing()) * scale
    origin = matrix @ numpy.array(image.GetOrigin()) + translation
    negative = spacing < 0  # a negative pixdim: the axis's direction turned instead
    spacing[negative] = -spacing[negative]
    direction[:, negative] = -direction[:, negative]
    if numpy.linalg.det(direction) < 0:
        # A flipped matrix (an sform of the other handedness than the qform
        # that set VTK's slice order): reverse the slices so that the
        # direction stays a rotation; every voxel keeps its world position.
        nz = image.GetDimensions()[2]
        origin = origin + direction[:, 2] * spacing[2] * (nz - 1)
        direction[:, 2] = -direction[:, 2]
        for array in point_arrays(image):
            values = numpy_array(array).reshape(nz, -1, array.GetNumberOfComponents())
            replace_array(image, array, numpy.ascontiguousarray(values[::-1]))
    image.SetSpacing(*spacing)
    image.SetOrigin(*origin)
    image.SetDirectionMatrix(*direction.ravel())
    name_scalars(image, entry["name"])
    return image


class TiffLog(logging.Handler):
    """Collects what tifffile logs while a file is open (it logs, rather than
    raises, about a broken page chain)."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())

    def __enter__(self):
        log = logging.getLogger("tifffile")
        self.propagate = log.propagate
        log.addHandler(self)
        log.propagate = False
        return self

    def __exit__(self, *args):
        log = logging.getLogger("tifffile")
        log.removeHandler(self)
        log.propagate = self.propagate


def ome_spacing(tf):
    """(spacing x, y, z, channel names) from the OME-XML: PhysicalSize*, in
    the x axis's unit when the others differ."""
    import xml.etree.ElementTree as ET

    pixels = next((e for e in ET.fromstring(tf.ome_metadata).iter() if e.tag.split("}")[-1] == "Pixels"), None)
    if pixels is None:
        return [1.0, 1.0, 1.0], []
    spacing = [float(pixels.get("PhysicalSize" + a, 1.0)) for a in "XYZ"]
    units = [pixels.get("PhysicalSize%sUnit" % a, "µm") for a in "XYZ"]
    if all(u in LENGTH_UNITS for u in units):
        spacing = [s * LENGTH_UNITS[u] / LENGTH_UNITS[units[0]] for s, u in zip(spacing, units)]
    names = [c.get("Name") for c in pixels if c.tag.split("}")[-1] == "Channel"]
    return spacing, names


def ome_color(text):
    """An OME-XML Channel's Color (a signed 32-bit integer, RGBA: red in the
    highest byte; writers that store it unsigned are read too) as (r, g, b)
    in [0, 1], or None when it is no such integer. Alpha is ignored."""
    try:
        value = int(str(text).strip())
    except ValueError:
        return None
    if not -(1 << 31) <= value < (1 << 32):
        return None
    value &= 0xFFFFFFFF
    return tuple(((value >> shift) & 0xFF) / 255.0 for shift in (24, 16, 8))


def ome_colors(tf, fn):
    """The Color of every Channel of the OME-XML's first image, as (r, g, b)
    or None (no Color, or one that is no OME colour: a warning names it)."""
    import xml.etree.ElementTree as ET

    from vtkmodules.vtkCommonCore import vtkOutputWindow

    pixels = next((e for e in ET.fromstring(tf.ome_metadata).iter() if e.tag.split("}")[-1] == "Pixels"), None)
    colors = []
    for c, channel in enumerate(e for e in (pixels if pixels is not None else []) if e.tag.split("}")[-1] == "Channel"):
        text = channel.get("Color")
        color = ome_color(text) if text is not None else None
        if text is not None and color is None:
            vtkOutputWindow.GetInstance().DisplayWarningText(
                "mcvol: '%s': channel %d (%s) has Color \"%s\", which is no OME colour (a signed 32-bit RGBA "
                "integer): it keeps its default colour\n" % (fn, c, channel.get("Name") or "no name", text))
        colors.append(color)
    return colors


def imagej_spacing(tf):
    """(spacing x, y, z): x and y from the resolution tags (pixels per
    unit), z from the ImageJ description's "spacing"."""
    spacing = []
    for tag in ("XResolution", "YResolution"):
        value = tf.pages[0].tags.get(tag)
        num, den = value.value if value is not None else (1, 1)
        spacing.append(den / num if num else 1.0)
    spacing.append(float((tf.imagej_metadata or {}).get("spacing", 1.0)))
    return spacing


def read_hyperstack(entry, tf):
    """An OME-TIFF or ImageJ hyperstack with tifffile: its first image
    (series), Z, Y and X as the grid, every other axis (C, T, S: channels,
    time, samples) as components, in the file's order."""
    import numpy

    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    fn, key = entry["file"], entry["file_key"]
    series = tf.series[0]
    axes = series.axes
    if "X" not in axes or "Y" not in axes:
        raise SceneError(key, "'%s' has axes %s: no X and Y" % (fn, axes))
    values = series.asarray()
    others = [i for i, a in enumerate(axes) if a not in "ZYX"]
    values = values.transpose([axes.index(a) for a in "ZYX" if a in axes] + others)
    if "Z" not in axes:
        values = values[numpy.newaxis]
    nz, ny, nx = values.shape[:3]
    ncomp = int(numpy.prod(values.shape[3:], dtype=numpy.int64))
    if values.dtype.kind == "c":
        raise SceneError(key, "'%s' holds complex values, which are not supported" % fn)
    if values.dtype.kind == "b" or values.dtype == numpy.float16:
        values = values.astype(numpy.uint8 if values.dtype.kind == "b" else numpy.float32)
    values = numpy.ascontiguousarray(values.reshape(nz * ny * nx, ncomp), dtype=values.dtype.newbyteorder("="))
    spacing, names = ome_spacing(tf) if tf.is_ome else (imagej_spacing(tf), [])
    array = numpy_to_vtk(values if ncomp > 1 else values.reshape(-1), deep=True)
    array.SetName(entry["name"])
    channels = [axes[i] for i in others] == ["C"]
    if channels and len(names) == ncomp and all(names):
        for c, n in enumerate(names):
            array.SetComponentName(c, n)
    image = vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    image.GetPointData().SetScalars(array)
    # The channels' colours as the array's default displays (as an
    # OME-Zarr's omero colours): a channel without one keeps the default.
    colors = ome_colors(tf, fn) if channels and tf.is_ome else []
    if len(colors) == ncomp and any(colors):
        from ..omezarr import display_array

        image.GetFieldData().AddArray(display_array(entry["name"], [{"color": c} for c in colors]))
    return image


def read_tiff(entry, errors):
    """A TIFF: checked with tifffile (every page's data inside the file), then
    an OME-TIFF or ImageJ file read with tifffile, any other with
    vtkTIFFReader. Both put the file's first row at y = 0."""
    fn, key = entry["file"], entry["file_key"]
    try:
        import tifffile
    except ImportError:
        raise RenderError("reading TIFF files needs the Python package tifffile (Debian: python3-tifffile)")
    size = os.path.getsize(fn)
    try:
        with TiffLog() as log, tifffile.TiffFile(fn) as tf:
            pages = list(tf.pages)
            if log.messages:
                raise SceneError(key, "cannot read '%s' as TIFF: %s" % (fn, one_line(log.messages[0])))
            ends = [(max((o + n for o, n in zip(p.dataoffsets, p.databytecounts)), default=0), "page %d" % i)
                    for i, p in enumerate(pages)]
            series = tf.series[0]
            # Contiguous data: all of it (ImageJ writes one page for more than 4 GB).
            if series.dataoffset is not None:
                ends.append((series.dataoffset + series.nbytes, "the image data"))
            end, what = max(ends)
            if end > size:
                raise SceneError(key, "'%s' is truncated: %d bytes, %s needs %d" % (fn, size, what, end))
            if tf.is_ome or tf.is_imagej:
                image = read_hyperstack(entry, tf)
                if log.messages:  # say, a file of a multi-file OME dataset missing
                    raise SceneError(key, "cannot read '%s' as TIFF: %s" % (fn, one_line(log.messages[0])))
                name_scalars(image, entry["name"])
                return image
            shape = (pages[0].imagewidth, pages[0].imagelength, len(pages))
    except SceneError:
        raise
    except MemoryError:
        raise SceneError(key, "cannot read '%s' as TIFF: its header asks for more memory than there is" % fn)
    except Exception as e:  # noqa: B902
        # tifffile parses untrusted bytes: a damaged tag surfaces as any
        # exception (TiffFileError, ValueError, TypeError, struct.error,
        # SyntaxError from bad OME-XML, ...). Each means the file is broken.
        raise SceneError(key, "cannot read '%s' as TIFF: %s" % (fn, one_line(e) or type(e).__name__))
    from vtkmodules.vtkIOImage import vtkTIFFReader

    reader = vtkTIFFReader()
    reader.SetFileName(fn)
    image = update(reader, key, fn, errors)
    if tuple(image.GetDimensions()) != shape:
        raise SceneError(key, "'%s' read as %s voxels, expected %s (pages of different sizes?)" % (
            fn, "x".join(map(str, image.GetDimensions())), "x".join(map(str, shape))))
    name_scalars(image, entry["name"])
    return image


def read_raw(entry, errors):
    """Raw voxels, x fastest, then y, then z, components interleaved; the
    file's size must be what the header says."""
    from vtkmodules.util.vtkConstants import VTK_DOUBLE, VTK_FLOAT, VTK_SHORT, VTK_UNSIGNED_CHAR, VTK_UNSIGNED_SHORT
    from vtkmodules.vtkIOImage import vtkImageReader2

    fn, key, raw = entry["file"], entry["file_key"], entry["raw"]
    x, y, z = raw["dimensions"]
    expected = x * y * z * raw["components"] * RAW_SIZES[raw["type"]]
    size = os.path.getsize(fn)
    if size != expected:
        raise SceneError(key, "'%s' has %d bytes, the header expects %d (%dx%dx%d voxels x %d component(s) x %d "
                              "bytes of %s)" % (fn, size, expected, x, y, z, raw["components"],
                                                RAW_SIZES[raw["type"]], raw["type"]))
    reader = vtkImageReader2()
    reader.SetFileName(fn)
    reader.SetFileDimensionality(3)
    reader.SetDataExtent(0, x - 1, 0, y - 1, 0, z - 1)
    reader.SetDataScalarType({"uint8": VTK_UNSIGNED_CHAR, "int16": VTK_SHORT, "uint16": VTK_UNSIGNED_SHORT,
                              "float32": VTK_FLOAT, "float64": VTK_DOUBLE}[raw["type"]])
    reader.SetNumberOfScalarComponents(raw["components"])
    if raw["endianness"] == "big":
        reader.SetDataByteOrderToBigEndian()
    else:
        reader.SetDataByteOrderToLittleEndian()
    reader.FileLowerLeftOn()  # the file's first row is y = 0 (vtkImageReader2 flips by default)
    image = update(reader, key, fn, errors)
    name_scalars(image, entry["name"])
    return image


def read_omezarr(entry, errors):
    """An OME-Zarr image (mcvol.omezarr): the level named, or the finest
    that fits the memory budget, its time step and region; one point array
    per channel. Which level was read goes to entry["report"]."""
    try:
        import numcodecs  # noqa: F401
    except ImportError:
        raise RenderError("reading OME-Zarr needs the Python package numcodecs (Debian: python3-zarr)")
    from ..omezarr import OMEZarrError, OMEZarrImage

    try:
        image = OMEZarrImage(entry["file"])
        data = image.read(level=entry.get("level"), time=entry.get("time", 0), region=entry.get("region"),
                          memory_budget=entry.get("memory_budget", 0.0))
    except OMEZarrError as e:
        raise SceneError(entry["file_key"], str(e))
    entry["report"] = image.report
    return data


def read_input(entry, errors):
    """One file as a vtkImageData, its "spacing" and "origin" applied."""
    read = {"nifti": read_nifti, "tiff": read_tiff, "raw": read_raw, "omezarr": read_omezarr}.get(
        entry["format"], read_vtk_format)
    image = read(entry, errors)
    if "spacing" in entry:
        image.SetSpacing(*entry["spacing"])
    if "origin" in entry:
        image.SetOrigin(*entry["origin"])
    if not all(0.0 < s < float("inf") for s in image.GetSpacing()):
        raise SceneError(entry["key"], "'%s' has voxel spacing %s: give \"spacing\"" % (
            entry["file"], " ".join("%g" % s for s in image.GetSpacing())))
    check_scale(entry, image)
    return image


# What VTK's camera and double precision can show (Rendering/VTK/View.h,
# CheckScale): a volume at least this many world units across, and no
# farther from the origin than 2^46 of its smallest spacings.
MINIMUM_VOLUME_SIZE = 1e-20
MAXIMUM_ORIGIN_IN_SPACINGS = 2.0 ** 46


def check_scale(entry, image):
    """The volume's size and position, checked as the mapper checks them, so
    that a scene says which input and key to change."""
    dims, spacing = image.GetDimensions(), image.GetSpacing()
    corners = []
    for k in range(8):
        ijk = [(dims[a] - 1 if k >> a & 1 else 0) for a in range(3)]
        xyz = [0.0, 0.0, 0.0]
        image.TransformContinuousIndexToPhysicalPoint(ijk, xyz)
        corners.append(xyz)
    size = max(max(c[a] for c in corners) - min(c[a] for c in corners) for a in range(3))
    size = max(size, max(spacing) if max(dims) == 1 else 0.0)
    far = max(abs(v) for c in corners for v in c)
    finest = min(spacing)
    if not far <= MAXIMUM_ORIGIN_IN_SPACINGS * finest:
        raise SceneError(entry["key"], "'%s' lies %g from the world origin with a smallest spacing of %g: beyond "
                         "2^46 spacings double precision cannot place rays on its voxels; give an \"origin\" nearer 0"
                         % (entry["file"], far, finest))
    if not size >= MINIMUM_VOLUME_SIZE:
        raise SceneError(entry["key"], "'%s' is %g world units across: VTK's camera shows nothing smaller than %g; "
                         "give a larger \"spacing\"" % (entry["file"], size, MINIMUM_VOLUME_SIZE))


def grid(image):
    """Dimensions, spacing, world position of the first voxel, direction rows."""
    d = image.GetDirectionMatrix()
    first = [0.0, 0.0, 0.0]
    image.TransformIndexToPhysicalPoint(image.GetExtent()[0::2], first)
    return (list(image.GetDimensions()), list(image.GetSpacing()), first,
            [[d.GetElement(r, c) for c in range(3)] for r in range(3)])


def grid_text(g):
    dims, spacing, origin, direction = g
    text = "%s, spacing %s, origin %s" % ("x".join(map(str, dims)), " ".join("%g" % s for s in spacing),
                                          " ".join("%g" % o for o in origin))
    if any(abs(direction[r][c] - (r == c)) > DIRECTION_TOLERANCE for r in range(3) for c in range(3)):
        text += ", direction %s" % " ".join("[%s]" % " ".join("%.4g" % v for v in row) for row in direction)
    return text


def grids_match(a, b):
    tol = ORIGIN_TOLERANCE * min(abs(s) for s in a[1] + b[1])
    return (a[0] == b[0]
            and all(abs(p - q) <= SPACING_TOLERANCE * max(abs(p), abs(q)) for p, q in zip(a[1], b[1]))
            and all(abs(p - q) <= tol for p, q in zip(a[2], b[2]))
            and all(abs(p - q) <= DIRECTION_TOLERANCE for r, s in zip(a[3], b[3]) for p, q in zip(r, s)))


def resample(image, reference, mode):
    """`image`'s point arrays on `reference`'s grid (vtkImageReslice), 0
    outside `image`. "auto": nearest for integer arrays (labels), linear for
    the others."""
    import numpy

    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkCommonMath import vtkMatrix4x4
    from vtkmodules.vtkImagingCore import vtkImageReslice

    def frame(im):
        d = im.GetDirectionMatrix()
        return numpy.array([[d.GetElement(r, c) for c in range(3)] for r in range(3)]), numpy.array(im.GetOrigin())

    # Reslice both in frames without origin and direction: an output point
    # y = spacing * index is the input's x = D_in^-1 (O_out + D_out y - O_in).
    d_in, o_in = frame(image)
    d_out, o_out = frame(reference)
    inverse = numpy.linalg.inv(d_in)
    axes = vtkMatrix4x4()
    for r, row in enumerate(numpy.hstack([inverse @ d_out, (inverse @ (o_out - o_in))[:, None]])):
        for c, v in enumerate(row):
            axes.SetElement(r, c, v)
    out = vtkImageData()
    out.CopyStructure(reference)
    for array in point_arrays(image):
        src = vtkImageData()
        src.CopyStructure(image)
        src.SetOrigin(0.0, 0.0, 0.0)
        src.SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1)
        src.GetPointData().SetScalars(array)
        reslice = vtkImageReslice()
        reslice.SetInputData(src)
        reslice.SetResliceAxes(axes)
        reslice.SetOutputSpacing(reference.GetSpacing())
        reslice.SetOutputOrigin(0.0, 0.0, 0.0)
        reslice.SetOutputExtent(reference.GetExtent())
        nearest = mode == "nearest" or (mode == "auto" and numpy_array(array).dtype.kind in "iu")
        if nearest:
            reslice.SetInterpolationModeToNearestNeighbor()
        else:
            reslice.SetInterpolationModeToLinear()
        reslice.Update()
        result = reslice.GetOutput().GetPointData().GetScalars()
        result.SetName(array.GetName())
        for c in range(array.GetNumberOfComponents()):
            if array.GetComponentName(c):
                result.SetComponentName(c, array.GetComponentName(c))
        if array is image.GetPointData().GetScalars():
            out.GetPointData().SetScalars(result)
        else:
            out.GetPointData().AddArray(result)
    out.GetFieldData().PassData(image.GetFieldData())  # the file's default displays
    return out


def read_inputs(spec, errors):
    """The image of a file input (parse.parse_input): one file as it is read,
    or a list of files as the point arrays of one image. In a list, a file's
    point scalars are named after the input ("name", by default the file's
    stem) and its other point arrays "name/array"; the image has no point
    scalars."""
    from vtkmodules.vtkCommonDataModel import vtkImageData

    entries = spec["inputs"]
    images = []
    for entry in entries:
        image = read_input(entry, errors)
        if images and entry["resample"]:
            image = resample(image, images[0], entry["resample"])
        elif images and not grids_match(grid(image), grid(images[0])):
            raise SceneError(entry["key"], "the grid of '%s' (%s) does not match the grid of '%s' (%s): give it "
                                           "\"resample\": true" % (entry["file"], grid_text(grid(image)),
                                                                   entries[0]["file"], grid_text(grid(images[0]))))
        convert_types(image)
        images.append(image)
    if not spec["list"]:
        return images[0]
    from ..omezarr import DISPLAY_PREFIX

    out = vtkImageData()
    out.CopyStructure(images[0])
    for entry, image in zip(entries, images):
        scalars = image.GetPointData().GetScalars()
        fd = image.GetFieldData()
        for k, array in enumerate(point_arrays(image)):
            display = fd.GetArray(DISPLAY_PREFIX + array.GetName()) if array.GetName() else None
            if array is not scalars:
                array.SetName("%s/%s" % (entry["name"], array.GetName() or "array %d" % k))
            else:
                array.SetName(entry["name"])
            out.GetPointData().AddArray(array)
            if display is not None:  # the file's default display goes with its array, renamed
                copy = display.NewInstance()
                copy.DeepCopy(display)
                copy.SetName(DISPLAY_PREFIX + array.GetName())
                out.GetFieldData().AddArray(copy)
    return out
