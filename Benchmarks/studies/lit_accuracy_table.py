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
    python3 Benchmarks/studies/lit_accuracy_table.py pictures OUT.png DIR...
        equal-time pictures, as Lerzer and Dachsbacher's Fig. 5: one row per
        DIR (an --out folder of mcvol-accuracy run without --score-only, one
        lighting each), the reference, then each Monte Carlo series' and
        the ray march's best image within the time the default Monte Carlo
        series takes to reach --target dB (scored here: premultiplied RGB
        over black, clipped, peak 1)
    python3 Benchmarks/studies/lit_accuracy_table.py prune DIR...
        deletes the images of DIR that pictures would not show, keeping every
        image's score in DIR/psnr.csv, which pictures then reads: what a run
        on a remote machine needs to send back
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


def load_image(folder, name, w, h):
    import numpy as np

    return np.fromfile(os.path.join(folder, name), dtype=np.float32).reshape(h, w, 4)


def shown(img):
    """Premultiplied RGB over black, clipped as the screen shows it, top row first."""
    import numpy as np

    return np.clip(img[::-1, :, :3], 0.0, 1.0)


def psnr_of(img, ref):
    import math

    import numpy as np

    mse = float(np.mean((shown(img) - shown(ref)) ** 2))
    return float("inf") if mse <= 0 else 10.0 * math.log10(1.0 / mse)


def equal_time(folder, target):
    """One pictures row: the folder's meta, the time budget (the default
    series' time to the target) and the cells, the reference first, then each
    series' best image within the budget as (title, (ms, label, dB, file) or
    a note, file or None). Scores come from the folder's psnr.csv where prune
    left one, else from the images."""
    m = meta(folder)
    w, h = (int(x) for x in m["size"].split())
    ref = None
    scores = {}
    kept = os.path.join(folder, "psnr.csv")
    if os.path.exists(kept):
        with open(kept) as f:
            scores = {r["file"]: float(r["psnr"]) for r in csv.DictReader(f)}
    reference_name = "reference"
    series = {}
    with open(os.path.join(folder, "timings.csv")) as f:
        for r in csv.DictReader(f):
            if r["method"] == "reference":
                if r["variant"] in ("raymarch", "montecarlo-reference"):
                    reference_name = ("lit ray march, %s voxel" % r["param"] if r["variant"] == "raymarch"
                                      else "Monte Carlo, %s spp" % r["param"])
                continue
            if r["method"] == "montecarlo":
                key = "Monte Carlo, %s" % r["estimator"]
                name = "mc_%s_%s_%s_%d.f32" % (r["estimator"], r["sampler"], r["variant"], int(float(r["param"])))
                label = "%d spp" % int(float(r["param"]))
            else:
                key = "lit ray march"
                name = "rm_%s_%g.f32" % (r["variant"], float(r["param"]))
                label = "step %g voxel" % float(r["param"])
            if name not in scores:
                if ref is None:
                    ref = load_image(folder, "reference.f32", w, h)
                scores[name] = psnr_of(load_image(folder, name, w, h), ref)
            series.setdefault(key, []).append((float(r["ms"]), label, scores[name], name))
    default = series.get("Monte Carlo, expected-value", [])
    reached = [x for x in default if x[2] >= target]
    budget = reached[0][0] if reached else max(x[0] for x in default)
    cells = [("reference: %s" % reference_name, None, "reference.f32")]
    for key in ("Monte Carlo, expected-value", "Monte Carlo, collision", "lit ray march"):
        if key not in series:
            cells.append((key, "not in this run\n(the march renders single\nscattering only)", None))
            continue
        within = [x for x in series[key] if x[0] <= budget * 1.0001]
        if not within:
            first = min(series[key], key=lambda x: x[0])
            cells.append((key, "no image within %.0f ms\n(the cheapest: %s,\n%.0f ms, %.1f dB)" % (
                budget, first[1], first[0], first[2]), None))
            continue
        best = max(within, key=lambda x: x[2])
        cells.append((key, best, best[3]))
    return m, budget, cells, scores


def prune(folders, target):
    """Keeps only the images a pictures run of these folders shows, with every
    image's score in psnr.csv: what a remote machine's runs need to send back."""
    for folder in folders:
        m, budget, cells, scores = equal_time(folder, target)
        with open(os.path.join(folder, "psnr.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["file", "psnr"])
            for name, value in sorted(scores.items()):
                w.writerow([name, value])
        keep = {c[2] for c in cells if c[2]}
        for name in os.listdir(folder):
            if name.endswith(".f32") and name not in keep:
                os.remove(os.path.join(folder, name))


def pictures(out, folders, target):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [equal_time(folder, target)[:3] for folder in folders]
    ncols = max(len(r[2]) for r in rows)
    fig, axes = plt.subplots(len(rows), ncols, figsize=(2.6 * ncols, 2.9 * len(rows)), squeeze=False)
    for i, (m, budget, cells) in enumerate(rows):
        w, h = (int(x) for x in m["size"].split())
        for j, (key, best, name) in enumerate(cells):
            ax = axes[i][j]
            ax.axis("off")
            if name is None:
                ax.text(0.5, 0.5, best, ha="center", va="center", fontsize=8)
                ax.set_title(key, fontsize=7)
                continue
            ax.imshow(shown(load_image(folders[i], name, w, h)), interpolation="nearest")
            if best is None:
                ax.set_title("%s, %s\n%s" % (m["dataset"], m["lighting"], key), fontsize=7)
            else:
                ax.set_title("%s\n%s, %.0f ms, %.1f dB" % (key, best[1], best[0], best[2]), fontsize=7)
    fig.suptitle("Equal time: each method's best image within the time the default reaches %g dB" % target,
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
    for m, budget, cells in rows:
        print("| %s, %s | %.0f ms | %s |" % (m["dataset"], m["lighting"], budget, " | ".join(
            "-" if c[2] is None else "%s: %s, %.1f dB" % (c[0], c[1][1], c[1][2]) for c in cells[1:])))


def main():
    p = argparse.ArgumentParser()
    sub = p.add_subparsers(dest="command", required=True)
    m = sub.add_parser("merge")
    m.add_argument("out")
    m.add_argument("folders", nargs="+")
    t = sub.add_parser("table")
    t.add_argument("csv", nargs="+")
    t.add_argument("--target", type=float, default=35.0)
    q = sub.add_parser("pictures")
    q.add_argument("out")
    q.add_argument("folders", nargs="+")
    q.add_argument("--target", type=float, default=35.0)
    r = sub.add_parser("prune")
    r.add_argument("folders", nargs="+")
    r.add_argument("--target", type=float, default=35.0)
    args = p.parse_args()
    if args.command == "merge":
        merge(args.out, args.folders)
    elif args.command == "pictures":
        pictures(args.out, args.folders, args.target)
    elif args.command == "prune":
        prune(args.folders, args.target)
    else:
        table(args.csv, args.target)


if __name__ == "__main__":
    main()
