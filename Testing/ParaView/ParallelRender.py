"""pvbatch script of TestParaViewParallel: renders the figure3 scene with the
plugin's representation and saves the composited image (rank 0).

Usage: [mpiexec -n N] pvbatch ParallelRender.py OUTPUT.png SEED [UNIT_DISTANCE_SCALE]
It prints the number of pieces the data is split into (from a ProcessIds
array) and each rank renders its own piece; ParaView composites the pieces'
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

view = T.make_view((200, 200))
rep = T.show(pids, view)
rep.ChannelSource = "Components of One Array"
rep.ChannelComponentsArray = "channels"
names = ["channels:0", "channels:1", "channels:2"]
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
