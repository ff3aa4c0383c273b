"""pvpython script of TestParaViewClientServer: renders the figure3 scene, in
builtin mode or connected to a pvserver (argv: OUTPUT.png [HOST:PORT
[OME-ZARR FOLDER]]). With a folder, it also opens it on the server and
prints what the client sees: the reader, the channels and DAPI's colours."""
import sys

from paraview import simple

import mcvolParaViewTesting as T

out = sys.argv[1]
if len(sys.argv) > 2:
    host, port = sys.argv[2].split(":")
    simple.Connect(host, int(port))
    # Lossless image delivery (ParaView's default LZ4 level 3 reduces colours).
    simple.GetSettingsProxy("RenderViewSettings").CompressorConfig = "NULL"
T.load_plugin()
reader = simple.XMLImageDataReader(FileName=[T.DATA + "/figure3.vti"])
view = T.make_view((200, 200))
rep = T.show(reader, view)
rep.ChannelSource = "Components of One Array"
rep.ChannelComponentsArray = "channels"
T.set_channel_functions(["channels:0", "channels:1", "channels:2"])
rep.ChannelBlendMode = "Max"
# Every Render() refines the server's image by SamplesPerRender (8) up to
# MaximumTotalSamples (32); more renders redraw the finished image. The
# client's copy of the representation holds no data and reports -1 samples.
for _ in range(8):
    simple.Render(view)
print("samples: %d (client copy)" % T.info(rep, "TotalSamples"))
# Read where the image is (the server in client-server mode).
from mcvol.paraview_progress import progress  # noqa: E402

p = progress(rep)
print("progress: samples %d converged %d psnr-positive %d" % (p.samples, p.converged, p.psnr > 0))
simple.SaveScreenshot(out, view, ImageResolution=[200, 200], TransparentBackground=0)

if len(sys.argv) > 3:
    # The OME-Zarr reader runs on the server; the client proxy picks the
    # channels and applies the file's displays from the data information.
    cells = simple.OpenDataFile(sys.argv[3])
    shown = simple.Show(cells, view)
    simple.Render(view)
    print("omezarr: %s %s %s" % (cells.GetXMLName(), list(shown.ChannelArrays),
                                 list(simple.GetColorTransferFunction("DAPI").RGBPoints)))
