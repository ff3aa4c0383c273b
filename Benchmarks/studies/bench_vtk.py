#!/usr/bin/python3
"""Frame time of vtkMultiChannelVolumeMapper against VTK's own volume mappers.

Renders the same 4-channel scene (independent components, one transfer
function per channel) at the same size with:
  - vtkMultiChannelVolumeMapper, 1 sample per pixel per frame, 1-DDA and N-DDA
  - vtkFixedPointVolumeRayCastMapper
  - vtkGPUVolumeRayCastMapper (on this machine: Mesa llvmpipe, i.e. the CPU)
and prints a Markdown table (median of the timed frames after warm-up).

VTK's mappers blend independent components with their own formulas (see
Documentation/design.md), so their images differ from ours by design: this compares time,
and writes a side-by-side picture, not an error.

Run from the build tree:  PYTHONPATH=build/lib/python3/dist-packages \
    xvfb-run -a /usr/bin/python3 Benchmarks/studies/bench_vtk.py --dims 256 256 256
"""
import argparse
import os
import statistics
import sys
import time

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (OpenGL factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
from vtkmodules.vtkRenderingCore import (vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty, vtkColorTransferFunction)
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingVolume import vtkFixedPointVolumeRayCastMapper, vtkGPUVolumeRayCastMapper
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper


def make_property(source, channels):
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    prop.SetInterpolationTypeToLinear()
    for c in range(channels):
        ctf = vtkColorTransferFunction()
        otf = vtkPiecewiseFunction()
        unit = [0.0]
        source.GetSuggestedTransferFunction(c, ctf, otf, unit)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, unit[0])
    return prop


def save_window(win, path):
    w2i = vtkWindowToImageFilter()
    w2i.SetInput(win)
    w2i.ReadFrontBufferOff()
    w2i.Update()
    png = vtkPNGWriter()
    png.SetFileName(path)
    png.SetInputConnection(w2i.GetOutputPort())
    png.Write()


def time_mapper(name, mapper, data, prop, args, out_dir):
    ren = vtkRenderer()
    ren.SetBackground(0.1, 0.1, 0.1)
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(args.size, args.size)
    win.AddRenderer(ren)
    mapper.SetInputData(data)
    vol = vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren.AddVolume(vol)
    ren.ResetCamera()
    cam = ren.GetActiveCamera()
    cam.Azimuth(30)
    cam.Elevation(20)
    ren.ResetCameraClippingRange()
    for _ in range(args.warmup):
        win.Render()
    times = []
    for _ in range(args.frames):
        t0 = time.perf_counter()
        win.Render()
        times.append(1e3 * (time.perf_counter() - t0))
    if out_dir:
        save_window(win, os.path.join(out_dir, "vtk_peer_%s.png" % name))
        if hasattr(mapper, "GetTotalSamples"):
            # The progressive image after more renders with nothing changed.
            mapper.SetSamplesPerPixel(16)
            while mapper.GetTotalSamples() < args.converged_spp:
                win.Render()
            save_window(win, os.path.join(out_dir, "vtk_peer_%s_%dspp.png" % (name, mapper.GetTotalSamples())))
    win.Finalize()
    return statistics.median(times), min(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default="cosmology")
    ap.add_argument("--dims", type=int, nargs=3, default=[256, 256, 256])
    ap.add_argument("--channels", type=int, default=4)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--warmup", type=int, default=2)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--images", default="", help="folder for a picture of each mapper's last frame")
    ap.add_argument("--converged-spp", type=int, default=256,
                    help="samples per pixel of the converged mcvol picture (with --images)")
    ap.add_argument("--skip", default="", help="comma-separated mapper names to skip")
    args = ap.parse_args()

    src = vtkMultiChannelDemoSource()
    src.SetDataset(args.dataset)
    src.SetDimensions(*args.dims)
    src.SetNumberOfChannels(args.channels)
    src.Update()
    data = src.GetOutput()
    prop = make_property(src, args.channels)
    if args.images:
        os.makedirs(args.images, exist_ok=True)

    skip = set(filter(None, args.skip.split(",")))
    rows = []
    for name in ["mcvol-1DDA", "mcvol-NDDA", "FixedPointRayCast", "GPURayCast-llvmpipe"]:
        if name in skip:
            continue
        if name.startswith("mcvol"):
            m = vtkMultiChannelVolumeMapper()
            m.SetSamplesPerPixel(1)
            m.SetBackendToCPU()
            m.SetTrackingMethod(m.ONE_DDA if name.endswith("1DDA") else m.N_DDA)
        elif name.startswith("Fixed"):
            m = vtkFixedPointVolumeRayCastMapper()
        else:
            m = vtkGPUVolumeRayCastMapper()
        med, mn = time_mapper(name, m, data, prop, args, args.images)
        rows.append((name, med, mn))
        print("%-22s median %8.1f ms  min %8.1f ms" % (name, med, mn), file=sys.stderr, flush=True)

    fixed = dict((r[0], r[1]) for r in rows).get("FixedPointRayCast")
    print("| mapper | median ms/frame | min ms | speed-up vs FixedPoint |")
    print("|---|---|---|---|")
    for name, med, mn in rows:
        sp = "%.1fx" % (fixed / med) if fixed else "-"
        print("| %s | %.1f | %.1f | %s |" % (name, med, mn, sp))


if __name__ == "__main__":
    main()
