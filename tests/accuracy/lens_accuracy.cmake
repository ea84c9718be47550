# Accuracy through lenses (issue: cameras as users have them). Arguments: -DVKLOC=path -DWORK=dir
# -DCASE=name [-DRELATIVE=ON]. Without RELATIVE the floors below are checked (regressions); with
# it the issue's comparisons (10 %).
#   fisheye_eis   the agile drone (airframe rolling and pitching ~25 deg at ~1 Hz) in the city,
#                 hard appearance, 210-degree fisheye 45 deg down, 100 frames: tracked through a
#                 stabilised view (EIS, 480x360, 90 deg, axis 45 deg below the horizon, the
#                 default dead band of 25 deg), through the same view fully compensated every
#                 frame (--view-dead-band 0) and through the fixed central crop of the same size:
#                 both stabilised views lose no frame and keep their median error within 0.5 % of
#                 the scene depth, and are bridged by the IMU alone in at most 5 % of the frames
#                 (RELATIVE: the default one's median error is at most 10 % above the crop's; its
#                 view never leaves the band on this drone, so that is the crop's own view; with
#                 FULL the fully compensated view's, label open).
#   fisheye_city_edge   the same drone and lens, seed 4, 300 frames: from frame ~104 the drone
#                 flies along the city's edge and the view's upper half is plain ground; the filter
#                 refuses the poses there and restarts (LocalizerOptions::restart_after_refused_s).
#                 Both views lose no frame and keep the median error within 0.5 % of the scene
#                 depth (a restart at rest, before the restart kept the filter's velocity, left
#                 the stabilised view 44 frames lost and the crop 45 m off over 183 frames).
#   fisheye_acro   the same lens on the acrobatic drone (twice the agile one's swings, up to 43 deg
#                 and 4.4 rad/s, so the default view turns beyond its band; RELATIVE: its median
#                 error at most 10 % above the crop's; the fully compensated view is checked
#                 too), seed 7, 100 frames: the crop's first alignments barely move
#                 while the drone flies 6.7 m/s, the filter takes that velocity and refuses every
#                 pose after; it restarts at a verified pose (not at one scoring 0.03 after poses
#                 verified at 0.47) at an unknown velocity (the velocity it kept was the wrong
#                 thing). Both views lose no frame and keep the median error within 0.5 % of the
#                 scene depth (the crop was 21 m off at the median before, bridged 300 m off).
#                 With -DVULKAN=ON the default view alone, its keyframes rendered and its edges
#                 aligned through Vulkan (lavapipe where there is no GPU): lost none, median within
#                 0.5 % of the depth (its filter took poses verified at 0.01 after refusing verified
#                 ones and stayed 16 m off before such a stretch took verified poses alone).
#   radtan_mild, radtan_euroc   the room (easy, 300 frames) and the same images through a
#                 radial-tangential lens (vkloc distort; mild: k1 -0.1 k2 0.01; euroc: EuRoC's
#                 k1 -0.28 k2 0.074), tracked through the undistorted view: no frame lost and
#                 median errors within 3x the undistorted run's (RELATIVE: within 10 %, +0.1 mm).
#                 300 frames, not 100: a sub-millimetre median over 100 frames moves by 20-30 %
#                 with changes as small as 0.03 px in the view's focal length.
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)

set(failures "")
function(track_case label seq)
  set(dir ${WORK}/${label})
  file(REMOVE_RECURSE ${dir})
  if(VULKAN)
    set(backend "")
  else()
    set(backend --no-vulkan)
  endif()
  run("track ${label}" ${VKLOC} track --sequence ${seq} --out ${dir}/t.txt --report ${dir}/report --keyframes sync
      --filter ekf --quiet ${backend} ${ARGN})
  foreach(key frames lost inertial translation_median_m translation_max_m rotation_median_deg hz_median
              scene_depth_median_m)
    json_number(${key} ${dir}/report/track.json ${key})
    set(${label}_${key} ${${key}} PARENT_SCOPE)
  endforeach()
  message(STATUS "${label}: ${frames} frames, lost ${lost}, inertial only ${inertial}, translation median "
                 "${translation_median_m} m max ${translation_max_m} m, rotation median ${rotation_median_deg} deg, "
                 "scene depth ${scene_depth_median_m} m, ${hz_median} Hz")
endfunction()

function(check label condition message)
  execute_process(COMMAND awk "BEGIN { if (${condition}) print \"ok\"; else print \"bad\" }"
                  OUTPUT_VARIABLE verdict OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT verdict STREQUAL "ok")
    set(failures "${failures}  ${label}: ${message}\n" PARENT_SCOPE)
  endif()
endfunction()

