# End-to-end test of `vkloc track --overlay`: overlay images of every Nth frame and their CSV, a
# frame whose overlay cannot be written reported without stopping tracking, bad options.
# Arguments: -DVKLOC=path -DWORK=dir.
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)
file(REMOVE_RECURSE ${WORK})

set(seq ${WORK}/room)
run_ok("simulate" simulate room easy --frames 5 --out ${seq} --no-imu --no-priors)
run_ok("track --overlay" track --sequence ${seq} --out ${WORK}/out/traj.txt --backend cpu --keyframes sync
       --overlay ${WORK}/ov --overlay-every 2)
if(NOT out MATCHES "overlays: 3 written to")
  message(FATAL_ERROR "track --overlay output lacks the overlay line:\n${out}")
endif()
foreach(f frame_000000.png frame_000002.png frame_000004.png overlays.csv)
  if(NOT EXISTS ${WORK}/ov/${f})
    message(FATAL_ERROR "missing ${WORK}/ov/${f}")
  endif()
endforeach()
if(EXISTS ${WORK}/ov/frame_000001.png OR EXISTS ${WORK}/ov/overlays.csv.partial)
  message(FATAL_ERROR "--overlay-every 2 wrote frame 1, or the CSV was left partial")
endif()
file(READ ${WORK}/ov/frame_000000.png png LIMIT 8 HEX)
if(NOT png STREQUAL "89504e470d0a1a0a")
  message(FATAL_ERROR "frame_000000.png is not a PNG (${png})")
endif()
file(STRINGS ${WORK}/ov/overlays.csv rows)
list(LENGTH rows n)
list(GET rows 0 header)
list(GET rows 1 first)
if(NOT n EQUAL 4 OR NOT header MATCHES "^frame,t_ns,file,state,tracker_inlier_ratio,points_in_image,inliers"
   OR NOT first MATCHES "^0,[0-9]+,frame_000000.png,tracking,[0-9.]+,[0-9]+,[0-9]+,[0-9.]+,[0-9.]+,[0-9.]+,[0-9.]+,")
  message(FATAL_ERROR "overlays.csv: ${n} lines, header '${header}', first row '${first}'")
endif()

# A frame whose overlay cannot be written (a folder holds its name): one warning, tracking and
# the other overlays go on, the summary counts it.
file(REMOVE_RECURSE ${WORK}/ov)
file(MAKE_DIRECTORY ${WORK}/ov/frame_000002.png)
execute_process(COMMAND ${VKLOC} track --sequence ${seq} --out ${WORK}/out/traj.txt --backend cpu --keyframes sync
                --overlay ${WORK}/ov --overlay-every 2 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err MATCHES "overlay of frame 2 not written" OR NOT out MATCHES "overlays: 2 written.*1 failed"
   OR NOT out MATCHES "tracked 5 frames")
  message(FATAL_ERROR "a failed overlay should be reported and tracking go on (${rc}):\n${out}\n${err}")
endif()

# Bad options: one line, before tracking.
run_fails("overlay-every 0" "overlay-every" track --sequence ${seq} --out ${WORK}/x.txt --overlay ${WORK}/ov2
          --overlay-every 0)
file(WRITE ${WORK}/a_file "")
run_fails("overlay folder is a file" "--overlay .*a_file" track --sequence ${seq} --out ${WORK}/x.txt
          --overlay ${WORK}/a_file/sub)
