"""mcvol: multi-channel Monte Carlo volume rendering for VTK.

Importing this package imports ParaView's VTK (``vtkmodules``) modules that the
wrapped classes depend on, so ``from mcvol import vtkMultiChannelVolumeMapper``
works in a plain interpreter.
"""

# The mapper draws through OpenGL: make sure the OpenGL render window and the
# object-factory overrides of the rendering modules are registered.
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401

from .mcvolRenderingMonteCarlo import *  # noqa: F401,F403

__version__ = "0.1.0"
