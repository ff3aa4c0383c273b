#!/usr/bin/python3
"""Plots of the levels-of-detail study (mcvol-pyramid --csv):

  pyramid-error-conv.png  image error against level, one panel per dataset,
                          each filter extinction-based (solid) and opacity-
                          averaged (dashed), against the paper's criterion
                          (the full-resolution image of the volume blurred by
                          the level's equivalent convolution)
  pyramid-error-full.png  the same against the full-resolution image
  pyramid-time.png        error against frame time: each dataset's box4
                          levels (ray march, against full resolution), and the
                          far views' levels against the supersampled image
                          (ray march per level, Monte Carlo at 64 spp)

    python3 Benchmarks/plots/plot_pyramid.py Benchmarks/results/levels-of-detail/pyramid-study/pyramid.csv \\
        --out Benchmarks/results/levels-of-detail/pyramid-study [--summary]

--summary also prints the Markdown summary tables of the performance page
(Documentation/performance.md, "Levels of detail": the ratios
of opacity to extinction error per dataset and level, the frame times per
level, the far views).
"""
import argparse
import csv
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FILTERS = [("box2", "tab:blue"), ("box4", "tab:orange"), ("bspline", "tab:green")]


def read(path):
    """{(section, dataset, filter, method, level, metric): value} and the datasets in order."""
    values = {}
    datasets = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            key = (r["section"], r["dataset"], r["filter"], r["method"], int(r["level"]), r["metric"])
            values[key] = float(r["value"])
            if r["dataset"] not in datasets[r["section"]]:
                datasets[r["section"]].append(r["dataset"])
    return values, datasets


def error_figure(values, datasets, metric, title, out):
    names = datasets.get("levels", [])
    if not names:
        return
    cols = min(4, len(names))
    rows = (len(names) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.3 * rows), squeeze=False)
    for ax, ds in zip(axes.flat, names):
        for filt, colour in FILTERS:
            for method, style in (("extinction", "-"), ("opacity", "--")):
                pts = sorted(
                    (k[4], v)
                    for k, v in values.items()
                    if k[:4] == ("levels", ds, filt, method) and k[5] == metric
                )
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], style, marker="o", color=colour,
                            label="%s %s" % (filt, method))
        ax.set_title(ds, fontsize=9)
        ax.set_xlabel("level")
        ax.set_ylabel("RMSE")
        ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=6)
    fig.suptitle(title, fontsize=10)
    plt.tight_layout()
    plt.savefig(out, dpi=100)
    print("wrote", out)


def time_figure(values, datasets, out):
    far = datasets.get("far", [])
    fig, axes = plt.subplots(1, 1 + len(far), figsize=(5 * (1 + len(far)), 4), squeeze=False)
    ax = axes[0][0]
    for ds in datasets.get("levels", []):
        pts = []
        for level in range(1, 10):
            ms = values.get(("levels", ds, "box4", "extinction", level, "march_ms"))
            e = values.get(("levels", ds, "box4", "extinction", level, "rmse_full"))
            if ms is not None and e is not None:
                pts.append((level, ms, e))
        if pts:
            line, = ax.plot([p[1] for p in pts], [p[2] for p in pts], "o-", label=ds)
            level0 = values.get(("levels", ds, "-", "scalar", 0, "march_ms"),
                                values.get(("levels", ds, "-", "classified", 0, "march_ms")))
            if level0 is not None:
                ax.axvline(level0, color=line.get_color(), alpha=0.3, lw=1)
            for level, ms, e in pts:
                ax.annotate(str(level), (ms, e), textcoords="offset points", xytext=(3, 3), fontsize=7)
    ax.set_title("box4 levels against full resolution\n(ray march; vertical lines: level 0 time)", fontsize=9)
    ax.set_xlabel("ray march ms per frame (CPU)")
    ax.set_ylabel("RMSE against full resolution")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    for ax, ds in zip(axes[0][1:], far):
        for method, metric, label, style in (
            ("raymarch", "rmse", "ray march, extinction pyramid", "o-"),
            ("raymarch_opacity", "rmse", "ray march, opacity pyramid", "s--"),
        ):
            pts = []
            for level in range(0, 10):
                ms = values.get(("far", ds, "box4", "raymarch", level, "ms"))
                e = values.get(("far", ds, "box4", method, level, metric))
                if ms is not None and e is not None:
                    pts.append((level, ms, e))
            if pts:
                ax.plot([p[1] for p in pts], [p[2] for p in pts], style, label=label)
                for level, ms, e in pts:
                    ax.annotate(str(level), (ms, e), textcoords="offset points", xytext=(3, 3), fontsize=7)
        pts = []
        for level in range(0, 10):
            ms = values.get(("far", ds, "box4", "montecarlo", level, "ms_64spp"))
            e = values.get(("far", ds, "box4", "montecarlo", level, "rmse_64spp"))
            if ms is not None and e is not None:
                pts.append((level, ms, e))
        if pts:
            ax.plot([p[1] for p in pts], [p[2] for p in pts], "^:", label="Monte Carlo, 64 spp (jittered)")
            for level, ms, e in pts:
                ax.annotate(str(level), (ms, e), textcoords="offset points", xytext=(3, -9), fontsize=7)
        auto = [k[4] for k in values if k[:4] == ("far", ds, "box4", "auto") and k[5] == "footprint_voxels"]
        ax.set_title("far view \"%s\" against the supersampled image%s" %
                     (ds, "\n(automatic level %d)" % auto[0] if auto else ""), fontsize=9)
        ax.set_xlabel("ms (CPU)")
        ax.set_ylabel("RMSE against the footprint-averaged image")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    plt.tight_layout()
    plt.savefig(out, dpi=100)
    print("wrote", out)


