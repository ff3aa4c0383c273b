"""pvbatch script of TestParaViewParallelLit: renders the lit split scene
(mcvolLitSplitScene, written to a .vti by the driver) with the plugin's
representation, Shade on, one directional scene light from +z, ambient
light and two scattering events, and saves the composited image (rank 0).

Usage: [mpiexec -n N] pvbatch ParallelLitRender.py SCENE.vti OUTPUT.png SEED LEVEL SAMPLES [VIEW [SPLIT]]
  LEVEL    the representation's LightingStandInLevel (-1 off, 0 exact, k coarse;
           "default": left as the representation sets it; "auto:MIB": automatic
           within LightingStandInMemoryLimit MIB)
  SAMPLES  samples per pixel of the saved image
  VIEW     "scene" (default): the scene's camera; "inside-lower": the camera
           inside the lower piece, looking down, away from the upper piece
           (IceT then renders only the lower piece's rank)
  SPLIT    "split" (default): the representation's SplitImageWithExactStandIn
           on; "sort-last": off
It prints the number of pieces the data is split into (from a ProcessIds
array) and rank 0's stand-in report and memory.
"""
import sys

from paraview import simple

import mcvolLitSplitScene as S
import mcvolParaViewTesting as T

scene, out, seed, level, samples = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], int(sys.argv[5])
camera = sys.argv[6] if len(sys.argv) > 6 else "scene"
split = (sys.argv[7] if len(sys.argv) > 7 else "split") == "split"
T.load_plugin()

reader = simple.XMLImageDataReader(FileName=[scene])
pids = simple.ProcessIdScalars(Input=reader)
pids.UpdatePipeline()
info = pids.GetDataInformation().DataInformation
arr = info.GetPointDataInformation().GetArrayInformation("ProcessId")
pieces = int(arr.GetComponentRange(0)[1]) + 1 if arr else 1
print("pieces: %d" % pieces)

view = T.make_view((S.SIZE, S.SIZE))
if camera == "inside-lower":
    view.CameraPosition = [20.0, 20.0, 10.0]
    view.CameraFocalPoint = [20.0, 20.0, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
else:
    view.CameraPosition = list(S.CAMERA)
    view.CameraFocalPoint = list(S.FOCAL)
    view.CameraViewUp = list(S.VIEW_UP)
view.CameraViewAngle = S.VIEW_ANGLE
view.UseLight = 0  # the light kit off: the scene light alone
light = simple.AddLight(view=view)
light.Coords = "Scene"
light.Type = "Directional"
light.FocalPoint = list(S.FOCAL)
light.Position = [f + 100.0 * d for f, d in zip(S.FOCAL, S.LIGHT_DIRECTION)]
light.Intensity = 1.0

rep = T.show(pids, view)
rep.ChannelArrays = [S.ARRAY]
lut = simple.GetColorTransferFunction(S.ARRAY)
lut.RGBPoints = [0.0] + list(S.COLOR) + [1.0] + list(S.COLOR)
lut.AutomaticRescaleRangeMode = "Never"
pwf = simple.GetOpacityTransferFunction(S.ARRAY)
pwf.Points = [v for x, a in S.OPACITY_POINTS for v in (x, a, 0.5, 0.0)]
rep.ScalarOpacityUnitDistance = 1.0
rep.Shade = 1
rep.ChannelAlbedos = [0.9]
rep.AmbientRadiance = [0.05, 0.05, 0.05]
rep.MaxScatteringDepth = 2
if level.startswith("auto:"):
    rep.LightingStandInLevel = -2
    rep.LightingStandInMemoryLimit = float(level[5:])
elif level != "default":
    rep.LightingStandInLevel = int(level)
rep.SplitImageWithExactStandIn = 1 if split else 0
rep.Seed = seed
rep.SamplesPerRender = min(64, samples)
rep.MaximumTotalSamples = samples
rep.PixelJitter = 0
simple.Render(view)
for _ in range((samples + 63) // 64 + 1):
    simple.Render(view)
simple.SaveScreenshot(out, view, ImageResolution=[S.SIZE, S.SIZE], TransparentBackground=0)
print("samples: %d" % T.info(rep, "TotalSamples"))
print("stand-in: %s; %.0f bytes" % (T.info(rep, "LightingStandInReport"), T.info(rep, "LightingStandInMemory")))
