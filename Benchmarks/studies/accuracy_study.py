#!/usr/bin/python3
"""The accuracy-versus-time study: what image quality each method
reaches and what it costs.

For each demo dataset and blend mode, `mcvol-accuracy` renders (one run):
  - the reference: a ray march with the extinction model at a fine step (1/16
    voxel), cross-checked against a high-sample Monte Carlo image (the
    renderer's default estimator and sampler);
  - Monte Carlo at 1, 2, 4, ... --spp-max spp (cumulative time), one series per
    configuration of MC_CONFIGS (--mc-configs): the renderer's default
    (expected-value estimator, Owen-scrambled Sobol' points, 1-DDA), the
    collision estimator with Sobol' points, the former default (collision
    estimator, independent samples, 1-DDA and N-DDA), the
    unbiased march (Sobol', its default 2 strata per voxel), and the
    automatic choice (mcvol::chooseEstimator aiming at 35 dB; the series
    starts with its pilots' wall time, and ACCURACY.md names what it
    chose; not under composite blending, where it does not apply). The composite
    blend keeps the collision estimator (Types.h, Estimator), so there the
    new default is the collision + Sobol' series;
  - the ray marcher at steps of 4 voxels down to 1/8 voxel, extinction- and
    opacity-based compositing.
This script scores every image against the reference (RMSE and PSNR with peak
1, SSIM from scikit-image, all on the premultiplied RGB over black, clipped to
[0, 1] as displayed), times VTK's own fixed-point and GPU ray-cast mappers on
the same data for comparison (their independent-components blend formula is
not ours, so they are pictured, not scored; --no-peers reuses vtk-peers.csv
and needs no VTK), and writes:
  accuracy.csv, accuracy-<dataset>.png (error against time, one panel per
  blend mode), grid-<dataset>.png (equal-time and equal-quality renders, like
  the paper's Figure 10), vtk-peers.csv, and ACCURACY.md (the summary).

Usage (from the repository, after building):
  PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 \\
      Benchmarks/studies/accuracy_study.py --bin build/bin --out Benchmarks/results/accuracy-study
or, without VTK (a build of the mcvol-accuracy target only), add --no-peers.
--gpu <folder> merges the series of Benchmarks/gpu/bench.sh's accuracy stage
(<dataset>-<mode>.csv, scored on the GPU machine against its own reference).
"""
import argparse
import csv
import math
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from skimage.metrics import structural_similarity  # noqa: E402

DATASETS = ["figure3", "microscopy", "cosmology", "weather"]
MODES = ["density", "max", "mix", "composite"]
STEPS = [4, 2, 1, 0.5, 0.25, 0.125]
# Monte Carlo series: (estimator, sampler, tracker, key, label, colour,
# line). The first is the renderer's default; "old" is the former default
# (collision estimator, independent samples), kept as a row so that the gain
# stays visible.
MC_CONFIGS = [
    ("expected-value", "sobol", "1dda", "new", "MC new default (expected value, Sobol', 1-DDA)", "tab:green", "-"),
    ("collision", "sobol", "1dda", "col-sobol", "MC collision, Sobol', 1-DDA", "tab:purple", "-"),
    ("collision", "independent", "1dda", "old", "MC old default (collision, independent, 1-DDA)", "tab:orange", "-"),
    ("collision", "independent", "ndda", "old-ndda", "MC old default, N-DDA", "tab:brown", "--"),
    ("unbiased-march", "sobol", "1dda", "march", "MC unbiased march (2 per voxel, Sobol')", "tab:olive", "-."),
    ("automatic", "sobol", "1dda", "auto", "MC automatic choice (its pilots counted)", "tab:cyan", "-"),
]
MARCHES = [("extinction", "RM extinction", "tab:blue", "-"), ("opacity", "RM opacity", "tab:red", "--")]
GPU_LABEL = "GPU"
QUALITY = [30.0, 35.0, 40.0]   # PSNR targets (dB)
BUDGETS = [50.0, 200.0, 1000.0]  # time budgets (ms)


# The automatic series' choices: (dataset, mode, gpu) -> (name, pilot ms,
# rounds), from the tool's meta.txt.
CHOICES = {}
CHOICE_LINE = re.compile(r"^automatic_choice (\S+) (.*) pilots_ms ([0-9.]+) rounds (\d+) rendered (\d+)"
                         r"(?: hinted_ms ([0-9.]+) hinted_rounds (\d+))?$")


