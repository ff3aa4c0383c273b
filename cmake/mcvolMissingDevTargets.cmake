# ParaView's VTK links some modules against system libraries through imported
# targets (VTK::glew -> GLEW::GLEW, VTK::tiff -> TIFF::TIFF) that only exist
# when the library's -dev package is installed. Nothing in mcvol includes
# those libraries' headers, so where the -dev package is missing but the
# runtime library that ParaView itself loads is present, define the target on
# the runtime library. Installing the -dev packages (libglew-dev, libtiff-dev)
# makes this a no-op.
option(MCVOL_STUB_MISSING_DEV_TARGETS
  "Define missing GLEW::GLEW/TIFF::TIFF targets on the runtime libraries" ON)
mark_as_advanced(MCVOL_STUB_MISSING_DEV_TARGETS)
if (NOT MCVOL_STUB_MISSING_DEV_TARGETS)
  return ()
endif ()

# Debian's ParaView imports its libraries for the DEBUG configuration only.
get_target_property(_mcvol_configs VTK::CommonCore IMPORTED_CONFIGURATIONS)
set(_mcvol_vtk_core_location)
foreach (_mcvol_config IN LISTS _mcvol_configs)
  get_target_property(_mcvol_vtk_core_location VTK::CommonCore "IMPORTED_LOCATION_${_mcvol_config}")
  if (_mcvol_vtk_core_location)
    break ()
  endif ()
endforeach ()
if (NOT _mcvol_vtk_core_location)
  return ()
endif ()
get_filename_component(_mcvol_libdir "${_mcvol_vtk_core_location}" DIRECTORY)

foreach (_mcvol_pair IN ITEMS "GLEW::GLEW=libGLEW.so" "TIFF::TIFF=libtiff.so")
  string(REPLACE "=" ";" _mcvol_pair "${_mcvol_pair}")
  list(GET _mcvol_pair 0 _mcvol_target)
  list(GET _mcvol_pair 1 _mcvol_stem)
  if (TARGET "${_mcvol_target}")
    continue ()
  endif ()
  file(GLOB _mcvol_candidates "${_mcvol_libdir}/${_mcvol_stem}.*")
  list(SORT _mcvol_candidates)
  list(LENGTH _mcvol_candidates _mcvol_count)
  if (_mcvol_count EQUAL 0)
    continue ()
  endif ()
  list(GET _mcvol_candidates 0 _mcvol_library) # shortest: libX.so.N
  add_library("${_mcvol_target}" SHARED IMPORTED)
  set_target_properties("${_mcvol_target}" PROPERTIES IMPORTED_LOCATION "${_mcvol_library}")
  message(STATUS "mcvol: ${_mcvol_target} not found (no -dev package); "
    "linking the runtime library ${_mcvol_library}")
endforeach ()
