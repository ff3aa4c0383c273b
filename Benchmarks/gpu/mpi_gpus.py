"""One GPU per MPI rank: `mpiexec -n N pvbatch --symmetric`, for the scaling
tables of the performance page.

Every rank generates only its own piece of a built-in demo volume
(vtkMultiChannelDemoSource asked for the rank's update extent; the default
"cosmology" at 512^3 x 4 is the NYX-like set of the paper benchmarks) and
renders it with the plugin's representation on its GPU (the GPU of its local
rank: vtkMultiChannelVolumeMapper::CUDADevice -1, the default); ParaView
(IceT) composites the pieces in visibility order. The transfer functions are
the dataset's suggested ones over the whole volume's range (an all-reduce of
the pieces' ranges), the estimator and sample sequence the product defaults.

For each lighting (`--lighting none shadows`; shadows = Shade on, one
directional scene light, ratio-tracking shadows, ambient 0.2, the lighting
across ranks at its default) rank 0 prints one JSON line with:
- `converge` (against a reference image of `--ref-spp` samples per pixel,
  seed 1, which `--save` writes): still renders of s samples per pixel, each a fresh image (a new
  seed) traced in one Render() and composited once (the still camera refines
  on every rank without a composite per sample), wall time of the Render()
  and PSNR of the displayed 8-bit image against the reference, up to the
  first s at or above `--target-db`; `time_to_db` is that Render()'s time;
- `moving`: the median of `--frames` Render()s of a moving camera at 1
  sample per pixel (the image restarts each frame): the wall time, and the
  largest over the ranks of the mapper's trace time (kernels and the copy of
  the image to the host) and draw time (the image over the framebuffer);
  what remains is ParaView's compositing and the rest of the frame;
- `still`: the median wall time of a still-camera Render() that adds
  `--still-spp` samples per pixel, and the samples per second it gives;
- `memory`: per rank, the backend's device memory (GetDeviceMemory), the
  process's device memory as nvidia-smi reports it, the piece's voxels and
  the process's peak host memory;
- `outline_ms`: the median wall time of a moving-camera Render() of
  ParaView's own Outline representation alone, at the same size and rank
  count: the cost of a composited frame, whatever it draws.

    mpiexec -n 2 pvbatch --symmetric Benchmarks/gpu/mpi_gpus.py --dims 512 512 512 --channels 4
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time

import numpy as np
from paraview import servermanager as sm
from paraview import simple
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkIntArray
from vtkmodules.vtkParallelCore import vtkCommunicator

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "Testing", "ParaView"))
import mcvolParaViewTesting as T  # noqa: E402



def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dataset", default="cosmology")
    ap.add_argument("--dims", type=int, nargs=3, default=[512, 512, 512])
    ap.add_argument("--channels", type=int, default=4)
    ap.add_argument("--size", type=int, nargs=2, default=[1024, 1024])
    ap.add_argument("--lighting", nargs="+", default=["none", "shadows"], choices=["none", "shadows"])
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--target-db", type=float, default=35.0)
    ap.add_argument("--spp", type=int, nargs="+", default=[1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--still-spp", type=int, default=16)
    ap.add_argument("--backend", default="CUDA", choices=["CUDA", "CPU", "Auto"])
    ap.add_argument("--label", default="")
    ap.add_argument("--save", default="", help="folder for rank 0's reference images (PNG)")
    args = ap.parse_args()

    controller = sm.vtkProcessModule.GetProcessModule().GetGlobalController()
    rank, ranks = controller.GetLocalProcessId(), controller.GetNumberOfProcesses()
    T.load_plugin()

    def reduce(values, op):
        """The element-wise reduction of `values` (floats) over the ranks, on every rank."""
        send, recv = vtkDoubleArray(), vtkDoubleArray()
        for v in values:
            send.InsertNextValue(float(v))
        if ranks == 1:
            return [float(v) for v in values]
        controller.AllReduce(send, recv, op)
        return [recv.GetValue(i) for i in range(recv.GetNumberOfTuples())]

    def broadcast_int(value):
        """Rank 0's integer on every rank (all ranks must render alike)."""
        a = vtkIntArray()
        a.InsertNextValue(int(value))
        if ranks > 1:
            controller.Broadcast(a, 0)
        return a.GetValue(0)

    def gather_rows(row):
        """Every rank's row of floats, on every rank (one all-reduce per rank)."""
        rows = []
        for r in range(ranks):
            mine = row if r == rank else [0.0] * len(row)
            rows.append(reduce(mine, vtkCommunicator.SUM_OP))
        return rows

    # ---------------------------------------------------------------- the volume
    t0 = time.perf_counter()
    volume = simple.ProgrammableSource()
    volume.OutputDataSetType = "vtkImageData"
    volume.ScriptRequestInformation = textwrap.dedent("""
        from paraview import util
        from vtkmodules.vtkCommonExecutionModel import vtkAlgorithm
        util.SetOutputWholeExtent(self, [0, %d, 0, %d, 0, %d])
        self.GetOutputInformation(0).Set(vtkAlgorithm.CAN_PRODUCE_SUB_EXTENT(), 1)
        """) % (args.dims[0] - 1, args.dims[1] - 1, args.dims[2] - 1)
    volume.Script = textwrap.dedent("""
        from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as sddp
        from mcvol import vtkMultiChannelDemoSource
        demo = vtkMultiChannelDemoSource()
        demo.SetDataset(%r)
        demo.SetDimensions(%d, %d, %d)
        demo.SetNumberOfChannels(%d)
        demo.InterleavedOff()
        demo.UpdateExtent(self.GetOutputInformation(0).Get(sddp.UPDATE_EXTENT()))
        self.GetOutput().ShallowCopy(demo.GetOutput())
        """) % (args.dataset, *args.dims, args.channels)
    volume.UpdatePipeline()
    piece = volume.GetClientSideObject().GetOutputDataObject(0)
    t_gen = time.perf_counter() - t0

    def progress(what):
        if rank == 0:
            print("progress: %s after %.1f s" % (what, time.perf_counter() - t0), flush=True)

    progress("pieces generated")

    # The dataset's suggested functions over the whole volume's range.
    from mcvol import vtkMultiChannelDemoSource
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction

    probe = vtkMultiChannelDemoSource()
    probe.SetDataset(args.dataset)
    probe.SetDimensions(2, 2, 2)
    probe.SetNumberOfChannels(args.channels)
    names = [probe.GetChannelName(c) for c in range(probe.GetNumberOfOutputChannels())]
    local = []
    for n in names:
        a = piece.GetPointData().GetArray(n)
        lo, hi = a.GetRange() if a is not None and a.GetNumberOfTuples() else (np.inf, -np.inf)
        local.append((lo, -hi))
    mins = reduce([v for pair in local for v in pair], vtkCommunicator.MIN_OP)
    for c, n in enumerate(names):
        color, opacity = vtkColorTransferFunction(), vtkPiecewiseFunction()
        probe.GetSuggestedTransferFunction(c, [mins[2 * c], -mins[2 * c + 1]], color, opacity, None)
        lut = simple.GetColorTransferFunction(n)
        lut.AutomaticRescaleRangeMode = "Never"
        points = []
        for i in range(color.GetSize()):
            node = [0.0] * 6
            color.GetNodeValue(i, node)
            points += node[:4]
        lut.RGBPoints = points
        pwf = simple.GetOpacityTransferFunction(n)
        points = []
        for i in range(opacity.GetSize()):
            node = [0.0] * 4
            opacity.GetNodeValue(i, node)
            points += [node[0], node[1], 0.5, 0.0]
        pwf.Points = points
    # The suggested unit distance depends on the size alone: a one-voxel piece of
    # the full-size volume gives it.
    full = vtkMultiChannelDemoSource()
    full.SetDataset(args.dataset)
    full.SetDimensions(*args.dims)
    full.SetNumberOfChannels(args.channels)
    full.UpdateExtent([0, 0, 0, 0, 0, 0])
    unit = full.GetSuggestedUnitDistance(0)
    assert full.GetOutput().GetNumberOfPoints() == 1, "the unit-distance query generated more than its piece"

    view = T.make_view(tuple(args.size))
    cx, cy, cz = [0.5 * (d - 1) for d in args.dims]
    r = 0.5 * max(args.dims)
    view.CameraFocalPoint = [cx, cy, cz]
    view.CameraPosition = [cx + 2.2 * r, cy + 1.6 * r, cz + 2.9 * r]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    rep = T.show(volume, view)
    rep.Backend = args.backend
    rep.ChannelArrays = names
    rep.ScalarOpacityUnitDistance = unit
    # The product's defaults, not the regression tests' (T.show pins those).
    rep.SampleSequence = "Sobol"
    rep.Estimator = "Expected Value"
    rep.PixelJitter = 1
    progress("functions set")
    simple.Render(view)
    t_first = time.perf_counter() - t0
    progress("first frame")
    mapper = T.local_mapper(rep)

    def device_memory_smi():
        try:
            out = subprocess.run(["nvidia-smi", "--query-compute-apps=pid,used_memory", "--format=csv,noheader,nounits"],
                                 capture_output=True, text=True, timeout=30).stdout
        except (OSError, subprocess.SubprocessError):
            return -1.0
        for line in out.splitlines():
            pid, mib = [x.strip() for x in line.split(",")]
            if int(pid) == os.getpid():
                return float(mib)
        return -1.0

    shot = os.path.join(tempfile.gettempdir(), "mcvol-mpi-gpus-%d.png" % os.getpid())

    def displayed():
        """The composited 8-bit image (rank 0; every rank takes part)."""
        simple.SaveScreenshot(shot, view, ImageResolution=list(args.size), TransparentBackground=0)
        return T.read_png(shot).astype(np.float64) if rank == 0 else None

    def psnr(a, b):
        mse = float(np.mean((a - b) ** 2))
        return 99.0 if mse == 0 else 10.0 * np.log10(255.0 ** 2 / mse)

    def timed_render():
        if ranks > 1:
            controller.Barrier()
        t = time.perf_counter()
        simple.Render(view)
        wall = time.perf_counter() - t
        trace, draw = reduce([mapper.GetLastTraceTime(), mapper.GetLastDrawTime()], vtkCommunicator.MAX_OP)
        return 1e3 * wall, 1e3 * trace, 1e3 * draw

    def restart(seed, spp, total):
        rep.Seed = seed
        rep.SamplesPerRender = spp
        rep.MaximumTotalSamples = total

    camera = view.GetActiveCamera()

    # ParaView's own Outline representation alone at the same size and rank
    # count, on the moving camera: what a composited frame costs whatever it
    # draws (IceT, the read-back and draw of the window), the floor under
    # any representation's frame.
    outline = simple.Show(simple.Outline(Input=volume), view)
    rep.Visibility = 0
    simple.Render(view)
    walls = []
    for _ in range(args.frames):
        camera.Azimuth(0.5)
        walls.append(timed_render()[0])
    for _ in range(args.frames):
        camera.Azimuth(-0.5)
    outline.Visibility = 0
    rep.Visibility = 1
    outline_ms = round(statistics.median(walls), 3)

    for lighting in args.lighting:
        if lighting == "shadows":
            view.UseLight = 0  # the light kit off: the scene light alone
            light = simple.AddLight(view=view)
            light.Coords = "Scene"
            light.Type = "Directional"
            light.FocalPoint = [cx, cy, cz]
            light.Position = [cx + 3 * r, cy + 4 * r, cz + 2 * r]
            light.Intensity = 1.0
            rep.Shade = 1
            rep.ShadowMode = "Ratio Tracking"
            rep.AmbientRadiance = [0.2, 0.2, 0.2]
        result = {"label": args.label, "dataset": args.dataset, "dims": args.dims, "channels": args.channels,
                  "size": args.size, "ranks": ranks, "lighting": lighting, "backend": args.backend}

        # Reference.
        restart(1, 64, args.ref_spp)
        for _ in range((args.ref_spp + 63) // 64 + 1):
            simple.Render(view)
        ref = displayed()
        if args.save and rank == 0:
            os.makedirs(args.save, exist_ok=True)
            T.write_png(os.path.join(args.save, "reference-%s-%dranks.png" % (lighting, ranks)), ref.astype(np.uint8))

        # Time to the target PSNR: one Render() of s samples per fresh image.
        rows = []
        for i, spp in enumerate(args.spp):
            restart(100 + i, spp, spp)
            wall, trace, draw = timed_render()
            img = displayed()
            db = psnr(img, ref) if rank == 0 else 0.0
            rows.append({"spp": spp, "ms": round(wall, 3), "trace_ms": round(trace, 3), "draw_ms": round(draw, 3),
                         "psnr": round(db, 2)})
            if broadcast_int(db >= args.target_db):
                break
        result["converge"] = rows
        hit = rows[-1] if rows and rows[-1]["psnr"] >= args.target_db else None
        result["time_to_db"] = hit["ms"] if hit else None
        result["spp_to_db"] = hit["spp"] if hit else None

        # Moving camera, 1 sample per pixel.
        restart(3, 1, 0)
        simple.Render(view)
        frames = []
        for _ in range(args.frames):
            camera.Azimuth(0.5)
            frames.append(timed_render())
        result["moving"] = {k: round(statistics.median(f[i] for f in frames), 3)
                            for i, k in enumerate(("ms", "trace_ms", "draw_ms"))}
        for _ in range(args.frames):
            camera.Azimuth(-0.5)

        # Still camera, --still-spp samples per Render().
        restart(5, args.still_spp, 0)
        simple.Render(view)
        frames = [timed_render() for _ in range(max(3, args.frames // 2))]
        still = {k: round(statistics.median(f[i] for f in frames), 3) for i, k in enumerate(("ms", "trace_ms", "draw_ms"))}
        still["samples_per_s"] = round(args.still_spp * args.size[0] * args.size[1] / (still["ms"] / 1e3), 1)
        result["still"] = still

        mine = [rank, mapper.GetDeviceMemory() / 2**20, device_memory_smi(), piece.GetNumberOfPoints(),
                resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10]
        result["memory"] = [{"rank": int(m[0]), "backend_mib": round(m[1], 1), "process_mib": m[2],
                             "voxels": int(m[3]), "host_peak_mib": round(m[4], 1)} for m in gather_rows(mine)]
        result["generate_s"] = round(t_gen, 2)
        result["first_frame_s"] = round(t_first, 2)
        result["stand_in"] = T.info(rep, "LightingStandInReport") if lighting != "none" else ""
        result["outline_ms"] = outline_ms
        if rank == 0:
            print("RESULT " + json.dumps(result), flush=True)
    print("rank %d: %s" % (rank, mapper.GetBackendReport()), flush=True)
    if os.path.exists(shot):
        os.remove(shot)


if __name__ == "__main__":
    # ParaView's programmable source runs its scripts in __main__, after
    # `from numpy import *` and more, which would replace names here (max,
    # round, ...): run from this file's own module instead.
    sys.path.insert(0, HERE)
    import mpi_gpus

    mpi_gpus.main()
