"""Hard cases of real data, on small synthetic volumes (numpy -> vtkImageData,
CPU backend, fixed seeds), each with both mappers where it matters:

1. Label volumes. (a) Trilinear interpolation between labels 10 and 30 passes
   through 20, a label that is not there: a transfer function opaque only
   around 20 shows a spurious shell with linear interpolation (covering the
   ball's silhouette, and only it), nothing at all with
   vtkVolumeProperty::SetInterpolationTypeToNearest(). (b) Pixel jitter on
   label edges: a rotated opaque box seen head-on. Without jitter every
   sample of a pixel goes through its centre, so the converged alpha is the
   centre's inside/outside (0 or 1, no intermediate value); with jitter it
   is the pixel's area coverage (computed here by supersampling the square):
   the statistic T = sum (a - c)^2 / sum c (1 - c) / n over edge pixels
   (expectation 1 under binomial noise) stays below its bound with jitter
   and far above it without.
2. Anisotropic spacing: a blob with spacing (1, 1, 4) gives the same
   ray-marched image as the same field upsampled 4x along z with spacing 1
   (trilinear interpolation of a linear upsampling is the same field), and
   the Monte Carlo image converges to it; extreme aspect ratios, spacing
   (1, 1, 50) and (0.01, 1, 1), give finite, non-empty images that the Monte
   Carlo mapper and the ray marcher agree on.
3. Orientation: direction matrices diag(+-1, +-1, +-1) (determinant -1
   included, i.e. reflections) with the data flipped and the origin moved,
   so that every voxel keeps its world position and value, render the same
   image as the unflipped volume (ray marcher: to float rounding; Monte
   Carlo: within noise); so does a rotation composed with a reflection, and
   lit gradient shading (the gradient is mapped to world space correctly
   under a reflection). An oblique direction matrix (30 degrees about z):
   the volume rendered with a camera looking at it equals the unrotated
   volume rendered with the camera rotated back by 30 degrees, and differs
   from the unrotated view (the silhouette turns).
4. 16-bit data with a few extreme voxels (tissue in 0..2000, five voxels at
   65535). (a) Through the mapper with DATA_RANGE (the default) the
   1024-entry table spans the data's range 0..65535 clipped to the
   functions' (they clamp), so a transfer function with 30-unit features in
   0..2000 keeps them: the image equals FUNCTION_RANGE's (ray-marched RMSE
   printed; it was 0.130 before the clipping, with 64 units per entry). (b) Through scene
   files: "normalized" points over the data range (the old default, now
   "range": "data") squash the function into the first 3 %: the tissue is
   invisible; the new default "range": "auto" (the [0.1, 99.9] percentiles;
   min..max for data with at most 256 distinct values) shows it, and
   the mapper tabulates over the functions' range. (c) With the
   visibility optimization on, FUNCTION_RANGE includes the importance
   function's points, so importance beyond the colour and opacity points is
   kept.
5. Empty channels: an all-zero channel added to a 2-channel volume renders a
   finite image, equal to the 2-channel image (ray marcher exactly; Monte
   Carlo identical with the same seed), for every blend mode, when the
   channel's function is 0 around 0; through mcvol-render too, and constant
   and all-NaN channels give finite images. A function rising from (0, 0)
   adds nothing either: a constant channel's value sits on its table's first
   entry.

Statistical checks: the mean of K Monte Carlo renders (different seeds)
against the ray-marched reference (a step of 1/16 voxel), by the statistic
of TestRayMarchReference.py, T = sum(D^2 - V) / sqrt(2 (1 + 1/(K-1)) sum V^2)
(about standard normal when the Monte Carlo image converges to the
reference), one-sided, and the coverage statistic of 1(b): family-wise
significance level 1e-3 over all of them (Bonferroni).

    TestRealDataCases.py [--work DIR]
"""

import argparse
import atexit
import json
import math
import os
import shutil
import statistics
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkIOXML import vtkXMLImageDataWriter
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkLight,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, use_test_backend

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))

# Statistical checks (each one-sided, each component of a T test counts):
# 1(b) coverage: 1; 2: 1 + 4 Monte Carlo comparisons; 3: 2; 4 components
# each.
N_STAT_TESTS = 1 + 4 * (1 + 4 + 2)
FAMILY_ALPHA = 1e-3
Z_LIMIT = statistics.NormalDist().inv_cdf(1.0 - FAMILY_ALPHA / N_STAT_TESTS)
K = 8  # Monte Carlo renders (seeds) per comparison
SPP = 16  # samples per pixel of each

t = Checker()
stat_tests = [0]


# --- Helpers -----------------------------------------------------------------
def make_image(values, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None):
    """values: (z, y, x) or (z, y, x, channels), x fastest as VTK stores it."""
    a = np.ascontiguousarray(values)
    nz, ny, nx = a.shape[:3]
    nc = a.shape[3] if a.ndim == 4 else 1
    image = vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    image.SetOrigin(*origin)
    if direction is not None:
        image.SetDirectionMatrix(*np.asarray(direction, float).ravel())
    scalars = numpy_to_vtk(a.reshape(-1, nc), deep=True)
    scalars.SetName("scalars")
    image.GetPointData().SetScalars(scalars)
    return image


def function(colors, opacities, unit=1.0):
    ctf = vtkColorTransferFunction()
    for p in colors:
        ctf.AddRGBPoint(*p)
    otf = vtkPiecewiseFunction()
    for p in opacities:
        otf.AddPoint(*p)
    return ctf, otf, unit


WINDOW = vtkRenderWindow()
WINDOW.SetOffScreenRendering(1)
WINDOW.SetMultiSamples(0)


