"""Helpers for the ParaView plugin tests (run by pvpython or pvbatch).

The plugin is found through PV_PLUGIN_PATH (the ctest entries set it to the
build's plugin folder) or MCVOL_PARAVIEW_PLUGIN (the plugin library).
"""
import os
import sys
import tempfile

import numpy as np
from paraview import simple
from paraview import servermanager as sm
from vtkmodules.vtkIOImage import vtkPNGReader, vtkPNGWriter
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

REPRESENTATION = "Multi-Channel Volume (Monte Carlo)"
HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.path.dirname(os.path.dirname(HERE))
DATA = os.path.join(SOURCE_DIR, "Data")
BASELINES = os.path.join(SOURCE_DIR, "Testing", "Data", "Baseline")


def load_plugin():
    """Loads the plugin unless PV_PLUGIN_PATH auto-loaded it already."""
    definitions = sm.ProxyManager().GetProxyDefinitionManager()
    if definitions.HasDefinition("representations", "MultiChannelVolumeRepresentation"):
        return
    path = os.environ.get("MCVOL_PARAVIEW_PLUGIN")
    if not path:
        for folder in os.environ.get("PV_PLUGIN_PATH", "").split(os.pathsep):
            candidate = os.path.join(folder, "mcvolPlugin.so")
            if folder and os.path.exists(candidate):
                path = candidate
                break
    if not path:
        raise SystemExit("mcvolPlugin.so not found: set PV_PLUGIN_PATH or MCVOL_PARAVIEW_PLUGIN")
    simple.LoadPlugin(path, remote=False, ns=globals())
    if sm.ActiveConnection.IsRemote():
        simple.LoadPlugin(path, remote=True, ns=globals())


def local_mapper(rep):
    """The vtkMultiChannelVolumeMapper behind `rep` in this process (builtin
    session or a pvbatch rank). The plugin's representation class is not
    wrapped for Python, so go through its volume actor, whose mapper is."""
    import mcvol  # noqa: F401 (registers the mapper's Python wrapping)
    return rep.GetClientSideObject().GetActiveRepresentation().GetActor().GetMapper()


def accumulated(mapper):
    """The mapper's accumulated image (premultiplied RGBA floats) as a list."""
    from vtkmodules.vtkCommonCore import vtkFloatArray
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    return [out.GetValue(i) for i in range(out.GetNumberOfValues())]


def info(rep, name):
    """Value of an information property (read from the server)."""
    rep.SMProxy.UpdatePropertyInformation()
    prop = rep.SMProxy.GetProperty(name)
    return prop.GetElement(0)


def split_channels(source, array, names):
    """One point array per component of `array` (Extract Component filters)."""
    out = source
    for k, name in enumerate(names):
        out = simple.ExtractComponent(Input=out, InputArray=["POINTS", array], Component=k, OutputArrayName=name)
    return out


# Transfer functions of the figure3 scene: channel k in pure colour k.
COLORS = [(1.0, 0.1, 0.1), (0.1, 1.0, 0.1), (0.2, 0.3, 1.0), (1.0, 1.0, 0.1), (1.0, 0.2, 1.0)]


def set_channel_functions(names, colors=COLORS, opacity=0.35, value_range=(0.0, 1.0)):
    """Gives each named transfer function a constant colour and a ramp."""
    lo, hi = value_range
    for k, name in enumerate(names):
        lut = simple.GetColorTransferFunction(name)
        r, g, b = colors[k % len(colors)]
        lut.RGBPoints = [lo, r, g, b, hi, r, g, b]
        lut.AutomaticRescaleRangeMode = "Never"
        pwf = simple.GetOpacityTransferFunction(name)
        pwf.Points = [lo, 0.0, 0.5, 0.0, 0.25 * lo + 0.75 * hi, opacity, 0.5, 0.0, hi, opacity, 0.5, 0.0]


def figure3_split_scene(size=(160, 160)):
    """figure3 with its three components split into the point arrays red,
    green and blue, shown as channels with constant-colour functions.
    Returns (source, view, representation, names)."""
    figure3 = simple.XMLImageDataReader(FileName=[DATA + "/figure3.vti"])
    names = ["red", "green", "blue"]
    split = split_channels(figure3, "channels", names)
    view = make_view(size)
    rep = show(split, view)
    rep.ChannelArrays = names
    set_channel_functions(names)
    return split, view, rep, names


def write_vti(image):
    """Writes a vtkImageData to a temporary .vti (inline binary) and returns
    its path; the caller removes it."""
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    handle, path = tempfile.mkstemp(suffix=".vti")
    os.close(handle)
    writer = vtkXMLImageDataWriter()
    writer.SetInputData(image)
    writer.SetFileName(path)
    writer.SetDataModeToBinary()
    writer.Write()
    return path


