# Helpers of the CMake-script tests (run with cmake -P; include with
# include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)).

# run(<what> <command> [args...]): fails the test unless the command exits 0; its standard output
# is left in `out` in the caller's scope.
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

# run_ok(<what> [vkloc args...]): run() of the tool at ${VKLOC}.
function(run_ok what)
  run("${what}" ${VKLOC} ${ARGN})
  set(out "${out}" PARENT_SCOPE)
endfunction()

# run_fails(<what> <pattern> [vkloc args...]): fails the test unless the tool at ${VKLOC} exits
# non-zero with a standard error that matches the regular expression <pattern>.
function(run_fails what pattern)
  execute_process(COMMAND ${VKLOC} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected a failure matching '${pattern}', got ${rc}:\n${out}\n${err}")
  endif()
endfunction()

# Sets `var` to the value of `key` in the JSON file `file`; fails naming both when it is missing.
function(json_number var file key)
  file(READ ${file} text)
  string(JSON value ERROR_VARIABLE error GET "${text}" ${key})
  if(error)
    message(FATAL_ERROR "${file}: no '${key}': ${error}")
  endif()
  set(${var} ${value} PARENT_SCOPE)
endfunction()