def render(image, functions, kind="rm", size=(48, 48), camera=None, spp=SPP, seed=1, jitter=True,
           nearest=False, blend=None, step_voxels=None, setup=None, shade=False):
    """One render of `image` with `functions` (colour, opacity, unit distance
    per channel) by the ray marcher ("rm") or the Monte Carlo mapper ("mc",
    CPU). Returns (float RGBA image (h, w, 4), the mapper's error messages,
    the mapper)."""
    mapper = vtkMultiChannelRayMarchMapper() if kind == "rm" else vtkMultiChannelVolumeMapper()
    errors = ErrorCatcher(mapper)
    if kind == "mc":
        use_test_backend(mapper)
        mapper.SetSamplesPerPixel(spp)
        mapper.SetSeed(seed)
        mapper.SetPixelJitter(jitter)
    elif step_voxels is not None:
        mapper.SetStepSize(step_voxels * min(abs(s) for s in image.GetSpacing()))
    if blend:
        getattr(mapper, "SetChannelBlendModeTo" + blend)()
    if setup:
        setup(mapper)
    mapper.SetInputData(image)
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    if nearest:
        prop.SetInterpolationTypeToNearest()
    else:
        prop.SetInterpolationTypeToLinear()
    if shade:
        prop.ShadeOn()
    for c, (ctf, otf, unit) in enumerate(functions):
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, unit)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(0, 0, 0)
    renderer.AddVolume(volume)
    WINDOW.SetSize(*size)
    WINDOW.AddRenderer(renderer)
    if camera:
        camera(renderer, renderer.GetActiveCamera())
    else:
        renderer.ResetCamera()
    renderer.ResetCameraClippingRange()
    WINDOW.Render()
    rgba = vtkFloatArray()
    mapper.GetAccumulatedImage(rgba)
    WINDOW.RemoveRenderer(renderer)
    if rgba.GetNumberOfTuples() != size[0] * size[1]:
        return None, errors.errors, mapper
    return vtk_to_numpy(rgba).reshape(size[1], size[0], 4).astype(np.float64), errors.errors, mapper


def orbit(azimuth, elevation, parallel=False):
    def camera(renderer, cam):
        cam.SetParallelProjection(parallel)
        renderer.ResetCamera()
        cam.Azimuth(azimuth)
        cam.Elevation(elevation)
        cam.OrthogonalizeViewUp()
    return camera


def t_statistic(images, reference):
    """Per component: T = sum(D^2 - V) / sqrt(2 (1 + 1/(K-1)) sum V^2), D the
    mean of the K images minus the reference, V the variance of that mean."""
    images = np.asarray(images)
    k = len(images)
    d = images.mean(axis=0) - reference
    v = images.var(axis=0, ddof=1) / k
    out = []
    for c in range(reference.shape[-1]):
        s = math.sqrt(2.0 * (1.0 + 1.0 / (k - 1)) * float((v[..., c] ** 2).sum()))
        num = float((d[..., c] ** 2 - v[..., c]).sum())
        out.append(num / s if s > 0 else (0.0 if num <= 0 else math.inf))
    return out


def check_converges(name, image, functions, camera, reference_step=1.0 / 16, size=(48, 48), **kw):
    """The mean of K Monte Carlo renders (pixel centres, seeds 1..K) against
    the ray-marched image: every component's T below Z_LIMIT. Returns the
    reference."""
    reference, errors, _ = render(image, functions, "rm", size, camera, step_voxels=reference_step, **kw)
    t.check(reference is not None and not errors, "%s: ray marcher renders (errors: %s)" % (name, errors))
    images = []
    for seed in range(1, K + 1):
        im, errors, _ = render(image, functions, "mc", size, camera, seed=seed, jitter=False, **kw)
        t.check(im is not None and not errors, "%s: Monte Carlo renders (errors: %s)" % (name, errors))
        images.append(im)
    t.check(all(np.isfinite(im).all() for im in images) and np.isfinite(reference).all(),
            "%s: images are finite" % name)
    ts = t_statistic(images, reference)
    stat_tests[0] += len(ts)
    print("%s: Monte Carlo vs ray march: T = %s (limit %.2f), mean alpha %.4f vs %.4f" % (
        name, ", ".join("%.2f" % x for x in ts), Z_LIMIT, np.mean(images, axis=0)[..., 3].mean(),
        reference[..., 3].mean()))
    t.check(max(ts) < Z_LIMIT, "%s: the Monte Carlo image does not converge to the ray-marched one: T = %s"
            % (name, ts))
    return reference


def max_diff(a, b):
    return float(np.abs(a - b).max())


def rmse(a, b):
    return float(np.sqrt(((a - b) ** 2).mean()))


GREY = [(0, 1, 1, 1), (65535, 1, 1, 1)]
BLOB_COLORS = [(0, 0.2, 0.5, 1.0), (0.5, 1.0, 0.3, 0.1), (1, 1.0, 1.0, 0.5)]


# --- 1. Label volumes ----------------------------------------------------------
def case_labels():
    n = 32
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    labels = np.where((x - 15.5) ** 2 + (y - 15.5) ** 2 + (z - 15.5) ** 2 < 10 ** 2, 30, 10).astype(np.uint8)
    image = make_image(labels)
    # Opaque only around the label 20, which the volume does not contain.
    only20 = function(GREY, [(10, 0), (18.5, 0), (19.5, 1), (20.5, 1), (21.5, 0), (30, 0)], 0.1)
    only30 = function(GREY, [(10, 0), (29, 0), (30, 1)], 0.1)
    # The shell is 0.05 to 0.15 voxel thick: the ray marcher's default step
    # (half a voxel) steps over it in places, so it marches at 1/16 voxel.
    coarse, _, _ = render(image, [only20], "rm")
    for kind in ("rm", "mc"):
        ball, errors, _ = render(image, [only30], kind, nearest=True, spp=8)
        silhouette = ball[..., 3] > 0.5
        shell, errors2, _ = render(image, [only20], kind, nearest=False, spp=8, step_voxels=1.0 / 16)
        none, errors3, _ = render(image, [only20], kind, nearest=True, spp=8, step_voxels=1.0 / 16)
        if kind == "rm":
            print("labels (rm): at the default step (half a voxel) the shell shows in %.2f of the ball's silhouette"
                  % (coarse[..., 3] > 0.05)[silhouette].mean())
        t.check(not (errors or errors2 or errors3), "labels (%s): no errors: %s" % (kind, errors + errors2 + errors3))
        lit = shell[..., 3] > 0.05
        # The silhouette grown by one pixel (the shell lies just outside the
        # nearest-neighbour boundary of the ball in places).
        grown = silhouette.copy()
        for axis in (0, 1):
            for shift in (-1, 1):
                grown |= np.roll(silhouette, shift, axis=axis)
        print("labels (%s): linear: %d pixels show the non-existent label 20 (the ball covers %d); nearest: "
              "alpha max %g" % (kind, lit.sum(), silhouette.sum(), none[..., 3].max()))
        t.check(silhouette.sum() > 150, "labels (%s): nearest shows the ball of label 30" % kind)
        t.check(lit[silhouette].mean() > 0.9,
                "labels (%s): linear interpolation shows the spurious label-20 shell over the ball: %.3f of "
                "its silhouette" % (kind, lit[silhouette].mean()))
        t.check(not (lit & ~grown).any(), "labels (%s): the spurious shell lies on the ball" % kind)
        t.check(np.all(none == 0.0), "labels (%s): nearest interpolation shows nothing of label 20 (alpha max %g)"
                % (kind, none[..., 3].max()))


