# One accuracy case of `vkloc track`. Arguments: -DVKLOC=path -DWORK=dir -DCASE=name [-DFRAMES=n]
# [-DFILTER=window|ekf] (the simulated cases' inertial fusion; window unless given).
#   castle         ViSP Castle-simu from the GT first pose: mean error <= 2 mm and <= 0.2 deg, none lost
#   castle_offset  same from a first pose 2 cm / 5 deg off: converges (none lost, mean <= 2 mm, 0.2 deg)
# Each case runs with keyframes on the worker thread (the default) and made synchronously.
#   city_hard, room_hard  simulated: per policy (every-frame, when-needed) no frame lost (at most a
#                  quarter bridged by the IMU alone; 30 % with the worker, see below), no stretch
#                  bridged by the IMU alone longer than 0.5 s, median translation error <= 0.5 % of
#                  the median scene depth, median rotation <= 0.3 deg.
#                  These limits were set with the window fit; with the EKF (`vkloc track`'s default)
#                  room hard bridged 8 (sync) and 2-15 (worker) of 100 frames by the IMU alone, and
#                  about one worker run in six had a stretch of 0.9-1.5 s: the filter took
#                  alignments biased on the simulator's blurred frames, its velocity and tilt went
#                  wrong and its gate then refused the right poses. Since a prior that refuses
#                  every pose for LocalizerOptions::restart_after_refused_s restarts, the test
#                  passes (4 sync, 8-10 worker, longest 0.15 s) and is no longer labelled open.
#                  Over 15 s room hard also failed with the window fit (29 of 301 frames, frames 126-157 in one stretch: the simplified model's rug,
#                  whiteboard and books have lost their texture, 35-42 % inliers at 0.66-0.76 px).
# Skipped when the ViSP data is not installed (a "-- skipped: " line, ctest SKIP_REGULAR_EXPRESSION:
# Debian 12 has CMake 3.25, without cmake_language(EXIT)).
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)

# Tracks `seq` and checks the figures; appends a failure line to the parent's `failures`.
function(track_and_check label seq policy mode extra)
  set(dir ${WORK}/${label}_${policy}_${mode})
  file(REMOVE_RECURSE ${dir})
  run("track ${label} ${policy} ${mode}" ${VKLOC} track --sequence ${seq} --out ${dir}/trajectory.txt
      --report ${dir}/report --policy ${policy} --keyframes ${mode} --quiet ${extra})
  set(j ${dir}/report/track.json)
  foreach(key frames lost inertial visual_rejected hz_median startup_ms first_frame_ms scene_depth_median_m translation_median_m
              translation_mean_m rotation_median_deg rotation_mean_deg localized_fraction translation_median_over_depth
              inertial_longest_s)
    json_number(${key} ${j} ${key})
  endforeach()
  message(STATUS "${label} ${policy} ${mode}: ${frames} frames, lost ${lost}, inertial only ${inertial} (longest "
                 "${inertial_longest_s} s; visual rejected "
                 "${visual_rejected}), translation median ${translation_median_m} m "
                 "mean ${translation_mean_m} m, rotation median ${rotation_median_deg} deg mean ${rotation_mean_deg} "
                 "deg, scene depth ${scene_depth_median_m} m, ${hz_median} Hz (start-up ${startup_ms} ms, first "
                 "frame ${first_frame_ms} ms)")
  set(bad "")
  if(label STREQUAL "castle_offset")
    # Converges: lost frames only before the first tracked one, at most 10 of them.
    json_number(first ${j} first_tracked_frame)
    json_number(after ${j} lost_after_first_tracked)
    message(STATUS "  first tracked frame ${first}, lost after it ${after}")
    if(first LESS 0 OR first GREATER 10 OR NOT after EQUAL 0)
      string(APPEND bad " did not converge (first tracked frame ${first}, lost after it ${after});")
    endif()
  elseif(NOT lost EQUAL 0)
    string(APPEND bad " lost ${lost} frames;")
  endif()
  # Frames bridged by the IMU alone (state "inertial") are localized, but a sequence that needs
  # many of them is no longer a test of the visual tracker: at most a quarter. With the worker,
  # which keyframe a frame meets depends on thread timing, so the count varies from run to run
  # (city_hard: 13-20 in 20 runs on an idle machine, 26 once in a full CI run, where the synchronous
  # mode gives 18-19 every time): 30 % there, so that the test fails on a regression, not on a
  # schedule.
  if(mode STREQUAL "worker")
    math(EXPR inertial_limit "${frames} * 3 / 10")
  else()
    math(EXPR inertial_limit "${frames} / 4")
  endif()
  if(inertial GREATER inertial_limit)
    string(APPEND bad " ${inertial} frames inertial only (> ${inertial_limit});")
  endif()
  # Simulated scenarios: no stretch bridged by the IMU alone longer than 0.5 s.
  if(NOT label MATCHES "^castle" AND inertial_longest_s GREATER 0.5)
    string(APPEND bad " ${inertial_longest_s} s inertial only in one stretch (> 0.5 s);")
  endif()
  if(label MATCHES "^castle")
    if(translation_mean_m GREATER 0.002)
      string(APPEND bad " mean translation ${translation_mean_m} m > 0.002;")
    endif()
    if(rotation_mean_deg GREATER 0.2)
      string(APPEND bad " mean rotation ${rotation_mean_deg} deg > 0.2;")
    endif()
  else()
    # 0.5 % of the median scene depth (if() compares decimal numbers as doubles).
    if(translation_median_over_depth GREATER 0.005)
      string(APPEND bad " median translation ${translation_median_m} m > 0.5 % of the scene depth ${scene_depth_median_m} m;")
    endif()
    if(rotation_median_deg GREATER 0.3)
      string(APPEND bad " median rotation ${rotation_median_deg} deg > 0.3;")
    endif()
  endif()
  if(bad)
    set(failures "${failures}\n  ${label} ${policy} ${mode}:${bad}" PARENT_SCOPE)
  endif()
