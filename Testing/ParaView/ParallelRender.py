"""pvbatch script of TestParaViewParallel: renders the figure3 scene with the
plugin's representation and saves the composited image (rank 0).

Usage: [mpiexec -n N] pvbatch ParallelRender.py OUTPUT.png SEED [UNIT_DISTANCE_SCALE]
It prints the number of pieces the data is split into (from a ProcessIds
array), the range of each channel's default colour function and the
representation's robust range of a "height" array (z^2, whose pieces' ranges
differ): both must be the whole data set's; each rank renders its own piece; ParaView composites the pieces'
premultiplied colour and alpha in visibility order.
"""
import sys

from paraview import simple

import mcvolParaViewTesting as T

out, seed = sys.argv[1], int(sys.argv[2])
scale = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
T.load_plugin()

reader = simple.XMLImageDataReader(FileName=[T.DATA + "/figure3.vti"])
pids = simple.ProcessIdScalars(Input=reader)
pids.UpdatePipeline()
info = pids.GetDataInformation().DataInformation
arr = info.GetPointDataInformation().GetArrayInformation("ProcessId")
pieces = int(arr.GetComponentRange(0)[1]) + 1 if arr else 1
print("pieces: %d" % pieces)

heights = simple.Calculator(Input=pids, ResultArrayName="height", Function="coordsZ*coordsZ")

view = T.make_view((200, 200))
rep = T.show(heights, view)
rep.ChannelSource = "Components of One Array"
rep.ChannelComponentsArray = "channels"
names = ["channels:0", "channels:1", "channels:2"]
for name in names:
    lut = simple.GetColorTransferFunction(name)
    print("default range %s: %.17g %.17g" % (name, lut.RGBPoints[0], lut.RGBPoints[-4]), flush=True)
for line in T.info(rep, "ChannelDefaultRanges").splitlines():
    if line.startswith("height\t"):
        print("default range height: %s %s" % tuple(line.split("\t")[2:]), flush=True)
T.set_channel_functions(names, opacity=0.5)
rep.ScalarOpacityUnitDistance = 1.0 * scale
rep.Seed = seed
rep.SamplesPerRender = 128
rep.MaximumTotalSamples = 1024
rep.PixelJitter = 0
simple.Render(view)
rep.SMProxy.UpdatePropertyInformation()
for _ in range(8):
    simple.Render(view)
simple.SaveScreenshot(out, view, ImageResolution=[200, 200], TransparentBackground=0)
print("samples: %d" % T.info(rep, "TotalSamples"))