def case_label_edges():
    n = 32
    z, y, x = np.mgrid[0:n, 0:n, 0:n]
    labels = np.where((abs(x - 15.5) < 8) & (abs(y - 15.5) < 8) & (abs(z - 15.5) < 8), 30, 10).astype(np.uint8)
    image = make_image(labels)
    opaque30 = function(GREY, [(10, 0), (29, 0), (30, 1)], 0.1)
    w = h = 48
    scale = 12.3  # parallel scale: half the view's height in world units
    basis = {}

    def camera(renderer, cam):
        # Head-on down z, rolled so that the box's edges cross pixels at
        # every offset.
        cam.SetFocalPoint(15.5, 15.5, 15.5)
        cam.SetPosition(15.5, 15.5, 100)
        cam.SetViewUp(0, 1, 0)
        cam.ParallelProjectionOn()
        cam.SetParallelScale(scale)
        cam.Roll(17)
        basis["up"] = np.array(cam.GetViewUp())
        basis["right"] = np.cross(cam.GetDirectionOfProjection(), cam.GetViewUp())

    spp = 32
    off, e1, _ = render(image, [opaque30], "mc", (w, h), camera, spp=spp, jitter=False, nearest=True, seed=1)
    on, e2, _ = render(image, [opaque30], "mc", (w, h), camera, spp=spp, jitter=True, nearest=True, seed=2)
    t.check(not (e1 or e2), "label edges: no errors: %s" % (e1 + e2))
    # The box's square (nearest-neighbour boundary at 7.5 and 23.5) in each
    # pixel: area coverage by 32x32 supersampling, and the pixel centre.
    pixel = 2.0 * scale / h
    sub = (np.arange(32) + 0.5) / 32
    u = ((np.arange(w)[None, :, None, None] + sub[None, None, None, :]) - w / 2) * pixel
    v = ((np.arange(h)[:, None, None, None] + sub[None, None, :, None]) - h / 2) * pixel
    X = 15.5 + u * basis["right"][0] + v * basis["up"][0]
    Y = 15.5 + u * basis["right"][1] + v * basis["up"][1]
    coverage = ((np.abs(X - 15.5) < 8) & (np.abs(Y - 15.5) < 8)).mean(axis=(2, 3))
    uc = (np.arange(w)[None, :] + 0.5 - w / 2) * pixel
    vc = (np.arange(h)[:, None] + 0.5 - h / 2) * pixel
    Xc = 15.5 + uc * basis["right"][0] + vc * basis["up"][0]
    Yc = 15.5 + uc * basis["right"][1] + vc * basis["up"][1]
    centre = ((np.abs(Xc - 15.5) < 8) & (np.abs(Yc - 15.5) < 8)).astype(float)

    a_off, a_on = off[..., 3], on[..., 3]
    edge = (coverage > 0) & (coverage < 1)
    between = lambda a: int(((a > 0.02) & (a < 0.98)).sum())  # noqa: E731
    var = coverage * (1 - coverage) / spp
    bound = 1.0 + Z_LIMIT * math.sqrt(2.0 * float((var[edge] ** 2).sum())) / float(var[edge].sum())
    t_on = float(((a_on - coverage) ** 2)[edge].sum() / var[edge].sum())
    t_off = float(((a_off - coverage) ** 2)[edge].sum() / var[edge].sum())
    stat_tests[0] += 1
    print("label edges, %d spp: %d pixels on the edge; intermediate alpha: %d without jitter, %d with; coverage "
          "statistic (expectation 1, bound %.2f): %.2f with jitter, %.2f without" % (
              spp, edge.sum(), between(a_off), between(a_on), bound, t_on, t_off))
    t.check(between(a_off) == 0, "label edges: without jitter no pixel is partly covered: %d are" % between(a_off))
    t.check(np.all(np.abs(a_off - centre) < 1e-6),
            "label edges: without jitter each pixel is its centre's label (%d pixels differ)"
            % (np.abs(a_off - centre) >= 1e-6).sum())
    t.check(between(a_on) > edge.sum() // 2,
            "label edges: with jitter the edge pixels are partly covered: %d of %d" % (between(a_on), edge.sum()))
    t.check(t_on < bound, "label edges: with jitter alpha is the pixel's area coverage: T = %.2f >= %.2f"
            % (t_on, bound))
    t.check(t_off > bound, "label edges: without jitter alpha is not the coverage: T = %.2f" % t_off)


