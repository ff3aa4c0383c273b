"""Frame time against level of detail, Monte Carlo against the ray marcher,
through the VTK mappers (no ParaView), with the macrocell edge varied at the
levels (does a smaller edge, which keeps the majorants' world extent, pay?).
The volume and transfer functions are lod_bench.py's, at --dims.

  PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 \\
      Benchmarks/studies/lod_levels_vtk.py --dims 256 --size 512

Prints a Markdown table: mapper, level, macrocell edge, median frame ms of 5
frames that each move the camera 1 degree (1 sample per pixel for Monte
Carlo; one deterministic march at the Nyquist step of the level), trace ms.
"""
import argparse
import os
import statistics
import time

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)

from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper


def make_volume(n):
    # lod_bench.py's volume (that script needs pvpython, this one does not).
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    image = vtkImageData()
    image.SetDimensions(n, n, n)
    x = np.linspace(0.0, 1.0, n, dtype=np.float32)
    freqs = [(3.1, 2.3, 1.7), (1.3, 3.7, 2.9), (2.2, 1.1, 3.3), (4.1, 3.9, 4.3)]
    keep = []
    for k, (fx, fy, fz) in enumerate(freqs):
        sx = np.sin(np.pi * fx * x + 0.3 * k)
        sy = np.sin(np.pi * fy * x + 0.7 * k)
        sz = np.sin(np.pi * fz * x + 1.1 * k)
        c = (sz[:, None, None] * (sy[:, None] * sx[None, :])[None, :, :]) * 0.5 + 0.5
        c = c.astype(np.float32)
        keep.append(c)
        a = numpy_to_vtk(c.reshape(-1), deep=False)
        a.SetName("c%d" % k)
        image.GetPointData().AddArray(a)
    return image, keep


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--dims", type=int, default=256)
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--opacity", type=float, default=0.05)
    args = p.parse_args()
    image, keep = make_volume(args.dims)  # noqa: F841 (numpy owns the data)
    prop = vtkVolumeProperty()
    colors = [(1.0, 0.3, 0.1), (0.1, 0.9, 0.3), (0.2, 0.4, 1.0), (1.0, 0.9, 0.2)]
    for k in range(4):
        ctf = vtkColorTransferFunction()
        ctf.AddRGBPoint(0.0, *colors[k])
        ctf.AddRGBPoint(1.0, *colors[k])
        otf = vtkPiecewiseFunction()
        otf.AddPoint(0.0, 0.0)
        otf.AddPoint(0.6, 0.0)
        otf.AddPoint(1.0, args.opacity)
        prop.SetColor(k, ctf)
        prop.SetScalarOpacity(k, otf)
    print("| mapper | level | macrocell edge | frame ms (median of 5) | trace ms |")
    print("|---|---|---|---|---|")
    for label, mapper in (("Monte Carlo", vtkMultiChannelVolumeMapper()), ("ray march", vtkMultiChannelRayMarchMapper())):
        mapper.SetInputData(image)
        for k in range(4):
            mapper.AddChannelArray("c%d" % k)
        mapper.SetBackendToCPU()
        volume = vtkVolume()
        volume.SetMapper(mapper)
        volume.SetProperty(prop)
        renderer = vtkRenderer()
        renderer.AddVolume(volume)
        window = vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetSize(args.size, args.size)
        window.AddRenderer(renderer)
        renderer.ResetCamera()
        for level in (0, 1, 2):
            for edge in (8, 4, 2):
                if level == 0 and edge != 8:
                    continue
                mapper.SetLevelOfDetail(level)
                mapper.SetMacrocellSize(edge)
                window.Render()  # builds the level
                times = []
                for _ in range(5):
                    renderer.GetActiveCamera().Azimuth(1.0)
                    t0 = time.perf_counter()
                    window.Render()
                    times.append(time.perf_counter() - t0)
                print("| %s | %d | %d | %.0f | %.0f |" % (label, mapper.GetLastLevelOfDetail(), edge,
                                                          1e3 * statistics.median(times),
                                                          1e3 * mapper.GetLastTraceTime()), flush=True)
    print("load average after: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
