"""Levels of detail in ParaView on the CPU: interactive
frame times of a 4-channel float volume with ParaView's LOD forced (the
view's LODThreshold at 0, so every interactive render uses the
representation's InteractiveLevelOfDetail), at level 0 (no coarser level
while interacting) and at levels 1 and 2; the time and memory of building
each level, the peak working memory of the streamed build, the process's
resident memory around the builds, and the time to rebuild level 1 after a
transfer-function edit.

Each frame moves the camera (Azimuth 1 degree) and renders once with
SamplesPerRender 1 (no frame-time budget), as dragging does, reading the
nearest voxel (the representation's InteractiveInterpolation default;
--interpolation as-still or both for linear): the frame time
is the wall time of the interactive render, the first frame at a level
(which builds it) left out of the median.

  bash scripts/paraview.sh pvpython Benchmarks/studies/lod_bench.py --dims 512 --size 512 \\
      --out Benchmarks/results/levels-of-detail/paraview-cpu

Prints a Markdown table and writes it, with the machine, date and command,
to OUT/README.md (and the rows to OUT/lod.csv).
"""
import argparse
import datetime
import os
import platform
import resource
import statistics
import sys
import time

import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "Testing", "ParaView"))
import mcvolParaViewTesting as T  # noqa: E402

NAMES = ["c0", "c1", "c2", "c3"]
COLORS = [(1.0, 0.3, 0.1), (0.1, 0.9, 0.3), (0.2, 0.4, 1.0), (1.0, 0.9, 0.2)]