# --- 2. Anisotropic spacing --------------------------------------------------------
def case_anisotropic():
    nx, ny, nz = 24, 24, 9
    z, y, x = np.mgrid[0:nz, 0:ny, 0:nx].astype(float)
    f = np.exp(-(((x - 11.5) / 6) ** 2 + ((y - 11.5) / 5) ** 2 + ((4 * z - 16) / 8) ** 2)).astype(np.float32)
    aniso = make_image(f, spacing=(1, 1, 4))
    # The same trilinear field on a grid 4x finer along z (linear upsampling
    # reproduces it exactly).
    zi = np.arange(4 * (nz - 1) + 1) / 4.0
    z0 = np.minimum(np.floor(zi).astype(int), nz - 2)
    wz = (zi - z0)[:, None, None]
    iso = make_image((f[z0] * (1 - wz) + f[z0 + 1] * wz).astype(np.float32))
    blob = function(BLOB_COLORS, [(0, 0), (0.1, 0), (1, 0.9)], 1.0)
    camera = orbit(40, 25)
    a, e1, _ = render(aniso, [blob], "rm", camera=camera)
    b, e2, _ = render(iso, [blob], "rm", camera=camera)
    t.check(not (e1 or e2), "anisotropic: no errors: %s" % (e1 + e2))
    print("anisotropic (1, 1, 4) vs upsampled isotropic, ray marcher: max difference %.3g, mean alpha %.4f"
          % (max_diff(a, b), a[..., 3].mean()))
    t.check(a[..., 3].max() > 0.5, "anisotropic: the blob is visible")
    t.check(max_diff(a, b) < 1e-5, "anisotropic: spacing (1, 1, 4) renders as its isotropic upsampling: %.3g"
            % max_diff(a, b))
    check_converges("anisotropic (1, 1, 4)", aniso, [blob], camera)

    # Extreme aspect ratios: a 3-slice stack 50 apart, a sheet 0.01 thick per voxel.
    for dims, spacing, unit in (((24, 24, 3), (1, 1, 50), 1.0), ((64, 24, 24), (0.01, 1, 1), 0.05)):
        nx, ny, nz = dims
        z, y, x = np.mgrid[0:nz, 0:ny, 0:nx].astype(float)
        r2 = sum(((a - (n - 1) / 2) / ((n - 1) / 2)) ** 2 for a, n in ((x, nx), (y, ny), (z, nz)))
        image = make_image(np.exp(-3 * r2).astype(np.float32), spacing=spacing)
        tf = function(BLOB_COLORS, [(0, 0), (0.1, 0), (1, 0.9)], unit)
        thin = int(np.argmin(spacing))
        along = (90, 0) if thin == 0 else (0, 0)  # looking along the odd axis
        for azimuth, elevation in (along, (30, 20)):
            name = "spacing %s, view %d/%d" % (spacing, azimuth, elevation)
            ref = check_converges(name, image, [tf], orbit(azimuth, elevation, parallel=True))
            t.check(ref[..., 3].max() > 0.5, "%s: the blob is visible (alpha max %.3f)" % (name, ref[..., 3].max()))


# --- 3. Orientation ---------------------------------------------------------------
def rotation_z(degrees):
    a = math.radians(degrees)
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


def case_orientation():
    nx, ny, nz = 33, 25, 21
    z, y, x = np.mgrid[0:nz, 0:ny, 0:nx].astype(float)
    # Nothing symmetric: an elongated blob and a small ball off its axis.
    f = (np.exp(-(((x - 12) / 8) ** 2 + ((y - 12) / 4) ** 2 + ((z - 10) / 5) ** 2))
         + 0.8 * np.exp(-(((x - 26) / 2.5) ** 2 + ((y - 18) / 2.5) ** 2 + ((z - 12) / 2.5) ** 2))).astype(np.float32)
    spacing = np.array([1.0, 0.8, 1.2])
    origin = np.array([3.0, -2.0, 1.0])
    dims = np.array([nx, ny, nz])
    tf = function(BLOB_COLORS, [(0, 0), (0.1, 0), (1, 0.8)], 2.0)
    plain = make_image(f, spacing, origin)
    camera = orbit(35, 25)
    reference, _, m0 = render(plain, [tf], "rm", camera=camera)
    bounds = m0.GetBounds()

    def flipped(signs, base=np.eye(3), data=f, org=origin):
        """The volume with direction base @ diag(signs): the data reversed
        along each negated axis and the origin moved to its far end, so that
        every voxel keeps its world position."""
        direction = base @ np.diag(signs)
        index = tuple(slice(None, None, -1) if signs[a] < 0 else slice(None) for a in (2, 1, 0))
        far = np.where(np.array(signs) < 0, (dims - 1) * spacing, 0.0)
        return make_image(data[index], spacing, org + base @ far, direction)

    for signs in ((-1, 1, 1), (1, -1, 1), (1, 1, -1), (-1, -1, 1), (-1, -1, -1)):
        image = flipped(signs)
        im, errors, m = render(image, [tf], "rm", camera=camera)
        det = int(round(np.linalg.det(np.diag(signs))))
        print("direction diag%s (det %+d): ray marcher max difference %.3g" % (signs, det, max_diff(im, reference)))
        t.check(not errors, "direction diag%s: no errors: %s" % (signs, errors))
        t.check(np.allclose(m.GetBounds(), bounds, atol=1e-9), "direction diag%s: same bounds" % (signs,))
        t.check(max_diff(im, reference) < 1e-5,
                "direction diag%s (det %+d): the same image as unflipped: %.3g" % (signs, det, max_diff(im, reference)))
    check_converges("direction diag(-1, 1, 1)", flipped((-1, 1, 1)), [tf], camera)

    # Lit, with gradient shading: the gradient must follow the reflection.
    def lit_camera(renderer, cam):
        camera(renderer, cam)
        renderer.AutomaticLightCreationOff()
        light = vtkLight()
        light.SetLightTypeToSceneLight()
        light.SetPosition(1, 2, 3)
        light.SetFocalPoint(0, 0, 0)
        light.SetIntensity(3)
        renderer.AddLight(light)

    def gradient(on):
        def setup(m):
            m.SetGradientShading(on)
            m.SetShadowMode(m.NO_SHADOWS)
        return setup

    lit, e1, _ = render(plain, [tf], "rm", camera=lit_camera, shade=True, setup=gradient(True))
    lit_flat, _, _ = render(plain, [tf], "rm", camera=lit_camera, shade=True, setup=gradient(False))
    lit_flip, e2, _ = render(flipped((-1, 1, 1)), [tf], "rm", camera=lit_camera, shade=True, setup=gradient(True))
    print("lit with gradient shading: reflected vs plain %.3g (gradient shading changes the image by %.3g)"
          % (max_diff(lit_flip, lit), max_diff(lit, lit_flat)))
    t.check(not (e1 or e2), "lit: no errors: %s" % (e1 + e2))
    t.check(max_diff(lit, lit_flat) > 0.02, "lit: gradient shading changes the image (else the check below is void)")
    t.check(max_diff(lit_flip, lit) < 1e-5, "lit: a reflected direction matrix shades as the plain volume: %.3g"
            % max_diff(lit_flip, lit))

    # Oblique: rotated 30 degrees about z (about the origin).
    R = rotation_z(30)
    rotated = make_image(f, spacing, origin, R)
    centre = origin + (dims - 1) * spacing / 2
    turned = origin + R @ (centre - origin)

    def look(at, up, offset=(0, 0, 100), parallel=True):
        def cam_setup(renderer, cam):
            cam.SetParallelProjection(parallel)
            cam.SetParallelScale(22)
            cam.SetFocalPoint(*at)
            cam.SetPosition(*(np.asarray(at) + offset))
            cam.SetViewUp(*up)
        return cam_setup

    a, e1, _ = render(rotated, [tf], "rm", camera=look(turned, (0, 1, 0)))
    b, e2, _ = render(plain, [tf], "rm", camera=look(centre, R.T @ np.array([0, 1, 0])))  # camera rolled back
    c, _, _ = render(plain, [tf], "rm", camera=look(centre, (0, 1, 0)))
    print("oblique 30 deg: vs unrotated with the camera rolled by -30 deg: %.3g; vs the unrotated view: %.3g"
          % (max_diff(a, b), max_diff(a, c)))
    t.check(not (e1 or e2), "oblique: no errors: %s" % (e1 + e2))
    t.check(max_diff(a, b) < 1e-5, "oblique: the rotated volume is the unrotated one seen by a rotated camera: %.3g"
            % max_diff(a, b))
    t.check(max_diff(a, c) > 0.3, "oblique: the silhouette turns with the direction matrix")
    # A perspective view from anywhere, and a rotation composed with a reflection.
    off = np.array([30.0, -40.0, 60.0])
    up = np.array([0.0, 1.0, 0.3])
    a, _, _ = render(rotated, [tf], "rm", camera=look(turned, R @ up, R @ off, parallel=False))
    b, _, _ = render(plain, [tf], "rm", camera=look(centre, up, off, parallel=False))
    t.check(max_diff(a, b) < 1e-5, "oblique, perspective: %.3g" % max_diff(a, b))
    mirrored = flipped((1, -1, 1), base=R)  # direction R diag(1, -1, 1): determinant -1
    m, e3, _ = render(mirrored, [tf], "rm", camera=look(turned, R @ up, R @ off, parallel=False))
    print("rotation x reflection (det %+.0f) vs rotation: %.3g" % (np.linalg.det(R @ np.diag([1, -1, 1])),
                                                                 max_diff(m, a)))
    t.check(not e3 and max_diff(m, a) < 1e-5, "rotation x reflection: the same image as the rotation: %.3g %s"
            % (max_diff(m, a), e3))
    check_converges("oblique 30 deg, perspective", rotated, [tf], look(turned, R @ up, R @ off, parallel=False))


