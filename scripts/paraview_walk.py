"""The GUI walk behind the quick start's screenshots, run by
`paraview --script` (scripts/paraview_screenshots.sh sets the environment):
open Data/figure3.vti, show its three components as channels of the
Multi-Channel Volume (Monte Carlo) representation; for the shot
"edit-channel" also edit channel 1 (which opens the colour map editor) and
show its legend. Writes MCVOL_WALK_READY when the scene is set up; the
plugin then refines the image while the GUI is idle."""
import os

from paraview.simple import (GetActiveViewOrCreate, GetOpacityTransferFunction, OpenDataFile, Render,
                             SetActiveSource, Show)

shot = os.environ.get("MCVOL_WALK_SHOT", "quick-start")
data = OpenDataFile(os.environ["MCVOL_WALK_DATA"])
SetActiveSource(data)
view = GetActiveViewOrCreate("RenderView")
view.OrientationAxesVisibility = 0
rep = Show(data, view)
rep.Representation = "Multi-Channel Volume (Monte Carlo)"
rep.ChannelSource = "Components of One Array"
rep.ChannelComponentsArray = "channels"
rep.Backend = "CPU"
for k in range(3):
    GetOpacityTransferFunction("channels:%d" % k).Points = [0.0, 0.0, 0.5, 0.0, 0.3, 0.0, 0.5, 0.0,
                                                            1.0, 0.6, 0.5, 0.0]
view.CameraPosition = [150.0, 110.0, 190.0]
view.CameraFocalPoint = [31.5, 31.5, 31.5]
view.CameraViewUp = [0.0, 1.0, 0.0]
if shot == "edit-channel":
    rep.ActiveChannel = 1
    rep.SetScalarBarVisibility(view, True)
Render(view)
with open(os.environ["MCVOL_WALK_READY"], "w") as f:
    f.write(shot + "\n")
