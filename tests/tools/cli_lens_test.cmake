# End-to-end test of lens cameras: `vkloc simulate --lens` (fisheye, radial-tangential),
# `vkloc track` through undistorted and stabilised views, `vkloc distort`, `--camera` with
# another tool's calibration file, and the mistakes refused with one line.
# Arguments: -DVKLOC=path -DWORK=dir.
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)
file(REMOVE_RECURSE ${WORK})

function(expect_tracked dir what max_median_m)
  json_number(lost ${dir}/report/track.json lost)
  json_number(median ${dir}/report/track.json translation_median_m)
  if(NOT lost EQUAL 0 OR median GREATER ${max_median_m})
    message(FATAL_ERROR "${what}: lost ${lost}, median error ${median} m (limit ${max_median_m} m)")
  endif()
endfunction()

# A fisheye (210 deg) in the room: a stabilised view and a central crop of it.
set(fe ${WORK}/fisheye)
run_ok("simulate fisheye" simulate room easy --lens fisheye --frames 8 --out ${fe} --no-priors)
file(READ ${fe}/camera.yaml camera_yaml)
if(NOT camera_yaml MATCHES "model: kannala_brandt" OR NOT camera_yaml MATCHES "max_angle_deg: 105")
  message(FATAL_ERROR "fisheye camera.yaml:\n${camera_yaml}")
endif()
# The stabilised view compensates every frame (no dead band): the handheld camera's tilt stays
# inside the default band, where the view would be the crop's.
foreach(view stabilised undistorted)
  run_ok("track ${view}" track --sequence ${fe} --out ${WORK}/fe_${view}/t.txt --report ${WORK}/fe_${view}/report
         --view ${view} --view-size 320x240 --view-hfov 90 --view-pitch 10 --view-dead-band 0 --backend cpu
         --keyframes sync)
  if(NOT out MATCHES "camera front: kannala_brandt" OR NOT out MATCHES "${view} view 320x240, hfov 90.0 deg")
    message(FATAL_ERROR "track ${view} did not name its view:\n${out}")
  endif()
  expect_tracked(${WORK}/fe_${view} "fisheye ${view}" 0.02)
endforeach()

# Radial-tangential: simulated, and a pinhole sequence distorted afterwards.
set(rt ${WORK}/radtan)
run_ok("simulate radtan" simulate room easy --lens radtan --frames 6 --out ${rt} --no-priors)
run_ok("track radtan" track --sequence ${rt} --out ${WORK}/rt/t.txt --report ${WORK}/rt/report --backend cpu
       --keyframes sync)
expect_tracked(${WORK}/rt "radtan" 0.01)
set(pin ${WORK}/pinhole)
run_ok("simulate pinhole" simulate room easy --frames 6 --out ${pin} --no-priors)
run_ok("distort" distort --sequence ${pin} --out ${WORK}/distorted)
if(NOT out MATCHES "distorted 6 images")
  message(FATAL_ERROR "distort output:\n${out}")
endif()
run_ok("track distorted" track --sequence ${WORK}/distorted --out ${WORK}/dt/t.txt --report ${WORK}/dt/report
       --backend cpu --keyframes sync)
expect_tracked(${WORK}/dt "distorted" 0.01)

# Another tool's calibration file: a Kalibr camchain with the same lens is tracked the same.
file(WRITE ${WORK}/camchain.yaml "cam0:
  camera_model: pinhole
  intrinsics: [500.0, 500.0, 319.5, 239.5]
  distortion_model: radtan
  distortion_coeffs: [-0.28, 0.074, 0.0002, 0.000018]
  resolution: [640, 480]
cam1:
  camera_model: pinhole
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  distortion_model: radtan
  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
  resolution: [752, 480]
")
run_ok("track --camera kalibr" track --sequence ${rt} --camera ${WORK}/camchain.yaml --out ${WORK}/kc/t.txt
       --report ${WORK}/kc/report --backend cpu --keyframes sync --max-frames 3)
# Mistakes: another camera's image size, an unknown model, a lens for a pinhole-only verb.
run_fails("calibration of another size" "640x480.*752x480" track --sequence ${rt} --camera ${WORK}/camchain.yaml
          --camera-name cam1 --out ${WORK}/bad/t.txt --backend cpu)
file(WRITE ${WORK}/unknown.yaml "cam0:\n  camera_model: fancy\n  intrinsics: [1, 2, 3, 4]\n  resolution: [640, 480]\n")
run_fails("unknown model" "fancy" track --sequence ${rt} --camera ${WORK}/unknown.yaml --out ${WORK}/bad2/t.txt)
run_fails("lens for a pinhole verb" "kannala_brandt lens" keyframes build --sequence ${fe} --out ${WORK}/fe.kdb)
run_fails("bad view size" "--view-size" track --sequence ${fe} --view-size 320 --out ${WORK}/bad3/t.txt)