# --- 4. 16-bit data with outliers ------------------------------------------------
def outlier_volume():
    n = 32
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    r = np.sqrt((x - 15.5) ** 2 + (y - 15.5) ** 2 + (z - 15.5) ** 2)
    # Tissue values in 0..2000 with noise, so that they take many values as
    # measured data do (a few hundred distinct values would count as labels).
    noise = np.random.default_rng(11).normal(0, 10, r.shape)
    tissue = np.round(np.clip(2000 * (1 - r / 14) + noise, 0, 2000)).astype(np.uint16)
    hot = tissue.copy()
    # Five hot voxels (a detector's, or metal), in the corners of the volume.
    for p in ((0, 0, 0), (1, 30, 2), (30, 1, 29), (31, 31, 31), (2, 2, 30)):
        hot[p] = 65535
    return tissue, hot


def case_outliers_mapper():
    tissue, hot = outlier_volume()
    camera = orbit(30, 20)
    smooth = function([(0, 0.1, 0.2, 0.8), (800, 0.9, 0.4, 0.1), (2000, 1, 1, 0.9)], [(0, 0), (300, 0), (2000, 0.6)],
                      2.0)
    points = [(0, 0)]
    for c in (600, 1100, 1600):  # three thin shells: 30-unit features
        points += [(c - 20, 0), (c - 5, 0.9), (c + 5, 0.9), (c + 20, 0)]
    fine = function([(0, 0.2, 0.6, 1), (1000, 1, 0.5, 0.2), (2000, 1, 1, 1)], points + [(2000, 0)], 1.0)
    function_range = lambda m: m.SetTransferFunctionRangeMode(m.FUNCTION_RANGE)  # noqa: E731
    for name, tf in (("smooth", smooth), ("fine", fine)):
        clean, _, _ = render(make_image(tissue), [tf], "rm", camera=camera)  # data range 0..2000
        data, e1, _ = render(make_image(hot), [tf], "rm", camera=camera)
        func, e2, _ = render(make_image(hot), [tf], "rm", camera=camera, setup=function_range)
        t.check(not (e1 or e2), "outliers: no errors: %s" % (e1 + e2))
        t.check(np.isfinite(data).all() and np.isfinite(func).all(), "outliers (%s): finite images" % name)
        print("uint16 with 5 voxels at 65535, %s function: ray-marched RMSE DATA_RANGE vs FUNCTION_RANGE %.4f "
              "(max %.3f; mean alpha %.4f vs %.4f); FUNCTION_RANGE vs the data without the outliers %.4f"
              % (name, rmse(data, func), max_diff(data, func), data[..., 3].mean(), func[..., 3].mean(),
                 rmse(func, clean)))
        # The table resolution: FUNCTION_RANGE (2 units per entry) keeps the
        # features the outlier-free data shows.
        t.check(func[..., 3].mean() > 0.8 * clean[..., 3].mean(),
                "outliers (%s): FUNCTION_RANGE keeps the function's features" % name)
        if name == "smooth":
            t.check(rmse(data, func) < 0.01, "outliers (smooth): DATA_RANGE is good enough for a smooth "
                    "function: RMSE %.4f" % rmse(data, func))
        else:
            # DATA_RANGE clips the data's range 0..65535 to the functions'
            # (they clamp): 2 units per entry, not 64, so the 30-unit
            # features stay (before the clipping: RMSE 0.130, alpha halved).
            t.check(rmse(data, func) < 0.01,
                    "outliers (fine): DATA_RANGE (the default, clipped to the functions' range) keeps 30-unit "
                    "features in 0..2000: RMSE %.4f against FUNCTION_RANGE, mean alpha %.4f and %.4f"
                    % (rmse(data, func), data[..., 3].mean(), func[..., 3].mean()))
    # The Monte Carlo mapper shares the tables: the same loss.
    mc_data, _, _ = render(make_image(hot), [fine], "mc", camera=camera, spp=16, seed=1)
    mc_func, _, _ = render(make_image(hot), [fine], "mc", camera=camera, spp=16, seed=1, setup=function_range)
    print("Monte Carlo, fine function, 16 spp: mean alpha DATA_RANGE %.4f, FUNCTION_RANGE %.4f, RMSE %.4f"
          % (mc_data[..., 3].mean(), mc_func[..., 3].mean(), rmse(mc_data, mc_func)))


