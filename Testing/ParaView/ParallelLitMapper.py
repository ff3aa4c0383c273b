"""`[mpiexec -n N] pvbatch --symmetric` script of the parallel lighting
tests at the mapper level: every rank renders its piece of the lit split
scene (mcvolLitSplitScene) with one mapper, rank 0 composites the pieces'
premultiplied float images front to back and saves the result (.npy).

Usage: pvbatch --symmetric ParallelLitMapper.py OUT.npy MAPPER SEED LEVEL SPP DEPTH AMBIENT [FRAMES [SCALE]]
  MAPPER  mc (vtkMultiChannelVolumeMapper) or march (vtkMultiChannelRayMarchMapper)
  LEVEL   the mapper's LightingStandInLevel: -1 off, 0 exact, k > 0 coarse;
          auto:BYTES the automatic level within BYTES (LightingStandInMemoryLimit);
          a suffix ":sort-last" turns SplitImageWithExactStandIn off
  SPP     samples per pixel (mc; march: ignored)
  DEPTH   MaxScatteringDepth; AMBIENT the ambient radiance (grey)
  FRAMES  renders to time after the first (default 0), each a new image of
          SPP samples: prints seconds per frame
  SCALE   voxels per axis times SCALE (default 1; benchmarks)
The volume is split along z into N pieces that share their boundary planes
(as ParaView's pieces do); VTK's global controller is the MPI one, so the
mapper gathers its stand-in from all ranks. Rank 0 prints each rank's
stand-in report, memory and gather time.
"""
import os
import sys
import time

import numpy as np
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkImagingCore import vtkExtractVOI
from vtkmodules.vtkParallelCore import vtkMultiProcessController
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkLight, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import vtk_to_numpy, numpy_to_vtk
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401

import mcvolLitSplitScene as S
from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper

out_path, mapper_kind = sys.argv[1], sys.argv[2]
seed, level, spp, depth = int(sys.argv[3]), sys.argv[4], int(sys.argv[5]), int(sys.argv[6])
ambient = float(sys.argv[7])
frames = int(sys.argv[8]) if len(sys.argv) > 8 else 0
scale = int(sys.argv[9]) if len(sys.argv) > 9 else 1

ctrl = vtkMultiProcessController.GetGlobalController()
ranks = ctrl.GetNumberOfProcesses() if ctrl else 1
rank = ctrl.GetLocalProcessId() if ctrl else 0

whole = S.image(scale)
nx, ny, nz = (n * scale for n in S.DIMS)
cuts = [round(k * (nz - 1) / ranks) for k in range(ranks + 1)]
if ranks > 1:
    voi = vtkExtractVOI()
    voi.SetInputData(whole)
    voi.SetVOI(0, nx - 1, 0, ny - 1, cuts[rank], cuts[rank + 1])
    voi.Update()
    data = voi.GetOutput()
else:
    data = whole

m = vtkMultiChannelRayMarchMapper() if mapper_kind == "march" else vtkMultiChannelVolumeMapper()
m.SetInputData(data)
# The CPU, or CUDA on the GPU machine (MCVOL_TEST_BACKEND=cuda, as the other tests).
if os.environ.get("MCVOL_TEST_BACKEND", "").lower() == "cuda":
    m.SetBackendToCUDA()
else:
    m.SetBackendToCPU()
m.SetSeed(seed)
m.SetSamplesPerPixel(spp)
m.SetMaxScatteringDepth(depth)
m.SetAmbientRadiance(ambient, ambient, ambient)
if level.endswith(":sort-last"):
    m.SplitImageWithExactStandInOff()
    level = level[: -len(":sort-last")]
if level.startswith("auto:"):
    m.SetLightingStandInLevelToAutomatic()
    m.SetLightingStandInMemoryLimit(float(level[5:]))
else:
    m.SetLightingStandInLevel(int(level))
m.SetTransferFunctionRangeMode(vtkMultiChannelVolumeMapper.FUNCTION_RANGE)
ctf = vtkColorTransferFunction()
ctf.AddRGBPoint(0, *S.COLOR)
ctf.AddRGBPoint(1, *S.COLOR)
pwf = vtkPiecewiseFunction()
for x, a in S.OPACITY_POINTS:
    pwf.AddPoint(x, a)
m.SetChannelColor(0, ctf)
m.SetChannelScalarOpacity(0, pwf)
m.SetChannelScalarOpacityUnitDistance(0, 1.0)
m.SetChannelAlbedo(0, 0.9)
prop = vtkVolumeProperty()
prop.ShadeOn()
volume = vtkVolume()
volume.SetMapper(m)
volume.SetProperty(prop)
ren = vtkRenderer()
ren.AutomaticLightCreationOff()
light = vtkLight()
light.SetLightTypeToSceneLight()
light.SetPositional(False)
light.SetFocalPoint(*S.FOCAL)
light.SetPosition(*[f + 100.0 * d for f, d in zip(S.FOCAL, S.LIGHT_DIRECTION)])
light.SetIntensity(1.0)
ren.AddLight(light)
ren.AddVolume(volume)
win = vtkRenderWindow()
win.SetOffScreenRendering(1)
win.AddRenderer(ren)
win.SetSize(S.SIZE, S.SIZE)
cam = ren.GetActiveCamera()
cam.SetPosition(*S.CAMERA)
cam.SetFocalPoint(*S.FOCAL)
cam.SetViewUp(*S.VIEW_UP)
cam.SetViewAngle(S.VIEW_ANGLE)
# The whole volume's clipping range on every rank.
ren.ResetCameraClippingRange(0, S.DIMS[0] - 1, 0, S.DIMS[1] - 1, 0, S.DIMS[2] - 1)
start = time.perf_counter()
win.Render()
first = time.perf_counter() - start
per_frame = 0.0
if frames > 0:
    start = time.perf_counter()
    for _ in range(frames):
        m.Modified()  # a new image each frame: the gather is not repeated, the trace is
        win.Render()
    per_frame = (time.perf_counter() - start) / frames
arr = vtkFloatArray()
m.GetAccumulatedImage(arr)
img = vtk_to_numpy(arr).reshape(S.SIZE, S.SIZE, 4).copy()
line = ("rank %d: extent %s, stand-in: %s, memory %.0f bytes, gathers %d, gather %.4f s, first frame %.3f s, "
        "frame %.3f s" % (rank, list(data.GetExtent()), m.GetLightingStandInReport(), m.GetLightingStandInMemory(),
                          m.GetNumberOfLightingStandInGathers(), m.GetLastLightingStandInGatherTime(), first,
                          per_frame))
if rank == 0:
    pieces = [img]
    print(line)
    for r in range(1, ranks):
        a = vtkFloatArray()
        ctrl.Receive(a, r, 4711)
        pieces.append(vtk_to_numpy(a).reshape(S.SIZE, S.SIZE, 4).copy())
        s = vtkFloatArray()
        ctrl.Receive(s, r, 4712)
        print(bytes(vtk_to_numpy(s).astype(np.uint8)).decode())
    # The camera is above every piece (z): the higher piece is in front.
    out = pieces[-1]
    for back in reversed(pieces[:-1]):
        out = out + (1.0 - out[..., 3:4]) * back
    np.save(out_path, out)
else:
    ctrl.Send(numpy_to_vtk(img.ravel(), deep=1), 0, 4711)
    ctrl.Send(numpy_to_vtk(np.frombuffer(line.encode(), dtype=np.uint8).astype(np.float32), deep=1), 0, 4712)