# A transfer-function edit timed to 35 dB on a backend that renders pilots at
# once: (dataset, mode, gpu) -> (frames, ms then, ms with the frames during
# the pilots, kept, expected value's frames, its ms).
EDITS = {}
EDIT_LINE = re.compile(r"^automatic_edit (\S+) frames (\d+) then_ms ([0-9.]+) ahead_ms ([0-9.]+) kept (\d) "
                       r"expected_value_frames (\d+) expected_value_ms ([0-9.]+)$")


def read_choices(meta, dataset, mode, gpu):
    if not os.path.exists(meta):
        return
    with open(meta) as f:
        for line in f:
            m = CHOICE_LINE.match(line.strip())
            if m:
                CHOICES[(dataset, mode, gpu)] = (m.group(2), float(m.group(3)), int(m.group(4)),
                                                 float(m.group(6)) if m.group(6) else None,
                                                 int(m.group(7)) if m.group(7) else None)
            m = EDIT_LINE.match(line.strip())
            if m:
                EDITS[(dataset, mode, gpu)] = (int(m.group(2)), float(m.group(3)), float(m.group(4)),
                                               m.group(5) == "1", int(m.group(6)), float(m.group(7)))


def load(path, w, h):
    return np.fromfile(path, dtype=np.float32).reshape(h, w, 4)


def display(img):
    """Premultiplied RGB over black, clipped as the screen shows it, top row first."""
    return np.clip(img[::-1, :, :3], 0.0, 1.0)


def scores(img, ref):
    a, b = display(img), display(ref)
    mse = float(((a - b) ** 2).mean())
    rmse = math.sqrt(mse)
    psnr = 10.0 * math.log10(1.0 / mse) if mse > 0 else float("inf")
    ssim = float(structural_similarity(a, b, data_range=1.0, channel_axis=2))
    return rmse, psnr, ssim


def mc_configs_arg():
    return ",".join("%s:%s:%s" % c[:3] for c in MC_CONFIGS)


def run_tool(binary, dataset, mode, size, work, ref_spp, spp_max):
    # The cache folder names every option (the configurations by a checksum),
    # so a rerun with others re-renders.
    folder = os.path.join(work, "%s-%s-%d-%d-%d-%08x" % (dataset, mode, size, ref_spp, spp_max,
                                                         zlib.crc32(mc_configs_arg().encode())))
    if os.path.exists(os.path.join(folder, "timings.csv")):
        return folder
    os.makedirs(folder, exist_ok=True)
    cmd = [os.path.join(binary, "mcvol-accuracy"), "--dataset", dataset, "--blend", mode, "--size", str(size),
           str(size), "--out", folder, "--ref-spp", str(ref_spp), "--spp-max", str(spp_max),
           "--steps", ",".join(str(s) for s in STEPS), "--mc-configs", mc_configs_arg()]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    return folder


def analyse(folder, dataset, mode, size):
    rows = []
    read_choices(os.path.join(folder, "meta.txt"), dataset, mode, False)
    ref = load(os.path.join(folder, "reference.f32"), size, size)
    with open(os.path.join(folder, "timings.csv")) as f:
        for r in csv.DictReader(f):
            method, variant, param, ms = r["method"], r["variant"], float(r["param"]), float(r["ms"])
            est, smp = r.get("estimator") or "", r.get("sampler") or ""
            if method == "reference":
                name = "reference.f32" if variant == "raymarch" else "reference_mc.f32"
            elif method == "montecarlo":
                name = "mc_%s_%s_%s_%d.f32" % (est, smp, variant, int(param))
            else:
                name = "rm_%s_%g.f32" % (variant, param)
            img = load(os.path.join(folder, name), size, size)
            rmse, psnr, ssim = scores(img, ref)
            rows.append(dict(dataset=dataset, mode=mode, method=method, variant=variant, param=param, ms=ms,
                             rmse=rmse, psnr=psnr, ssim=ssim, file=os.path.join(folder, name),
                             estimator=est, sampler=smp))
    return rows


