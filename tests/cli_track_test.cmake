# End-to-end test of `vkloc track`: a short simulated sequence, outputs, and errors that keep
# what was already written. Arguments: -DVKLOC=path -DWORK=dir.
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK})

function(run_ok what)
  execute_process(COMMAND ${VKLOC} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()
function(run_fails what pattern)
  execute_process(COMMAND ${VKLOC} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected a failure matching '${pattern}', got ${rc}:\n${out}\n${err}")
  endif()
endfunction()

set(seq ${WORK}/room)
run_ok("simulate" simulate room easy --frames 6 --out ${seq} --no-imu --no-priors)
run_ok("track" track --sequence ${seq} --out ${WORK}/out/traj.txt --frames-csv ${WORK}/out/frames.csv
       --policy every-frame --backend cpu)
if(NOT out MATCHES "tracked 6 frames" OR NOT out MATCHES "Hz" OR NOT out MATCHES "report: ")
  message(FATAL_ERROR "track output lacks the summary:\n${out}")
endif()
file(STRINGS ${WORK}/out/frames.csv rows)
list(LENGTH rows n)
list(GET rows 0 header)
if(NOT n EQUAL 7 OR NOT header MATCHES "^t_ns,state,render_ms,reference_ms,live_ms,align_ms,total_ms,inlier_ratio")
  message(FATAL_ERROR "frames.csv: ${n} lines, header '${header}'")
endif()
foreach(f out/traj_report/report.html out/traj_report/report.json out/traj_report/track.json)
  if(NOT EXISTS ${WORK}/${f})
    message(FATAL_ERROR "missing ${WORK}/${f}")
  endif()
endforeach()
# The evaluation reads the written files back.
run_ok("eval" eval --estimate ${WORK}/out/traj.txt --sequence ${seq} --frames ${WORK}/out/frames.csv)

# The tracking benchmark on the same sequence: both backends in one process, a row each.
run_ok("bench track" bench track --sequence ${seq} --runs 1 --backends cpu,vulkan)
if(NOT out MATCHES "\ncpu +[0-9.]+ +[0-9.]+" OR NOT out MATCHES "\nvulkan +[0-9.]+ +[0-9.]+")
  message(FATAL_ERROR "bench track output lacks a row per backend:\n${out}")
endif()
run_fails("bench track, missing sequence" "not found" bench track --sequence ${WORK}/nope)
# The live-stage benchmark: GPU stages, GPU vs CPU; a frame index past the end is an error.
run_ok("bench live" bench live --sequence ${seq} --runs 2)
if(NOT out MATCHES "edge lines +[0-9.]+" OR NOT out MATCHES "GPU / CPU \\(medians\\): [0-9.]+")
  message(FATAL_ERROR "bench live output lacks the stages or the ratio:\n${out}")
endif()
run_fails("bench live, bad frame" "--frame 99" bench live --sequence ${seq} --frame 99)

# Errors: missing sequence, bad option values, bad --init-offset.
run_fails("missing sequence" "not|No such" track --sequence ${WORK}/nope --out ${WORK}/x.txt)
run_fails("bad backend" "backend" track --sequence ${seq} --out ${WORK}/x.txt --backend gpu)
run_fails("bad offset" "init-offset" track --sequence ${seq} --out ${WORK}/x.txt --init-offset 1,2)

# A corrupt image in the middle: the run stops with the image's name, frames before it are kept.
file(STRINGS ${seq}/images.txt lines REGEX "^[0-9]")
list(GET lines 3 fourth)
string(REGEX REPLACE "^[^ ]+ +" "" fourth_path "${fourth}")
file(WRITE ${seq}/${fourth_path} "not an image")
run_fails("corrupt image" "${fourth_path}" track --sequence ${seq} --out ${WORK}/cut/traj.txt --backend cpu)
file(STRINGS ${WORK}/cut/traj_frames.csv cut_rows)
list(LENGTH cut_rows m)
if(NOT m EQUAL 4)
  message(FATAL_ERROR "after a corrupt 4th image the frames log should keep 3 rows, has ${m} lines")
endif()
