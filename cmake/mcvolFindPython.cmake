# Picks the Python interpreter for ParaView's VTK before find_package(ParaView)
# looks for Python3 itself: the one that can import ParaView's `vtkmodules`.
# A PATH with another interpreter first (pyenv, a virtualenv) would otherwise
# give wrappers built against one Python and tests run with another.
if (DEFINED Python3_EXECUTABLE)
  return ()
endif ()

set(_mcvol_python_candidates)
find_program(_mcvol_python_on_path NAMES python3 NO_CACHE)
if (_mcvol_python_on_path)
  list(APPEND _mcvol_python_candidates "${_mcvol_python_on_path}")
endif ()
# Where distributions install the interpreter their ParaView package targets.
foreach (_mcvol_prefix IN LISTS CMAKE_SYSTEM_PREFIX_PATH)
  if (EXISTS "${_mcvol_prefix}/bin/python3")
    list(APPEND _mcvol_python_candidates "${_mcvol_prefix}/bin/python3")
  endif ()
endforeach ()
list(REMOVE_DUPLICATES _mcvol_python_candidates)

foreach (_mcvol_python IN LISTS _mcvol_python_candidates)
  execute_process(
    COMMAND "${_mcvol_python}" -c "import vtkmodules.vtkCommonCore"
    RESULT_VARIABLE _mcvol_python_result
    OUTPUT_QUIET ERROR_QUIET)
  if (_mcvol_python_result EQUAL 0)
    set(Python3_EXECUTABLE "${_mcvol_python}" CACHE FILEPATH
      "Python interpreter (one that imports ParaView's vtkmodules)")
    message(STATUS "mcvol: Python interpreter with vtkmodules: ${_mcvol_python}")
    break ()
  endif ()
endforeach ()
if (NOT DEFINED Python3_EXECUTABLE)
  message(WARNING
    "mcvol: no python3 found that imports `vtkmodules` (tried: "
    "${_mcvol_python_candidates}); Python tests will fail. Install "
    "python3-paraview or set Python3_EXECUTABLE.")
endif ()