def load_gpu(folder, datasets, modes, notes):
    """Series measured with the CUDA backend (mcvol-accuracy --backend cuda
    --score-only; Benchmarks/gpu/bench.sh accuracy): RMSE and PSNR against
    the same ray-marched reference, computed by the tool. Monte Carlo rows,
    and ray-march rows whose backend column says the march ran on CUDA too
    (older files have no such column: their marches ran on the CPU).
    Monte Carlo rows name their estimator and sampler; files without those
    columns and without the backend column predate both (collision,
    independent: the old default); files with a backend column but no
    estimator column come from the weeks the tool's defaults changed, so
    what they ran is not known and they are left out (said in `notes`)."""
    rows = []
    unknown = []
    for ds in datasets:
        for mode in modes:
            path = os.path.join(folder, "%s-%s.csv" % (ds, mode))
            if not os.path.exists(path):
                continue
            read_choices(os.path.join(folder, "%s-%s.meta.txt" % (ds, mode)), ds, mode, True)
            with open(path) as f:
                for r in csv.DictReader(f):
                    est, smp = r.get("estimator") or "", r.get("sampler") or ""
                    if r["method"] == "montecarlo":
                        method = "montecarlo-cuda"
                        if not est and "backend" not in r:
                            est, smp = "collision", "independent"
                        elif not est:
                            unknown.append("%s-%s.csv" % (ds, mode))
                            continue
                    elif r["method"] == "raymarch" and r.get("backend") == "cuda":
                        method = "raymarch-cuda"
                    else:
                        continue
                    rows.append(dict(dataset=ds, mode=mode, method=method, variant=r["variant"],
                                     param=float(r["param"]), ms=float(r["ms"]), rmse=float(r["rmse"]),
                                     psnr=float(r["psnr"]), ssim=float("nan"), file=None,
                                     estimator=est, sampler=smp))
    if unknown:
        notes.append("Left out: the Monte Carlo rows of %s (a backend column but no estimator column: the "
                     "tool's defaults were changing then, so their estimator and sampler are not known)." %
                     ", ".join(sorted(set(unknown))))
    return rows


def effective_estimator(mode, estimator):
    """The estimator the renderer runs when `estimator` is asked for (unlit):
    the composite blend keeps the collision estimator (Integrator.h,
    usesExpectedValue)."""
    if mode == "composite":
        return None if estimator == "automatic" else "collision"
    return estimator


def methods_for(mode, gpu=False):
    """The series of one blend mode, each once: (method, variant, estimator,
    sampler, key, label, colour, line). Where a configuration runs as
    another (the new default under the composite blend) the first keeps the
    series and says so."""
    out, seen = [], set()
    for est, smp, trk, key, label, colour, line in MC_CONFIGS:
        run = effective_estimator(mode, est)
        if run is None or (run, smp, trk) in seen:
            continue
        seen.add((run, smp, trk))
        if run != est:
            label += " = collision here"
        out.append(("montecarlo-cuda" if gpu else "montecarlo", trk, run, smp, key, label, colour, line))
    for model, label, colour, line in MARCHES:
        out.append(("raymarch-cuda" if gpu else "raymarch", model, "", "", model, label, colour, line))
    return out


def find(rows, mode, key, gpu=False):
    """The series of `key` (a MC_CONFIGS key or a march model) for one mode."""
    for m in methods_for(mode, gpu):
        if m[4] == key:
            return series(rows, *m[:4])
    return []


def series(rows, method, variant, estimator="", sampler=""):
    s = [r for r in rows if r["method"] == method and r["variant"] == variant
         and (not method.startswith("montecarlo") or (r["estimator"], r["sampler"]) == (estimator, sampler))]
    return sorted(s, key=lambda r: r["ms"])


def plot_dataset(rows, dataset, modes, out):
    """One panel per blend mode; CPU series solid markers, GPU series the
    same colours with triangles and dotted lines; one legend for the figure
    (the same series in every panel, bar the composite one's relabelled new
    default)."""
    fig, axes = plt.subplots(1, len(modes), figsize=(4.6 * len(modes), 4.4), squeeze=False)
    handles = {}
    for ax, mode in zip(axes[0], modes):
        rs = [r for r in rows if r["dataset"] == dataset and r["mode"] == mode]
        for gpu in (False, True):
            for method, variant, est, smp, key, label, colour, line in methods_for(mode, gpu):
                s = series(rs, method, variant, est, smp)
                if not s:
                    continue
                mc = method.startswith("montecarlo")
                marker = ("^" if mc else "v") if gpu else ("o" if mc else "s")
                h, = ax.plot([r["ms"] for r in s], [r["psnr"] for r in s], marker=marker, color=colour,
                             linestyle=":" if gpu else line, markersize=3.5 if gpu else 4,
                             linewidth=1.2, alpha=0.8 if gpu else 1.0)
                handles.setdefault(label + (" (%s)" % GPU_LABEL if gpu else ", CPU"), h)
                for r in s:
                    # Label a few points of each CPU series: spp (MC) or step (RM).
                    if gpu or (mc and int(r["param"]) not in (1, 16, 256, 1024)):
                        continue
                    ax.annotate(("%d" % r["param"]) if mc else ("%g" % r["param"]), (r["ms"], r["psnr"]),
                                fontsize=6, xytext=(2, 2), textcoords="offset points", color=colour)
        ax.axhline(35.0, color="black", linestyle="-", linewidth=0.5, alpha=0.5)
        cross = [r for r in rs if r["method"] == "reference" and r["variant"] == "montecarlo"]
        if cross:
            h = ax.axhline(cross[0]["psnr"], color="gray", linestyle=":", linewidth=1)
            handles.setdefault("cross-check: MC new default, %d spp, against the reference" %
                               int(cross[0]["param"]), h)
        ax.set_xscale("log")
        ax.set_xlabel("time (ms, log)")
        ax.set_ylabel("PSNR (dB, peak 1) against the reference")
        ax.set_title("%s, %s" % (dataset, mode))
        ax.grid(True, which="both", alpha=0.3)
    ncol = 2 if len(modes) <= 2 else 3  # the labels are long: fewer columns on a narrow figure
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=ncol, fontsize=7,
               frameon=False)
    fig.suptitle("%s: error against time (MC labels: spp; RM labels: step in voxels; line: 35 dB)" % dataset)
    rows_of_legend = (len(handles) + ncol - 1) // ncol
    fig.tight_layout(rect=(0, 0.032 * rows_of_legend + 0.01, 1, 1))
    fig.savefig(out, dpi=100)
    plt.close(fig)


