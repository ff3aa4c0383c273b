#!/usr/bin/python3
"""Plots of the visibility-optimization benchmark (mcvol-bench --sections
visibility): error against time for each quality knob (samples per pixel,
importance samples per pass, light-ray samples), one line per result file.

    python3 Benchmarks/plots/plot_visibility.py Benchmarks/results/visibility-optimization/*-800x800.md \
        --out Benchmarks/results/visibility-optimization/visibility-knobs.png
"""
import argparse
import os
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TABLES = [
    ("Optimized image against samples per pixel", "samples per pixel"),
    ("Importance samples per camera ray and pass", "importance samples per pass"),
    ("Light-ray importance samples", "light-ray samples"),
]


def read_tables(path):
    """{heading prefix: [(label, ms, rmse)]} from one mcvol-bench Markdown output."""
    out = {}
    current = None
    for line in open(path):
        line = line.rstrip("\n")
        if line.startswith("### "):
            current = next((t for t, _ in TABLES if line[4:].startswith(t)), None)
            if current:
                out[current] = []
            continue
        if current and line.startswith("|") and not line.startswith("|---"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) == 3 and re.match(r"^[0-9.]+$", cells[1]):
                out[current].append((cells[0], float(cells[1]), float(cells[2])))
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("files", nargs="+")
    p.add_argument("--out", required=True)
    args = p.parse_args()
    fig, axes = plt.subplots(1, len(TABLES), figsize=(5 * len(TABLES), 4))
    for ax, (title, knob) in zip(axes, TABLES):
        for path in args.files:
            rows = read_tables(path).get(title, [])
            if not rows:
                continue
            name = os.path.splitext(os.path.basename(path))[0].replace("vis-knobs-", "")
            ax.plot([r[1] for r in rows], [r[2] for r in rows], "o-", label=name)
            for label, ms, e in rows:
                ax.annotate(label.split(" ")[0], (ms, e), textcoords="offset points", xytext=(4, 4), fontsize=7)
        ax.set_title("error against time: %s" % knob, fontsize=9)
        ax.set_xlabel("time (ms)")
        ax.set_ylabel("RMSE (premultiplied RGB)")
        if title.startswith("Optimized image"):
            ax.set_xscale("log")
            ax.set_yscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    plt.tight_layout()
    plt.savefig(args.out, dpi=100)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
