#!/usr/bin/python3
"""The accuracy-versus-time study (issue 3): what image quality each method
reaches and what it costs.

For each demo dataset and blend mode, `mcvol-accuracy` renders (one run):
  - the reference: a ray march with the extinction model at a fine step (1/16
    voxel), cross-checked against a high-sample Monte Carlo image;
  - Monte Carlo at 1, 2, 4, ..., 1024 spp, 1-DDA and N-DDA (cumulative time);
  - the ray marcher at steps of 4 voxels down to 1/8 voxel, extinction- and
    opacity-based compositing.
This script scores every image against the reference (RMSE and PSNR with peak
1, SSIM from scikit-image, all on the premultiplied RGB over black, clipped to
[0, 1] as displayed), times VTK's own fixed-point and GPU ray-cast mappers on
the same data for comparison (their independent-components blend formula is
not ours, so they are pictured, not scored), and writes:
  accuracy.csv, accuracy-<dataset>.png (error against time, one panel per
  blend mode), grid-<dataset>.png (equal-time and equal-quality renders, like
  the paper's Figure 10), vtk-peers.csv, and ACCURACY.md (the summary).

Usage (from the repository, after building):
  PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 \\
      Benchmarks/accuracy_study.py --bin build/bin --out Benchmarks/results/accuracy
"""
import argparse
import csv
import math
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from skimage.metrics import structural_similarity  # noqa: E402

DATASETS = ["figure3", "microscopy", "cosmology", "weather"]
MODES = ["density", "max", "mix", "composite"]
STEPS = [4, 2, 1, 0.5, 0.25, 0.125]
METHODS = [("montecarlo", "1dda", "MC 1-DDA"), ("montecarlo", "ndda", "MC N-DDA"),
           ("raymarch", "extinction", "RM extinction"), ("raymarch", "opacity", "RM opacity")]
GPU_METHODS = [("montecarlo-cuda", "1dda", "MC 1-DDA (CUDA)"), ("montecarlo-cuda", "ndda", "MC N-DDA (CUDA)"),
               ("raymarch-cuda", "extinction", "RM extinction (CUDA)"), ("raymarch-cuda", "opacity", "RM opacity (CUDA)")]
COLOURS = {"1dda": "tab:green", "ndda": "tab:olive", "extinction": "tab:blue", "opacity": "tab:red"}
GPU_LABEL = "GPU"
QUALITY = [30.0, 35.0, 40.0]   # PSNR targets (dB)
BUDGETS = [50.0, 200.0, 1000.0]  # time budgets (ms)


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


def run_tool(binary, dataset, mode, size, work, ref_spp, spp_max):
    # The cache folder names every option, so a rerun with others re-renders.
    folder = os.path.join(work, "%s-%s-%d-%d-%d" % (dataset, mode, size, ref_spp, spp_max))
    if os.path.exists(os.path.join(folder, "timings.csv")):
        return folder
    os.makedirs(folder, exist_ok=True)
    cmd = [os.path.join(binary, "mcvol-accuracy"), "--dataset", dataset, "--blend", mode, "--size", str(size),
           str(size), "--out", folder, "--ref-spp", str(ref_spp), "--spp-max", str(spp_max),
           "--steps", ",".join(str(s) for s in STEPS)]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    return folder


def analyse(folder, dataset, mode, size):
    rows = []
    ref = load(os.path.join(folder, "reference.f32"), size, size)
    with open(os.path.join(folder, "timings.csv")) as f:
        for r in csv.DictReader(f):
            method, variant, param, ms = r["method"], r["variant"], float(r["param"]), float(r["ms"])
            if method == "reference":
                name = "reference.f32" if variant == "raymarch" else "reference_mc.f32"
            elif method == "montecarlo":
                name = "mc_%s_%d.f32" % (variant, int(param))
            else:
                name = "rm_%s_%g.f32" % (variant, param)
            img = load(os.path.join(folder, name), size, size)
            rmse, psnr, ssim = scores(img, ref)
            rows.append(dict(dataset=dataset, mode=mode, method=method, variant=variant, param=param, ms=ms,
                             rmse=rmse, psnr=psnr, ssim=ssim, file=os.path.join(folder, name)))
    return rows


def load_gpu(folder, datasets):
    """Series measured with the CUDA backend (mcvol-accuracy --backend cuda
    --score-only; Benchmarks/gpu/bench.sh accuracy): RMSE and PSNR against
    the same ray-marched reference, computed by the tool. Monte Carlo rows,
    and ray-march rows whose backend column says the march ran on CUDA too
    (older files have no such column: their marches ran on the CPU)."""
    rows = []
    for ds in datasets:
        for mode in MODES:
            path = os.path.join(folder, "%s-%s.csv" % (ds, mode))
            if not os.path.exists(path):
                continue
            with open(path) as f:
                for r in csv.DictReader(f):
                    if r["method"] == "montecarlo":
                        method = "montecarlo-cuda"
                    elif r["method"] == "raymarch" and r.get("backend") == "cuda":
                        method = "raymarch-cuda"
                    else:
                        continue
                    rows.append(dict(dataset=ds, mode=mode, method=method, variant=r["variant"],
                                     param=float(r["param"]), ms=float(r["ms"]), rmse=float(r["rmse"]),
                                     psnr=float(r["psnr"]), ssim=float("nan"), file=None))
    return rows


