#!/usr/bin/python3
"""Plot of the sample-sequence benchmark (mcvol-bench --sections sequences
--csv FILE): RMSE against samples per pixel, log-log, one panel per result
file, the independent sampler and Owen-scrambled Sobol' points, with the
1/sqrt(spp) Monte Carlo rate for reference.

    /usr/bin/python3 Benchmarks/plots/plot_sequences.py Benchmarks/results/sample-sequences-cpu/*.csv \
        --out Benchmarks/results/sample-sequences-cpu/sequences-cpu.png
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    """(dataset, {sampler: [(spp, rmse)]}, {sampler: slope})."""
    series, slopes, dataset = {}, {}, ""
    for row in csv.DictReader(open(path)):
        if row["section"] != "sequences":
            continue
        dataset = row["dataset"]
        if row["unit"] == "rmse":
            spp = int(row["extra"].split("=")[1])
            series.setdefault(row["tracker"], []).append((spp, float(row["value"])))
        elif row["unit"] == "slope":
            slopes[row["tracker"]] = float(row["value"])
    return dataset, series, slopes


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv", nargs="+")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    fig, axes = plt.subplots(1, len(a.csv), figsize=(4.2 * len(a.csv), 3.8), squeeze=False)
    for ax, path in zip(axes[0], a.csv):
        dataset, series, slopes = read(path)
        for name, pts in sorted(series.items()):
            pts.sort()
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", ms=3,
                      label="%s (slope %.3f)" % (name, slopes.get(name, float("nan"))))
        if "independent" in series:
            s0, e0 = sorted(series["independent"])[0]
            xs = [p[0] for p in sorted(series["independent"])]
            ax.loglog(xs, [e0 * (x / s0) ** -0.5 for x in xs], ":", color="grey", label="spp^-1/2")
        ax.axhline(0.01, color="grey", lw=0.5)
        ax.set_title(dataset.split(" float")[0].split(" uint")[0], fontsize=9)
        ax.set_xlabel("samples per pixel")
        ax.set_ylabel("RMSE")
        ax.legend(fontsize=7)
        ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)


if __name__ == "__main__":
    main()
