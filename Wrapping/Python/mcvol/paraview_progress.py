# SPDX-License-Identifier: BSD-3-Clause
"""ParaView: how far a multi-channel volume has refined, read where it renders.

    from mcvol.paraview_progress import progress
    Render(view)
    p = progress(rep)
    p.samples, p.psnr, p.converged, p.text, p.status

In builtin mode (pvpython, pvbatch, the GUI alone) `rep.TotalSamples`,
`rep.Converged` and the other information properties are current after every
Render(). Connected to a pvserver they are not: ParaView reads a
representation's information properties from the client's copy, which holds
no data and reports -1 samples. progress() reads the same values on the
server, through the plugin's probe proxy (vtkMultiChannelProgressProbe), and
works in builtin mode too. With several ranks it is the first rank's image.
"""
from collections import namedtuple

Progress = namedtuple("Progress", "samples psnr converged text status")

_PROBES = {}


def _probe(rep):
    proxy = rep.SMProxy
    key = proxy.GetGlobalIDAsString()
    probe = _PROBES.get(key)
    if probe is None:
        # The property belongs to the plugin's representation, a subproxy of
        # the one ParaView shows.
        exposed = proxy.GetProperty("ChannelBlendMode")
        ours = exposed.GetParent() if exposed is not None else None
        if ours is None:
            raise ValueError("progress() needs a representation of image data with the mcvol plugin loaded")
        probe = proxy.GetSessionProxyManager().NewProxy("mcvol_misc", "MultiChannelProgressProbe")
        if probe is None:
            raise RuntimeError("the mcvol plugin is not loaded on the server (MultiChannelProgressProbe is unknown)")
        probe.GetProperty("Representation").AddProxy(ours)
        probe.UpdateVTKObjects()
        _PROBES[key] = probe
    return probe


def progress(rep):
    """The representation's samples per pixel (-1 before the first image),
    estimated PSNR in dB (-1 without an estimate), whether it has converged,
    the corner annotation's text and why nothing is drawn (empty when the
    channels are complete), as the process that renders sees them."""
    probe = _probe(rep)
    probe.UpdatePropertyInformation()

    def value(name):
        return probe.GetProperty(name).GetElement(0)

    return Progress(int(value("TotalSamples")), float(value("EstimatedPSNR")), bool(value("Converged")),
                    value("ProgressText") or "", value("ChannelStatus") or "")
