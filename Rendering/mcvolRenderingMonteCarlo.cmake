# Body of the mcvol::RenderingMonteCarlo VTK module.
#
# vtk_module_build() adds the folder holding the scanned vtk.module as a
# subdirectory and expects its CMakeLists.txt to call vtk_module_add_module().
# The vtk.module lives at the repository root (so the repository also works as
# a VTK remote module), which the standalone build cannot add as its own
# subdirectory. So the module body lives here, with absolute paths, and is
# include()d from whichever folder vtk_module_build() added:
#   - standalone build: a generated folder in the build tree holding a copy
#     of vtk.module (top-level CMakeLists.txt, cmake/mcvolModuleDir.CMakeLists.txt.in);
#   - VTK remote module: the repository root CMakeLists.txt.

set(_mcvol_rendering_dir "${CMAKE_CURRENT_LIST_DIR}")

# The VTK-free core, its CPU backend and the backend factory (static,
# position independent, linked privately into the module library). The
# standalone build adds them (and the CUDA backend, when it has one) from the
# top level; inside a VTK build nobody has yet.
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
foreach (_mcvol_part IN ITEMS Core CPU Backends)
  if (EXISTS "${_mcvol_rendering_dir}/${_mcvol_part}/CMakeLists.txt")
    string(TOLOWER "mcvol_${_mcvol_part}" _mcvol_part_target)
    if (NOT TARGET "${_mcvol_part_target}")
      add_subdirectory("${_mcvol_rendering_dir}/${_mcvol_part}"
        "${CMAKE_CURRENT_BINARY_DIR}/mcvol${_mcvol_part}")
    endif ()
  endif ()
endforeach ()

set(classes
  vtkMultiChannelDemoSource
  vtkMultiChannelRayMarchMapper
  vtkMultiChannelVolumeMapper)
list(TRANSFORM classes PREPEND "${_mcvol_rendering_dir}/")

# The mapper's Render() stages (Rendering/VTK/, one unit a file; see
# Documentation/architecture.md): private to the module, not wrapped.
set(_mcvol_stages
  Accumulation
  ChannelBinding
  DependentComponents
  FrameCompositor
  LevelOfDetail
  RenderBackend
  StandIn
  TransferFunctionTables
  View)
set(_mcvol_stage_sources ${_mcvol_stages})
list(TRANSFORM _mcvol_stage_sources PREPEND "${_mcvol_rendering_dir}/VTK/")
set(_mcvol_stage_headers ${_mcvol_stage_sources})
list(TRANSFORM _mcvol_stage_sources APPEND ".cxx")
list(TRANSFORM _mcvol_stage_headers APPEND ".h")
list(APPEND _mcvol_stage_headers "${_mcvol_rendering_dir}/VTK/ScalarTypeMap.h" "${_mcvol_rendering_dir}/VTK/Settings.h")

vtk_module_add_module(mcvol::RenderingMonteCarlo
  CLASSES ${classes}
  SOURCES ${_mcvol_stage_sources}
  PRIVATE_HEADERS ${_mcvol_stage_headers})
# vtk_module_add_module() exports the folder it is called from; the headers
# are here (the Python wrappers and users compile against them).
vtk_module_include(mcvol::RenderingMonteCarlo
  PUBLIC
    "$<BUILD_INTERFACE:${_mcvol_rendering_dir}>")

foreach (_mcvol_core_target IN ITEMS mcvol_core mcvol_cpu mcvol_backends)
  if (NOT TARGET "${_mcvol_core_target}")
    message(FATAL_ERROR
      "mcvol::RenderingMonteCarlo needs the target ${_mcvol_core_target} "
      "(Rendering/Core, Rendering/CPU and Rendering/Backends).")
  endif ()
  set_property(TARGET "${_mcvol_core_target}" PROPERTY POSITION_INDEPENDENT_CODE ON)
endforeach ()
# mcvol_backends brings the CPU backend and, when the build has one, the
# CUDA backend.
vtk_module_link(mcvol::RenderingMonteCarlo
  PRIVATE
    mcvol_backends
    mcvol_cpu
    mcvol_core)
