"""Pre-classified RGBA input through vtkVolumeProperty::IndependentComponentsOff
(VTK's dependent components):
- a 4-component unsigned char slab of constant colour c and opacity a, seen
  along its thickness L with an orthographic camera, shows colour c and alpha
  1 - (1 - a)^(L / u) (u the opacity unit distance) with the Monte Carlo
  mapper and the ray-marching reference;
- 2 components (colour function of component 0, opacity of component 1) give
  the image of the equivalent 4-component RGBA input;
- changing the opacity function classifies again and changes the image;
  re-rendering, moving the camera or touching a function without changing
  its values classifies nothing; new data values classify again;
- float RGBA: constant colour components are taken as they are; NaN voxels
  are transparent; unsigned short RGBA: each colour component is scaled over
  its finite range (VTK's GPU ray caster); 2 float components with a gray
  colour function;
- lighting (ShadeOn) works on the classified channel;
- 3 components, or channel arrays, with IndependentComponentsOff are a clear
  error (nothing drawn, no crash); 1 component renders as with
  IndependentComponentsOn;
- IndependentComponentsOn (the default) still renders the components as
  independent channels.
"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkLight,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba, use_test_backend

t = Checker()

NX, NY, NZ = 16, 16, 9  # the slab: thickness NZ - 1 = 8 world units along z
SIZE = 64
UNIT = 4.0  # opacity unit distance


def make_image(values, array_type=vtkUnsignedCharArray):
    """values: (NZ, NY, NX, C) array."""
    nz, ny, nx, nc = values.shape
    image = vtkImageData()
    image.SetDimensions(nx, ny, nz)
    array = array_type()
    array.SetName("rgba")
    array.SetNumberOfComponents(nc)
    array.SetNumberOfTuples(nx * ny * nz)
    dst = vtk_to_numpy(array)
    dst[:] = values.reshape(dst.shape)
    image.GetPointData().SetScalars(array)
    return image


def make_property(dependent=True):
    prop = vtkVolumeProperty()
    prop.SetIndependentComponents(not dependent)
    prop.SetInterpolationTypeToLinear()
    ctf = vtkColorTransferFunction()
    # At even values v = 2k: (2k, k, 255 - 2k) / 255, representable in 8 bits.
    ctf.AddRGBPoint(0, 0.0, 0.0, 1.0)
    ctf.AddRGBPoint(255, 1.0, 0.5, 0.0)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(255, 1.0)  # opacity = value / 255
    for c in range(4):
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, UNIT)
    return prop, ctf, otf


class Scene:
    def __init__(self, mapper, prop, image):
        self.mapper = mapper
        use_test_backend(mapper)
        mapper.SetInputData(image)
        mapper.SetSeed(7)
        self.errors = ErrorCatcher(mapper)
        self.volume = vtkVolume()
        self.volume.SetMapper(mapper)
        self.volume.SetProperty(prop)
        self.renderer = vtkRenderer()
        self.renderer.SetBackground(0, 0, 0)
        self.renderer.AddVolume(self.volume)
        self.window = vtkRenderWindow()
        self.window.SetOffScreenRendering(1)
        self.window.SetMultiSamples(0)
        self.window.SetSize(SIZE, SIZE)
        self.window.AddRenderer(self.renderer)
        cam = self.renderer.GetActiveCamera()
        cam.ParallelProjectionOn()
        cam.SetFocalPoint((NX - 1) / 2.0, (NY - 1) / 2.0, (NZ - 1) / 2.0)
        cam.SetPosition((NX - 1) / 2.0, (NY - 1) / 2.0, 100.0)
        cam.SetViewUp(0, 1, 0)
        cam.SetParallelScale(10.0)
        self.renderer.ResetCameraClippingRange()

    def render(self, times=1):
        for _ in range(times):
            self.window.Render()
        out = vtkFloatArray()
        self.mapper.GetAccumulatedImage(out)
        w = self.mapper.GetAccumulatedImageWidth()
        h = self.mapper.GetAccumulatedImageHeight()
        if w * h == 0:
            return np.zeros((SIZE, SIZE, 4))
        return vtk_to_numpy(out).reshape(h, w, 4).astype(np.float64)


def centre(img):
    """Mean RGBA of the pixels well inside the slab's footprint."""
    return img[SIZE // 2 - 8:SIZE // 2 + 8, SIZE // 2 - 8:SIZE // 2 + 8].reshape(-1, 4).mean(axis=0)


def constant_slab(rgb, alpha, nc=4):
    v = np.zeros((NZ, NY, NX, nc))
    v[..., :3] = rgb
    v[..., 3] = alpha
    return v


# --- 1. Constant RGBA slab against the analytic answer -------------------------
RGB8 = (200, 100, 50)
A8 = 77
a = A8 / 255.0
expected_alpha = 1.0 - (1.0 - a) ** ((NZ - 1) / UNIT)
expected_rgb = np.array(RGB8) / 255.0 * expected_alpha  # premultiplied
slab = constant_slab(RGB8, A8)

prop, ctf, otf = make_property()
mc = Scene(vtkMultiChannelVolumeMapper(), prop, make_image(slab))
mc.mapper.SetSamplesPerPixel(64)
img = mc.render()
got = centre(img)
t.check(not mc.errors.errors, "RGBA slab: unexpected errors %s" % mc.errors.errors)
t.check(mc.mapper.GetNumberOfChannels() == 1,
        "RGBA slab: expected 1 classified channel, got %d" % mc.mapper.GetNumberOfChannels())
t.check(mc.mapper.GetNumberOfClassifications() == 1,
        "RGBA slab: expected 1 classification, got %d" % mc.mapper.GetNumberOfClassifications())
t.check(mc.mapper.GetClassifiedMemory() == 16 * NX * NY * NZ,
        "classified copy: %g bytes, expected 16 per voxel" % mc.mapper.GetClassifiedMemory())
# Monte Carlo, 64 samples per pixel, mean of 256 pixels: within 0.01.
t.check(abs(got[3] - expected_alpha) < 0.01,
        "MC alpha %.4f, analytic 1 - (1 - a)^(L/u) = %.4f" % (got[3], expected_alpha))
t.check(np.abs(got[:3] - expected_rgb).max() < 0.01,
        "MC premultiplied colour %s, expected %s" % (np.round(got[:3], 4), np.round(expected_rgb, 4)))
# Colour un-premultiplied: c itself.
t.check(np.abs(got[:3] / got[3] - np.array(RGB8) / 255.0).max() < 0.01,
        "MC colour %s, expected %s" % (np.round(got[:3] / got[3], 4), np.round(np.array(RGB8) / 255.0, 4)))

rm_prop, _, _ = make_property()
rm = Scene(vtkMultiChannelRayMarchMapper(), rm_prop, make_image(slab))
rm_img = rm.render()
got = centre(rm_img)
t.check(not rm.errors.errors, "ray march: unexpected errors %s" % rm.errors.errors)
# The ray march is exact for a constant medium up to float rounding: 1e-3.
t.check(abs(got[3] - expected_alpha) < 1e-3,
        "ray-march alpha %.5f, analytic %.5f" % (got[3], expected_alpha))
t.check(np.abs(got[:3] - expected_rgb).max() < 1e-3,
        "ray-march colour %s, expected %s" % (np.round(got[:3], 5), np.round(expected_rgb, 5)))
rm.mapper.SetCompositingModelToOpacity()
got = centre(rm.render())
t.check(abs(got[3] - expected_alpha) < 2e-3,
        "ray march, opacity compositing: alpha %.5f, analytic %.5f" % (got[3], expected_alpha))

# --- 2. Two components = the equivalent RGBA ----------------------------------
rng = np.random.default_rng(3)
k = rng.integers(0, 128, size=(NZ, NY, NX))  # colour value 2k (even)
alpha8 = rng.integers(0, 256, size=(NZ, NY, NX))
two = np.stack([2 * k, alpha8], axis=-1)
four = np.stack([2 * k, k, 255 - 2 * k, alpha8], axis=-1)

images = {}
for name, values in (("2", two), ("4", four)):
    for kind, cls in (("mc", vtkMultiChannelVolumeMapper), ("rm", vtkMultiChannelRayMarchMapper)):
        p, _, _ = make_property()
        s = Scene(cls(), p, make_image(values))
        s.mapper.SetSamplesPerPixel(16)
        images[(name, kind)] = s.render()
        t.check(not s.errors.errors, "%s components (%s): unexpected errors %s" % (name, kind, s.errors.errors))
for kind in ("mc", "rm"):
    d = np.abs(images[("2", kind)] - images[("4", kind)])
    t.check(images[("4", kind)][..., 3].max() > 0.2, "%s: the random volume should be visible" % kind)
    t.check(d.max() < 2e-3 and d.mean() < 1e-4,
            "%s: 2 components differ from the equivalent RGBA by max %.2e, mean %.2e" % (kind, d.max(), d.mean()))

# --- 3. Classified only when something changed -------------------------------
mc.mapper.SetSamplesPerPixel(4)
before = mc.render()
n = mc.mapper.GetNumberOfClassifications()
samples = mc.mapper.GetTotalSamples()
mc.render(2)
t.check(mc.mapper.GetNumberOfClassifications() == n,
        "re-rendering classified again (%d -> %d)" % (n, mc.mapper.GetNumberOfClassifications()))
t.check(mc.mapper.GetTotalSamples() == samples + 8,
        "re-rendering should refine the image (%d -> %d samples)" % (samples, mc.mapper.GetTotalSamples()))
mc.renderer.GetActiveCamera().Azimuth(10)
mc.render()
t.check(mc.mapper.GetNumberOfClassifications() == n, "moving the camera classified again")
t.check(mc.mapper.GetTotalSamples() == 4, "moving the camera should restart the image")
mc.renderer.GetActiveCamera().Azimuth(-10)
otf.Modified()  # a new time, the same values (ParaView does this every render)
mc.render()
t.check(mc.mapper.GetNumberOfClassifications() == n, "touching the opacity function classified again")
otf.RemoveAllPoints()
otf.AddPoint(0, 0.0)
otf.AddPoint(255, 0.5)  # half the opacity
after = centre(mc.render(4))
t.check(mc.mapper.GetNumberOfClassifications() == n + 1,
        "a new opacity function should classify once (%d -> %d)" % (n, mc.mapper.GetNumberOfClassifications()))
expected_half = 1.0 - (1.0 - a / 2) ** ((NZ - 1) / UNIT)
t.check(abs(after[3] - expected_half) < 0.02,
        "after halving the opacity: alpha %.4f, expected %.4f" % (after[3], expected_half))
prop.SetScalarOpacityUnitDistance(0, 2 * UNIT)
after2 = centre(mc.render(4))
t.check(mc.mapper.GetNumberOfClassifications() == n + 2, "a new unit distance should classify once")
expected_u = 1.0 - (1.0 - a / 2) ** ((NZ - 1) / (2 * UNIT))
t.check(abs(after2[3] - expected_u) < 0.02,
        "after doubling the unit distance: alpha %.4f, expected %.4f" % (after2[3], expected_u))
prop.SetScalarOpacityUnitDistance(0, UNIT)
# New values in place, with only the image marked modified.
image = mc.mapper.GetInput()
vtk_to_numpy(image.GetPointData().GetScalars())[:, 3] = 0
image.Modified()
gone = centre(mc.render())
t.check(mc.mapper.GetNumberOfClassifications() == n + 3, "new data values should classify again")
t.check(gone[3] < 1e-6, "all alphas 0: the slab should vanish (alpha %.3g)" % gone[3])

# --- 4. Float RGBA: constant components as they are; NaN voxels ----------------
fslab = constant_slab((1.0, 0.5, 0.25), 0.0)
fslab[..., 3] = 255.0 * a  # through the same opacity function: opacity a
fslab[:, :, : NX // 2, 3] = np.nan  # left half NaN
fp, _, _ = make_property()
fs = Scene(vtkMultiChannelRayMarchMapper(), fp, make_image(fslab.astype(np.float32), vtkFloatArray))
fimg = fs.render()
t.check(not fs.errors.errors, "float RGBA: unexpected errors %s" % fs.errors.errors)
t.check(np.isfinite(fimg).all(), "float RGBA with NaN voxels: non-finite pixels")
right = fimg[SIZE // 2 - 4:SIZE // 2 + 4, SIZE // 2 + 8:SIZE // 2 + 12].reshape(-1, 4).mean(axis=0)
left = fimg[SIZE // 2 - 4:SIZE // 2 + 4, SIZE // 2 - 12:SIZE // 2 - 8].reshape(-1, 4).mean(axis=0)
t.check(abs(right[3] - expected_alpha) < 1e-3, "float RGBA: alpha %.4f, expected %.4f" % (right[3], expected_alpha))
t.check(np.abs(right[:3] / right[3] - np.array([1.0, 0.5, 0.25])).max() < 1e-3,
        "float RGBA: constant colour components should be taken as they are, got %s"
        % np.round(right[:3] / right[3], 4))
t.check(left[3] == 0.0, "NaN voxels should be transparent (alpha %.3g)" % left[3])

# unsigned short RGBA: each colour component scaled over its finite range
# (VTK's GPU ray caster), opacity through the function at the data value.
from vtkmodules.vtkCommonCore import vtkUnsignedShortArray  # noqa: E402

us = np.zeros((NZ, NY, NX, 4))
us[..., 0] = 1000 + 2000 * np.arange(NX)[None, None, :] / (NX - 1)  # red 0..1 along x
us[..., 1] = 500  # constant: clamped to [0, 1] -> 1
us[..., 2] = 0  # constant 0 -> 0
us[..., 3] = A8
up, _, _ = make_property()
ust = Scene(vtkMultiChannelRayMarchMapper(), up, make_image(us, vtkUnsignedShortArray))
uimg = ust.render()
t.check(not ust.errors.errors, "unsigned short RGBA: unexpected errors %s" % ust.errors.errors)
row = uimg[SIZE // 2]
cols = [x for x in range(SIZE) if row[x, 3] > 0.5 * expected_alpha]
mid = row[cols[len(cols) // 2]]
t.check(abs(mid[3] - expected_alpha) < 1e-3, "unsigned short RGBA: alpha %.4f, expected %.4f" % (mid[3], expected_alpha))
t.check(abs(mid[1] / mid[3] - 1.0) < 1e-3 and mid[2] == 0.0,
        "unsigned short RGBA: constant green 500 -> 1 and blue 0 -> 0, got %s" % np.round(mid[:3] / mid[3], 4))
reds = row[cols, 0] / row[cols, 3]
t.check(reds[0] < 0.1 and reds[-1] > 0.9 and np.all(np.diff(reds) >= -1e-6),
        "unsigned short RGBA: red should rise from 0 to 1 across the slab, got %s" % np.round(reds[::4], 3))

# Two float components with a gray colour function.
gp, _, _ = make_property()
gray = vtkPiecewiseFunction()
gray.AddPoint(0.0, 0.25)
gray.AddPoint(1.0, 0.25)
gp.SetColor(0, gray)
two_f = np.zeros((NZ, NY, NX, 2))
two_f[..., 0] = 0.5
two_f[..., 1] = A8
gs = Scene(vtkMultiChannelRayMarchMapper(), gp, make_image(two_f.astype(np.float32), vtkFloatArray))
got = centre(gs.render())
t.check(not gs.errors.errors and abs(got[3] - expected_alpha) < 1e-3 and np.abs(got[:3] / got[3] - 0.25).max() < 1e-3,
        "2 float components, gray function: colour %s alpha %.4f (%s)" % (got[:3] / max(got[3], 1e-9), got[3],
                                                                          gs.errors.errors))

# --- 5. Lighting --------------------------------------------------------------
lp, _, _ = make_property()
lp.ShadeOn()
ls = Scene(vtkMultiChannelVolumeMapper(), lp, make_image(slab))
light = vtkLight()
light.SetPosition(1, 1, 1)
light.SetFocalPoint(0, 0, 0)
ls.renderer.AddLight(light)
ls.mapper.SetSamplesPerPixel(16)
lit = ls.render()
t.check(not ls.errors.errors, "ShadeOn: unexpected errors %s" % ls.errors.errors)
t.check(np.isfinite(lit).all() and centre(lit)[:3].max() > 0.01, "ShadeOn: the slab should be lit")
t.check(abs(centre(lit)[3] - expected_alpha) < 0.02,
        "ShadeOn: alpha %.4f, expected %.4f" % (centre(lit)[3], expected_alpha))

# --- 6. Errors, one component, and independent components -------------------
ep, _, _ = make_property()
es = Scene(vtkMultiChannelVolumeMapper(), ep, make_image(slab[..., :3].copy()))
pixels = capture_rgba(es.window)
t.check(any("2 or 4" in e and "IndependentComponentsOn" in e for e in es.errors.errors),
        "3 components: expected a clear error, got %s" % es.errors.errors)
t.check(pixels[..., :3].max() == 0, "3 components: nothing should be drawn")
t.check(es.mapper.GetNumberOfChannels() == 0, "3 components: no channels should render")
# The same mapper renders a valid input afterwards.
es.errors.clear()
es.mapper.SetInputData(make_image(slab))
es.mapper.SetSamplesPerPixel(16)
got = centre(es.render())
t.check(not es.errors.errors and abs(got[3] - expected_alpha) < 0.02,
        "after the error a 4-component input should render (alpha %.4f, errors %s)" % (got[3], es.errors.errors))
# Channel arrays listed on the mapper: an error.
es.errors.clear()
es.mapper.AddChannelArray("rgba")
es.mapper.AddChannelArray("rgba")
es.render()
t.check(any("channel arrays" in e for e in es.errors.errors), "channel arrays: expected an error, got %s"
        % es.errors.errors)
es.mapper.RemoveAllChannelArrays()
# One component: as with independent components (no classification).
es.errors.clear()
one = make_image(np.full((NZ, NY, NX, 1), A8, dtype=np.float64))
es.mapper.SetInputData(one)
n = es.mapper.GetNumberOfClassifications()
got = centre(es.render())
t.check(not es.errors.errors and es.mapper.GetNumberOfChannels() == 1, "1 component: %s" % es.errors.errors)
t.check(es.mapper.GetNumberOfClassifications() == n, "1 component should not classify")
t.check(es.mapper.GetClassifiedMemory() == 0, "1 component: the classified copy should be released")
t.check(abs(got[3] - expected_alpha) < 0.02, "1 component: alpha %.4f, expected %.4f" % (got[3], expected_alpha))
# Independent components (the default): 4 channels, no classification.
ip, _, _ = make_property(dependent=False)
ins = Scene(vtkMultiChannelVolumeMapper(), ip, make_image(slab))
ins.render()
t.check(not ins.errors.errors and ins.mapper.GetNumberOfChannels() == 4,
        "IndependentComponentsOn: expected 4 channels, got %d (%s)"
        % (ins.mapper.GetNumberOfChannels(), ins.errors.errors))
t.check(ins.mapper.GetNumberOfClassifications() == 0, "IndependentComponentsOn should not classify")
# Switching the same mapper between the two.
ip.IndependentComponentsOff()
ins.render()
t.check(ins.mapper.GetNumberOfChannels() == 1 and ins.mapper.GetNumberOfClassifications() == 1,
        "switched to IndependentComponentsOff: %d channels, %d classifications"
        % (ins.mapper.GetNumberOfChannels(), ins.mapper.GetNumberOfClassifications()))
ip.IndependentComponentsOn()
ins.render()
t.check(not ins.errors.errors and ins.mapper.GetNumberOfChannels() == 4 and ins.mapper.GetClassifiedMemory() == 0,
        "switched back to IndependentComponentsOn: %d channels (%s)"
        % (ins.mapper.GetNumberOfChannels(), ins.errors.errors))

t.finish()
