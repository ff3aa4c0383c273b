"""pvpython: the representation's level-of-detail properties
(Documentation/user-guide/levels-of-detail.md, paraview.md):
- LevelOfDetail, InteractiveLevelOfDetail, LevelOfDetailFilter and
  MemoryBudget exist with their documented defaults (0, 1, Box 4, 0), round
  trip, and reach the mapper;
- still renders use LevelOfDetail; an interactive render with ParaView's
  LOD (the view's LODThreshold at 0, so every interactive render uses it)
  uses InteractiveLevelOfDetail and restarts the image; the next still
  render goes back to the still level, restarts, and then refines (the
  same accumulation rules as any change);
- InteractiveLevelOfDetail 0 keeps the still level while interacting; -1 is
  the automatic rule;
- a memory budget below level 0's size renders a coarser level and the
  report says so;
- without LOD (a threshold above the data size) interactive renders keep
  the still level;
- renders with ParaView's LOD are interactive renders for the mapper
  (SetInteractiveRendering), still renders are not;
- renders with ParaView's LOD read the nearest voxel (InteractiveInterpolation):
  the image of a still render of the same level with nearest voxels, bit for
  bit; "As Still Renders" keeps the still interpolation.
"""
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

split, view, rep, names = T.figure3_split_scene()
simple.Render(view)
mapper = T.local_mapper(rep)  # the actor has its mapper after a render

# --- Defaults and round trip ------------------------------------------------------
checks.check(rep.LevelOfDetail == 0, "LevelOfDetail defaults to 0 (%s)" % rep.LevelOfDetail)
checks.check(rep.InteractiveLevelOfDetail == 1, "InteractiveLevelOfDetail defaults to 1")
checks.check(rep.LevelOfDetailFilter == "Box 4", "the filter defaults to Box 4 (%s)" % rep.LevelOfDetailFilter)
checks.check(rep.MemoryBudget == 0.0, "MemoryBudget defaults to 0")
rep.LevelOfDetailFilter = "B-Spline"
rep.MemoryBudget = 512.0
simple.Render(view)
checks.check(mapper.GetLevelOfDetailFilter() == 2, "the filter reaches the mapper")
checks.check(mapper.GetMemoryBudget() == 512.0 * 1048576, "the budget reaches the mapper in bytes")
rep.LevelOfDetailFilter = "Box 4"
rep.MemoryBudget = 0.0

simple.Render(view)
checks.check(T.info(rep, "LastLevelOfDetail") == 0, "a still render at level 0")
levels = mapper.GetNumberOfLevelsOfDetail()
checks.check(levels >= 2, "figure3 has levels above 0 (%d)" % levels)

rep.LevelOfDetail = 2
simple.Render(view)
checks.check(T.info(rep, "LastLevelOfDetail") == 2, "LevelOfDetail 2 renders level 2")
checks.check("requested" in T.info(rep, "LevelOfDetailReport"), "report: %s" % T.info(rep, "LevelOfDetailReport"))
rep.LevelOfDetail = 0

# --- Interaction with ParaView's LOD ------------------------------------------------
view.LODThreshold = 0.0  # MB: every interactive render uses LOD
simple.Render(view)
simple.Render(view)
still_samples = T.info(rep, "TotalSamples")
checks.check(T.info(rep, "LastLevelOfDetail") == 0 and still_samples == 16,
             "two still renders at level 0 (%d samples)" % still_samples)
view.SMProxy.InteractiveRender()
checks.check(T.info(rep, "LastLevelOfDetail") == 1,
             "an interactive render with LOD uses level 1 (got %d)" % T.info(rep, "LastLevelOfDetail"))
