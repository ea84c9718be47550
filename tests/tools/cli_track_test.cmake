# End-to-end test of `vkloc track`: a short simulated sequence, outputs, and errors that keep
# what was already written. Arguments: -DVKLOC=path -DWORK=dir.
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)
file(REMOVE_RECURSE ${WORK})

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
foreach(f out/traj_report/report.html out/traj_report/report.json out/traj_report/track.json out/traj_visual.txt)
  if(NOT EXISTS ${WORK}/${f})
    message(FATAL_ERROR "missing ${WORK}/${f}")
  endif()
endforeach()
# The alignments' own poses beside the trajectory: one per tracked frame (here, without an IMU,
# the trajectory's own).
file(STRINGS ${WORK}/out/traj_visual.txt visual_poses REGEX "^[0-9]")
file(STRINGS ${WORK}/out/traj.txt poses REGEX "^[0-9]")
if(NOT visual_poses STREQUAL poses)
  message(FATAL_ERROR "traj_visual.txt differs from traj.txt without a filter:\n${visual_poses}\n${poses}")
endif()
# The evaluation reads the written files back.
run_ok("eval" eval --estimate ${WORK}/out/traj.txt --sequence ${seq} --frames ${WORK}/out/frames.csv)

# The tracking benchmark on the same sequence: both backends in one process, a row each.
run_ok("bench track" bench track --sequence ${seq} --runs 1 --backends cpu,vulkan)
if(NOT out MATCHES "\ncpu +worker +[0-9.]+ +[0-9.]+" OR NOT out MATCHES "\nvulkan +sync +[0-9.]+ +[0-9.]+")
  message(FATAL_ERROR "bench track output lacks a row per backend:\n${out}")
endif()
run_fails("bench track, missing sequence" "not found" bench track --sequence ${WORK}/nope)
# The live-stage benchmark: GPU stages, GPU vs CPU; a frame index past the end is an error.
run_ok("bench live" bench live --sequence ${seq} --runs 2)
if(NOT out MATCHES "edge lines +[0-9.]+" OR NOT out MATCHES "GPU / CPU \\(medians\\): [0-9.]+")
  message(FATAL_ERROR "bench live output lacks the stages or the ratio:\n${out}")
endif()
run_fails("bench live, bad frame" "--frame 99" bench live --sequence ${seq} --frame 99)
run_ok("bench live, CPU only" bench live --sequence ${seq} --runs 2 --no-vulkan)
if(NOT out MATCHES "CPU only" OR NOT out MATCHES "CPU frame \\(buildLiveFrame\\): median [0-9.]+ ms" OR
   out MATCHES "edge lines")
  message(FATAL_ERROR "bench live --no-vulkan output:\n${out}")
endif()
# Frames at the camera's pace (timestamps 1/30 s apart here).
run_ok("bench track, camera pace" bench track --sequence ${seq} --runs 1 --backends cpu --keyframes worker
       --pace camera)
if(NOT out MATCHES "camera's pace" OR NOT out MATCHES "\ncpu +worker +[0-9.]+ +[0-9.]+")
  message(FATAL_ERROR "bench track --pace camera output:\n${out}")
endif()
# A keyframe's render and edge points at a true pose, on the device and on the CPU rasterizer.
run_ok("bench keyframe" bench keyframe --sequence ${seq} --frame 2 --runs 2)
if(NOT out MATCHES "render \\(colour, depth, normals\\) +[0-9.]+ ms" OR
   NOT out MATCHES "edge points, one thread \\(worker\\) +[0-9.]+ ms" OR
   NOT out MATCHES "edge points, thread pool \\(sync\\) +[0-9.]+ ms" OR NOT out MATCHES "[1-9][0-9]* edge points at level 0")
  message(FATAL_ERROR "bench keyframe output:\n${out}")
endif()
run_ok("bench keyframe, CPU rasterizer" bench keyframe --sequence ${seq} --runs 1 --no-vulkan)
if(NOT out MATCHES "CPU reference renderer")
  message(FATAL_ERROR "bench keyframe --no-vulkan output:\n${out}")
endif()
run_fails("bench keyframe, bad frame" "--frame 99" bench keyframe --sequence ${seq} --frame 99)
# Without ground truth there is no true pose to render a keyframe at: a one-line error.
file(COPY ${seq}/ DESTINATION ${WORK}/no_truth)
file(REMOVE ${WORK}/no_truth/groundtruth.txt)
run_fails("bench keyframe, no ground truth" "no ground-truth pose" bench keyframe --sequence ${WORK}/no_truth --runs 1)

# Errors: missing sequence, bad option values, bad --init-offset.
run_fails("missing sequence" "not|No such" track --sequence ${WORK}/nope --out ${WORK}/x.txt)
run_fails("bad backend" "backend" track --sequence ${seq} --out ${WORK}/x.txt --backend gpu)
run_fails("bad offset" "init-offset" track --sequence ${seq} --out ${WORK}/x.txt --init-offset 1,2)
run_fails("huge offset rotation" "init-offset: rx = 1e\\+308 is outside" track --sequence ${seq} --out ${WORK}/x.txt
          --init-offset 0,0,0,1e308,0,0)
run_fails("negative frame count" "max-frames" track --sequence ${seq} --out ${WORK}/x.txt --max-frames -1)

# A corrupt image in the middle: the run stops with the image's name; the previous run's files
# at --out are untouched, and the frames tracked before are kept in "<file>.partial" (said so).
run_ok("track before corruption" track --sequence ${seq} --out ${WORK}/cut/traj.txt --backend cpu --max-frames 8
       --keyframes sync)
file(READ ${WORK}/cut/traj.txt previous_traj)
file(READ ${WORK}/cut/traj_frames.csv previous_frames)
file(STRINGS ${seq}/images.txt lines REGEX "^[0-9]")
list(GET lines 3 fourth)
string(REGEX REPLACE "^[^ ]+ +" "" fourth_path "${fourth}")
file(WRITE ${seq}/${fourth_path} "not an image")
run_fails("corrupt image" "${fourth_path}.*traj.txt.partial" track --sequence ${seq} --out ${WORK}/cut/traj.txt
          --backend cpu)
file(READ ${WORK}/cut/traj.txt after_traj)
file(READ ${WORK}/cut/traj_frames.csv after_frames)
if(NOT after_traj STREQUAL previous_traj OR NOT after_frames STREQUAL previous_frames)
  message(FATAL_ERROR "a failed run changed the previous run's trajectory or frames log")
endif()
file(STRINGS ${WORK}/cut/traj_frames.csv.partial cut_rows)
list(LENGTH cut_rows m)
if(NOT m EQUAL 4)
  message(FATAL_ERROR "after a corrupt 4th image the partial frames log should keep 3 rows, has ${m} lines")
endif()
file(STRINGS ${WORK}/cut/traj.txt.partial cut_poses REGEX "^[0-9]")
list(LENGTH cut_poses p)
if(NOT p EQUAL 3)
  message(FATAL_ERROR "after a corrupt 4th image the partial trajectory should keep 3 poses, has ${p}")
endif()