def make_view(size=(200, 200)):
    view = simple.CreateView("RenderView")
    view.ViewSize = list(size)
    view.OrientationAxesVisibility = 0
    # FXAA (on by default in ParaView 5.11) smooths silhouette pixels, and
    # does so differently in builtin, client-server and parallel rendering
    # (where it runs on the composited image): compare unfiltered images.
    view.UseFXAA = 0
    view.Background = [0.0, 0.0, 0.0]
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.CameraPosition = [150.0, 110.0, 190.0]
    view.CameraFocalPoint = [31.5, 31.5, 31.5]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraViewAngle = 30.0
    return view


def show(source, view):
    rep = simple.Show(source, view)
    rep.SetRepresentationType(REPRESENTATION)
    # The baselines' backend, or CUDA on the GPU machine (Benchmarks/gpu/vtk.sh
    # sets MCVOL_TEST_BACKEND=cuda, as for the core and Python tests).
    rep.Backend = "CUDA" if os.environ.get("MCVOL_TEST_BACKEND", "").lower() == "cuda" else "CPU"
    rep.Seed = 7
    # The baselines were made with the independent sampler (the default Sobol'
    # sampler is tested statistically in Testing/Core/sequence_test.cxx).
    rep.SampleSequence = "Independent"
    rep.Estimator = "Collision"  # and with the collision estimator
    rep.SamplesPerRender = 8
    rep.InteractiveFrameTime = 0  # fixed batches: the tests count samples
    rep.MaximumTotalSamples = 32
    rep.TargetError = 0  # the tests count samples to the cap
    rep.ProgressAnnotation = 0  # the baselines are of the volume alone
    return rep


def render_converged(view, rep, limit=1000):
    """Renders until the representation reports it is finished."""
    for _ in range(limit):
        simple.Render(view)
        if info(rep, "Converged"):
            return info(rep, "TotalSamples")
    raise RuntimeError("the image did not converge in %d renders" % limit)


def capture(view, path=None):
    """The view's image as an (h, w, 3) uint8 array (rows from the top)."""
    own = path is None
    if own:
        handle, path = tempfile.mkstemp(suffix=".png")
        os.close(handle)
    size = list(view.ViewSize)
    simple.SaveScreenshot(path, view, ImageResolution=size, TransparentBackground=0)
    image = read_png(path)
    if own:
        os.remove(path)
    return image


def read_png(path):
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    out = reader.GetOutput()
    w, h, _ = out.GetDimensions()
    arr = vtk_to_numpy(out.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3]
    return np.ascontiguousarray(arr)


def write_png(path, arr):
    from vtkmodules.vtkCommonDataModel import vtkImageData

    h, w, _ = arr.shape
    image = vtkImageData()
    image.SetDimensions(w, h, 1)
    data = numpy_to_vtk(np.ascontiguousarray(arr[::-1].reshape(-1, 3)), deep=True)
    image.GetPointData().SetScalars(data)
    writer = vtkPNGWriter()
    writer.SetFileName(path)
    writer.SetInputData(image)
    writer.Write()


class Checks:
    def __init__(self):
        self.failures = 0

    def check(self, condition, message):
        print(("PASS: " if condition else "FAIL: ") + message)
        sys.stdout.flush()
        if not condition:
            self.failures += 1

    def finish(self):
        if self.failures:
            print("%d check(s) failed" % self.failures)
        else:
            print("all checks passed")
        sys.stdout.flush()
        sys.stderr.flush()
        # Not sys.exit(): pvpython 5.11 tears its render windows down in an
        # order that makes X report GLXBadContext and exit with 1 after
        # sys.exit(), with any representation (checked with "Volume").
        os._exit(1 if self.failures else 0)


def compare_baseline(checks, image, name, max_mean=1.0, max_fraction=0.005, tolerance=8):
    """Compares with Testing/Data/Baseline/<name>.png; MCVOL_UPDATE_BASELINES=1 rewrites it."""
    path = os.path.join(BASELINES, name + ".png")
    if os.environ.get("MCVOL_UPDATE_BASELINES") == "1":
        write_png(path, image)
        print("wrote baseline " + path)
    if not os.path.exists(path):
        out = os.path.join(tempfile.gettempdir(), name + ".png")
        write_png(out, image)
        checks.check(False, "%s: no baseline %s (image in %s)" % (name, path, out))
        return
    base = read_png(path)
    if base.shape != image.shape:
        checks.check(False, "%s: size %s differs from the baseline's %s" % (name, image.shape, base.shape))
        return
    diff = np.abs(base.astype(int) - image.astype(int))
    mean = diff.mean()
    fraction = (diff.max(axis=2) > tolerance).mean()
    out = os.path.join(tempfile.gettempdir(), name + ".png")
    write_png(out, image)
    checks.check(
        mean <= max_mean and fraction <= max_fraction,
        "%s matches its baseline: mean |diff| %.3f (<= %.1f), pixels off by > %d: %.4f (<= %.4f); image in %s"
        % (name, mean, max_mean, tolerance, fraction, max_fraction, out),
    )
