# End-to-end test of the keyframe database: `vkloc keyframes build/info`, `vkloc track --db
# --global-init` (a first pose found from the database), `vkloc bench reloc`, and the files and
# options it refuses with one line. Arguments: -DVKLOC=path -DWORK=dir.
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)
file(REMOVE_RECURSE ${WORK})

set(seq ${WORK}/room)
run_ok("simulate" simulate room easy --frames 6 --out ${seq} --no-priors)
set(db ${WORK}/room.kdb)
run_ok("keyframes build" keyframes build --sequence ${seq} --out ${db} --spacing 0.5 --margin 0.5 --headings 12
       --renderer cpu --threads 2 -q)
if(NOT out MATCHES "keyframes: [1-9][0-9]* of [0-9]+ views kept" OR NOT out MATCHES "7[0-9.]+ bytes per keyframe")
  message(FATAL_ERROR "keyframes build output lacks the counts:\n${out}")
endif()
run_ok("keyframes info" keyframes info ${db} --sequence ${seq})
if(NOT out MATCHES "matches the sequence's model")
  message(FATAL_ERROR "keyframes info did not check the model:\n${out}")
endif()

# Global initialization: no pose given, the database searched around a prior 0.3 m off.
run_ok("track --global-init" track --sequence ${seq} --out ${WORK}/gi/traj.txt --db ${db} --global-init
       --prior-sigma 0.3 --backend cpu --keyframes sync)
if(NOT out MATCHES "global initialization within" OR NOT out MATCHES "[1-9][0-9]* relocalized")
  message(FATAL_ERROR "track --global-init did not relocalize:\n${out}")
endif()
file(STRINGS ${WORK}/gi/traj_frames.csv rows)
list(GET rows 0 header)
list(GET rows 1 first)
list(GET rows 2 second)
# The search's pose (first frame) is reported once the next frame, IMU-propagated, confirms it.
if(NOT header MATCHES "relocalization_candidates,search_radius_m,relocalization_ms,front_ms,view_tilt_deg,image_content,image_contrast,pose_filtered$"
   OR NOT first MATCHES "^[0-9]+,initializing," OR NOT second MATCHES "^[0-9]+,relocalized,")
  message(FATAL_ERROR "frames log: header '${header}', first frame '${first}', second '${second}'")
endif()
json_number(median ${WORK}/gi/traj_report/track.json translation_median_m)
if(median GREATER 0.05)
  message(FATAL_ERROR "global initialization tracked with a median error of ${median} m")
endif()

# A sequence that gives no start pose (no initial_T_world_camera, no ground truth): with --db
# alone the first pose is searched for over the whole database; without it, one line says what
# to give.
set(nopose ${WORK}/nopose)
file(MAKE_DIRECTORY ${nopose})
foreach(item camera.yaml images.txt imu.csv images)
  file(COPY ${seq}/${item} DESTINATION ${nopose})