def summary(values, datasets):
    """Prints the performance page's summary tables from the CSV."""
    filters = [f for f, _ in FILTERS]
    print("| dataset | level | ext. RMSE vs conv (box2 / box4 / bspline) | ratio opacity/ext., conv | "
          "ratio opacity/ext., full |")
    print("|---|---|---|---|---|")
    for ds in datasets.get("levels", []):
        for level in range(1, 10):
            conv = [values.get(("levels", ds, f, "extinction", level, "rmse_conv")) for f in filters]
            if conv[0] is None:
                break
            rc = [values[("levels", ds, f, "ratio", level, "rmse_conv")] for f in filters]
            rf = [values[("levels", ds, f, "ratio", level, "rmse_full")] for f in filters]
            fmt = lambda xs, d: " / ".join(("**%.*f**" if x <= 1.0 else "%.*f") % (d, x) for x in xs)  # noqa: E731
            print("| %s | %d | %s | %s | %s |" % (ds, level, " / ".join("%.4f" % x for x in conv), fmt(rc, 2),
                                                  fmt(rf, 2)))
    print()
    print("| dataset | level 0 scalar: RM / MC ms | level 0 classified | level 1 | level 2 | level 3 |")
    print("|---|---|---|---|---|---|")
    for ds in datasets.get("levels", []):
        cells = []
        for method, level in (("scalar", 0), ("classified", 0), ("extinction", 1), ("extinction", 2),
                              ("extinction", 3)):
            filt = "-" if level == 0 else "box4"
            rm = values.get(("levels", ds, filt, method, level, "march_ms"))
            mc = values.get(("levels", ds, filt, method, level, "mc_ms"))
            cells.append("-" if rm is None else "%.1f / %.1f" % (rm, mc))
        print("| %s | %s |" % (ds, " | ".join(cells)))
    print()
    for ds in datasets.get("far", []):
        print("far view %s:" % ds)
        print("| level | RM ms | RM RMSE | opacity-pyramid RM RMSE | MC ms/spp | MC 64 spp RMSE |")
        print("|---|---|---|---|---|---|")
        auto = [k[4] for k in values if k[:4] == ("far", ds, "box4", "auto")]
        for level in range(0, 10):
            ms = values.get(("far", ds, "box4", "raymarch", level, "ms"))
            if ms is None:
                break
            opa = values.get(("far", ds, "box4", "raymarch_opacity", level, "rmse"))
            print("| %d%s | %.1f | %.4f | %s | %.1f | %.4f |" % (
                level, " (auto)" if auto and auto[0] == level else "", ms,
                values[("far", ds, "box4", "raymarch", level, "rmse")], "-" if opa is None else "%.4f" % opa,
                values[("far", ds, "box4", "montecarlo", level, "ms_per_spp")],
                values[("far", ds, "box4", "montecarlo", level, "rmse_64spp")]))
        print()


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("csv")
    p.add_argument("--out", required=True, help="folder for the PNGs")
    p.add_argument("--summary", action="store_true", help="print the summary tables (Markdown)")
    args = p.parse_args()
    values, datasets = read(args.csv)
    if args.summary:
        summary(values, datasets)
    os.makedirs(args.out, exist_ok=True)
    error_figure(values, datasets, "rmse_conv",
                 "level error against the equivalent convolution (paper's criterion): extinction solid, "
                 "opacity averaging dashed", os.path.join(args.out, "pyramid-error-conv.png"))
    error_figure(values, datasets, "rmse_full",
                 "level error against full resolution: extinction solid, opacity averaging dashed",
                 os.path.join(args.out, "pyramid-error-full.png"))
    time_figure(values, datasets, os.path.join(args.out, "pyramid-time.png"))


if __name__ == "__main__":
    main()
