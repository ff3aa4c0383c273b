"""The gallery of real brain volumes (Documentation/gallery.md): the scene
Data/gallery/colin27-subcortical.json (Colin27 T1, its brain-extracted copy and
the AAL atlas from Debian's mricron-data) renders through mcvol-render, small
and at a few samples per pixel, to an image that is not blank; and, with the
same inputs and channels seen from above, the AAL labels of the left
hemisphere land on the image's left half and those of the right hemisphere on
its right half (NIfTI RAS: +x is the subject's right; from above with anterior
up, the right is on the image's right), and inside the brain's silhouette
drawn by the T1 channel alone. A reader that flipped x, or channels fed from
the wrong array, fails these checks.

Without mricron-data the test is skipped (exit status 125, ctest's
SKIP_RETURN_CODE). Rendering needs an X server: run ctest under `xvfb-run -a`.

    TestGallery.py [--mcvol-render PROGRAM] [--work DIR]

Registered by Testing/Python/CMakeLists.txt (the build's package on PYTHONPATH).
"""

import argparse
import copy
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from mcvolTesting import Checker, read_png_rgb

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
SCENE = os.path.join(SOURCE, "Data", "gallery", "colin27-subcortical.json")
MRICRON = "/usr/share/mricron/templates"
SKIP = 125
SIZE = 64
SPP = 4


