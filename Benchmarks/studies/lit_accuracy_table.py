#!/usr/bin/env python3
"""The lit accuracy series (mcvol-accuracy --lighting ... --score-only): their
timings gathered into one CSV, and the time to a target PSNR as a Markdown
table.

    python3 Benchmarks/studies/lit_accuracy_table.py merge OUT.csv DIR...
        DIR: an --out folder of mcvol-accuracy (timings.csv, meta.txt); the
        rows of all of them in OUT.csv with the dataset and lighting first
    python3 Benchmarks/studies/lit_accuracy_table.py table CSV... [--target 35]
        one row per dataset and lighting: each Monte Carlo series' time to
        the target (the first sample count at or above it, cumulative render
        time) and the lit ray march's (the coarsest step at or above it, one
        march), and the march's time over the default's
"""
import argparse
import csv
import os


def meta(folder):
    out = {}
    with open(os.path.join(folder, "meta.txt")) as f:
        for line in f:
            key, _, value = line.strip().partition(" ")
            out[key] = value
    return out


def merge(out_path, folders):
    with open(out_path, "w", newline="") as out:
        writer = None
        for folder in folders:
            m = meta(folder)
            with open(os.path.join(folder, "timings.csv")) as f:
                for row in csv.DictReader(f):
                    row = dict(dataset=m["dataset"], lighting=m["lighting"], size=m["size"].replace(" ", "x"),
                               threads=m["threads"], **row)
                    if writer is None:
                        writer = csv.DictWriter(out, fieldnames=list(row))
                        writer.writeheader()
                    writer.writerow(row)


def first_at(series, target):
    """The first (ms, param, psnr) of a series, in the order run, at or above target dB."""
    for r in series:
        if float(r["psnr"]) >= target:
            return float(r["ms"]), r["param"], float(r["psnr"])
    return None


def table(paths, target):
    groups = {}
    for path in paths:
        with open(path) as f:
            for r in csv.DictReader(f):
                if r["method"] != "reference":
                    groups.setdefault((r["dataset"], r["lighting"]), []).append(r)
    print("| data, lighting | expected value (default) | collision | lit ray march (coarsest step to %g dB) "
          "| ray march / expected value |" % target)
    print("|---|---|---|---|---|")

    def cell(x, unit):
        return "not reached" if x is None else "%.1f ms (%s %s, %.1f dB)" % (x[0], x[1], unit, x[2])

    for (dataset, lighting), rs in groups.items():
        mc = [r for r in rs if r["method"] == "montecarlo"]
        ev = first_at([r for r in mc if r["estimator"] == "expected-value"], target)
        co = first_at([r for r in mc if r["estimator"] == "collision"], target)
        # The steps run from coarse to fine.
        marches = [r for r in rs if r["method"] == "raymarch"]
        rm = first_at(marches, target)
        march = cell(rm, "voxel") if marches else "none (single scattering only)"
        ratio = "%.1fx" % (rm[0] / ev[0]) if ev and rm else "-"
        print("| %s, %s | %s | %s | %s | %s |" % (dataset, lighting, cell(ev, "spp"), cell(co, "spp"), march, ratio))


def main():
    p = argparse.ArgumentParser()
    sub = p.add_subparsers(dest="command", required=True)
    m = sub.add_parser("merge")
    m.add_argument("out")
    m.add_argument("folders", nargs="+")
    t = sub.add_parser("table")
    t.add_argument("csv", nargs="+")
    t.add_argument("--target", type=float, default=35.0)
    args = p.parse_args()
    if args.command == "merge":
        merge(args.out, args.folders)
    else:
        table(args.csv, args.target)


if __name__ == "__main__":
    main()