def write_vti(filename, image):
    writer = vtkXMLImageDataWriter()
    writer.SetFileName(filename)
    writer.SetInputData(image)
    t.check(writer.Write() == 1, "wrote %s" % filename)


def named_image(arrays, spacing=(1, 1, 1)):
    """A vtkImageData with one point array per (name, values (z, y, x))."""
    first = next(iter(arrays.values()))
    nz, ny, nx = first.shape
    image = vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    for name, values in arrays.items():
        a = numpy_to_vtk(np.ascontiguousarray(values).reshape(-1), deep=True)
        a.SetName(name)
        image.GetPointData().AddArray(a)
    return image


def scene_render(scene, work, name, reference=True):
    """Renders a scene (a dict) with mcvol.scenefile as mcvol-render does.
    Returns (RGB, alpha, the assembled pipeline) or raises."""
    from mcvol.scenefile import ErrorCollector, Presets, parse_scene, render as render_scene
    from mcvol.scenefile.assemble import assemble

    presets = Presets(os.path.join(SOURCE, "Data", "presets.json"))
    parsed = parse_scene(scene, work, presets)
    if reference:
        parsed["renderer"] = "raymarch"
    pipeline = assemble(parse_scene(scene, work, presets), ErrorCollector(), "test")
    rgb_file, alpha_file = (os.path.join(work, "%s%s.pfm" % (name, s)) for s in ("", "-alpha"))
    render_scene(parsed, os.path.join(work, name + ".png"), rgb_file, alpha_file)
    return read_pfm(rgb_file), read_pfm(alpha_file)[..., 0], pipeline


def read_pfm(filename):
    with open(filename, "rb") as f:
        data = f.read()
    kind, size, scale, body = data.split(b"\n", 3)
    w, h = (int(v) for v in size.split())
    return np.frombuffer(body, "<f4").reshape(h, w, 3 if kind == b"PF" else 1).astype(np.float64)


def case_outliers_scene(work):
    from mcvol.scenefile import SceneError, parse_scene, Presets
    from mcvol.scenefile.assemble import auto_range, channel_range

    tissue, hot = outlier_volume()
    write_vti(os.path.join(work, "hot.vti"), named_image({"ct": hot}))
    write_vti(os.path.join(work, "tissue.vti"), named_image({"ct": tissue}))

    def scene(file, range_=None):
        ch = {"array": "ct", "color": [[0, 1, 0.8, 0.6], [1, 1, 1, 1]], "opacity": [[0, 0], [0.2, 0], [1, 0.8]],
              "normalized": True, "unit_distance": 2.0}
        if range_ is not None:
            ch["range"] = range_
        return {"input": file, "channels": [ch], "image_size": [48, 48], "camera": {"azimuth": 30, "elevation": 20},
                "samples_per_pixel": 1}

    centre = np.zeros((48, 48), bool)
    yy, xx = np.mgrid[0:48, 0:48]
    centre[(xx - 23.5) ** 2 + (yy - 23.5) ** 2 < 8 ** 2] = True  # the middle of the tissue ball's image
    results = {}
    spreads = {}
    for label, file, range_ in (("auto", "hot.vti", None), ("auto, clean", "tissue.vti", None),
                                ("data", "hot.vti", "data"), ("explicit", "hot.vti", [0, 2000]),
                                ("explicit, clean", "tissue.vti", [0, 2000])):
        rgb, alpha, pipeline = scene_render(scene(file, range_), work, "outliers-" + label)
        ch = pipeline.channels[0]
        results[label] = (rgb, alpha)
        spread = spreads[label] = channel_range(ch)
        print("scene file, range %s (%s): normalised points over [%g, %g], tissue alpha %.4f"
              % (json.dumps(range_), file, spread[0], spread[1], alpha[centre].mean()))
        if label == "auto":
            t.check(spread[0] == 0 and 1700 < spread[1] < 2000, "auto range of the outlier volume: %s" % spread)
        if label == "data":
            t.check(spread == [0, 65535], "range data: the data range: %s" % spread)
    t.check(results["auto"][1][centre].mean() > 0.3,
            "scene file: with the default range the tissue is visible: alpha %.3f" % results["auto"][1][centre].mean())
    t.check(results["data"][1][centre].mean() < 0.02,
            "scene file: with \"range\": \"data\" the 65535 voxels squash the function (the old default): alpha %.3f"
            % results["data"][1][centre].mean())
    # Five outliers move the default range by at most five ranks of the
    # clean data's values (2.7 % here: 33 voxels are above the 99.9th
    # percentile of 32^3; in a real volume of millions, nothing), and the
    # tissue's image with it; "data" they move from 2000 to 65535.
    a, b = spreads["auto"], spreads["auto, clean"]
    upper = float(np.percentile(tissue, 99.9 + 100.0 * 5 / (tissue.size - 1)))
    t.check(a[0] == b[0] and b[1] <= a[1] <= upper * (1 + 1e-9), "scene file: five outliers move the auto range "
            "by at most five ranks: %s with, %s without (bound %g)" % (a, b, upper))
    for label, limit in (("auto", 0.05), ("explicit", 1e-4)):  # explicit: the tables differ in range
        d = max_diff(results[label][1][centre], results[label + ", clean"][1][centre])
        t.check(d < limit, "scene file, range %s: the tissue looks as it does without the outliers: alpha differs by "
                "%.3g" % (label, d))
    t.check(results["explicit"][1][centre].mean() > 0.3, "scene file: [0, 2000] shows the tissue")

    # auto_range itself: labels keep their rare labels (<= 256 distinct
    # values: min..max), uint8 likewise, sparse data fall back to min..max.
    def vtk_array(values):
        return numpy_to_vtk(np.ascontiguousarray(values).reshape(-1, 1), deep=True)

    labels = np.zeros(40000, np.uint16)
    labels[:20000] = 3
    labels[-5:] = 40000  # a rare label with a large number
    t.check(auto_range(vtk_array(labels), 0) == [0.0, 40000.0], "auto range of uint16 labels: min..max")
    t.check(auto_range(vtk_array(labels.astype(np.float32)), 0) == [0.0, 40000.0],
            "auto range of float labels: min..max")
    sparse = np.zeros(100000, np.float32)
    sparse[:20] = np.linspace(1, 5, 20)  # 0.02 % of the voxels
    t.check(auto_range(vtk_array(sparse), 0) == [0.0, 5.0], "auto range of sparse data: min..max")
    noisy = np.random.default_rng(3).normal(100, 10, 100000).astype(np.float32)
    noisy[:3] = [np.nan, np.inf, 1e6]
    lo, hi = auto_range(vtk_array(noisy), 0)
    t.check(60 < lo < 75 and 125 < hi < 140, "auto range of noisy float data: the percentiles [%g, %g]" % (lo, hi))
    t.check(auto_range(vtk_array(np.full(10, np.nan, np.float32)), 0) is None, "auto range of NaN: none")

    presets = Presets(os.path.join(SOURCE, "Data", "presets.json"))
    for bad, words in (("robust", 'channels[0].range: expected one of "auto", "data"'),
                       ([5, 1], "channels[0].range: min must be less than max")):
        try:
            parse_scene(scene("hot.vti", bad), work, presets)
            t.check(False, "range %s: a scene error expected" % json.dumps(bad))
        except SceneError as e:
            text = "%s: %s" % (e.key, e.message)
            t.check(words in text, "range %s: the error names the key: %s" % (json.dumps(bad), text))


