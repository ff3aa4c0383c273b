#!/usr/bin/python3
"""Plots the GPU benchmark (Benchmarks/gpu/bench.sh output): frame rate
against macrocell size (paper Fig. 8) and against channel count (Fig. 9), the
CUDA backend beside the CPU backend, and the paper-protocol frame rates
against the paper's targets.
Usage: plot_gpu.py RESULTS_DIR   (writes the PNGs into RESULTS_DIR)
"""
import csv
import glob
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    ("cuda", "1-DDA"): dict(color="tab:green", marker="o", linestyle="-"),
    ("cuda", "N-DDA"): dict(color="tab:green", marker="s", linestyle="--"),
    ("cpu", "1-DDA"): dict(color="tab:blue", marker="o", linestyle="-"),
    ("cpu", "N-DDA"): dict(color="tab:blue", marker="s", linestyle="--"),
}


def load(pattern):
    rows = []
    for p in sorted(glob.glob(pattern)):
        with open(p) as f:
            for r in csv.DictReader(f):
                r["value"] = float(r["value"])
                r["channels"] = int(r["channels"])
                r["macrocell"] = int(r["macrocell"])
                rows.append(r)
    return rows


def short(ds):
    return ds.split(" = ")[0]


def sweep(rows, section, xkey, title, xlabel, out, logx=False):
    sets = sorted({short(r["dataset"]) for r in rows if r["section"] == section})
    if not sets:
        print("no %s rows: %s not written" % (section, out))
        return
    fig, axes = plt.subplots(1, len(sets), figsize=(4.2 * len(sets), 3.8), squeeze=False)
    for ax, ds in zip(axes[0], sets):
        lines = defaultdict(list)
        for r in rows:
            if r["section"] == section and short(r["dataset"]) == ds and r["unit"] == "ms":
                lines[(r["backend"], r["tracker"])].append((r[xkey], 1000.0 / r["value"]))
        for key, pts in sorted(lines.items()):
            pts.sort()
            ax.plot([p[0] for p in pts], [p[1] for p in pts], label=f"{key[0].upper()} {key[1]}", **STYLE[key])
        ax.set_yscale("log")
        if logx:
            ax.set_xscale("log", base=2)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("frames per second (1024x1024, 1 spp)")
        ax.set_title(ds)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print("wrote", out)


def paper_bars(rows, out):
    targets = {"NYX-like": 291, "Zebrafish-like": 686}
    sets, one, n = [], [], []
    for r in rows:
        if r["section"] == "paper" and r["unit"] == "fps":
            ds = short(r["dataset"])
            if ds not in sets:
                sets.append(ds)
                one.append(0)
                n.append(0)
            i = sets.index(ds)
            if r["tracker"] == "1-DDA":
                one[i] = r["value"]
            else:
                n[i] = r["value"]
    fig, ax = plt.subplots(figsize=(7.5, 4))
    x = range(len(sets))
    ax.bar([i - 0.2 for i in x], one, width=0.4, label="1-DDA", color="tab:green")
    ax.bar([i + 0.2 for i in x], n, width=0.4, label="N-DDA", color="tab:olive")
    for i, ds in enumerate(sets):
        if ds in targets:
            t = targets[ds]
            ax.plot([i - 0.45, i + 0.45], [t, t], color="red")
            ax.plot([i - 0.45, i + 0.45], [2 * t, 2 * t], color="red", linestyle=":")
            ax.text(i + 0.47, t, f"paper {t}", color="red", fontsize=7, va="center")
            ax.text(i + 0.47, 2 * t, "2x", color="red", fontsize=7, va="center")
    ax.set_xticks(list(x))
    ax.set_xticklabels(sets)
    ax.set_ylabel("frames per second")
    ax.set_title("Paper protocol: 1024x1024, 1 spp, 500 timed frames (red: paper's 1-DDA FPS, dotted: 2x)")
    ax.title.set_fontsize(9)
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print("wrote", out)


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "results", "gpu")
    mc = load(os.path.join(d, "macrocell-*.csv"))
    sweep(mc, "macrocell", "macrocell", "Frame rate against macrocell size (paper Fig. 8)", "macrocell edge (voxels)",
          os.path.join(d, "gpu-macrocell.png"), logx=True)
    ch = load(os.path.join(d, "channels-*.csv"))
    sweep(ch, "channels", "channels", "Frame rate against channel count (paper Fig. 9)", "channels",
          os.path.join(d, "gpu-channels.png"))
    paper_bars(load(os.path.join(d, "paper-*.csv")), os.path.join(d, "gpu-paper-fps.png"))


if __name__ == "__main__":
    main()
