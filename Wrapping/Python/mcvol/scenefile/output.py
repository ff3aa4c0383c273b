# SPDX-License-Identifier: BSD-3-Clause
"""The rendered image out to files: the window as an 8-bit PNG, and the
mapper's float accumulation buffer as PFMs."""

from .errors import RenderError


def write_png(window, filename, errors):
    from vtkmodules.vtkIOImage import vtkPNGWriter
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOff()
    grab.Update()
    writer = vtkPNGWriter()
    errors.watch(writer)
    writer.SetFileName(filename)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    if errors.messages:
        raise RenderError("cannot write '%s': %s" % (filename, errors.messages[-1]))


def write_pfm(filename, width, height, channels, values):
    """PFM: "PF" (RGB) or "Pf" (gray), little-endian floats, bottom row first
    (the order OpenGL reads pixels in). `values`: a numpy array."""
    import numpy

    header = "%s\n%d %d\n-1.0\n" % ("PF" if channels == 3 else "Pf", width, height)
    with open(filename, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(numpy.ascontiguousarray(values, dtype="<f4").tobytes())


def write_raw(mapper, size, background, raw=None, raw_alpha=None):
    """`raw`: the linear RGB over `background`; `raw_alpha`: the alpha.
    Either file name may be None."""
    from vtkmodules.vtkCommonCore import vtkFloatArray

    w, h = size
    # Full float precision from the mapper's accumulation buffer
    # (premultiplied), not the 8-bit window.
    rgba = vtkFloatArray()
    mapper.GetAccumulatedImage(rgba)
    if (mapper.GetAccumulatedImageWidth(), mapper.GetAccumulatedImageHeight()) != (w, h):
        raise RenderError("the accumulated image is %dx%d, expected %dx%d" % (
            mapper.GetAccumulatedImageWidth(), mapper.GetAccumulatedImageHeight(), w, h))
    import numpy
    from vtkmodules.util.numpy_support import vtk_to_numpy

    values = vtk_to_numpy(rgba).reshape(-1, 4).astype(numpy.float32)
    alpha = values[:, 3]
    if raw:
        bg = numpy.asarray(background, dtype=numpy.float32)
        write_pfm(raw, w, h, 3, values[:, :3] + bg[None, :] * (1.0 - alpha[:, None]))
    if raw_alpha:
        write_pfm(raw_alpha, w, h, 1, alpha)