def case_importance_range(work):
    """FUNCTION_RANGE tabulates over the colour and opacity functions' range;
    the importance table is sampled over the same range, so importance
    beyond it is cut off. mcvol-render extends the opacity function (by its
    end values) to cover the importance function."""
    n = 24
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    blob = np.exp(-(((x - 12) / 6) ** 2 + ((y - 12) / 6) ** 2 + ((z - 12) / 6) ** 2)).astype(np.float32)  # 0..1
    tf = function([(0, 1, 1, 1), (0.5, 1, 1, 1)], [(0, 0), (0.05, 0.3), (0.5, 0.3)], 1.0)  # functions on [0, 0.5]

    def importance(mode, on):
        def setup(m):
            f = vtkPiecewiseFunction()
            for p in ((0, 0), (0.79, 0), (0.8, 1), (1, 1)):  # important where the value is >= 0.8
                f.AddPoint(*p)
            m.SetChannelImportance(0, f)
            m.SetVisibilityOptimization(on)
            m.SetTransferFunctionRangeMode(mode)
        return setup

    effect = {}
    for name, mode in (("DATA_RANGE", vtkMultiChannelVolumeMapper.DATA_RANGE),
                       ("FUNCTION_RANGE", vtkMultiChannelVolumeMapper.FUNCTION_RANGE)):
        off, _, _ = render(make_image(blob), [tf], "rm", setup=importance(mode, False))
        on, errors, _ = render(make_image(blob), [tf], "rm", setup=importance(mode, True))
        t.check(not errors, "importance range: no errors: %s" % errors)
        effect[name] = max_diff(on, off)
    print("importance beyond the opacity function's range: the visibility optimization changes the image by %.3g "
          "with DATA_RANGE, %.3g with FUNCTION_RANGE" % (effect["DATA_RANGE"], effect["FUNCTION_RANGE"]))
    t.check(effect["DATA_RANGE"] > 0.05, "importance range: the optimization acts with DATA_RANGE")
    # With the optimization on, the importance function's points join the
    # functions' range (TransferFunctionTables.cxx, UpdateChannel).
    t.check(effect["FUNCTION_RANGE"] > 0.05,
            "importance range: FUNCTION_RANGE (the ParaView plugin's mode) keeps importance at values beyond the "
            "colour and opacity points (the optimization changes the image by %.3g)" % effect["FUNCTION_RANGE"])

    write_vti(os.path.join(work, "blob.vti"), named_image({"v": blob}))
    scene = {"input": "blob.vti", "image_size": [48, 48], "samples_per_pixel": 1, "channels": [
        {"array": "v", "color": [[0, 1, 1, 1], [0.5, 1, 1, 1]], "opacity": [[0, 0], [0.05, 0.3], [0.5, 0.3]],
         "importance": [[0, 0], [0.79, 0], [0.8, 1], [1, 1]], "normalized": True, "range": "data"}]}
    on = scene_render(dict(scene, visibility={}), work, "importance-on")
    off = scene_render(dict(scene, visibility={"enabled": False}), work, "importance-off")
    d = max_diff(on[1], off[1])
    print("scene file, importance beyond the opacity function's range: the optimization changes alpha by %.3g" % d)
    t.check(d > 0.05, "scene file: importance beyond the opacity function's range is kept (%.3g)" % d)