endfunction()

set(failures "")
if(CASE MATCHES "^castle")
  set(castle /usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu)
  if(NOT EXISTS ${castle})
    message(STATUS "skipped: ${castle} not installed (Debian package visp-images-data)")
    return()
  endif()
  set(seq ${WORK}/castle_sequence)
  if(NOT EXISTS ${seq}/images.txt)
    run("import visp" ${VKLOC} import visp ${castle} --out ${seq})
  endif()
  if(CASE STREQUAL "castle")
    foreach(policy every-frame when-needed)
      foreach(mode worker sync)
        track_and_check(castle ${seq} ${policy} ${mode} "")
      endforeach()
    endforeach()
  else()
    # 2 cm (1.155 cm per axis) and 5 degrees (2.887 degrees about each camera axis).
    foreach(mode worker sync)
      track_and_check(castle_offset ${seq} when-needed ${mode}
                      "--init-offset=0.011547,0.011547,0.011547,2.8868,2.8868,2.8868")
    endforeach()
  endif()
else()
  string(REGEX MATCH "^(city|room)_(easy|hard)$" ok "${CASE}")
  if(NOT ok)
    message(FATAL_ERROR "unknown CASE '${CASE}'")
  endif()
  set(scene ${CMAKE_MATCH_1})
  set(difficulty ${CMAKE_MATCH_2})
  if(NOT FRAMES)
    set(FRAMES 100)
  endif()
  if(NOT FILTER)
    set(FILTER window)
  endif()
  set(label ${CASE})
  if(NOT FILTER STREQUAL "window")
    set(label ${CASE}_${FILTER})
  endif()
  set(seq ${WORK}/${label}_sequence)
  file(REMOVE_RECURSE ${seq})
  run("simulate ${CASE}" ${VKLOC} simulate ${scene} ${difficulty} --frames ${FRAMES} --out ${seq})
  foreach(policy every-frame when-needed)
    foreach(mode worker sync)
      track_and_check(${label} ${seq} ${policy} ${mode} "--filter;${FILTER}")
    endforeach()
  endforeach()
endif()
if(failures)
  message(FATAL_ERROR "below the requirements:${failures}")
endif()
