"""One GPU per MPI rank: `mpiexec -n N pvbatch --symmetric`.

Every rank renders its piece of a generated multi-channel volume (a
programmable source: numpy fields, only the rank's extent generated) with the
plugin's representation on the CUDA backend; each picks its GPU by its local
rank (vtkMultiChannelVolumeMapper::CUDADevice -1, the default) and prints the
device it took. Rank 0 prints the median time of a moving-camera frame (the
image restarts, 1 sample per pixel; tracing, read-back, ParaView's
compositing and the draw) and of a still-camera progressive frame, for the
strong-scaling table (the same volume on 1 and on 2 GPUs).

    mpiexec -n 2 pvbatch --symmetric Benchmarks/gpu/mpi_gpus.py --dims 1024 1024 1024 --channels 4
"""
import argparse
import os
import statistics
import sys
import time

from paraview import servermanager as sm
from paraview import simple

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "Testing", "ParaView"))
import mcvolParaViewTesting as T  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--dims", type=int, nargs=3, default=[512, 512, 512])
ap.add_argument("--channels", type=int, default=4)
ap.add_argument("--size", type=int, nargs=2, default=[1024, 1024])
ap.add_argument("--frames", type=int, default=30)
ap.add_argument("--backend", default="CUDA", choices=["CUDA", "CPU", "Auto"])
args = ap.parse_args()

controller = sm.vtkProcessModule.GetProcessModule().GetGlobalController()
rank, ranks = controller.GetLocalProcessId(), controller.GetNumberOfProcesses()
T.load_plugin()

# A programmable source generates each rank's piece with numpy (ParaView asks
# every rank for its own extent of the whole one, so no rank holds the
# volume): smooth fields of different frequency in [0, 1]. (The Wavelet source
# with calculators takes minutes per rank on a 768^3 volume.)
t_gen = time.perf_counter()
names = ["c%d" % k for k in range(args.channels)]
source = simple.ProgrammableSource()
source.OutputDataSetType = "vtkImageData"
source.ScriptRequestInformation = """
from paraview import util
from vtkmodules.vtkCommonExecutionModel import vtkAlgorithm
util.SetOutputWholeExtent(self, [0, %d, 0, %d, 0, %d])
# Each rank is asked for its own extent (a piece), not the whole one.
self.GetOutputInformation(0).Set(vtkAlgorithm.CAN_PRODUCE_SUB_EXTENT(), 1)
""" % (args.dims[0] - 1, args.dims[1] - 1, args.dims[2] - 1)
source.Script = """
import numpy as np
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as sddp
info = self.GetOutputInformation(0)
ext = info.Get(sddp.UPDATE_EXTENT())
out = self.GetOutput()
out.SetExtent(ext)
dims = %r
nc = %d
x = (np.arange(ext[0], ext[1] + 1, dtype=np.float32) - dims[0] / 2)[None, None, :]
y = (np.arange(ext[2], ext[3] + 1, dtype=np.float32) - dims[1] / 2)[None, :, None]
z = (np.arange(ext[4], ext[5] + 1, dtype=np.float32) - dims[2] / 2)[:, None, None]
r2 = x * x + y * y + z * z
h = max(dims) / 2.0
fields = [
    lambda: 0.5 + 0.5 * np.sin(x / 13.0) * np.cos(y / 17.0) * np.sin(z / 19.0),
    lambda: np.abs(np.sin(x / 23.0) * np.cos(y / 31.0)) + 0 * z,
    lambda: np.exp(-r2 / (h * h)),
    lambda: 0.5 + 0.5 * np.sin((x + z) / 17.0) + 0 * y,
]
from vtkmodules.util.numpy_support import numpy_to_vtk
for k in range(nc):
    a = np.ascontiguousarray(np.broadcast_to(fields[k %% len(fields)](), (ext[5] - ext[4] + 1, ext[3] - ext[2] + 1, ext[1] - ext[0] + 1)), dtype=np.float32)
    arr = numpy_to_vtk(a.ravel(), deep=1)
    arr.SetName("c%%d" %% k)
    out.GetPointData().AddArray(arr)
""" % (list(args.dims), args.channels)
T.set_channel_functions(names, opacity=0.05)

view = T.make_view(tuple(args.size))
rep = T.show(source, view)
rep.Backend = args.backend
rep.SamplesPerRender = 1
rep.ChannelArrays = names
simple.Render(view)
t_gen = time.perf_counter() - t_gen

mapper = T.local_mapper(rep)
print("rank %d of %d: %s; %.0f MiB on the device, %d uploads; piece generated and first frame in %.1f s"
      % (rank, ranks, mapper.GetBackendReport(), mapper.GetDeviceMemory() / 2**20,
         mapper.GetNumberOfDataUploads(), t_gen), flush=True)

camera = view.GetActiveCamera()
times = {}
for mode in ("moving", "still"):
    frame = []
    for _ in range(args.frames):
        if mode == "moving":
            camera.Azimuth(0.5)
        t0 = time.perf_counter()
        simple.Render(view)
        frame.append(1e3 * (time.perf_counter() - t0))
    times[mode] = statistics.median(frame)
if rank == 0:
    print("| %dx%dx%d x%d channels | %dx%d | %d rank(s), %s | moving %.1f ms | still %.1f ms |"
          % (*args.dims, args.channels, *args.size, ranks, args.backend, times["moving"], times["still"]),
          flush=True)