def cheapest_reaching(s, psnr):
    ok = [r for r in s if r["psnr"] >= psnr]
    return min(ok, key=lambda r: r["ms"]) if ok else None


def time_to(s, psnr):
    """Time to reach `psnr`, interpolated: log(time) linear in PSNR between
    the cheapest point reaching it and the point before it in time (which
    does not reach it). The measured points are a factor of about 2 apart
    (spp doubles, steps halve), too coarse for a ratio of two series."""
    r = cheapest_reaching(s, psnr)
    if r is None:
        return None
    before = [x for x in s if x["ms"] < r["ms"]]
    if not before:
        return r["ms"]
    p = max(before, key=lambda x: x["ms"])
    f = (psnr - p["psnr"]) / (r["psnr"] - p["psnr"])
    return math.exp(math.log(p["ms"]) + f * (math.log(r["ms"]) - math.log(p["ms"])))


def best_within(s, ms):
    ok = [r for r in s if r["ms"] <= ms]
    return max(ok, key=lambda r: r["psnr"]) if ok else None


def grid_dataset(rows, dataset, size, peers, out):
    """Like the paper's Figure 10, density blending: equal time (each method's
    best image within the time of the ray march at the Nyquist rate) and
    equal quality (each method's cheapest image reaching 35 dB), plus VTK's
    mappers for comparison (another blend formula)."""
    rs = [r for r in rows if r["dataset"] == dataset and r["mode"] == "density"]
    ref = [r for r in rs if r["method"] == "reference" and r["variant"] == "raymarch"][0]
    nyq = [r for r in rs if r["method"] == "raymarch" and r["variant"] == "extinction" and r["param"] == 0.5][0]
    budget, target = nyq["ms"], 35.0
    # The new and the old Monte Carlo default, the automatic choice (where
    # the run has it) and both marches (the other series are in the plots
    # and tables).
    picked = [("new", "MC new default"), ("old", "MC old default")]
    if find(rs, "density", "auto"):
        picked.append(("auto", "MC automatic (pilots counted)"))
    picked += [("extinction", "RM extinction"), ("opacity", "RM opacity")]
    cols = []
    for label, pick in (("equal time: %.0f ms" % budget, lambda s: best_within(s, budget)),
                        ("equal quality: %.1f dB" % target, lambda s: cheapest_reaching(s, target))):
        for key, name in picked:
            r = pick(find(rs, "density", key))
            cols.append((label, name, r))
    # Two rows: equal time, then equal quality; the reference and VTK's
    # mappers (another blend formula: pictured, not scored) in the outer
    # columns.
    n = len(picked)
    fig, axes = plt.subplots(2, n + 2, figsize=(2.4 * (n + 2), 5.6))
    ref_img = display(load(ref["file"], size, size))
    for row in range(2):
        axes[row][0].imshow(ref_img)
        axes[row][0].set_title("reference\n(RM extinction, 1/16 voxel)", fontsize=7)
        for ax, (label, name, r) in zip(axes[row][1:1 + n], cols[row * n:(row + 1) * n]):
            if r is None:
                ax.text(0.5, 0.5, "no image within the time" if row == 0 else "not reached", ha="center",
                        va="center", fontsize=8)
                ax.set_title("%s\n%s" % (label, name), fontsize=7)
                continue
            ax.imshow(display(load(r["file"], size, size)))
            param = ("%d spp" % r["param"]) if r["method"] == "montecarlo" else ("step %g" % r["param"])
            ax.set_title("%s\n%s, %s\n%.0f ms, %.1f dB" % (label, name, param, r["ms"], r["psnr"]), fontsize=7)
        ax = axes[row][-1]
        if row < len(peers):
            name, ms, png = peers[row]
            if png and os.path.exists(png):
                ax.imshow(plt.imread(png))
            ax.set_title("VTK %s mapper\n%.0f ms (its own blend\nformula: not scored)" % (name, ms), fontsize=7)
    for row in axes:
        for ax in row:
            ax.axis("off")
    fig.suptitle("%s, density blending: equal time (top) and equal quality (bottom)" % dataset, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def vtk_peers(dataset, size, out_dir):
    """Times vtkFixedPointVolumeRayCastMapper and vtkGPUVolumeRayCastMapper
    (independent components, at most 4) on the dataset; saves their images."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import bench_vtk
    from vtkmodules.vtkRenderingVolume import vtkFixedPointVolumeRayCastMapper, vtkGPUVolumeRayCastMapper
    from mcvol import vtkMultiChannelDemoSource

    src = vtkMultiChannelDemoSource()
    src.SetDataset(dataset)
    src.Update()
    n = min(4, src.GetNumberOfOutputChannels())
    data = src.GetOutput()
    if src.GetNumberOfOutputChannels() > 4:
        # VTK's mappers take at most 4 independent components: the first 4.
        from vtkmodules.vtkCommonDataModel import vtkImageData
        from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
        arr = vtk_to_numpy(data.GetPointData().GetScalars())[:, :4].copy()
        img = vtkImageData()
        img.CopyStructure(data)
        a = numpy_to_vtk(arr, deep=True)
        a.SetName("first4")
        img.GetPointData().SetScalars(a)
        data = img
    prop = bench_vtk.make_property(src, n)

    class A:
        pass

    args = A()
    args.size, args.warmup, args.frames, args.converged_spp = size, 1, 3, 0
    out = []
    for name, mapper in (("fixed-point", vtkFixedPointVolumeRayCastMapper()), ("GPU", vtkGPUVolumeRayCastMapper())):
        folder = tempfile.mkdtemp()
        ms, _ = bench_vtk.time_mapper(name.replace(" ", "_"), mapper, data, prop, args, folder)
        png = os.path.join(out_dir, "vtk-%s-%s.png" % (dataset, name.lower()))
        os.replace(os.path.join(folder, "vtk_peer_%s.png" % name.replace(" ", "_")), png)
        out.append((name, ms, png))
    return out, n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default="build/bin")
    ap.add_argument("--out", default="Benchmarks/results/accuracy-study")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "mcvol-accuracy"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--spp-max", type=int, default=1024)
    ap.add_argument("--datasets", default=",".join(DATASETS))
    ap.add_argument("--modes", default=",".join(MODES), help="blend modes (a shorter study: density,composite)")
    ap.add_argument("--no-peers", action="store_true", help="do not time VTK's mappers (reuse vtk-peers.csv if present)")
    ap.add_argument("--gpu", default="", help="folder of CUDA series (<dataset>-<mode>.csv)")
    ap.add_argument("--gpu-label", default="GPU", help="how the plots name the GPU")
    ap.add_argument("--note", default="", help="a paragraph for ACCURACY.md's header (e.g. what else loaded the "
                    "machine while it ran: the CPU times depend on it)")
    args = ap.parse_args()
    datasets = args.datasets.split(",")
    modes = args.modes.split(",")
    if "density" not in modes:
        sys.exit("accuracy_study.py: --modes must include density (the grids and the summary table use it)")
    os.makedirs(args.out, exist_ok=True)
    os.makedirs(args.work, exist_ok=True)
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows = []
    for ds in datasets:
        for mode in modes:
            folder = run_tool(args.bin, ds, mode, args.size, args.work, args.ref_spp, args.spp_max)
            rows += analyse(folder, ds, mode, args.size)
    global GPU_LABEL
    GPU_LABEL = args.gpu_label
    notes = []
    if args.gpu:
        gpu = load_gpu(args.gpu, datasets, modes, notes)
        if not gpu:
            sys.exit("accuracy_study.py: --gpu %s: no <dataset>-<mode>.csv series found" % args.gpu)
        rows += gpu
    with open(os.path.join(args.out, "accuracy.csv"), "w", newline="") as f:
        w = csv.writer(f)
        # estimator and sampler last: the older columns keep their places.
        w.writerow(["dataset", "mode", "method", "variant", "param", "ms", "rmse", "psnr_db", "ssim",
                    "estimator", "sampler"])
        for r in rows:
            w.writerow([r["dataset"], r["mode"], r["method"], r["variant"], r["param"], "%.3f" % r["ms"],
                        "%.6f" % r["rmse"], "%.3f" % r["psnr"], "" if math.isnan(r["ssim"]) else "%.5f" % r["ssim"],
                        r["estimator"], r["sampler"]])
    peers = {}
    peer_csv = os.path.join(args.out, "vtk-peers.csv")
    if args.no_peers and os.path.exists(peer_csv):
        # Reuse the recorded VTK timings and pictures.
        with open(peer_csv) as f:
            for r in csv.DictReader(f):
                png = os.path.join(args.out, "vtk-%s-%s.png" % (r["dataset"], r["mapper"].lower()))
                peers.setdefault(r["dataset"], []).append((r["mapper"], float(r["ms"]), png))
    elif not args.no_peers:
        with open(os.path.join(args.out, "vtk-peers.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["dataset", "mapper", "channels", "ms"])
            for ds in datasets:
                p, n = vtk_peers(ds, args.size, args.out)
                peers[ds] = p
                for name, ms, _ in p:
                    w.writerow([ds, name, n, "%.1f" % ms])
    for ds in datasets:
        plot_dataset(rows, ds, modes, os.path.join(args.out, "accuracy-%s.png" % ds))
        grid_dataset(rows, ds, args.size, peers.get(ds, []), os.path.join(args.out, "grid-%s.png" % ds))
    write_summary(rows, peers, datasets, modes, args, started, notes)


def fmt_ms(r):
    return "—" if r is None else (("%.0f ms (%s)" if r["ms"] >= 10 else "%.2g ms (%s)") % (
        r["ms"], ("%d spp" % r["param"]) if r["method"].startswith("montecarlo") else ("step %g" % r["param"])))


def fmt_q(r):
    return "—" if r is None else ("%.1f dB (%s)" % (r["psnr"], ("%d spp" % r["param"]) if
                                                     r["method"].startswith("montecarlo") else ("step %g" % r["param"])))


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def reach(s, q):
    """The table cell of a series at quality q: time and spp/step, "never
    (best ...)" when no point reaches it, n/a when there is no series."""
    if not s:
        return "n/a"
    r = cheapest_reaching(s, q)
    if r is None:
        return "never (best %.1f dB)" % max(x["psnr"] for x in s)
    return fmt_ms(r)


def ratio_range(pairs):
    v = sorted(b / a for a, b in pairs if a is not None and b is not None)
    if not v:
        return None
    return ("%.1f" % v[0]) if len(v) == 1 or "%.1f" % v[0] == "%.1f" % v[-1] else "%.1f to %.1f" % (v[0], v[-1])


def headline(rows, datasets, args, target=35.0):
    """The summary table: time to `target` dB, density blending, each
    dataset; CPU columns from this run, GPU columns from --gpu where its
    files have the series (n/a otherwise). Returns markdown lines."""
    g = args.gpu_label
    cols = [("MC new default, CPU", "new", False), ("MC collision + Sobol', CPU", "col-sobol", False),
            ("MC old default, CPU", "old", False), ("MC unbiased march, CPU", "march", False),
            ("MC automatic, CPU", "auto", False), ("RM extinction, CPU", "extinction", False),
            ("RM opacity, CPU", "opacity", False), ("MC new default, %s" % g, "new", True),
            ("MC old default, %s" % g, "old", True), ("MC unbiased march, %s" % g, "march", True),
            ("MC automatic, %s" % g, "auto", True), ("RM extinction, %s" % g, "extinction", True)]
    lines = ["| dataset | " + " | ".join(c[0] for c in cols) + " | old / new MC, CPU |",
             "|---|" + "---|" * (len(cols) + 1)]
    pairs = {k: [] for k in ("old-new", "new-rm", "old-rm", "gold-gnew", "gnew-grm")}
    spp, cost = [], []
    missing = set()
    for ds in datasets:
        rs = [r for r in rows if r["dataset"] == ds and r["mode"] == "density"]
        ss = {(k, gpu): find(rs, "density", k, gpu) for _, k, gpu in cols}
        cells = []
        for name, k, gpu in cols:
            cells.append(reach(ss[(k, gpu)], target))
            if not ss[(k, gpu)]:
                missing.add(name)
        at = {kg: time_to(s, target) if s else None for kg, s in ss.items()}
        new, old, rm = at[("new", False)], at[("old", False)], at[("extinction", False)]
        ratio = "%.1f×" % (old / new) if new and old else "—"
        lines.append("| %s | %s | %s |" % (ds, " | ".join(cells), ratio))
        pairs["old-new"].append((new, old))
        pairs["new-rm"].append((rm, new))
        pairs["old-rm"].append((rm, old))
        sn, so = cheapest_reaching(ss[("new", False)], target), cheapest_reaching(ss[("old", False)], target)
        if sn and so:
            spp.append(so["param"] / sn["param"])
        # Cost per sample: cumulative times at the largest spp both series have.
        common = {r["param"]: r["ms"] for r in ss[("new", False)]}
        both = [(p, r["ms"]) for r in ss[("old", False)] for p in [r["param"]] if p in common]
        if both:
            p, ms = max(both)
            cost.append((ms, common[p]))
        pairs["gold-gnew"].append((at[("new", True)], at[("old", True)]))
        pairs["gnew-grm"].append((at[("extinction", True)], at[("new", True)]))
    lines += ["", "Each time is that of the first point of the series at or above %.0f dB: Monte Carlo points are "
              "1, 2, 4, ... spp (cumulative progressive time), ray-march points the steps %s voxels, so a time "
              "is resolved to a factor of about 2. \"never\": no point of the series reaches it. The ratios (last column "
              "and below) use times interpolated between the two points around %.0f dB (log time linear in "
              "PSNR)." %
              (target, ", ".join("%g" % x for x in STEPS), target)]
    if missing:
        lines += ["", "n/a: %s — no such series%s." % (", ".join(sorted(missing)), (
            " in the --gpu folder (%s: older series name no estimator and sampler, so only collision + "
            "independent ones count as the old default, and their marches ran on the CPU)" % args.gpu)
            if args.gpu else " (no --gpu folder given)")]
    said = []
    r = ratio_range(pairs["old-new"])
    if r:
        said.append("On the CPU the new Monte Carlo default reaches %.0f dB %s times sooner than the old default "
                    "(1-DDA)." % (target, r))
    if spp:
        said.append("It needs %s times fewer samples (%s), and a sample costs %s times an old one (cumulative "
                    "times at the same spp)." % (
                        ("%.0f" % min(spp)) if min(spp) == max(spp) else "%.0f to %.0f" % (min(spp), max(spp)),
                        "powers of 2: coarse", ratio_range(cost)))
    r = ratio_range(pairs["new-rm"])
    if r:
        said.append("It takes %s times as long as the CPU ray marcher (extinction model) to get there (the old "
                    "default: %s)." % (r, ratio_range(pairs["old-rm"]) or "never, within its series"))
    r = ratio_range(pairs["gold-gnew"])
    if r:
        said.append("On the %s the new default is %s times sooner than the old." % (g, r))
    r = ratio_range(pairs["gnew-grm"])
    if r:
        said.append("On the %s it takes %s times as long as the CUDA ray marcher (extinction model)." % (g, r))
    if said:
        lines += ["", " ".join(said) + " (Datasets where both reach it; a ratio below 1 means sooner.)"]
    chosen = []
    for ds in datasets:
        for gpu, where in ((False, "CPU"), (True, g)):
            c = CHOICES.get((ds, "density", gpu))
            if c:
                ms = lambda v: ("%.0f" % v) if v >= 10 else ("%.2g" % v)
                hinted = "" if c[3] is None else "; hinted by the previous choice %s ms, %d rounds" % (ms(c[3]), c[4])
                chosen.append("%s, %s: %s (pilots %s ms, %d rounds%s)" % (ds, where, c[0], ms(c[1]), c[2], hinted))
    if chosen:
        lines += ["", "The automatic choice (`chooseEstimator`, aiming at %.0f dB, pixel centres; its series' times "
                  "start with the pilots' wall time, a choice made after a first one in the process): %s." % (
                      target, "; ".join(chosen))]
    edits = []
    for ds in datasets:
        for gpu, where in ((False, "CPU"), (True, g)):
            e = EDITS.get((ds, "density", gpu))
            if e:
                edits.append("%s, %s: automatic %d frames, %.2f ms with the hinted pilots first, **%.2f ms** with "
                             "the frames rendered during them%s; expected value %d frames, **%.2f ms**" % (
                                 ds, where, e[0], e[1], e[2], "" if e[3] else " (**not kept**)", e[4], e[5]))
    if edits:
        lines += ["", "A transfer-function edit timed to 35 dB against the reference (`mcvol-accuracy` on a backend "
                  "that renders pilots at once: the warm, hinted choice and the chosen estimator's frames, or "
                  "expected value's frames with no pilots; each from its start to the last frame's end, median "
                  "of 5): %s." % "; ".join(edits)]
    return lines


def write_summary(rows, peers, datasets, modes, args, started, notes):
    cmd = " ".join(shlex.quote(a) for a in ["python3", "Benchmarks/studies/accuracy_study.py"] + sys.argv[1:])
    lines = ["# Accuracy against time", "",
             "Generated by `Benchmarks/studies/accuracy_study.py` (%s) on %s (%s, %d cores); CPU backend, %d x %d "
             "images, Monte Carlo up to %d spp, cross-check %d spp. Command: `%s`." %
             (started, platform.node() or "this machine", cpu_model(), os.cpu_count(), args.size, args.size,
              args.spp_max, args.ref_spp, cmd), "",
             "Reference: ray march, extinction model, 1/16 voxel, no early termination. Errors are against it, on "
             "the premultiplied RGB over black clipped to [0, 1]: RMSE, PSNR (peak 1) and SSIM (scikit-image). "
             "Monte Carlo samples pixel centres (no pixel jitter), like the ray marcher; its time is the cumulative "
             "render time of the progressive image. Ray-march steps are in voxels (of the smallest spacing); "
             "those runs stop rays at transmittance 1e-4, the mapper's default.", ""]
    if args.note:
        lines += [args.note, ""]
    lines += ["Monte Carlo series (`mcvol-accuracy --mc-configs %s`, one run and one reference per dataset and "
             "mode):" % mc_configs_arg(), ""]
    for est, smp, trk, key, label, _, _ in MC_CONFIGS:
        lines.append("- %s: `%s:%s:%s`" % (label, est, smp, trk))
    lines += ["", "The composite blend keeps the collision estimator whatever is asked (`Types.h`, `Estimator`), "
              "so there the new default is the collision + Sobol' series (labelled \"= collision here\").", ""]
    if args.gpu:
        lines += ["Rows marked (%s) were measured on the %s with the CUDA backend (`Benchmarks/gpu/bench.sh "
                  "accuracy`: `mcvol-accuracy --backend cuda --score-only`, same datasets, camera, size and "
                  "reference, which the tool renders on that machine and scores against itself; the ray marches "
                  "run on CUDA too, with software interpolation, when the series says so in its backend column); "
                  "they have RMSE and PSNR but no SSIM. Raw series: `%s`." %
                  (args.gpu_label, args.gpu_label, os.path.relpath(args.gpu, args.out)), ""]
    lines += notes + ([""] if notes else [])
    lines += ["## Time to reach 35 dB, density blending", ""] + headline(rows, datasets, args) + [""]
    lines += ["## Cross-check of the reference", "",
              "| dataset | mode | MC | MC spp | PSNR of MC against the reference | SSIM |", "|---|---|---|---|---|---|"]
    for ds in datasets:
        for mode in modes:
            c = [r for r in rows if r["dataset"] == ds and r["mode"] == mode and r["method"] == "reference"
                 and r["variant"] == "montecarlo"][0]
            lines.append("| %s | %s | %s, %s | %d | %.1f dB | %.4f |" % (ds, mode, c["estimator"], c["sampler"],
                                                                        c["param"], c["psnr"], c["ssim"]))
    lines += ["", "A Monte Carlo image of that many samples has noise of its own; its PSNR against the reference "
              "is the quality above which the two cannot be told apart by this check.", ""]
    for ds in datasets:
        lines += ["## %s" % ds, "", "![error against time](accuracy-%s.png)" % ds, "",
                  "![equal time and equal quality](grid-%s.png)" % ds, ""]
        head = "| mode | method | " + " | ".join("time to %.0f dB" % q for q in QUALITY) + " | " + \
               " | ".join("PSNR within %.0f ms" % b for b in BUDGETS) + " |"
        lines += [head, "|" + "---|" * (2 + len(QUALITY) + len(BUDGETS))]
        for mode in modes:
            rs = [r for r in rows if r["dataset"] == ds and r["mode"] == mode]
            for gpu in (False, True):
                for method, variant, est, smp, key, label, _, _ in methods_for(mode, gpu):
                    s = series(rs, method, variant, est, smp)
                    if not s:
                        continue
                    cells = [fmt_ms(cheapest_reaching(s, q)) for q in QUALITY]
                    cells += [fmt_q(best_within(s, b)) for b in BUDGETS]
                    name = label + (" (%s)" % args.gpu_label if gpu else "")
                    lines.append("| %s | %s | %s |" % (mode, name, " | ".join(cells)))
        if ds in peers:
            lines += ["", "VTK's own mappers on the same data (%s): %s. They blend independent components with their "
                      "own weighted formula, not any of ours, so they are timed and pictured, not scored." %
                      ("first 4 channels" if ds == "weather" else "all channels",
                       ", ".join("%s %.0f ms per frame" % (n, ms) for n, ms, _ in peers[ds]))]
        lines.append("")
    with open(os.path.join(args.out, "ACCURACY.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", os.path.join(args.out, "ACCURACY.md"))


if __name__ == "__main__":
    main()