endforeach()
file(GLOB model_files ${seq}/*.glb ${seq}/*.obj ${seq}/*.mtl ${seq}/*.drc ${seq}/*.png)
file(COPY ${model_files} DESTINATION ${nopose})
file(STRINGS ${seq}/sequence.yaml yaml_lines)
set(yaml "")
foreach(line IN LISTS yaml_lines)
  if(NOT line MATCHES "^initial_T_world_camera")
    string(APPEND yaml "${line}\n")
  endif()
endforeach()
file(WRITE ${nopose}/sequence.yaml "${yaml}")
run_fails("no start pose, no database" "no initial_T_world_camera.*pass --db" track --sequence ${nopose}
          --out ${WORK}/x/traj.txt --backend cpu)
run_ok("track with no start pose" track --sequence ${nopose} --out ${WORK}/np/traj.txt --db ${db} --backend cpu
       --keyframes sync)
if(NOT out MATCHES "global initialization over the whole database \\(the sequence gives no start pose\\)"
   OR NOT out MATCHES "[1-9][0-9]* relocalized")
  message(FATAL_ERROR "track with no start pose did not search the database:\n${out}")
endif()
run_fails("an offset of no start pose" "--init-offset: the sequence gives no start pose" track --sequence ${nopose}
          --out ${WORK}/x/traj.txt --db ${db} --init-offset 0.1,0,0,0,0,0 --backend cpu)
# A sequence that gives its start pose starts there, with or without a database.
run_ok("track from the start pose with a database" track --sequence ${seq} --out ${WORK}/sp/traj.txt --db ${db}
       --backend cpu --keyframes sync)
if(out MATCHES "global initialization" OR NOT out MATCHES "0 initializing")
  message(FATAL_ERROR "track --db from a start pose searched the database:\n${out}")
endif()
run_ok("eval of the no-start-pose run" eval --estimate ${WORK}/np/traj.txt --groundtruth ${seq}/groundtruth.txt
       --json ${WORK}/np/eval.json)
json_number(median ${WORK}/np/eval.json "ate;translation_m;median")
if(median GREATER 0.05)
  message(FATAL_ERROR "no start pose: tracked with a median error of ${median} m")
endif()

run_ok("bench reloc" bench reloc --sequence ${seq} --db ${db} --queries 3 --no-vulkan)
if(NOT out MATCHES "ms per 1000 keyframes" OR NOT out MATCHES "recovered \\(verified"
   OR NOT out MATCHES "retrieval after the re-ranking")
  message(FATAL_ERROR "bench reloc output lacks its figures:\n${out}")
endif()
# Global-initialization trials: seeded frames with no pose, a prior 0.3 m (1 sigma) off.
run_ok("bench reloc start trials" bench reloc --sequence ${seq} --db ${db} --queries 0 --trials 2 --loss start
       --prior-sigma 0.3 --start-frames 3 --no-vulkan)
if(NOT out MATCHES "global initialization from a prior of sigma 0.3 m" OR NOT out MATCHES "in 2 of 2 starts"
   OR out MATCHES "recovered \\(verified")
  message(FATAL_ERROR "bench reloc start trials:\n${out}")
endif()
run_fails("start trials longer than the sequence" "shorter than --start-frames" bench reloc --sequence ${seq}
          --db ${db} --queries 0 --trials 1 --loss start --start-frames 50 --no-vulkan)

# Refused with one line: a truncated database, one built for another model, --global-init
# without a database, a placement that would render too many views.
file(SIZE ${db} size)
math(EXPR cut_size "${size} - 100")
execute_process(COMMAND head -c ${cut_size} ${db} OUTPUT_FILE ${WORK}/cut.kdb RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "head -c failed")
endif()
run_fails("truncated database" "cut.kdb: truncated or damaged" keyframes info ${WORK}/cut.kdb)
run_ok("other model's database" keyframes build --model city --intrinsics 500,500,319.5,239.5,640,480
       --volume 0,0,20,10,10,20 --spacing 10 --headings 2 --tilts 45 --renderer cpu --out ${WORK}/city.kdb -q)
# "--spacing auto" (the default): a fraction of the typical depth, here from a coarse grid of the
# volume's own views (no ground truth); the city 20 m up, 45 deg down, ~28 m deep.
run_ok("auto spacing" keyframes build --model city --intrinsics 500,500,319.5,239.5,640,480
       --volume 0,0,20,10,10,20 --headings 2 --tilts 45 --renderer cpu --out ${WORK}/city_auto.kdb)
if(NOT out MATCHES "spacing ([0-9.]+) m \\(auto: 0.12 x the scene's typical depth ([0-9.]+) m, from [0-9]+ views of a coarse grid\\)")
  message(FATAL_ERROR "keyframes build --spacing auto output:\n${out}")
endif()
if(CMAKE_MATCH_1 LESS 1 OR CMAKE_MATCH_1 GREATER 8 OR CMAKE_MATCH_2 LESS 10 OR CMAKE_MATCH_2 GREATER 60)
  message(FATAL_ERROR "keyframes build --spacing auto: spacing ${CMAKE_MATCH_1} m from depth ${CMAKE_MATCH_2} m")
endif()
run_fails("spacing neither metres nor auto" "--spacing" keyframes build --model city
          --intrinsics 500,500,319.5,239.5,640,480 --volume 0,0,20,10,10,20 --spacing fine --out ${WORK}/x.kdb)
run_fails("spacing out of range" "expected 0.001..1e6 m or auto" keyframes build --model city
          --intrinsics 500,500,319.5,239.5,640,480 --volume 0,0,20,10,10,20 --spacing 0 --out ${WORK}/x.kdb)
run_fails("database of another model" "another model" track --sequence ${seq} --out ${WORK}/x/traj.txt
          --db ${WORK}/city.kdb --backend cpu)
run_fails("global init without a database" "--global-init needs --db" track --sequence ${seq}
          --out ${WORK}/x/traj.txt --global-init --backend cpu)
run_fails("too many views" "exceed the limit" keyframes build --sequence ${seq} --out ${WORK}/x.kdb --spacing 0.001
          --renderer cpu)
run_fails("missing database" "not|No such" track --sequence ${seq} --out ${WORK}/x/traj.txt --db ${WORK}/nope.kdb)
# A corridor: only the positions within its radius of a path (the ground truth, or --path).
run_ok("corridor build" keyframes build --sequence ${seq} --out ${WORK}/tube.kdb --spacing 0.25 --margin 0.5
       --corridor 0.3 --headings 4 --renderer cpu --threads 2)
if(NOT out MATCHES "within 0.3 m of a path of [0-9]+ poses" OR NOT out MATCHES "keyframes: [1-9][0-9]* of")
  message(FATAL_ERROR "keyframes build --corridor output:\n${out}")
endif()
run_ok("corridor build from a path file" keyframes build --sequence ${seq} --out ${WORK}/tube2.kdb --spacing 0.25
       --corridor 0.3 --path ${seq}/groundtruth.txt --headings 4 --renderer cpu --threads 2 -q)
run_fails("a path without a corridor" "--path is the corridor's path: give --corridor" keyframes build
          --sequence ${seq} --out ${WORK}/x.kdb --path ${seq}/groundtruth.txt --renderer cpu)
run_fails("a corridor's missing path" "nope.tum" keyframes build --sequence ${seq} --out ${WORK}/x.kdb
          --corridor 1 --path ${WORK}/nope.tum --renderer cpu)
run_fails("a corridor with too many views" "corridor holds more than" keyframes build --sequence ${seq}
          --out ${WORK}/x.kdb --corridor 1 --spacing 0.002 --renderer cpu)
