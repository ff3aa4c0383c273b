"""Image regression of vtkMultiChannelVolumeMapper: each of the four blend
modes on two datasets (the paper's Figure 3 cubes, float32; the microscopy
phantom, uint8), both trackers, against baselines in Testing/Data/Baseline.

A fixed seed gives the same Monte Carlo image on the same backend whatever
the thread count, so the comparison is tight: at most 2 of 255 levels on any
pixel (OpenGL's 8-bit blending over the background may round differently on
another driver) and a mean difference under 0.1 level. Any change to
sampling, tracking, blending, transfer-function handling or the camera moves
noise pixels by tens of levels and fails. 1-DDA and N-DDA draw random numbers
differently, so each has its own baselines; that they agree in expectation
is tested statistically in the core tests (Testing/Core/render_test.cxx).

Run with --generate to (re)write missing baselines for review.
"""
import os
import sys

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty, vtkWindowToImageFilter)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, read_png_rgb, write_png_rgb, use_test_backend

HERE = os.path.dirname(os.path.abspath(__file__))
BASELINES = os.path.join(HERE, "..", "Data", "Baseline")
SIZE = 160
SPP = 32
# "Mix" is Eq. 10 as published (SetMixColorModeToEquation10); "MixAverage" is
# the default mix colour, the weighted average of the channels present.
MODES = ["Density", "Max", "Mix", "MixAverage", "Composite"]
DATASETS = ["figure3", "microscopy"]


WINDOW = None


def window():
    """One render window for every render of the test (each window holds an
    X connection; many of them in parallel tests exhaust the X server)."""
    global WINDOW
    if WINDOW is None:
        WINDOW = vtkRenderWindow()
        WINDOW.SetOffScreenRendering(1)
        WINDOW.SetMultiSamples(0)
        WINDOW.SetSize(SIZE, SIZE)
    return WINDOW


def render(dataset, mode, tracker, spp=SPP, seed=7):
    src = vtkMultiChannelDemoSource()
    src.SetDataset(dataset)
    src.Update()
    n = src.GetNumberOfOutputChannels()
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    for c in range(n):
        ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
        src.GetSuggestedTransferFunction(c, ctf, otf, u)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, u[0])
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputConnection(src.GetOutputPort())
    getattr(mapper, "SetChannelBlendModeTo" + ("Mix" if mode == "MixAverage" else mode))()
    if mode == "Mix":
        mapper.SetMixColorModeToEquation10()
    mapper.SetTrackingMethod(tracker)
    mapper.SetSamplesPerPixel(spp)
    mapper.SetSeed(seed)
    # The baselines were made with the independent sampler: pinning it keeps
    # this test an exact regression of that sampler's images (the default
    # Sobol' sampler is tested statistically in Testing/Core/sequence_test.cxx).
    mapper.SetSampleSequenceToIndependent()
    mapper.SetEstimatorToCollision()  # and the collision estimator
    use_test_backend(mapper)
    if mode in ("Mix", "MixAverage"):
        for c in range(n):
            mapper.SetMixWeight(c, 1.0 + c)  # unequal weights, normalised by the mapper
    vol = vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtkRenderer()
    ren.SetBackground(0.1, 0.1, 0.15)
    ren.AddVolume(vol)
    win = window()
    win.AddRenderer(ren)
    ren.ResetCamera()
    ren.GetActiveCamera().Azimuth(30)
    ren.GetActiveCamera().Elevation(20)
    ren.ResetCameraClippingRange()
    win.Render()
    # The baselines hold the image that vtkWindowToImageFilter's own render
    # traced anew (spp samples, its camera's view angle recomputed through a
    # truncated pi, which moves a few Monte Carlo paths): start over, so that
    # its render traces the spp samples again rather than adding a batch.
    mapper.ResetAccumulation()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.ReadFrontBufferOff()
    grab.SetInputBufferTypeToRGB()
    grab.Update()
    img = grab.GetOutput()
    arr = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(SIZE, SIZE, 3).astype(np.float64)
    win.RemoveRenderer(ren)
    return arr





def main():
    generate = "--generate" in sys.argv
    t = Checker()
    for dataset in DATASETS:
        for mode in MODES:
            for tracker, tname in ((vtkMultiChannelVolumeMapper.ONE_DDA, "1dda"),
                                   (vtkMultiChannelVolumeMapper.N_DDA, "ndda")):
                name = "TestBlendMode_%s_%s_%s.png" % (dataset, mode.lower(), tname)
                path = os.path.join(BASELINES, name)
                img = render(dataset, mode, tracker)
                if not os.path.exists(path):
                    if generate:
                        write_png_rgb(path, img)
                        print("generated", path)
                        continue
                    t.check(False, "%s: baseline missing (run with --generate, review, commit)" % name)
                    continue
                diff = np.abs(img - read_png_rgb(path))
                t.check(diff.max() <= 2.0 and diff.mean() < 0.1,
                        "%s: differs from the baseline: max %.1f, mean %.3f levels" % (name, diff.max(), diff.mean()))
                print("%s: max %.1f mean %.4f levels" % (name, diff.max(), diff.mean()))
    t.finish()


if __name__ == "__main__":
    main()
