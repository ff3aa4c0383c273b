#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""A scene file rendered by mcvol and by VTK's own GPU volume mapper, side by side.

    PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 \\
        Benchmarks/studies/compare_vtk_mapper.py SCENE.json -o side.png [--size 384x384] [--spp N]

The scene is assembled as mcvol-render assembles it (same data, transfer
functions, unit distances, camera, background, interpolation). VTK's
vtkGPUVolumeRayCastMapper then renders the same vtkVolumeProperty with the
channels stacked into one array of independent components (at most 4, VTK's
limit), and vtkFixedPointVolumeRayCastMapper does as well for reference where
the GPU mapper is not available. Lighting (ShadeOn) is passed on as it is.

VTK's mappers blend independent components with their own formula
(per-component opacity and colour weighted by the component weights), not by
any of mcvol's blend modes; the closest is mcvol's density blending. The
script prints the time of each render and the mean colour of the volume's
pixels, and writes the three images side by side: mcvol | VTK GPU | a
difference image (|mcvol - VTK| x 4).
"""

import argparse
import os
import sys
import time

import numpy as np


def grab(window):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    w2i = vtkWindowToImageFilter()
    w2i.SetInput(window)
    w2i.SetInputBufferTypeToRGB()
    w2i.ReadFrontBufferOff()
    w2i.Update()
    img = w2i.GetOutput()
    w, h, _ = img.GetDimensions()
    return vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, 3)[::-1].copy()


def stacked_image(pipeline):
    """The channels as the components of one array of a copy of the image."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData

    mapper = pipeline.mapper
    image = pipeline.mapper.GetInput()
    names = [mapper.GetChannelArray(i) for i in range(mapper.GetNumberOfChannelArrays())]
    if names:
        columns = [vtk_to_numpy(image.GetPointData().GetArray(n)) for n in names]
    else:
        s = vtk_to_numpy(image.GetPointData().GetScalars())
        columns = [s] if s.ndim == 1 else [s[:, k] for k in range(s.shape[1])]
    if len(columns) > 4:
        raise SystemExit("VTK's mappers take at most 4 independent components; this scene has %d channels"
                         % len(columns))
    dtype = np.result_type(*[c.dtype for c in columns])
    data = np.stack([c.astype(dtype) for c in columns], axis=1) if len(columns) > 1 else columns[0].astype(dtype)
    out = vtkImageData()
    out.CopyStructure(image)
    arr = numpy_to_vtk(np.ascontiguousarray(data), deep=True)
    arr.SetName("channels")
    out.GetPointData().SetScalars(arr)
    return out, len(columns)


def render_vtk(pipeline, mapper_class, size):
    from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume

    data, n = stacked_image(pipeline)
    prop = pipeline.volume.GetProperty()
    prop.SetIndependentComponents(True)
    mapper = mapper_class()
    mapper.SetInputData(data)
    if hasattr(mapper, "SetAutoAdjustSampleDistances"):
        mapper.SetAutoAdjustSampleDistances(0)
        spacing = min(data.GetSpacing())
        mapper.SetSampleDistance(spacing / 2.0)  # Nyquist, as mcvol's reference
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(pipeline.renderer.GetBackground())
    renderer.AddVolume(volume)
    renderer.SetActiveCamera(pipeline.renderer.GetActiveCamera())
    lights = pipeline.renderer.GetLights()
    lights.InitTraversal()
    for _ in range(lights.GetNumberOfItems()):
        renderer.AddLight(lights.GetNextItem())
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(*size)
    window.AddRenderer(renderer)
    window.Render()  # upload
    start = time.perf_counter()
    window.Render()
    seconds = time.perf_counter() - start
    return grab(window), seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--size", default=None, help="WxH (default: the scene's)")
    ap.add_argument("--spp", type=int, default=None, help="mcvol samples per pixel (default: the scene's)")
    ap.add_argument("--unlit", action="store_true", help="drop the scene's lighting (VTK's shading model differs)")
    ap.add_argument("--blend", default=None, help="override the scene's blend mode")
    args = ap.parse_args()

    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
    import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
    from vtkmodules.vtkRenderingVolume import vtkFixedPointVolumeRayCastMapper
    from vtkmodules.vtkRenderingVolumeOpenGL2 import vtkOpenGLGPUVolumeRayCastMapper

    import json

    from mcvol.scenefile import Presets, parse_scene
    from mcvol.scenefile.assemble import assemble
    from mcvol.scenefile.errors import ErrorCollector
    from mcvol.scenefile.render import accumulate

    top = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    presets = os.environ.get("MCVOL_PRESETS", os.path.join(top, "Data", "presets.json"))
    with open(args.scene) as f:
        scene = parse_scene(json.load(f), os.path.dirname(os.path.abspath(args.scene)), Presets(presets))
    if args.size:
        scene["image_size"] = [int(v) for v in args.size.lower().split("x")]
    if args.spp:
        scene["samples_per_pixel"] = args.spp
    if args.unlit:
        scene["lighting"] = None
    if args.blend:
        scene["blend"] = args.blend
    size = scene["image_size"]
    errors = ErrorCollector()
    pipeline = assemble(scene, errors, "compare_vtk_mapper")
    seconds = accumulate(pipeline, errors)
    ours = grab(pipeline.window)
    gpu, gpu_s = render_vtk(pipeline, vtkOpenGLGPUVolumeRayCastMapper, size)
    fixed, fixed_s = render_vtk(pipeline, vtkFixedPointVolumeRayCastMapper, size)

    bg = np.array(scene["background"]) * 255.0
    for name, img, s in (("mcvol", ours, seconds), ("VTK GPU", gpu, gpu_s), ("VTK fixed point", fixed, fixed_s)):
        mask = np.abs(img.astype(float) - bg).sum(axis=2) > 6
        mean = img[mask].mean(axis=0) if mask.any() else np.zeros(3)
        print("%-16s %8.3f s  volume pixels %6d  mean colour %5.1f %5.1f %5.1f" % (name, s, mask.sum(), *mean))
    diff = np.clip(np.abs(ours.astype(int) - gpu.astype(int)) * 4, 0, 255).astype(np.uint8)
    print("mean |mcvol - VTK GPU| %.2f levels" % np.abs(ours.astype(float) - gpu.astype(float)).mean())

    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter

    side = np.concatenate([ours, gpu, diff], axis=1)[::-1]
    h, w, _ = side.shape
    img = vtkImageData()
    img.SetDimensions(w, h, 1)
    img.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(side.reshape(-1, 3)), deep=True))
    writer = vtkPNGWriter()
    writer.SetFileName(args.output)
    writer.SetInputData(img)
    writer.Write()
    print("wrote", os.path.abspath(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
