# End-to-end test of `vkloc bench remap`: a few runs with and without Vulkan, the table, the
# summary and the CSV, and a bad option. Timings are not checked. Arguments: -DVKLOC=path -DWORK=dir.
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# With Vulkan (validation on): GPU rows and their agreement, nothing on stderr.
execute_process(COMMAND ${VKLOC} bench remap --runs 3 --size 320x240 RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err STREQUAL "")
  message(FATAL_ERROR "bench remap failed (${rc}) or printed to stderr:\n${out}\n${err}")
endif()
foreach(row "undistort: CameraFront::remap \\(OpenCV\\) +[0-9.]+ +[0-9.]+" "undistort: GpuRemap::remap, wall +[0-9.]+"
        "stabilised: grid table \\+ OpenCV remap +[0-9.]+" "agreement undistort: GPU vs reference +- +- +[0-9.]+ %"
        "\nsummary: ")
  if(NOT out MATCHES "${row}")
    message(FATAL_ERROR "bench remap output lacks '${row}':\n${out}")
  endif()
endforeach()

# Without Vulkan: the GPU rows say they were skipped; the CSV has a header and a row per stage.
run_ok("bench remap --no-vulkan" bench remap --runs 2 --size 320x240 --no-vulkan --csv ${WORK}/remap.csv)
if(NOT out MATCHES "skipped \\(--no-vulkan\\)" OR out MATCHES "GPU vs reference")
  message(FATAL_ERROR "bench remap --no-vulkan output:\n${out}")
endif()
file(STRINGS ${WORK}/remap.csv rows)
list(LENGTH rows n)
list(GET rows 0 header)
if(NOT header STREQUAL "stage,median_ms,p90_ms,runs,notes" OR n LESS 10)
  message(FATAL_ERROR "remap.csv: ${n} lines, header '${header}'")
endif()

run_fails("bench remap, bad size" "--size" bench remap --size 320x)
run_fails("bench remap, no runs" "runs" bench remap --runs 0)
