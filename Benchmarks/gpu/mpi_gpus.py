"""One GPU per MPI rank (issue 15): `mpiexec -n N pvbatch --symmetric`.

Every rank renders its piece of a generated multi-channel volume (ParaView's
Wavelet source and calculators, generated piece by piece on the ranks) with the
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

# ParaView's Wavelet source splits by extent across the ranks, so each rank
# generates and holds only its piece; three calculators make the other
# channels (smooth fields of different frequency, scaled to [0, 1]).
half = [d // 2 for d in args.dims]
source = simple.Wavelet(WholeExtent=[-half[0], args.dims[0] - half[0] - 1, -half[1], args.dims[1] - half[1] - 1,
                                     -half[2], args.dims[2] - half[2] - 1])
names = ["c0"]
chain = simple.Calculator(Input=source, ResultArrayName="c0", Function="(RTData-37)/240")
exprs = ["abs(sin(coordsX/23)*cos(coordsY/31))", "exp(-(coordsX^2+coordsY^2+coordsZ^2)/(%d^2))" % max(half),
         "0.5+0.5*sin((coordsX+coordsZ)/17)"]
for k in range(1, args.channels):
    name = "c%d" % k
    chain = simple.Calculator(Input=chain, ResultArrayName=name, Function=exprs[(k - 1) % len(exprs)])
    names.append(name)
source = chain
T.set_channel_functions(names, opacity=0.05)

view = T.make_view(tuple(args.size))
rep = T.show(source, view)
rep.Backend = args.backend
rep.SamplesPerRender = 1
rep.ChannelArrays = names
simple.Render(view)

mapper = T.local_mapper(rep)
print("rank %d of %d: %s; %.0f MiB on the device, %d uploads"
      % (rank, ranks, mapper.GetBackendReport(), mapper.GetDeviceMemory() / 2**20,
         mapper.GetNumberOfDataUploads()), flush=True)

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
    print("| %dx%dx%d x%d channels | %dx%d | %d GPU(s) | moving %.1f ms | still %.1f ms |"
          % (*args.dims, args.channels, *args.size, ranks, times["moving"], times["still"]),
          flush=True)