def rss_mib():
    """Peak resident memory of this process so far (MiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def make_volume(n):
    """Four smooth float32 channels on an n^3 grid (separable products of
    sines at different frequencies, so no n^3 temporaries beyond the
    channels), as one vtkImageData with point arrays c0..c3."""
    image = vtkImageData()
    image.SetDimensions(n, n, n)
    x = np.linspace(0.0, 1.0, n, dtype=np.float32)
    freqs = [(3.1, 2.3, 1.7), (1.3, 3.7, 2.9), (2.2, 1.1, 3.3), (4.1, 3.9, 4.3)]
    for k, (fx, fy, fz) in enumerate(freqs):
        sx = np.sin(np.pi * fx * x + 0.3 * k)
        sy = np.sin(np.pi * fy * x + 0.7 * k)
        sz = np.sin(np.pi * fz * x + 1.1 * k)
        c = np.empty((n, n, n), dtype=np.float32)  # z, y, x
        np.multiply(sz[:, None, None], (sy[:, None] * sx[None, :])[None, :, :], out=c)
        c *= 0.5
        c += 0.5
        a = numpy_to_vtk(c.reshape(-1), deep=False)
        a.SetName(NAMES[k])
        image.GetPointData().AddArray(a)
        image._keep = getattr(image, "_keep", []) + [c]  # numpy owns the memory
    return image


def set_functions(opacity):
    for k, name in enumerate(NAMES):
        lut = simple.GetColorTransferFunction(name)
        r, g, b = COLORS[k]
        lut.RGBPoints = [0.0, r, g, b, 1.0, r, g, b]
        lut.AutomaticRescaleRangeMode = "Never"
        pwf = simple.GetOpacityTransferFunction(name)
        pwf.Points = [0.0, 0.0, 0.5, 0.0, 0.6, 0.0, 0.5, 0.0, 1.0, opacity, 0.5, 0.0]


def frames(view, count, cpu=None):
    """Wall seconds of `count` interactive frames; `cpu` (a list) receives
    each frame's CPU seconds over all threads (less sensitive than wall time
    to other work on a shared machine, though OpenMP's waiting counts)."""
    cam = view.GetActiveCamera()
    times = []
    for _ in range(count):
        cam.Azimuth(1.0)
        c0 = time.process_time()
        t0 = time.perf_counter()
        view.SMProxy.InteractiveRender()
        times.append(time.perf_counter() - t0)
        if cpu is not None:
            cpu.append(time.process_time() - c0)
    return times


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--dims", type=int, default=512)
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--frames", type=int, default=9, help="timed frames per level (after the first)")
    p.add_argument("--levels", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--opacity", type=float, default=0.05)
    p.add_argument("--backend", default="CPU", choices=["CPU", "CUDA"],
                   help="the representation's Backend (CUDA on the GPU machine, Benchmarks/gpu/vtk.sh)")
    p.add_argument("--macrocell", type=int, default=0, help="the representation's MacrocellSize (0: its default)")
    p.add_argument("--precision", default="half", choices=["half", "float", "both"],
                   help="levels above 0 in half precision (the default, LevelOfDetailHalfPrecision) or float32; "
                        "both: each level in float32, then in half precision (an A/B in one run)")
    p.add_argument("--interpolation", default="nearest", choices=["nearest", "as-still", "both"],
                   help="the representation's InteractiveInterpolation: the nearest voxel while interacting (the "
                        "default), the still renders' (linear), or both: each level as still, then nearest")
    p.add_argument("--repeat", type=int, default=1, help="run the list of levels this many times (A/B on a noisy machine)")
    p.add_argument("--out", help="folder for README.md and lod.csv")
    args = p.parse_args()
    T.load_plugin()
    load_before = os.getloadavg()

    t0 = time.perf_counter()
    image = make_volume(args.dims)
    gen_s = time.perf_counter() - t0
    data_mib = 4 * 4 * args.dims ** 3 / 1048576.0
    producer = simple.PVTrivialProducer()
    producer.GetClientSideObject().SetOutput(image)
    producer.UpdatePipeline()

    view = simple.CreateView("RenderView")
    view.ViewSize = [args.size, args.size]
    view.OrientationAxesVisibility = 0
    view.LODThreshold = 0.0  # every interactive render uses ParaView's LOD
    rep = simple.Show(producer, view)
    rep.SetRepresentationType(T.REPRESENTATION)
    rep.Backend = args.backend
    rep.ChannelArrays = NAMES
    set_functions(args.opacity)
    rep.SamplesPerRender = 1
    rep.InteractiveFrameTime = 0  # one sample per pixel per frame
    rep.MaximumTotalSamples = 0
    if args.macrocell > 0:
        rep.MacrocellSize = args.macrocell
    simple.ResetCamera(view)
    t0 = time.perf_counter()
    simple.Render(view)  # level 0: bounds, tables, macrocell and majorant grids
    first_still_s = time.perf_counter() - t0
    mapper = T.local_mapper(rep)
    rows = []
    configs = []
    interps = ["as-still", "nearest"] if args.interpolation == "both" else [args.interpolation]
    for level in args.levels:
        for interp in interps:
            if level == 0:
                configs.append((0, args.precision != "float", interp))
            elif args.precision == "both":
                configs += [(level, False, interp), (level, True, interp)]
            else:
                configs.append((level, args.precision == "half", interp))
    for level, half, interp in configs * max(1, args.repeat):
        rep.LevelOfDetailHalfPrecision = int(half)
        rep.InteractiveInterpolation = "Nearest" if interp == "nearest" else "As Still Renders"
        rep.InteractiveLevelOfDetail = level  # 0: the still level (0) while interacting
        builds = mapper.GetNumberOfLevelOfDetailBuilds()
        rss_before = rss_mib()
        first = frames(view, 1)[0]
        built = mapper.GetNumberOfLevelOfDetailBuilds() > builds
        build_ms = 1e3 * mapper.GetLastLevelOfDetailBuildTime() if built else 0.0
        work_mib = mapper.GetLastLevelOfDetailBuildMemory() / 1048576.0 if built else 0.0
        # The levels the mapper keeps after this level's first frame (a
        # precision change drops the others; without one, the levels so far).
        level_mib = mapper.GetLevelOfDetailMemory() / 1048576.0 if level > 0 else data_mib
        rss_growth = rss_mib() - rss_before
        cpu = []
        times = frames(view, args.frames, cpu)
        used = T.info(rep, "LastLevelOfDetail")
        width = mapper.GetAccumulatedImageWidth()
        trace_ms = 1e3 * mapper.GetLastTraceTime()
        draw_ms = 1e3 * mapper.GetLastDrawTime()
        rows.append(dict(level=used, precision="half" if half and used > 0 else "float", interpolation=interp, frame_ms=1e3 * statistics.median(times), cpu_ms=1e3 * statistics.median(cpu),
                         min_ms=1e3 * min(times),
                         max_ms=1e3 * max(times), trace_ms=trace_ms, draw_ms=draw_ms, first_ms=1e3 * first, build_ms=build_ms,
                         level_mib=level_mib, work_mib=work_mib, rss_growth=rss_growth, width=width))
        print(rows[-1], T.info(rep, "LevelOfDetailReport"))
        sys.stdout.flush()

    # Rebuild after a transfer-function edit while interacting at level 1.
    rep.LevelOfDetailHalfPrecision = int(args.precision != "float")
    rep.InteractiveLevelOfDetail = 1
    rep.InteractiveInterpolation = "As Still Renders" if args.interpolation == "as-still" else "Nearest"
    frames(view, 2)
    builds = mapper.GetNumberOfLevelOfDetailBuilds()
    pwf = simple.GetOpacityTransferFunction(NAMES[0])
    pts = list(pwf.Points)
    pts[-3] = args.opacity * 2.0  # the top opacity of channel 0
    pwf.Points = pts
    edit_frame = frames(view, 1)[0]
    rebuilt = mapper.GetNumberOfLevelOfDetailBuilds() - builds
    rebuild_ms = 1e3 * mapper.GetLastLevelOfDetailBuildTime()

    lines = []
    lines.append("| level | precision | interactive interpolation | grid | frame ms, moving camera (median; min-max) | CPU ms a frame, all threads | trace ms | draw ms | "
                 "build ms of the level | levels kept MiB (level 0: the data) | build work MiB | RSS growth MiB |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        n = -(-args.dims // (1 << r["level"]))
        grid = "%d^3 x %s" % (n, "4 float" if r["level"] == 0 else
                              "1 half4 (summed)" if r["precision"] == "half" else "1 float4 (summed)")
        lines.append("| %d | %s | %s | %s | %.0f (%.0f-%.0f) | %.0f | %.0f | %.1f | %s | %.0f | %s | %.0f |" % (
            r["level"], r["precision"], "nearest" if r["interpolation"] == "nearest" else "linear (as still)", grid, r["frame_ms"], r["min_ms"], r["max_ms"], r["cpu_ms"], r["trace_ms"],
            r["draw_ms"],
            "%.0f" % r["build_ms"] if r["level"] > 0 else "-", r["level_mib"],
            "%.1f" % r["work_mib"] if r["level"] > 0 else "-", r["rss_growth"]))
    table = "\n".join(lines)
    extra = ("Rebuild of level 1 after an opacity edit of one channel: %.0f ms (%d build; that frame %.0f ms).\n"
             "Image %dx%d (the mapper's image: %d pixels wide in interactive renders); data generation %.1f s; "
             "first still render (level 0 grids) %.1f s; volume %d^3 x 4 float32 = %.0f MiB; peak RSS %.0f MiB."
             % (rebuild_ms, rebuilt, 1e3 * edit_frame, args.size, args.size, rows[0]["width"], gen_s,
                first_still_s, args.dims, data_mib, rss_mib()))
    print(table)
    print(extra)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        cpu = "unknown CPU"
        try:
            with open("/proc/cpuinfo") as f:
                cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
        except (OSError, StopIteration):
            pass
        command = "bash scripts/paraview.sh pvpython Benchmarks/studies/lod_bench.py " + " ".join(sys.argv[1:])
        with open(os.path.join(args.out, "README.md"), "w") as f:
            f.write("# Levels of detail in ParaView, %s backend\n\n" % args.backend)
            f.write("%s, %d cores (os.cpu_count), %s, %s UTC. Load average (1, 5, 15 min) %s before the "
                    "run and %s after it: the machine was shared with other work, so the times are upper "
                    "bounds of what it does idle.\n\n" % (
                        cpu, os.cpu_count(), platform.platform(),
                        datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"),
                        "%.2f %.2f %.2f" % load_before, "%.2f %.2f %.2f" % os.getloadavg()))
            f.write("    %s\n\n" % command)
            f.write("4 smooth float32 channels (density blend, opacity up to %g per unit distance), "
                    "%s backend, %d samples per pixel per frame, expected-value estimator; ParaView's LOD "
                    "forced (LODThreshold 0) and the representation's InteractiveLevelOfDetail set to the "
                    "level; each frame moves the camera 1 degree, so every frame restarts the image. The "
                    "first frame at a level (which builds it) is not in the median.\n\n" % (args.opacity, args.backend, 1))
            f.write(table + "\n\n" + extra + "\n")
        with open(os.path.join(args.out, "lod.csv"), "w") as f:
            keys = list(rows[0].keys())
            f.write(",".join(keys) + "\n")
            for r in rows:
                f.write(",".join(str(r[k]) for k in keys) + "\n")
    T.Checks().finish()  # os._exit: see mcvolParaViewTesting.Checks.finish


if __name__ == "__main__":
    main()
