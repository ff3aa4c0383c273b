#!/usr/bin/python3
"""Plots mcvol-bench CSV output: frame time against macrocell size and
against channel count (one curve per tracker), plus memory against macrocell
size. Usage: plot_results.py results.csv [more.csv ...] --out DIR
"""
import argparse
import csv
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(paths):
    rows = []
    for p in paths:
        with open(p) as f:
            for r in csv.DictReader(f):
                r["value"] = float(r["value"])
                r["channels"] = int(r["channels"])
                r["macrocell"] = int(r["macrocell"])
                rows.append(r)
    return rows


def curves(rows, section, xkey, unit):
    out = defaultdict(list)
    for r in rows:
        if r["section"] == section and r["unit"] == unit:
            out[(r["dataset"], r["backend"], r["tracker"])].append((r[xkey], r["value"]))
    return {k: sorted(v) for k, v in out.items()}


def plot(ax, data, xlabel, ylabel, logx=False):
    for (ds, backend, tracker), pts in sorted(data.items()):
        xs, ys = zip(*pts)
        label = "%s, %s" % (tracker, backend) if tracker != "-" else backend
        ax.plot(xs, ys, marker="o", label="%s (%s)" % (label, ds))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if logx:
        ax.set_xscale("log", base=2)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv", nargs="+")
    ap.add_argument("--out", default=".")
    args = ap.parse_args()
    rows = load(args.csv)
    os.makedirs(args.out, exist_ok=True)

    mc = curves(rows, "macrocell", "macrocell", "ms")
    if mc:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4))
        plot(axes[0], mc, "macrocell edge (voxels)", "frame time at 1 spp (ms)", logx=True)
        axes[0].set_title("Frame time against macrocell size (paper Fig. 8)")
        mem = curves(rows, "macrocell", "macrocell", "percent_of_data")
        plot(axes[1], mem, "macrocell edge (voxels)", "macrocells + majorants (% of data)", logx=True)
        axes[1].set_yscale("log")
        axes[1].axhline(5.0, color="gray", ls="--", lw=1)
        axes[1].set_title("Memory against macrocell size (target: 5%)")
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "macrocell.png"), dpi=110)

    ch = curves(rows, "channels", "channels", "ms")
    if ch:
        fig, ax = plt.subplots(figsize=(6, 4))
        plot(ax, ch, "channels", "frame time at 1 spp (ms)")
        ax.set_title("Frame time against channel count (paper Fig. 9)")
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "channels.png"), dpi=110)


if __name__ == "__main__":
    main()
