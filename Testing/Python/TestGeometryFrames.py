"""The volume lands where VTK's geometry lands: perspective and parallel
cameras, the vtkVolume's position/orientation/scale matrix, and the image's
origin, spacing and direction matrix.

For each case an opaque box of voxels is rendered by vtkMultiChannelVolumeMapper,
and the same box as a polygonal cube (an actor with the same prop matrix) by
VTK's own surface renderer. The two coverage masks must agree except along
the outline: a wrong matrix, a flipped axis, a half-voxel offset or a wrong
projection moves whole rows or columns of pixels and fails.
"""

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkCommonMath import vtkMatrix3x3
from vtkmodules.vtkCommonTransforms import vtkTransform
from vtkmodules.vtkFiltersGeneral import vtkTransformPolyDataFilter
from vtkmodules.vtkFiltersSources import vtkCubeSource
from vtkmodules.vtkRenderingCore import (vtkActor, vtkColorTransferFunction, vtkPolyDataMapper, vtkRenderer,
                                         vtkRenderWindow, vtkVolume, vtkVolumeProperty)

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, capture_rgba

SIZE = 160
DIMS = (24, 20, 16)
BOX_LO, BOX_HI = (6, 5, 4), (17, 14, 11)  # voxels with value 1


def make_image(origin, spacing, direction):
    img = vtkImageData()
    img.SetDimensions(*DIMS)
    img.SetOrigin(*origin)
    img.SetSpacing(*spacing)
    m = vtkMatrix3x3()
    for r in range(3):
        for c in range(3):
            m.SetElement(r, c, direction[r][c])
    img.SetDirectionMatrix(m)
    values = np.zeros(DIMS[::-1], dtype=np.float32)  # z, y, x
    values[BOX_LO[2]:BOX_HI[2] + 1, BOX_LO[1]:BOX_HI[1] + 1, BOX_LO[0]:BOX_HI[0] + 1] = 1.0
    arr = vtkFloatArray()
    arr.SetName("box")
    arr.SetNumberOfValues(values.size)
    for i, v in enumerate(values.ravel()):
        arr.SetValue(i, float(v))
    img.GetPointData().SetScalars(arr)
    return img


def index_to_physical(origin, spacing, direction):
    """vtkTransform taking continuous voxel indices to physical coordinates."""
    t = vtkTransform()
    t.PostMultiply()
    t.Scale(*spacing)
    m = [[direction[r][c] for c in range(3)] for r in range(3)]
    flat = [m[0][0], m[0][1], m[0][2], 0, m[1][0], m[1][1], m[1][2], 0, m[2][0], m[2][1], m[2][2], 0, 0, 0, 0, 1]
    t.Concatenate(flat)
    t.Translate(*origin)
    return t


def place(prop, case):
    prop.SetPosition(*case["position"])
    prop.SetOrientation(*case["orientation"])
    prop.SetScale(*case["scale"])


def make_window():
    # One window for all renders: each window holds an X connection, and
    # many of them in parallel tests exhaust the X server.
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(SIZE, SIZE)
    win.SetMultiSamples(0)
    return win