def render(program, work, name, scene, t):
    """Writes `scene` to WORK/NAME.json, renders it to WORK/NAME.png on the CPU
    at SIZE x SIZE and SPP samples; returns the image (row 0 at the bottom) or None."""
    fn = os.path.join(work, name + ".json")
    png = os.path.join(work, name + ".png")
    with open(fn, "w") as f:
        json.dump(scene, f)
    p = subprocess.run([sys.executable, program, fn, "-o", png, "--backend", "cpu", "--spp", str(SPP),
                        "--size", "%dx%d" % (SIZE, SIZE)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
    print("%s: %s" % (name, " ".join(x for x in (p.stdout.strip(), p.stderr.strip()) if x)))
    if not t.check(p.returncode == 0, "%s: mcvol-render exited %d: %s" % (name, p.returncode, p.stderr.strip())):
        return None
    if not t.check(os.path.isfile(png), "%s: no image written" % name):
        return None
    return read_png_rgb(png)


def transparent(channel):
    c = dict(channel)
    c["opacity"] = [[0, 0], [1, 0]]
    return c


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mcvol-render", default=os.path.join(SOURCE, "Tools", "mcvol-render.py"))
    p.add_argument("--work", default=None)
    args = p.parse_args()

    with open(SCENE) as f:
        scene = json.load(f)
    needed = [os.path.join(MRICRON, n) for n in ("ch2.nii.gz", "ch2bet.nii.gz", "aal.nii.gz")]
    missing = [n for n in needed if not os.path.isfile(n)]
    if missing:
        print("mricron-data not installed: apt-get install mricron-data (missing %s); skipped" % ", ".join(missing))
        sys.exit(SKIP)

    work = args.work or tempfile.mkdtemp(prefix="TestGallery-")
    os.makedirs(work, exist_ok=True)
    t = Checker()
    names = [c["name"] for c in scene["channels"]]
    t.check(names == ["scalp", "brain", "nuclei"] and scene["interpolation"] == "nearest",
            "the gallery scene's channels are %s (expected scalp, brain, nuclei, nearest interpolation)" % names)
    background = np.array(scene.get("background", [0, 0, 0]), float) * 255

    # 1. The gallery scene itself, lit as in the gallery: renders, and is not blank.
    image = render(args.mcvol_render, work, "gallery", scene, t)
    if image is not None:
        t.check(image.shape[:2] == (SIZE, SIZE), "gallery: image size %s" % (image.shape[:2],))
        lit = np.abs(image - background).max(axis=2) > 40
        t.check(lit.mean() > 0.1, "gallery: only %.1f %% of the pixels differ from the background by more than "
                "40 levels" % (100 * lit.mean()))

    # 2. The same inputs and channels seen from above (parallel projection,
    # anterior up, so the subject's right is the image's right), unlit.
    top = copy.deepcopy(scene)
    top.pop("lighting", None)
    top["camera"] = {"focal_point": [0, -17, 15], "position": [0, -17, 600], "view_up": [0, 1, 0],
                     "parallel": True, "parallel_scale": 110}
    nuclei = top["channels"][2]
    xs, alphas = zip(*nuclei["opacity"])
    labels = [L for L in range(1, 117) if np.interp(L, xs, alphas) > 0]
    t.check(labels == [37, 38, 41, 42, 71, 72, 73, 74, 75, 76, 77, 78], "nuclei: labels %s" % labels)
    # AAL: odd labels are in the left hemisphere, even ones in the right.
    colors = []
    for label in labels:
        rgb = [1, 0, 0] if label % 2 else [0, 1, 0]
        colors += [[label - 0.45] + rgb, [label + 0.45] + rgb]
    nuclei["color"] = colors

    atlas = copy.deepcopy(top)
    atlas["channels"][0] = transparent(atlas["channels"][0])
    atlas["channels"][1] = transparent(atlas["channels"][1])
    brain = copy.deepcopy(top)
    brain["channels"][0] = transparent(brain["channels"][0])
    brain["channels"][2] = transparent(brain["channels"][2])
    brain["channels"][1]["color"] = [[0, 1, 1, 1], [255, 1, 1, 1]]
    brain["channels"][1]["opacity"] = [[0, 0], [30, 0], [40, 0.5], [255, 0.5]]

    a = render(args.mcvol_render, work, "atlas-from-above", atlas, t)
    b = render(args.mcvol_render, work, "brain-from-above", brain, t)
    if a is not None and b is not None:
        r, g = a[:, :, 0], a[:, :, 1]
        left = (r > 80) & (r > g + 50)   # odd labels: left hemisphere
        right = (g > 80) & (g > r + 50)  # even labels: right hemisphere
        silhouette = np.abs(b - background).max(axis=2) > 40
        cols = np.arange(SIZE)[None, :].repeat(SIZE, axis=0)
        print("left labels: %d pixels, mean column %.1f; right labels: %d pixels, mean column %.1f; brain: %d pixels"
              % (left.sum(), cols[left].mean() if left.any() else -1, right.sum(),
                 cols[right].mean() if right.any() else -1, silhouette.sum()))
        t.check(left.sum() >= 20 and right.sum() >= 20,
                "atlas from above: %d left-label and %d right-label pixels (expected >= 20 each)"
                % (left.sum(), right.sum()))
        if left.any() and right.any():
            half = (SIZE - 1) / 2
            t.check(cols[left].mean() < half - 3 and cols[right].mean() > half + 3,
                    "atlas from above: left labels at mean column %.1f, right labels at %.1f (expected left of and "
                    "right of %.1f): left and right swapped or not apart" % (cols[left].mean(), cols[right].mean(), half))
            t.check((cols[left] < half).mean() > 0.9 and (cols[right] > half).mean() > 0.9,
                    "atlas from above: %.0f %% of the left labels on the left half, %.0f %% of the right labels on "
                    "the right half (expected > 90 %%)" % (100 * (cols[left] < half).mean(),
                                                        100 * (cols[right] > half).mean()))
        t.check(0.2 < silhouette.mean() < 0.9, "brain from above: silhouette covers %.0f %% of the image"
                % (100 * silhouette.mean()))
        # A pixel's neighbours count as inside too (a label on the silhouette's edge).
        grown = silhouette.copy()
        grown[1:, :] |= silhouette[:-1, :]
        grown[:-1, :] |= silhouette[1:, :]
        grown[:, 1:] |= silhouette[:, :-1]
        grown[:, :-1] |= silhouette[:, 1:]
        labelled = left | right
        if labelled.any():
            inside = grown[labelled].mean()
            t.check(inside > 0.98, "atlas from above: %.1f %% of the label pixels inside the brain's silhouette"
                    % (100 * inside))
            # Deep nuclei: well inside, nowhere near the silhouette's bounding box edge.
            rows, cols_b = np.nonzero(silhouette)
            lr, lc = np.nonzero(labelled)
            t.check(lc.min() > cols_b.min() + 3 and lc.max() < cols_b.max() - 3 and
                    lr.min() > rows.min() + 3 and lr.max() < rows.max() - 3,
                    "atlas from above: the deep nuclei reach the edge of the brain (labels in columns %d..%d, rows "
                    "%d..%d; brain in columns %d..%d, rows %d..%d)" % (lc.min(), lc.max(), lr.min(), lr.max(),
                                                                       cols_b.min(), cols_b.max(), rows.min(),
                                                                       rows.max()))
    t.finish()


if __name__ == "__main__":
    main()