checks.check(T.info(rep, "TotalSamples") == 8, "the interactive level restarts the image")
view.SMProxy.InteractiveRender()
checks.check(T.info(rep, "TotalSamples") == 16, "interactive renders at the same level accumulate")
builds = mapper.GetNumberOfLevelOfDetailBuilds()
simple.Render(view)
checks.check(T.info(rep, "LastLevelOfDetail") == 0, "the still render after interaction returns to level 0")
checks.check(T.info(rep, "TotalSamples") == 8, "and restarts the image there")
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 16, "still renders then refine level 0")
view.SMProxy.InteractiveRender()
checks.check(mapper.GetNumberOfLevelOfDetailBuilds() == builds,
             "interacting again reuses level 1 (%d builds)" % mapper.GetNumberOfLevelOfDetailBuilds())

rep.InteractiveLevelOfDetail = 0
view.SMProxy.InteractiveRender()
checks.check(T.info(rep, "LastLevelOfDetail") == 0, "InteractiveLevelOfDetail 0 keeps the still level")
rep.InteractiveLevelOfDetail = -1
view.SMProxy.InteractiveRender()
checks.check("automatic" in T.info(rep, "LevelOfDetailReport"),
             "InteractiveLevelOfDetail -1 is automatic: %s" % T.info(rep, "LevelOfDetailReport"))
rep.InteractiveLevelOfDetail = 1

# ParaView's LOD renders are the mapper's interactive renders (where the
# automatic estimator keeps expected value); still renders are not.
view.SMProxy.InteractiveRender()
checks.check(mapper.GetLastRenderInteractive(), "a render with ParaView's LOD is interactive for the mapper")
simple.Render(view)
checks.check(not mapper.GetLastRenderInteractive(), "a still render is not")

# Renders with ParaView's LOD read the nearest voxel (InteractiveInterpolation,
# default Nearest): the image of a still render of the same level with the
# interpolation set to Nearest by hand, bit for bit. Still renders keep the
# still interpolation; "As Still Renders" keeps it while interacting too.
checks.check(rep.InteractiveInterpolation == "Nearest", "InteractiveInterpolation defaults to Nearest (%s)"
             % rep.InteractiveInterpolation)
view.SMProxy.InteractiveRender()
checks.check(mapper.GetInterpolationType() == 0, "an interactive render with LOD reads the nearest voxel")
lod_image = T.accumulated(mapper)
lod_samples = T.info(rep, "TotalSamples")
simple.Render(view)
checks.check(mapper.GetInterpolationType() == -1, "a still render goes back to the volume property's interpolation")
rep.LevelOfDetail = 1
rep.MultiChannelInterpolation = "Nearest"
view.LODThreshold = 1e6  # no LOD: a still render of level 1 with nearest voxels
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == lod_samples, "the same samples (%d, %d)"
             % (T.info(rep, "TotalSamples"), lod_samples))
checks.check(T.accumulated(mapper) == lod_image,
             "the interactive image is level 1 with nearest voxels, bit for bit")
rep.MultiChannelInterpolation = "Volume Property"
rep.LevelOfDetail = 0
view.LODThreshold = 0.0
rep.InteractiveInterpolation = "As Still Renders"
view.SMProxy.InteractiveRender()
checks.check(mapper.GetInterpolationType() == -1, "As Still Renders keeps the still interpolation while interacting")
rep.InteractiveInterpolation = "Nearest"

view.LODThreshold = 1e6  # far above the data: no LOD
view.SMProxy.InteractiveRender()
checks.check(T.info(rep, "LastLevelOfDetail") == 0, "without ParaView's LOD interactive renders keep level 0")

# --- Memory budget ------------------------------------------------------------------
rep.MemoryBudget = 1e-3  # MiB: below level 0's three float channels
simple.Render(view)
report = T.info(rep, "LevelOfDetailReport")
checks.check(T.info(rep, "LastLevelOfDetail") > 0, "a budget below level 0 renders a coarser level")
checks.check("memory fallback" in report, "report: %s" % report)
rep.MemoryBudget = 0.0
simple.Render(view)
checks.check(T.info(rep, "LastLevelOfDetail") == 0, "no budget: level 0 again")

checks.finish()