def series(rows, method, variant):
    s = [r for r in rows if r["method"] == method and r["variant"] == variant]
    return sorted(s, key=lambda r: r["ms"])


def plot_dataset(rows, dataset, out):
    fig, axes = plt.subplots(1, len(MODES), figsize=(4.4 * len(MODES), 4.0), squeeze=False)
    for ax, mode in zip(axes[0], MODES):
        rs = [r for r in rows if r["dataset"] == dataset and r["mode"] == mode]
        for method, variant, label in METHODS + GPU_METHODS:
            s = series(rs, method, variant)
            if not s:
                continue
            gpu = method.endswith("-cuda")
            marker = {"montecarlo": "o", "raymarch": "s", "montecarlo-cuda": "^", "raymarch-cuda": "v"}[method]
            colour = COLOURS[variant]
            if method == "montecarlo-cuda":
                colour = "black" if variant == "1dda" else "gray"
            elif method == "raymarch-cuda":
                colour = "navy" if variant == "extinction" else "darkred"
            ax.plot([r["ms"] for r in s], [r["psnr"] for r in s], marker=marker, color=colour,
                    label=label + (" " + GPU_LABEL if gpu else ""),
                    linestyle="-" if variant in ("1dda", "extinction") else "--", markersize=4)
            for r in s:
                tag = ("%d" % r["param"]) if method == "montecarlo" else ("%g" % r["param"])
                if method.startswith("raymarch") or (method == "montecarlo" and int(r["param"]) in (1, 16, 256, 1024)):
                    ax.annotate(tag, (r["ms"], r["psnr"]), fontsize=6, xytext=(2, 2), textcoords="offset points")
        cross = [r for r in rs if r["method"] == "reference" and r["variant"] == "montecarlo"]
        if cross:
            ax.axhline(cross[0]["psnr"], color="gray", linestyle=":", linewidth=1,
                       label="MC %d spp vs reference" % int(cross[0]["param"]))
        ax.set_xscale("log")
        ax.set_xlabel("time (ms, log)")
        ax.set_ylabel("PSNR (dB, peak 1) against the reference")
        ax.set_title("%s, %s" % (dataset, mode))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    fig.suptitle("Error against time (MC labels: spp; RM labels: step in voxels)")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def cheapest_reaching(s, psnr):
    ok = [r for r in s if r["psnr"] >= psnr]
    return min(ok, key=lambda r: r["ms"]) if ok else None


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
    cols = []
    for label, pick in (("equal time: %.0f ms" % budget, lambda s: best_within(s, budget)),
                        ("equal quality: %.1f dB" % target, lambda s: cheapest_reaching(s, target))):
        for method, variant, name in METHODS:
            r = pick(series(rs, method, variant))
            cols.append((label, name, r))
    # Two rows: equal time, then equal quality; the reference and VTK's
    # mappers (another blend formula: pictured, not scored) in the outer
    # columns.
    fig, axes = plt.subplots(2, len(METHODS) + 2, figsize=(2.4 * (len(METHODS) + 2), 5.6))
    ref_img = display(load(ref["file"], size, size))
    for row in range(2):
        axes[row][0].imshow(ref_img)
        axes[row][0].set_title("reference\n(RM extinction, 1/16 voxel)", fontsize=7)
        for ax, (label, name, r) in zip(axes[row][1:1 + len(METHODS)], cols[row * len(METHODS):(row + 1) * len(METHODS)]):
            if r is None:
                ax.text(0.5, 0.5, "not reached", ha="center", va="center", fontsize=8)
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
    ap.add_argument("--out", default="Benchmarks/results/accuracy")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "mcvol-accuracy"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--spp-max", type=int, default=1024)
    ap.add_argument("--datasets", default=",".join(DATASETS))
    ap.add_argument("--no-peers", action="store_true", help="do not time VTK's mappers (reuse vtk-peers.csv if present)")
    ap.add_argument("--gpu", default="", help="folder of CUDA Monte Carlo series (<dataset>-<mode>.csv)")
    ap.add_argument("--gpu-label", default="GPU", help="how the plots name the GPU")
    args = ap.parse_args()
    datasets = args.datasets.split(",")
    os.makedirs(args.out, exist_ok=True)
    os.makedirs(args.work, exist_ok=True)
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows = []
    for ds in datasets:
        for mode in MODES:
            folder = run_tool(args.bin, ds, mode, args.size, args.work, args.ref_spp, args.spp_max)
            rows += analyse(folder, ds, mode, args.size)
    global GPU_LABEL
    GPU_LABEL = args.gpu_label
    if args.gpu:
        gpu = load_gpu(args.gpu, datasets)
        if not gpu:
            sys.exit("accuracy_study.py: --gpu %s: no <dataset>-<mode>.csv series found" % args.gpu)
        rows += gpu
    with open(os.path.join(args.out, "accuracy.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["dataset", "mode", "method", "variant", "param", "ms", "rmse", "psnr_db", "ssim"])
        for r in rows:
            w.writerow([r["dataset"], r["mode"], r["method"], r["variant"], r["param"], "%.3f" % r["ms"],
                        "%.6f" % r["rmse"], "%.3f" % r["psnr"], "" if math.isnan(r["ssim"]) else "%.5f" % r["ssim"]])
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
        plot_dataset(rows, ds, os.path.join(args.out, "accuracy-%s.png" % ds))
        grid_dataset(rows, ds, args.size, peers.get(ds, []), os.path.join(args.out, "grid-%s.png" % ds))
    write_summary(rows, peers, datasets, args, started)


def fmt_ms(r):
    return "—" if r is None else (("%.0f ms (%s)" if r["ms"] >= 10 else "%.2g ms (%s)") % (
        r["ms"], ("%d spp" % r["param"]) if r["method"].startswith("montecarlo") else ("step %g" % r["param"])))


def fmt_q(r):
    return "—" if r is None else ("%.1f dB (%s)" % (r["psnr"], ("%d spp" % r["param"]) if
                                                     r["method"].startswith("montecarlo") else ("step %g" % r["param"])))


def write_summary(rows, peers, datasets, args, started):
    lines = ["# Accuracy against time", "",
             "Generated by `Benchmarks/accuracy_study.py` (%s) on %s, %s; CPU backend, %d x %d images. "
             "Command: `PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 "
             "Benchmarks/accuracy_study.py --bin build/bin --out Benchmarks/results/accuracy`." %
             (started, platform.node() or "this machine", "%d cores" % os.cpu_count(), args.size, args.size), "",
             "Reference: ray march, extinction model, 1/16 voxel, no early termination. Errors are against it, on "
             "the premultiplied RGB over black clipped to [0, 1]: RMSE, PSNR (peak 1) and SSIM (scikit-image). "
             "Monte Carlo samples pixel centres (no pixel jitter), like the ray marcher; its time is the cumulative "
             "render time of the progressive image. Ray-march steps are in voxels (of the smallest spacing); "
             "those runs stop rays at transmittance 1e-4, the mapper's default.", ""]
    if args.gpu:
        lines += ["Rows marked (CUDA) were measured on the %s with the CUDA backend (`Benchmarks/gpu/bench.sh "
                  "accuracy`: `mcvol-accuracy --backend cuda --score-only`, same datasets, camera, size and "
                  "reference, which the tool renders on that machine and scores against itself; the ray marches "
                  "run on CUDA too, with software interpolation, when the series says so in its backend column); "
                  "they have RMSE and PSNR but no SSIM. Raw series: `gpu/`." % args.gpu_label, ""]
    lines += ["## Cross-check of the reference", "",
              "| dataset | mode | MC spp | PSNR of MC against the reference | SSIM |", "|---|---|---|---|---|"]
    for ds in datasets:
        for mode in MODES:
            c = [r for r in rows if r["dataset"] == ds and r["mode"] == mode and r["method"] == "reference"
                 and r["variant"] == "montecarlo"][0]
            lines.append("| %s | %s | %d | %.1f dB | %.4f |" % (ds, mode, c["param"], c["psnr"], c["ssim"]))
    lines += ["", "A Monte Carlo image of that many samples has noise of its own; its PSNR against the reference "
              "is the quality above which the two cannot be told apart by this check.", ""]
    for ds in datasets:
        lines += ["## %s" % ds, "", "![error against time](accuracy-%s.png)" % ds, "",
                  "![equal time and equal quality](grid-%s.png)" % ds, ""]
        head = "| mode | method | " + " | ".join("time to %.0f dB" % q for q in QUALITY) + " | " + \
               " | ".join("PSNR within %.0f ms" % b for b in BUDGETS) + " |"
        lines += [head, "|" + "---|" * (2 + len(QUALITY) + len(BUDGETS))]
        for mode in MODES:
            rs = [r for r in rows if r["dataset"] == ds and r["mode"] == mode]
            for method, variant, name in METHODS + GPU_METHODS:
                s = series(rs, method, variant)
                if not s:
                    continue
                cells = [fmt_ms(cheapest_reaching(s, q)) for q in QUALITY]
                cells += [fmt_q(best_within(s, b)) for b in BUDGETS]
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
