# SPDX-License-Identifier: BSD-3-Clause
"""ParaView: several image files on one grid as the point arrays of one image.

    from mcvol.paraview_channels import ChannelFiles
    brain = ChannelFiles(["/data/T1.nii.gz", "/data/atlas.nii.gz"])
    rep = Show(brain)
    rep.Representation = "Multi-Channel Volume (Monte Carlo)"
    rep.ChannelArrays = ["T1", "atlas"]

An anatomy scan and its atlases, one TIFF stack per stain, one field per
file: ChannelFiles returns a Programmable Source (so it shows in the
pipeline browser, is saved in state files and runs where the data lives with
a pvserver) whose output is one vtkImageData. It reads with the scene files'
readers (mcvol.scenefile.readers): NIfTI .nii/.nii.gz with its orientation
as the image's direction matrix, TIFF stacks, OME-TIFF and ImageJ
hyperstacks (one array per channel), .vti, .mha/.mhd, .nrrd/.nhdr. Each
file's array is named after the file (T1.nii.gz -> "T1"), a file's other
arrays "stem/array". Grids must match, unless resample=True: then every file
after the first is resampled onto the first one's grid (nearest for integer
data such as labels, linear otherwise).

This does in one step what opening each file and combining them with Append
Attributes does, without its catches in ParaView 5.11: its NIfTI reader is a
plugin (AnalyzeNIfTIReaderWriter) that reads no .nii.gz and ignores the
orientation, and every array is called "NIfTIImage", "NIfTIImage_input_1".

A problem (missing file, grids that differ, ...) is an error in the Output
Messages window that names the file, and the output stays empty. The mcvol
package must be importable where the source runs (scripts/paraview.sh sets
PYTHONPATH for paraview, pvpython, pvbatch and pvserver).

The GUI has the same as a Sources menu entry, "mcvol Channel Files" (the
plugin's Readers.xml.in, mcvol.paraview_readers), which File > Open also
offers for .ome.tif files.
"""

_CACHE = {}


def read_channel_files(files, resample=False):
    """The combined vtkImageData of `files` (a list of paths), or raises
    mcvol.scenefile.errors.SceneError naming the file. Cached per process by
    (files, resample, modification times), so RequestInformation and
    RequestData read once."""
    import os

    from mcvol.scenefile.errors import ErrorCollector
    from mcvol.scenefile.parse import parse_input
    from mcvol.scenefile.readers import read_inputs

    files = [os.path.abspath(f) for f in files]
    stamps = tuple(os.path.getmtime(f) if os.path.isfile(f) else None for f in files)
    key = (tuple(files), bool(resample), stamps)
    if key in _CACHE:
        return _CACHE[key]
    inputs = [{"file": f, "resample": bool(resample) and i > 0} for i, f in enumerate(files)]
    image = read_inputs(parse_input(inputs, os.getcwd()), ErrorCollector())
    _CACHE.clear()
    _CACHE[key] = image
    return image


def _report(error):
    from vtkmodules.vtkCommonCore import vtkOutputWindow

    text = str(error).replace('give it "resample": true', "pass resample=True")
    vtkOutputWindow.GetInstance().DisplayErrorText("mcvol ChannelFiles: %s\n" % text)


def request_information(algorithm, files, resample):
    """ScriptRequestInformation of the source: extent, spacing, origin and
    direction of the combined image."""
    from vtkmodules.vtkCommonDataModel import vtkDataObject
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as SDDP

    from mcvol.scenefile.errors import SceneError

    info = algorithm.GetOutputInformation(0)
    try:
        image = read_channel_files(files, resample)
    except SceneError as e:
        _report(e)
        info.Set(SDDP.WHOLE_EXTENT(), (0, -1, 0, -1, 0, -1), 6)
        return
    info.Set(SDDP.WHOLE_EXTENT(), image.GetExtent(), 6)
    info.Set(vtkDataObject.SPACING(), image.GetSpacing(), 3)
    info.Set(vtkDataObject.ORIGIN(), image.GetOrigin(), 3)
    m = image.GetDirectionMatrix()
    info.Set(vtkDataObject.DIRECTION(), [m.GetElement(i, j) for i in range(3) for j in range(3)], 9)


def request_data(algorithm, files, resample):
    """Script of the source: the combined image into its output."""
    from mcvol.scenefile.errors import SceneError

    try:
        image = read_channel_files(files, resample)
    except SceneError:
        return  # reported by request_information
    algorithm.GetOutput().ShallowCopy(image)


def ChannelFiles(files, resample=False, registrationName=None):
    """A Programmable Source reading `files` as the channels of one image
    (see the module's documentation). Needs paraview.simple."""
    from paraview import simple

    if isinstance(files, str):
        files = [files]
    files = [str(f) for f in files]
    if not files:
        raise ValueError("ChannelFiles needs at least one file")
    args = "%r, %r" % (files, bool(resample))
    kw = {"registrationName": registrationName} if registrationName else {}
    source = simple.ProgrammableSource(**kw)
    source.OutputDataSetType = "vtkImageData"
    source.ScriptRequestInformation = (
        "from mcvol.paraview_channels import request_information\nrequest_information(self, %s)\n" % args
    )
    source.Script = "from mcvol.paraview_channels import request_data\nrequest_data(self, %s)\n" % args
    return source
