"""pvpython: colouring by a channel's array (ColorBy, the way to ParaView's
colour map editor) and saving a screenshot keep the image refining; an edit
of the channel's functions in the editor restarts it, and it refines again."""
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

split, view, rep, names = T.figure3_split_scene()
rep.MaximumTotalSamples = 0  # no cap: every render adds Samples Per Render (8)
RENDERS = 5


def growth(label):
    """Samples added by RENDERS renders after a first one."""
    simple.Render(view)
    start = T.info(rep, "TotalSamples")
    for _ in range(RENDERS):
        simple.Render(view)
    end = T.info(rep, "TotalSamples")
    print("%s: %d -> %d samples" % (label, start, end))
    return end - start


before = growth("solid colour")
checks.check(before == 8 * RENDERS, "without colouring every render adds 8 samples (%d)" % before)

simple.ColorBy(rep, ("POINTS", "red"))
after = growth("coloured by 'red'")
checks.check(after >= before // 2,
             "coloured by a channel array, the image refines at least half as fast (%d against %d)" % (after, before))
checks.check(T.info(rep, "ChannelStatus") == "", "no channel problem reported after ColorBy")
more = growth("coloured, later")
checks.check(more == before, "and keeps refining at the full rate (%d against %d)" % (more, before))

# A screenshot renders the view again: it keeps the samples.
total = T.info(rep, "TotalSamples")
T.capture(view)
after_shot = T.info(rep, "TotalSamples")
checks.check(after_shot >= total, "SaveScreenshot keeps the accumulated samples (%d -> %d)" % (total, after_shot))
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == after_shot + 8,
             "the render after a screenshot adds a batch (%d -> %d)" % (after_shot, T.info(rep, "TotalSamples")))

# An edit in the colour map editor (the channel's function) restarts the
# image, which then refines again.
lut = simple.GetColorTransferFunction("red")
lut.RGBPoints = [0.0, 1.0, 0.5, 0.1, 1.0, 1.0, 0.5, 0.1]
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 8, "an edit of the coloured channel's function restarts the image (%d)"
             % T.info(rep, "TotalSamples"))
edited = growth("after an edit")
checks.check(edited == before, "after the edit the image refines at the full rate (%d)" % edited)

simple.ColorBy(rep, None)
solid = growth("back to solid colour")
checks.check(solid == before, "back to Solid Color the image refines at the full rate (%d)" % solid)
checks.finish()
