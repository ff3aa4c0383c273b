#!/usr/bin/env python3
"""Time to 35 dB of the lit accuracy series (mcvol-accuracy --lighting ...
--score-only): one Markdown row per folder DATASET-LIGHTING holding a
timings.csv, with each Monte Carlo series' time to reach the target (the
first sample count at or above it, cumulative render time) and the ray
march's (the coarsest step at or above it, one march), and what each
reaches at the Monte Carlo's time to target.

    python3 Benchmarks/studies/lit_accuracy_table.py FOLDER... [--target 35]
"""
import argparse
import csv
import os


def rows(path):
    with open(os.path.join(path, "timings.csv")) as f:
        return [r for r in csv.DictReader(f) if r["method"] != "reference"]


def first_at(series, target):
    """The first (ms, param, psnr) of a series, in the order run, at or above target dB."""
    for r in series:
        if float(r["psnr"]) >= target:
            return float(r["ms"]), r["param"], float(r["psnr"])
    return None


def main():
    p = argparse.ArgumentParser()
    p.add_argument("folders", nargs="+")
    p.add_argument("--target", type=float, default=35.0)
    args = p.parse_args()
    t = args.target
    print("| data, lighting | expected value (default) | collision | lit ray march (coarsest step to %g dB) | ray march / expected value |" % t)
    print("|---|---|---|---|---|")
    for folder in args.folders:
        name = os.path.basename(os.path.normpath(folder))
        rs = rows(folder)
        ev = first_at([r for r in rs if r["method"] == "montecarlo" and r["estimator"] == "expected-value"], t)
        co = first_at([r for r in rs if r["method"] == "montecarlo" and r["estimator"] == "collision"], t)
        # Coarsest step first: the steps run from coarse to fine.
        rm = first_at([r for r in rs if r["method"] == "raymarch"], t)

        def cell(x, unit):
            return "not reached" if x is None else "%.1f ms (%s %s, %.1f dB)" % (x[0], x[1], unit, x[2])

        ratio = "%.1fx" % (rm[0] / ev[0]) if ev and rm else "-"
        print("| %s | %s | %s | %s | %s |" % (name, cell(ev, "spp"), cell(co, "spp"), cell(rm, "voxel"), ratio))


if __name__ == "__main__":
    main()
