"""The lit scene of the parallel lighting tests: a volume whose pieces shadow
each other when it is split over two ranks along z (its longest axis, which
ParaView's extent translator and the tests' own split halve).

An opaque block high in z (the occluder, z 44..54, in the upper piece) hangs
over a slab low in z (z 6..14, in the lower piece) that covers the whole xy
extent; one directional light shines straight down (-z), so the occluder's
shadow falls onto the slab across the split at z = 32. The camera looks at
the slab's lit top from above and to the side, past the occluder, so the
shadow fills part of the image. Index space is world space (spacing 1,
origin 0).
"""
import numpy as np

DIMS = (40, 40, 64)  # x, y, z
LIGHT_DIRECTION = (0.0, 0.0, 1.0)  # towards the light
FOCAL = (20.0, 20.0, 22.0)
CAMERA = (112.0, 14.0, 96.0)
VIEW_UP = (0.0, 0.0, 1.0)
VIEW_ANGLE = 30.0
SIZE = 120
ARRAY = "density"
# Transfer function: value 0 transparent, 0.5 (slab) opacity 0.25,
# 1 (occluder) opacity 0.6, grey-white.
OPACITY_POINTS = [(0.0, 0.0), (0.5, 0.25), (1.0, 0.6)]
COLOR = (0.9, 0.9, 0.85)


def density(scale=1):
    """The scalar field, indexed [z, y, x] (x fastest when flattened); with
    `scale` > 1 (benchmarks) every axis has `scale` times the voxels, at
    1 / scale the spacing (the same world box and shapes)."""
    nx, ny, nz = (n * scale for n in DIMS)
    d = np.zeros((nz, ny, nx), dtype=np.float32)
    s = scale
    d[6 * s:15 * s, 2 * s:38 * s, 2 * s:38 * s] = 0.5
    d[44 * s:55 * s, 12 * s:29 * s, 12 * s:29 * s] = 1.0
    return d


def image(scale=1):
    """The field as a vtkImageData with the point array ARRAY."""
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.util.numpy_support import numpy_to_vtk

    img = vtkImageData()
    img.SetDimensions(*(n * scale for n in DIMS))
    img.SetSpacing(*([1.0 / scale] * 3))
    arr = numpy_to_vtk(density(scale).ravel(), deep=1)
    arr.SetName(ARRAY)
    img.GetPointData().SetScalars(arr)
    return img


def msd_ratio(test, other, reference, mask=None):
    """Mean squared difference test - reference over other - reference, and
    its standard error by the delta method over pixels (the per-pixel
    squared differences a_i and b_i: var(R) ~ var(a - R b) / (n mean(b)^2)).
    Images are (h, w, channels); the colour channels (the first 3) count."""
    a = ((test - reference)[..., :3] ** 2).mean(axis=2)
    b = ((other - reference)[..., :3] ** 2).mean(axis=2)
    if mask is not None:
        a, b = a[mask], b[mask]
    a, b = a.ravel(), b.ravel()
    r = a.mean() / b.mean()
    se = np.sqrt(np.var(a - r * b) / a.size) / b.mean()
    return r, se
