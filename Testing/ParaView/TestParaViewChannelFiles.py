"""pvpython: separate files as the channels of one image (mcvol.paraview_channels).

Two NIfTI files on one grid (a "T1" sphere and a "labels" block, written
here with an oblique orientation) become the arrays "T1" and "labels" of one
image with the files' grid and direction; the representation renders them
as two channels; a state file brings the source back; a file on another
grid gives an empty output and an error naming it, unless resample=True."""
import os
import tempfile

import numpy as np
from paraview import simple
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkCommonMath import vtkMatrix4x4
from vtkmodules.vtkIOImage import vtkNIFTIImageWriter
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

import mcvolParaViewTesting as T
from mcvol.paraview_channels import ChannelFiles

checks = T.Checks()
T.load_plugin()
work = tempfile.mkdtemp()
N = 24
z, y, x = np.mgrid[0:N, 0:N, 0:N].astype(np.float32)
c = 30.0 * np.pi / 180.0
ROTATION = [[np.cos(c), -np.sin(c), 0.0], [np.sin(c), np.cos(c), 0.0], [0.0, 0.0, 1.0]]


def write_nifti(name, values, dims=(N, N, N), spacing=(1.5, 1.5, 1.5)):
    image = vtkImageData()
    image.SetDimensions(*dims)
    image.SetSpacing(*spacing)
    image.GetPointData().SetScalars(numpy_to_vtk(values.ravel(), deep=True))
    m = vtkMatrix4x4()  # voxel (mm) -> world: rotation about z, then a shift
    for i in range(3):
        for j in range(3):
            m.SetElement(i, j, ROTATION[i][j])
    m.SetElement(0, 3, -10.0)
    m.SetElement(1, 3, 5.0)
    m.SetElement(2, 3, 20.0)
    writer = vtkNIFTIImageWriter()
    writer.SetInputData(image)
    writer.SetQFormMatrix(m)
    writer.SetSFormMatrix(m)
    path = os.path.join(work, name)
    writer.SetFileName(path)
    writer.Write()
    return path


sphere = np.clip(8.0 - np.sqrt((x - 11.5) ** 2 + (y - 11.5) ** 2 + (z - 11.5) ** 2), 0, 1).astype(np.float32)
labels = np.zeros((N, N, N), np.uint8)
labels[4:10, 4:10, 14:20] = 7
t1 = write_nifti("T1.nii.gz", sphere)
lab = write_nifti("labels.nii", labels)

brain = ChannelFiles([t1, lab], registrationName="brain")
brain.UpdatePipeline()
info = brain.GetDataInformation()
checks.check(sorted(brain.PointData.keys()) == ["T1", "labels"],
             "the arrays are named after the files (%s)" % brain.PointData.keys())
checks.check(tuple(info.GetExtent()) == (0, N - 1, 0, N - 1, 0, N - 1), "the files' extent (%s)" % (info.GetExtent(),))
image = simple.servermanager.Fetch(brain)
d = image.GetDirectionMatrix()
direction = [[d.GetElement(i, j) for j in range(3)] for i in range(3)]
checks.check(np.allclose(direction, ROTATION, atol=1e-5), "the NIfTI orientation is the image's direction (%s)" % direction)
checks.check(np.allclose(image.GetSpacing(), (1.5, 1.5, 1.5)) and np.allclose(image.GetOrigin(), (-10, 5, 20), atol=1e-4),
             "spacing %s and origin %s" % (image.GetSpacing(), image.GetOrigin()))
values = vtk_to_numpy(image.GetPointData().GetArray("labels")).reshape(N, N, N)
checks.check(np.array_equal(values, labels), "the label voxels are where the file has them")

view = T.make_view((96, 96))
rep = T.show(brain, view)
rep.ChannelArrays = ["T1", "labels"]
T.set_channel_functions(["T1", "labels"], colors=[(0.8, 0.8, 0.8), (1.0, 0.2, 0.1)], opacity=0.5)
view.ResetCamera()
T.render_converged(view, rep)
checks.check(T.info(rep, "ChannelStatus") == "", "both channels bind (%r)" % T.info(rep, "ChannelStatus"))
img = T.capture(view).astype(int)
red = (img[..., 0] > img[..., 1] + 40).sum()
grey = ((img.sum(axis=2) > 150) & (abs(img[..., 0] - img[..., 1]) < 20)).sum()
checks.check(red > 10 and grey > 50, "both channels show (%d red, %d grey pixels)" % (red, grey))

# A state file keeps the source (its scripts name the files).
state = os.path.join(work, "channels.pvsm")
simple.SaveState(state)
simple.ResetSession()
T.load_plugin()
simple.LoadState(state)
again = simple.FindSource("brain")
again.UpdatePipeline()
checks.check(again is not None and sorted(again.PointData.keys()) == ["T1", "labels"], "the state brings the source back")

# Another grid: an error naming the file, an empty output; resample=True fits it in.
other = write_nifti("coarse.nii.gz", np.ones((12, 12, 12), np.float32), dims=(12, 12, 12), spacing=(3.0, 3.0, 3.0))
messages = vtkStringOutputWindow()
previous = vtkOutputWindow.GetInstance()
vtkOutputWindow.SetInstance(messages)
bad = ChannelFiles([t1, other])
bad.UpdatePipeline()
vtkOutputWindow.SetInstance(previous)
text = messages.GetOutput()
checks.check("coarse.nii.gz" in text and "does not match" in text and "resample=True" in text,
             "a grid that differs is an error naming the file: %r" % text.strip()[:200])
checks.check(bad.GetDataInformation().GetNumberOfPoints() == 0, "and the output is empty")
fitted = ChannelFiles([t1, other], resample=True)
fitted.UpdatePipeline()
checks.check(sorted(fitted.PointData.keys()) == ["T1", "coarse"]
             and fitted.GetDataInformation().GetNumberOfPoints() == N ** 3,
             "resample=True puts it on the first file's grid")
checks.finish()
