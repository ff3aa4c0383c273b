# mcvol_detect_cuda_architectures(<var>)
#
# Sets <var> to the CUDA architectures of the GPUs that nvidia-smi lists
# ("90" for compute capability 9.0), each once, or to an empty string where
# nvidia-smi is missing or lists no GPU. A build then compiles the kernels only
# for the cards that will run them.
function (mcvol_detect_cuda_architectures out_var)
  set(_archs "")
  find_program(MCVOL_NVIDIA_SMI nvidia-smi
    HINTS /usr/bin /usr/local/nvidia/bin /usr/lib/wsl/lib)
  mark_as_advanced(MCVOL_NVIDIA_SMI)
  if (MCVOL_NVIDIA_SMI)
    execute_process(
      COMMAND "${MCVOL_NVIDIA_SMI}" --query-gpu=compute_cap --format=csv,noheader
      OUTPUT_VARIABLE _caps
      RESULT_VARIABLE _result
      ERROR_QUIET
      TIMEOUT 30)
    if (_result EQUAL 0)
      string(REGEX MATCHALL "[0-9]+\\.[0-9]+" _caps "${_caps}")
      foreach (_cap IN LISTS _caps)
        string(REPLACE "." "" _arch "${_cap}")
        list(APPEND _archs "${_arch}")
      endforeach ()
      list(REMOVE_DUPLICATES _archs)
    endif ()
  endif ()
  set(${out_var} "${_archs}" PARENT_SCOPE)
endfunction ()
