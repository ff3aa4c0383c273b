#!/usr/bin/python3
"""Side-by-side picture of bench_vtk.py's images: mcvol at 1 spp and
converged, vtkFixedPointVolumeRayCastMapper, vtkGPUVolumeRayCastMapper.
Usage: montage_peers.py IMAGE_FOLDER OUT.png"""
import glob
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mi  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


def main(folder, out):
    converged = sorted(glob.glob(os.path.join(folder, "vtk_peer_mcvol-1DDA_*spp.png")))
    panels = [("vtk_peer_mcvol-1DDA.png", "mcvol 1-DDA, 1 spp (one frame)")]
    if converged:
        spp = os.path.basename(converged[-1]).split("_")[-1][:-len("spp.png")]
        panels.append((os.path.basename(converged[-1]), "mcvol 1-DDA, %s spp" % spp))
    panels += [("vtk_peer_FixedPointRayCast.png", "vtkFixedPointVolumeRayCastMapper"),
               ("vtk_peer_GPURayCast-llvmpipe.png", "vtkGPUVolumeRayCastMapper (llvmpipe)")]
    panels = [(f, t) for f, t in panels if os.path.exists(os.path.join(folder, f))]
    fig, axes = plt.subplots(1, len(panels), figsize=(4 * len(panels), 4.4))
    for ax, (f, title) in zip(axes, panels):
        ax.imshow(mi.imread(os.path.join(folder, f)))
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(out, dpi=80)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
