# End-to-end test of `vkloc simulate`, `vkloc import visp` and `vkloc eval` through the CLI.
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)
file(REMOVE_RECURSE ${WORK})

# A small simulated sequence with every appearance change and model damage on.
run_ok("simulate room hard" simulate room hard --frames 3 --intrinsics 100,100,63.5,47.5,128,96 --out ${WORK}/room)
foreach(f sequence.yaml camera.yaml images.txt groundtruth.txt imu.csv prior.csv)
  if(NOT EXISTS ${WORK}/room/${f})
    message(FATAL_ERROR "vkloc simulate did not write ${f}: ${out}")
  endif()
endforeach()
file(STRINGS ${WORK}/room/images.txt images REGEX "^[0-9]")
list(LENGTH images n)
if(NOT n EQUAL 3)
  message(FATAL_ERROR "vkloc simulate --frames 3 wrote ${n} images")
endif()

# Ground truth against itself: zero error, every frame localized, reports written.
run_ok("eval" eval --estimate ${WORK}/room/groundtruth.txt --sequence ${WORK}/room --json ${WORK}/eval.json
       --html ${WORK}/eval.html)
file(READ ${WORK}/eval.json json)
string(JSON t_rmse GET "${json}" ate translation_m rmse)
if(NOT t_rmse LESS 1e-9 OR NOT EXISTS ${WORK}/eval.html)
  message(FATAL_ERROR "eval of ground truth against itself: rmse ${t_rmse}: ${out}")
endif()

# A malformed estimate: one-line error naming file and line, exit code 1, earlier output kept.
file(WRITE ${WORK}/bad.txt "0.0 1 2 3 0 0 0 1\n0.05 1 2 three 0 0 0 1\n")
execute_process(COMMAND ${VKLOC} eval --estimate ${WORK}/bad.txt --sequence ${WORK}/room --json ${WORK}/eval.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "bad.txt:2" OR NOT EXISTS ${WORK}/eval.json)
  message(FATAL_ERROR "malformed estimate: rc ${rc}, stderr '${err}'")
endif()

# Devices and pipes are written directly: /dev/null stays a device, a full device is an error
# (the report is not "written" into a regular file replacing /dev/full).
run_ok("eval to /dev/null" eval --estimate ${WORK}/room/groundtruth.txt --sequence ${WORK}/room --json /dev/null)
if(EXISTS /dev/full)
  execute_process(COMMAND ${VKLOC} eval --estimate ${WORK}/room/groundtruth.txt --sequence ${WORK}/room
                  --json /dev/full RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "/dev/full")
    message(FATAL_ERROR "eval --json /dev/full: expected a one-line error, got ${rc}: '${err}'")
  endif()
endif()
execute_process(COMMAND stat -c %F /dev/null /dev/full OUTPUT_VARIABLE kinds)
if(kinds MATCHES "regular")
  message(FATAL_ERROR "a device node was replaced by a regular file: ${kinds}")
endif()

# ViSP Castle-simu (Debian visp-images-data) converted into a sequence.
set(castle /usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu)
if(EXISTS ${castle})
  run_ok("import visp" import visp ${castle} --out ${WORK}/castle)
  if(NOT out MATCHES "frames: +40")
    message(FATAL_ERROR "import visp: ${out}")
  endif()
  run_ok("eval castle" eval --estimate ${WORK}/castle/groundtruth.txt --sequence ${WORK}/castle --json ${WORK}/castle.json)
endif()
