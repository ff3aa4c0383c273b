"""How the mapper reacts to changes of its input image:
- moving the image (origin) resets the accumulation but rebuilds no tables;
- values written in place followed by image.Modified() rebuild the tables
  (their range changed) and change the picture;
- double data far from zero (1e9 + [0, 63]) keeps its resolution: a transfer
  function that is opaque only above 1e9 + 32 shows exactly that half;
- zero spacing is refused with an error and nothing is drawn.
"""
import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkDoubleArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba, use_test_backend

N = 64
BASE = 1e9


def make_image():
    img = vtkImageData()
    img.SetDimensions(N, 16, 16)
    arr = vtkDoubleArray()
    arr.SetName("ramp")
    arr.SetNumberOfTuples(N * 16 * 16)
    values = BASE + (np.arange(N * 16 * 16) % N).astype(np.float64)  # x index, offset by 1e9
    vtk_to_numpy(arr)[:] = values
    img.GetPointData().SetScalars(arr)
    return img, arr


def main():
    t = Checker()
    img, arr = make_image()
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputData(img)
    use_test_backend(mapper)
    mapper.SetSamplesPerPixel(4)
    errors = ErrorCatcher(mapper)
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(BASE, 1, 1, 1)
    ctf.AddRGBPoint(BASE + N, 1, 1, 1)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(BASE, 0.0)
    otf.AddPoint(BASE + 31.9, 0.0)
    otf.AddPoint(BASE + 32.1, 1.0)
    otf.AddPoint(BASE + N, 1.0)
    prop = vtkVolumeProperty()
    prop.SetColor(0, ctf)
    prop.SetScalarOpacity(0, otf)
    prop.SetScalarOpacityUnitDistance(0, 0.5)
    vol = vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtkRenderer()
    ren.AddVolume(vol)
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(128, 64)
    win.AddRenderer(ren)
    cam = ren.GetActiveCamera()
    cam.ParallelProjectionOn()
    cam.SetFocalPoint(31.5, 7.5, 7.5)
    cam.SetPosition(31.5, 7.5, 100)
    cam.SetParallelScale(16)
    ren.ResetCameraClippingRange()

    # Double data at 1e9: the opaque half is x > 32 (the right half of the
    # frame); columns of the left half are transparent.
    rgba = capture_rgba(win)
    alpha = rgba[:, :, 3].astype(float)
    cols = alpha[24:40].mean(axis=0)  # rows through the volume
    t.check(cols[:60].max() < 5 and cols[70:120].min() > 250,
            "double 1e9 + ramp: expected transparent left half and opaque right half, got column alpha %s"
            % np.round(cols[::8]).tolist())

    # Moving the image: accumulation restarts, no table is rebuilt.
    win.Render()
    before = mapper.GetTotalSamples()
    img.SetOrigin(5.0, 0.0, 0.0)
    win.Render()
    t.check(before > 4 and mapper.GetTotalSamples() == 4,
            "moving the image should restart the accumulation (%d -> %d)" % (before, mapper.GetTotalSamples()))
    t.check(mapper.GetLastTransferFunctionUpdates() == 0,
            "moving the image rebuilt %d tables" % mapper.GetLastTransferFunctionUpdates())
    img.SetOrigin(0.0, 0.0, 0.0)
    win.Render()

    # Values written in place, then image.Modified(): the range changes, so
    # the table is rebuilt, and the picture changes (all below the step now).
    vtk_to_numpy(arr)[:] -= 40.0
    img.Modified()
    rgba2 = capture_rgba(win)
    t.check(mapper.GetLastTransferFunctionUpdates() == 1,
            "in-place values + Modified(): %d tables rebuilt, expected 1" % mapper.GetLastTransferFunctionUpdates())
    t.check(rgba2[:, :, 3].max() < 5, "after lowering every value below the step the volume should vanish")

    # The values are compared from then on: image.Modified() (or a touch of
    # the point data, as ParaView's colouring sets the active scalars) with
    # the values unchanged keeps the samples; values written in place again
    # still restart.
    vtk_to_numpy(arr)[:] += 40.0
    img.Modified()
    win.Render()
    for _ in range(3):
        win.Render()
    before = mapper.GetTotalSamples()
    img.Modified()
    win.Render()
    t.check(mapper.GetTotalSamples() == before + 4,
            "image.Modified() with unchanged values keeps the samples (%d -> %d)" % (before, mapper.GetTotalSamples()))
    img.GetPointData().Modified()
    win.Render()
    t.check(mapper.GetTotalSamples() == before + 8,
            "a touch of the point data keeps the samples (%d -> %d)" % (before + 4, mapper.GetTotalSamples()))
    vtk_to_numpy(arr)[0] += 1.0
    img.Modified()
    win.Render()
    t.check(mapper.GetTotalSamples() == 4,
            "one voxel written in place + image.Modified() restarts (%d)" % mapper.GetTotalSamples())
    vtk_to_numpy(arr)[0] -= 1.0
    img.Modified()
    win.Render()

    # Zero spacing: an error, nothing drawn.
    errors.clear()
    img.SetSpacing(1.0, 0.0, 1.0)
    rgba3 = capture_rgba(win)
    t.check(any("spacing" in e for e in errors.errors), "zero spacing: expected an error, got %s" % errors.errors)
    t.check(rgba3[:, :, 3].max() == 0, "zero spacing: something was drawn")
    t.finish()


if __name__ == "__main__":
    main()
