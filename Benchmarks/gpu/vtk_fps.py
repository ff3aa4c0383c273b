#!/usr/bin/python3
"""User-visible frame rate of vtkMultiChannelVolumeMapper in a VTK render window.

What a user sees while dragging: every render moves the camera (the image
restarts) and traces one sample per pixel. For each dataset and window size
the table gives frames per second and the median milliseconds of

- trace: the mapper's trace stage (on the GPU: the kernels and the copy of
  the image back to the host; GetLastTraceTime()),
- draw: drawing the image over the framebuffer (GetLastDrawTime()),
- frame: the whole vtkRenderWindow::Render() (VTK's own work, the mapper's
  checks of input, tables and camera, the depth read, the trace, the draw,
  and the buffer swap), timed from Python,

and the same for still-camera progressive renders (the image refines). The
kernel alone is mcvol-bench's figure (Benchmarks/gpu/bench.sh paper).

    PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a -s "-screen 0 1920x1200x24" \\
        /usr/bin/python3 Benchmarks/gpu/vtk_fps.py --backend cuda
"""
import argparse
import platform
import statistics
import time

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper

DATASETS = {
    # name: (demo dataset, dimensions, channels), the paper protocol's sizes
    "NYX-like": ("cosmology", (512, 512, 512), 4),
    "Zebrafish-like": ("microscopy", (640, 640, 121), 3),
}


def build(dataset, dims, channels):
    src = vtkMultiChannelDemoSource()
    src.SetDataset(dataset)
    src.SetDimensions(*dims)
    src.SetNumberOfChannels(channels)
    src.Update()
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    prop.SetInterpolationTypeToLinear()
    for c in range(src.GetNumberOfOutputChannels()):
        ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
        src.GetSuggestedTransferFunction(c, ctf, otf, u)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, u[0])
    return src, prop


def percentile(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(round(q * (len(v) - 1))))]


def run(src, prop, size, backend, frames, warmup, moving):
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputConnection(src.GetOutputPort())
    getattr(mapper, "SetBackendTo" + {"cpu": "CPU", "cuda": "CUDA", "auto": "Auto"}[backend])()
    mapper.SetSamplesPerPixel(1)
    vol = vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtkRenderer()
    ren.AddVolume(vol)
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(0)
    win.SetSize(*size)
    win.AddRenderer(ren)
    ren.ResetCamera()
    cam = ren.GetActiveCamera()
    for _ in range(warmup):
        if moving:
            cam.Azimuth(0.5)
        win.Render()
    frame, trace, draw = [], [], []
    start = time.perf_counter()
    for _ in range(frames):
        if moving:
            cam.Azimuth(0.5)
        t0 = time.perf_counter()
        win.Render()
        frame.append(1e3 * (time.perf_counter() - t0))
        trace.append(1e3 * mapper.GetLastTraceTime())
        draw.append(1e3 * mapper.GetLastDrawTime())
    total = time.perf_counter() - start
    result = dict(fps=frames / total, frame=statistics.median(frame), frame95=percentile(frame, 0.95),
                  trace=statistics.median(trace), draw=statistics.median(draw),
                  backend=mapper.GetActiveBackendName(), uploads=mapper.GetNumberOfDataUploads(),
                  memory=mapper.GetDeviceMemory() / 2**20, spp=mapper.GetTotalSamples())
    win.Finalize()
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--datasets", default="NYX-like,Zebrafish-like")
    ap.add_argument("--sizes", default="1024x1024,1920x1080")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--backend", default="cuda", choices=["cpu", "cuda", "auto"])
    args = ap.parse_args()

    print("# VTK render window frame rate (%s backend, 1 spp per render)" % args.backend)
    print("")
    print("%s, %s; %d timed renders after %d warm-up renders; OpenGL draw through Xvfb (Mesa llvmpipe)."
          % (platform.node(), time.strftime("%Y-%m-%d"), args.frames, args.warmup))
    print("")
    print("| dataset | window | camera | FPS | frame ms (median / 95th) | trace ms | draw ms "
          "| rest ms | uploads | device MiB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in args.datasets.split(","):
        dataset, dims, channels = DATASETS[name]
        src, prop = build(dataset, dims, channels)
        for size in args.sizes.split(","):
            w, h = (int(v) for v in size.split("x"))
            for moving in (True, False):
                r = run(src, prop, (w, h), args.backend, args.frames, args.warmup, moving)
                print("| %s | %dx%d | %s | %.0f | %.2f / %.2f | %.2f | %.2f | %.2f | %d | %.0f |" % (
                    name, w, h, "moving" if moving else "still", r["fps"], r["frame"], r["frame95"], r["trace"],
                    r["draw"], r["frame"] - r["trace"] - r["draw"], r["uploads"], r["memory"]), flush=True)


if __name__ == "__main__":
    main()
