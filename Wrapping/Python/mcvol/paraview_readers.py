# SPDX-License-Identifier: BSD-3-Clause
"""The scripts behind the plugin's Python readers (Plugin/Readers.xml).

ParaView 5.11 from Debian cannot load Python algorithm plugins under Python
3.11 (paraview.detail.pythonalgorithm imports inspect.getargspec, which 3.11
removed), so the plugin's readers are server-manager proxies of
vtkPythonProgrammableFilter whose scripts call these functions, with the
proxy's properties as the script's variables. They run where the data is
(builtin, pvserver, pvbatch); the plugin puts the mcvol package's folder on
their Python path.

- OME-Zarr (File > Open of a .zarr folder or its .zattrs): mcvol.omezarr;
  the level named (Level: an index or a dataset path; -1 or empty: the
  finest that fits MemoryBudget, in MiB, 0 = level 0), the region of
  interest (Region: "x0 x1 y0 y1 z0 z1", full-resolution voxels, empty =
  all), the file's time steps as ParaView's time. The output carries the
  channels' default displays (mcvol_display/<array> field arrays, which the
  Multi-Channel Volume representation applies) and, in the field array
  "OME-Zarr level", which level was read and why.
- Channel files (several files, or one OME-TIFF, as the channels of one
  image): mcvol.paraview_channels.read_channel_files.

A problem becomes one error line in the Output Messages window and an empty
output.
"""

_OMEZARR = {}


def _report(who, error):
    from vtkmodules.vtkCommonCore import vtkOutputWindow

    vtkOutputWindow.GetInstance().DisplayErrorText("mcvol %s: %s\n" % (who, error))


def _empty(algorithm):
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as SDDP

    info = algorithm.GetOutputInformation(0)
    info.Set(SDDP.WHOLE_EXTENT(), (0, -1, 0, -1, 0, -1), 6)
    info.Remove(SDDP.TIME_STEPS())
    info.Remove(SDDP.TIME_RANGE())


def _omezarr(filename):
    """The OMEZarrImage of a path, kept while its .zattrs is unchanged."""
    import os

    from .omezarr import OMEZarrImage, image_folder

    folder = image_folder(filename)
    stamp = os.path.getmtime(os.path.join(folder, ".zattrs")) if os.path.isfile(os.path.join(folder, ".zattrs")) \
        else None
    cached = _OMEZARR.get(folder)
    if cached is None or cached[0] != stamp:
        cached = (stamp, OMEZarrImage(folder), {})
        _OMEZARR.clear()
        _OMEZARR[folder] = cached
    return cached[1], cached[2]


def _arguments(level, budget_mib, region):
    from .omezarr import OMEZarrError

    level = str(level).strip() if level is not None else ""
    level = None if level in ("", "-1") else level
    text = str(region or "").replace(",", " ").split()
    if text:
        try:
            region = [int(v) for v in text]
        except ValueError:
            raise OMEZarrError("Region must be six voxel indices x0 x1 y0 y1 z0 z1, got '%s'" % region)
        if len(region) != 6 or min(region) < 0:
            raise OMEZarrError("Region must be six voxel indices >= 0 (x0 x1 y0 y1 z0 z1), got '%s'"
                               % " ".join(text))
    else:
        region = None
    return level, max(0.0, float(budget_mib or 0.0)) * 1048576.0, region


def omezarr_information(algorithm, filename, level, budget_mib, region):
    """RequestInformation: the grid of the level that will be read, and the
    time steps."""
    from vtkmodules.vtkCommonDataModel import vtkDataObject
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as SDDP

    from .omezarr import OMEZarrError

    info = algorithm.GetOutputInformation(0)
    try:
        image, _ = _omezarr(filename)
        level, budget, region = _arguments(level, budget_mib, region)
        _, dims, spacing, origin = image.grid(level, budget, region)
    except (OMEZarrError, OSError) as e:
        _report("OME-Zarr reader", e)
        _empty(algorithm)
        return
    info.Set(SDDP.WHOLE_EXTENT(), (0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1), 6)
    info.Set(vtkDataObject.SPACING(), spacing, 3)
    info.Set(vtkDataObject.ORIGIN(), origin, 3)
    if image.time_values:
        info.Set(SDDP.TIME_STEPS(), image.time_values, len(image.time_values))
        info.Set(SDDP.TIME_RANGE(), (image.time_values[0], image.time_values[-1]), 2)
    else:
        info.Remove(SDDP.TIME_STEPS())
        info.Remove(SDDP.TIME_RANGE())


def omezarr_data(algorithm, filename, level, budget_mib, region):
    """RequestData: the time step ParaView asks for (the nearest), read once
    per (level, region, time step) while the file is unchanged."""
    from vtkmodules.vtkCommonCore import vtkStringArray
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as SDDP

    from .omezarr import OMEZarrError

    try:
        image, reads = _omezarr(filename)
        level, budget, region = _arguments(level, budget_mib, region)
    except (OMEZarrError, OSError):
        return  # reported by omezarr_information
    step = 0
    info = algorithm.GetOutputInformation(0)
    if image.time_values and info.Has(SDDP.UPDATE_TIME_STEP()):
        t = info.Get(SDDP.UPDATE_TIME_STEP())
        step = min(range(len(image.time_values)), key=lambda k: abs(image.time_values[k] - t))
    key = (level, budget, tuple(region) if region else None, step)
    if key not in reads:
        try:
            data = image.read(level=level, time=step, region=region, memory_budget=budget)
        except (OMEZarrError, OSError) as e:
            _report("OME-Zarr reader", e)
            return
        note = vtkStringArray()
        note.SetName("OME-Zarr level")
        note.InsertNextValue(image.report)
        data.GetFieldData().AddArray(note)
        reads.clear()  # one image at a time: levels and steps can be large
        reads[key] = data
    output = algorithm.GetOutput()
    output.ShallowCopy(reads[key])
    if image.time_values:
        output.GetInformation().Set(output.DATA_TIME_STEP(), image.time_values[step])


def _file_list(files):
    if isinstance(files, str):
        files = [files]
    return [f for f in (files or []) if f]


def channel_files_information(algorithm, files, resample):
    from .paraview_channels import request_information

    files = _file_list(files)
    if not files:
        _empty(algorithm)
        return
    request_information(algorithm, files, bool(resample))


def channel_files_data(algorithm, files, resample):
    from .paraview_channels import request_data

    files = _file_list(files)
    if files:
        request_data(algorithm, files, bool(resample))
