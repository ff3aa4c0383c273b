#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Fit the automatic estimator choice's cost model (mcvol::CostModel,
Rendering/Core/EstimatorChoice/CostModel.cxx) to measured frame times.

Reads mcvol-bench converge outputs (their "Work per pixel and frame" tables:
rays, DDA steps, tentative collisions, channel samples per pixel and the
back-to-back ms per frame, with the image size from the section's heading),
and fits ns per pixel = a rays + b dda + c tentative + d samples by least
squares on the relative error (each row weighted by 1 / its time), the
weights kept non-negative (a negative weight's feature is dropped and the
rest refitted). Prints the weights, each row's measured and modelled time,
and the largest relative error. Pure Python (no numpy on the GPU machine).

    python3 Benchmarks/studies/fit_cost_model.py converge-*.md
"""
import re
import sys


def rows(path):
    text = open(path).read()
    m = re.search(r", (\d+)x(\d+), 1 spp per frame", text)
    if not m:
        raise SystemExit(f"{path}: no converge heading with the image size")
    pixels = int(m.group(1)) * int(m.group(2))
    out = []
    table = text.split("Work per pixel and frame", 1)
    if len(table) < 2:
        raise SystemExit(f"{path}: no work table (an mcvol-bench from before the automatic estimator?)")
    for line in table[1].splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 6 or cells[0].startswith("configuration") or cells[0].startswith("---"):
            continue
        if cells[0].startswith("automatic"):
            continue  # the same work as the row it chose
        try:
            feats = [float(c) for c in cells[1:5]]
            ms = float(cells[5])
        except ValueError:
            continue
        out.append((path, cells[0], feats, ms * 1e6 / pixels))
    return out


def solve(A, y, w, active):
    """Weighted least squares over the active columns (normal equations)."""
    k = len(active)
    N = [[0.0] * k for _ in range(k)]
    r = [0.0] * k
    for row, t, wt in zip(A, y, w):
        x = [row[j] for j in active]
        for i in range(k):
            r[i] += wt * x[i] * t
            for j in range(k):
                N[i][j] += wt * x[i] * x[j]
    # Gaussian elimination with partial pivoting.
    for c in range(k):
        p = max(range(c, k), key=lambda i: abs(N[i][c]))
        N[c], N[p] = N[p], N[c]
        r[c], r[p] = r[p], r[c]
        if abs(N[c][c]) < 1e-300:
            raise SystemExit("singular fit: too few distinct rows")
        for i in range(c + 1, k):
            f = N[i][c] / N[c][c]
            for j in range(c, k):
                N[i][j] -= f * N[c][j]
            r[i] -= f * r[c]
    x = [0.0] * k
    for i in reversed(range(k)):
        x[i] = (r[i] - sum(N[i][j] * x[j] for j in range(i + 1, k))) / N[i][i]
    full = [0.0] * 4
    for i, j in enumerate(active):
        full[j] = x[i]
    return full


def main():
    data = [r for p in sys.argv[1:] for r in rows(p)]
    if len(data) < 4:
        raise SystemExit("need at least 4 rows")
    A = [d[2] for d in data]
    y = [d[3] for d in data]
    w = [1.0 / (t * t) for t in y]  # relative error
    active = [0, 1, 2, 3]
    while True:
        coef = solve(A, y, w, active)
        neg = [j for j in active if coef[j] < 0]
        if not neg:
            break
        active.remove(min(neg, key=lambda j: coef[j]))
    names = ["ray", "dda", "tentative", "sample"]
    print("| dataset file | configuration | measured ns/pixel | model | error |")
    print("|---|---|---|---|---|")
    worst = 0.0
    for (path, name, f, t) in data:
        m = sum(c * x for c, x in zip(coef, f))
        e = (m - t) / t
        worst = max(worst, abs(e))
        print(f"| {path.split('/')[-1]} | {name} | {t:.2f} | {m:.2f} | {100 * e:+.1f}% |")
    print()
    print("weights (ns): " + ", ".join(f"{n} {c:.4g}" for n, c in zip(names, coef)))
    print(f"largest relative error: {100 * worst:.1f}%")
    print("--cost-model " + ",".join(f"{c:.6g}" for c in coef))


if __name__ == "__main__":
    main()