# --- 5. Empty channels --------------------------------------------------------------
def case_empty_channel(work):
    n = 24
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    a = np.exp(-(((x - 9) / 5) ** 2 + ((y - 11) / 6) ** 2 + ((z - 12) / 5) ** 2)).astype(np.float32)
    b = np.exp(-(((x - 15) / 5) ** 2 + ((y - 12) / 4) ** 2 + ((z - 11) / 6) ** 2)).astype(np.float32)
    zero = np.zeros_like(a)
    fa = function([(0, 1, 0.2, 0.1), (1, 1, 0.6, 0.3)], [(0, 0), (1, 0.8)], 2.0)
    fb = function([(0, 0.1, 0.4, 1), (1, 0.2, 0.9, 1)], [(0, 0), (1, 0.8)], 2.0)
    gap = function([(0, 0, 1, 0), (1, 0, 1, 0)], [(0, 0), (0.01, 0), (1, 0.9)], 1.0)  # 0 on [0, 0.01]
    kink = function([(0, 0, 1, 0), (1, 0, 1, 0)], [(0, 0), (1, 0.9)], 1.0)  # rises from (0, 0)
    camera = orbit(30, 20)
    two = make_image(np.stack([a, b], -1))
    last = make_image(np.stack([a, b, zero], -1))
    middle = make_image(np.stack([a, zero, b], -1))
    for blend in ("Density", "Max", "Mix", "Composite"):
        for kind in ("rm", "mc"):
            ref, e0, _ = render(two, [fa, fb], kind, camera=camera, blend=blend, seed=5, spp=8)
            im1, e1, m1 = render(last, [fa, fb, gap], kind, camera=camera, blend=blend, seed=5, spp=8)
            im2, e2, _ = render(middle, [fa, gap, fb], kind, camera=camera, blend=blend, seed=5, spp=8)
            what = "empty channel, %s, %s" % (blend, "ray marcher" if kind == "rm" else "Monte Carlo, same seed")
            t.check(not (e0 or e1 or e2) and m1.GetNumberOfChannels() == 3, "%s: renders, no errors: %s"
                    % (what, e0 + e1 + e2))
            t.check(np.isfinite(im1).all() and np.isfinite(im2).all(), "%s: finite" % what)
            # Mix averages colours with weights normalised over all channels:
            # equal up to float rounding.
            d = max(max_diff(im1, ref), max_diff(im2, ref))
            t.check(d <= (1e-6 if blend == "Mix" else 0.0), "%s: the image of the two channels: %.3g" % (what, d))
    # Opacity rising from (0, 0): the channel's table over its padded data
    # range [-0.5, 0.5] holds 0 between its entries 511 and 512, the second
    # already above 0: a faint haze fills the volume's box.
    ref, _, _ = render(two, [fa, fb], "rm", camera=camera)
    haze, _, _ = render(last, [fa, fb, kink], "rm", camera=camera)
    ref_mc, _, _ = render(two, [fa, fb], "mc", camera=camera, seed=5, spp=8)
    haze_mc, _, _ = render(last, [fa, fb, kink], "mc", camera=camera, seed=5, spp=8)
    print("empty channel, opacity rising from (0, 0), DATA_RANGE: ray marcher differs by %.4g, Monte Carlo (same "
          "seed) by %.4g" % (max_diff(haze, ref), max_diff(haze_mc, ref_mc)))
    # A constant channel's value sits on its table's first entry
    # (ChannelBinding.cxx): it reads exactly the function's value, 0 here.
    t.check(max_diff(haze, ref) == 0.0 and max_diff(haze_mc, ref_mc) == 0.0,
            "an all-zero channel whose opacity is 0 at 0 (and rises after it) adds nothing with DATA_RANGE: "
            "ray marcher %.4g, Monte Carlo %.4g" % (max_diff(haze, ref), max_diff(haze_mc, ref_mc)))
    function_range = lambda m: m.SetTransferFunctionRangeMode(m.FUNCTION_RANGE)  # noqa: E731
    ref_f, _, _ = render(two, [fa, fb], "rm", camera=camera, setup=function_range)
    haze_f, _, _ = render(last, [fa, fb, kink], "rm", camera=camera, setup=function_range)
    t.check(max_diff(haze_f, ref_f) == 0.0, "empty channel, FUNCTION_RANGE: no haze: %.3g" % max_diff(haze_f, ref_f))

    # Through mcvol-render: channels by name; an all-zero, a constant and an
    # all-NaN channel.
    write_vti(os.path.join(work, "channels.vti"), named_image({
        "a": a, "b": b, "zero": zero, "seven": np.full_like(a, 7.0), "nan": np.full_like(a, np.nan)}))

    def channel(name, rgb):
        return {"array": name, "color": [[0] + rgb, [1] + rgb], "opacity": [[0, 0], [1, 0.8]], "normalized": True,
                "unit_distance": 2.0}

    def scene(names):
        colors = {"a": [1, 0.3, 0.1], "b": [0.1, 0.5, 1], "zero": [0, 1, 0], "seven": [1, 1, 0], "nan": [1, 0, 1]}
        return {"input": "channels.vti", "channels": [channel(nm, colors[nm]) for nm in names],
                "image_size": [48, 48], "camera": {"azimuth": 30, "elevation": 20}, "samples_per_pixel": 8, "seed": 4}

    for reference in (True, False):
        what = "mcvol-render %s" % ("--reference" if reference else "(Monte Carlo, same seed)")
        rgb2, alpha2, _ = scene_render(scene(["a", "b"]), work, "two", reference)
        rgb3, alpha3, p3 = scene_render(scene(["a", "b", "zero"]), work, "three", reference)
        print("%s: an all-zero third channel changes the image by %.3g" % (
            what, max(max_diff(rgb3, rgb2), max_diff(alpha3, alpha2))))
        t.check(np.isfinite(rgb3).all() and np.isfinite(alpha3).all(), "%s: finite with an all-zero channel" % what)
        t.check(alpha2.max() > 0.5, "%s: the two channels are visible" % what)
        t.check(max(max_diff(rgb3, rgb2), max_diff(alpha3, alpha2)) == 0.0,
                "%s: an all-zero channel changes nothing" % what)
        for extra in ("seven", "nan"):
            rgb, alpha, p = scene_render(scene(["a", "b", extra]), work, extra, reference)
            rng = p.channels[2].get("auto_range") or p.channels[2]["data_range"]
            t.check(np.isfinite(rgb).all() and np.isfinite(alpha).all() and all(np.isfinite(rng)),
                    "%s: a %s channel gives a finite image and range (%s)" % (what, extra, rng))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--work", default=None)
    args = parser.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="TestRealDataCases-")
    os.makedirs(work, exist_ok=True)
    if not args.work:
        atexit.register(shutil.rmtree, work, True)
    start = time.time()
    import mcvol.scenefile.assemble as scene_assemble
    if not hasattr(scene_assemble, "auto_range"):
        t.check(False, "%s is older than the source (no \"range\": \"auto\"): build first" % scene_assemble.__file__)
        t.finish()
    for name, case in (("1a labels", case_labels), ("1b label edges", case_label_edges),
                       ("2 anisotropic", case_anisotropic), ("3 orientation", case_orientation),
                       ("4a outliers (mapper)", case_outliers_mapper),
                       ("4b outliers (scene files)", lambda: case_outliers_scene(work)),
                       ("4c importance and the table range", lambda: case_importance_range(work)),
                       ("5 empty channels", lambda: case_empty_channel(work))):
        t0 = time.time()
        print("--- %s" % name)
        case()
        print("    (%.1f s)" % (time.time() - t0))
    t.check(stat_tests[0] == N_STAT_TESTS, "the statistical checks counted for the significance level (%d) are "
            "the ones made (%d)" % (N_STAT_TESTS, stat_tests[0]))
    print("total %.1f s" % (time.time() - start))
    t.finish()


if __name__ == "__main__":
    main()