def render(win, case, with_volume):
    win.GetRenderers().RemoveAllItems()
    ren = vtkRenderer()
    ren.SetBackground(0, 0, 0)
    win.AddRenderer(ren)
    spacing = case["spacing"]
    if with_volume:
        img = make_image(case["origin"], spacing, case["direction"])
        mapper = vtkMultiChannelVolumeMapper()
        mapper.SetInputData(img)
        mapper.SetSamplesPerPixel(8)
        prop = vtkVolumeProperty()
        ctf = vtkColorTransferFunction()
        ctf.AddRGBPoint(0.0, 1, 1, 1)
        ctf.AddRGBPoint(1.0, 1, 1, 1)
        otf = vtkPiecewiseFunction()
        otf.AddPoint(0.0, 0.0)
        otf.AddPoint(0.49, 0.0)
        otf.AddPoint(0.51, 1.0)
        otf.AddPoint(1.0, 1.0)
        prop.SetColor(0, ctf)
        prop.SetScalarOpacity(0, otf)
        prop.SetScalarOpacityUnitDistance(0, 1e-3 * min(spacing))  # opaque at once
        prop.SetInterpolationTypeToNearest()
        vol = vtkVolume()
        vol.SetMapper(mapper)
        vol.SetProperty(prop)
        place(vol, case)
        ren.AddVolume(vol)
    else:
        # Nearest sampling: voxel i covers indices [i - 0.5, i + 0.5].
        cube = vtkCubeSource()
        cube.SetBounds(BOX_LO[0] - 0.5, BOX_HI[0] + 0.5, BOX_LO[1] - 0.5, BOX_HI[1] + 0.5,
                       BOX_LO[2] - 0.5, BOX_HI[2] + 0.5)
        tf = vtkTransformPolyDataFilter()
        tf.SetInputConnection(cube.GetOutputPort())
        tf.SetTransform(index_to_physical(case["origin"], spacing, case["direction"]))
        pm = vtkPolyDataMapper()
        pm.SetInputConnection(tf.GetOutputPort())
        actor = vtkActor()
        actor.SetMapper(pm)
        actor.GetProperty().SetAmbient(1.0)
        actor.GetProperty().SetDiffuse(0.0)
        actor.GetProperty().SetColor(1, 1, 1)
        place(actor, case)
        ren.AddActor(actor)
    cam = ren.GetActiveCamera()
    cam.SetFocalPoint(*case["focal"])
    cam.SetPosition(*case["eye"])
    cam.SetViewUp(0, 1, 0)
    cam.SetParallelProjection(case["parallel"])
    cam.SetParallelScale(case["parallel_scale"])
    cam.SetViewAngle(30)
    ren.ResetCameraClippingRange(-1000, 1000, -1000, 1000, -1000, 1000)
    win.Render()
    rgba = capture_rgba(win)
    win.RemoveRenderer(ren)
    return rgba[:, :, 0] > 127


IDENTITY = ((1, 0, 0), (0, 1, 0), (0, 0, 1))
ROT_Z90 = ((0, -1, 0), (1, 0, 0), (0, 0, 1))  # index x runs along world +y
CASES = [
    dict(name="perspective, identity", parallel=False, origin=(0, 0, 0), spacing=(1, 1, 1), direction=IDENTITY,
         position=(0, 0, 0), orientation=(0, 0, 0), scale=(1, 1, 1), focal=(11.5, 9.5, 7.5), eye=(40, 30, 60),
         parallel_scale=15),
    dict(name="parallel, identity", parallel=True, origin=(0, 0, 0), spacing=(1, 1, 1), direction=IDENTITY,
         position=(0, 0, 0), orientation=(0, 0, 0), scale=(1, 1, 1), focal=(11.5, 9.5, 7.5), eye=(-30, 40, 50),
         parallel_scale=14),
    dict(name="perspective, anisotropic spacing and far origin", parallel=False, origin=(1000.0, -500.0, 20.0),
         spacing=(0.5, 2.0, 1.5), direction=IDENTITY, position=(0, 0, 0), orientation=(0, 0, 0), scale=(1, 1, 1),
         focal=(1005.75, -481.0, 31.25), eye=(1040, -450, 90), parallel_scale=15),
    dict(name="parallel, volume matrix (position, orientation, scale)", parallel=True, origin=(0, 0, 0),
         spacing=(1, 1, 1), direction=IDENTITY, position=(3, -2, 5), orientation=(20, 35, -10),
         scale=(1.5, 0.8, 1.2), focal=(15, 8, 12), eye=(15, 8, 80), parallel_scale=18),
    dict(name="perspective, image direction matrix", parallel=False, origin=(2, 1, 0), spacing=(1, 1, 1),
         direction=ROT_Z90, position=(0, 0, 0), orientation=(0, 0, 0), scale=(1, 1, 1), focal=(-7.5, 12.5, 7.5),
         eye=(-30, 40, 60), parallel_scale=15),
]


def main():
    t = Checker()
    win = make_window()
    for case in CASES:
        vol = render(win, case, True)
        geo = render(win, case, False)
        area = int(geo.sum())
        t.check(area > 400, "%s: the box covers only %d pixels (bad test set-up)" % (case["name"], area))
        # The outline: pixels within one pixel of the geometry's edge.
        edge = geo ^ np.roll(geo, 1, 0) | geo ^ np.roll(geo, -1, 0) | geo ^ np.roll(geo, 1, 1) | geo ^ np.roll(geo, -1, 1)
        inner_mismatch = int(((vol ^ geo) & ~edge).sum())
        t.check(inner_mismatch == 0,
                "%s: %d pixels away from the outline differ between volume and geometry (area %d)"
                % (case["name"], inner_mismatch, area))
        print("%s: area %d, mismatch off the outline %d, on it %d"
              % (case["name"], area, inner_mismatch, int(((vol ^ geo) & edge).sum())))
    t.finish()


if __name__ == "__main__":
    main()