if(CASE STREQUAL "fisheye_eis")
  set(seq ${WORK}/city_hard_agile_fisheye)
  if(NOT EXISTS ${seq}/images.txt)
    run("simulate" ${VKLOC} simulate city hard --lens fisheye --trajectory drone_agile --frames 100 --out ${seq})
  endif()
  set(view --view-size 480x360 --view-hfov 90 --view-pitch 45)
  track_case(eis ${seq} --view stabilised ${view})
  track_case(full ${seq} --view stabilised --view-dead-band 0 ${view})
  track_case(crop ${seq} --view undistorted ${view})
  foreach(label eis full)
    check(${label} "${${label}_lost} == 0" "lost ${${label}_lost} frames")
    check(${label} "${${label}_lost} <= ${crop_lost}" "lost ${${label}_lost} frames, the crop ${crop_lost}")
    check(${label} "${${label}_translation_median_m} <= 0.005 * ${${label}_scene_depth_median_m}"
          "median ${${label}_translation_median_m} m > 0.5 % of the depth")
    check(${label} "${${label}_inertial} <= 0.05 * ${${label}_frames}"
          "${${label}_inertial} frames by the IMU alone (the crop ${crop_inertial})")
  endforeach()
  if(RELATIVE)
    # FULL: the view compensated every frame (label open: its median error is 3x the crop's here).
    if(FULL)
      set(compared full)
    else()
      set(compared eis)
    endif()
    check(${compared} "${${compared}_translation_median_m} <= 1.1 * ${crop_translation_median_m}"
          "median ${${compared}_translation_median_m} m > 1.1 x the crop's ${crop_translation_median_m} m")
  endif()
elseif(CASE MATCHES "^fisheye_(city_edge|acro)$")
  if(CASE STREQUAL "fisheye_city_edge")
    set(seq ${WORK}/city_hard_agile_fisheye_seed4)
    set(simulation --trajectory drone_agile --frames 300 --seed 4)
  else()
    set(seq ${WORK}/city_hard_acro_fisheye_seed7)
    set(simulation --trajectory drone_acro --frames 100 --seed 7)
  endif()
  if(NOT EXISTS ${seq}/images.txt)
    run("simulate" ${VKLOC} simulate city hard --lens fisheye ${simulation} --out ${seq})
  endif()
  set(view --view-size 480x360 --view-hfov 90 --view-pitch 45)
  set(labels eis crop)
  track_case(eis ${seq} --view stabilised ${view})
  if(VULKAN)
    # The default view alone, rendered and aligned through Vulkan.
    set(labels eis)
  elseif(CASE STREQUAL "fisheye_acro")
    track_case(full ${seq} --view stabilised --view-dead-band 0 ${view})
    list(APPEND labels full)
  endif()
  if(NOT VULKAN)
    track_case(crop ${seq} --view undistorted ${view})
  endif()
  foreach(label ${labels})
    check(${label} "${${label}_lost} == 0" "lost ${${label}_lost} frames")
    check(${label} "${${label}_translation_median_m} <= 0.005 * ${${label}_scene_depth_median_m}"
          "median ${${label}_translation_median_m} m > 0.5 % of the depth")
  endforeach()
  if(CASE STREQUAL "fisheye_acro" AND RELATIVE AND NOT VULKAN)
    # Here the default view turns beyond its band (67 of the 100 frames): the issue's comparison
    # on a view that is not the crop (label open: on this drone which view wins changes with the
    # seed and with a rounding of the remap, 2026-12-07: band 6.1 vs crop 6.7 cm with OpenCV's
    # bicubic remap, 9.2 vs 3.8 cm with the fixed-point one; over seeds 1-7 but 4, 68 vs 62 cm).
    check(eis "${eis_translation_median_m} <= 1.1 * ${crop_translation_median_m}"
          "median ${eis_translation_median_m} m > 1.1 x the crop's ${crop_translation_median_m} m")
  endif()
elseif(CASE MATCHES "^radtan_(mild|euroc)$")
  set(k_mild "-0.1,0.01,1e-4,-1e-4,0")
  set(k_euroc "-0.28,0.074,2e-4,1.8e-5,0")
  set(seq ${WORK}/room_easy_300)
  if(NOT EXISTS ${seq}/images.txt)
    run("simulate" ${VKLOC} simulate room easy --frames 300 --out ${seq})
  endif()
  set(lens ${CMAKE_MATCH_1})
  set(distorted ${WORK}/room_easy_300_${lens})
  file(REMOVE_RECURSE ${distorted})
  run("distort" ${VKLOC} distort --sequence ${seq} --out ${distorted} --k=${k_${lens}})
  track_case(pinhole ${seq})
  track_case(${lens} ${distorted})
  check(${lens} "${${lens}_lost} == 0" "lost ${${lens}_lost} frames")
  if(RELATIVE)
    set(factor 1.1)
    set(margin_m 1e-4)
    set(margin_deg 0.005)
  else()
    set(factor 3)
    set(margin_m 0)
    set(margin_deg 0)
  endif()
  check(${lens} "${${lens}_translation_median_m} <= ${factor} * ${pinhole_translation_median_m} + ${margin_m}"
        "median ${${lens}_translation_median_m} m > ${factor} x the pinhole's ${pinhole_translation_median_m} m + ${margin_m}")
  check(${lens} "${${lens}_rotation_median_deg} <= ${factor} * ${pinhole_rotation_median_deg} + ${margin_deg}"
        "median rotation ${${lens}_rotation_median_deg} deg > ${factor} x the pinhole's ${pinhole_rotation_median_deg} deg")
else()
  message(FATAL_ERROR "unknown case ${CASE}")
endif()
if(NOT failures STREQUAL "")
  message(FATAL_ERROR "${CASE}: requirements not met:\n${failures}")
endif()
