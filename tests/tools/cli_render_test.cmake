# End-to-end test of `vkloc render`, `vkloc info` and error handling through the CLI.
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${VKLOC} render --model room --out ${WORK}/room RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "vkloc render failed (${rc}): ${out} ${err}")
endif()
foreach(f view000_rgba.png view000_gray.png view000_depth_mm.png view000_depth.tiff view000_normals.png
          view000_back_faces.png)
  if(NOT EXISTS ${WORK}/room/${f})
    message(FATAL_ERROR "vkloc render did not write ${f}: ${out}")
  endif()
endforeach()
if(NOT err STREQUAL "")
  message(FATAL_ERROR "vkloc render printed to stderr: ${err}")
endif()
execute_process(COMMAND ${VKLOC} info --model city RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "triangles: +[0-9]+" OR NOT out MATCHES "blocks:")
  message(FATAL_ERROR "vkloc info failed (${rc}): ${out} ${err}")
endif()
# A model file written by `vkloc export` renders through the file loaders (glTF + Draco, OBJ).
foreach(file city.glb room.obj)
  string(REGEX REPLACE "\\..*" "" name ${file})
  execute_process(COMMAND ${VKLOC} export --model ${name} --out ${WORK}/${file} --draco RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "vkloc export ${file} failed (${rc}): ${out} ${err}")
  endif()
  execute_process(COMMAND ${VKLOC} render --model ${WORK}/${file} --look-at 0,-20,30,0,0,0 --out ${WORK}/${name}_file
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK}/${name}_file/view000_depth.tiff)
    message(FATAL_ERROR "vkloc render of exported ${file} failed (${rc}): ${out} ${err}")
  endif()
endforeach()
# Output already written survives a later failure: render two views into a directory, then a
# failing render (bad pose) must leave them in place.
execute_process(COMMAND ${VKLOC} render --model room --pose "0 0 1.5 0 0 0 2" --out ${WORK}/room RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT EXISTS ${WORK}/room/view000_rgba.png)
  message(FATAL_ERROR "a failing render removed earlier output or did not fail (${rc}): ${err}")
endif()
# The README's main job, and render variants.
execute_process(COMMAND ${VKLOC} demo --no-track --out ${WORK}/demo RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "view 0: +[0-9.]+ ms" OR NOT EXISTS ${WORK}/demo/city/view00_depth.tiff OR NOT err STREQUAL "")
  message(FATAL_ERROR "vkloc demo failed (${rc}): ${out} ${err}")
endif()
execute_process(COMMAND ${VKLOC} render --model city --no-normals --cull --out ${WORK}/variants
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err STREQUAL "" OR EXISTS ${WORK}/variants/view000_normals.png
   OR EXISTS ${WORK}/variants/view000_back_faces.png OR NOT EXISTS ${WORK}/variants/view000_rgba.png)
  message(FATAL_ERROR "vkloc render --no-normals --cull failed (${rc}): ${out} ${err}")
endif()
# Errors: one line on stderr, non-zero exit, no crash.
foreach(args "bench;render;--runs;0" "render;--bogus" "render;--pose" "info;--block-triangles;-1" "frobnicate" ""
        "render;--model;room;--near;nan" "render;--model;room;--far;inf" "render;--model;room;--intrinsics;1,1,1,1,1e20,5" "info;--model;${WORK}/missing.obj" "render;--model;room;--pose;1 2 3" "render;--model;room;--intrinsics;0,1,2,3,4,5"
        "render;--model;${WORK}/room/view000_gray.png;--pose;0 0 0 0 0 0 1")
  execute_process(COMMAND ${VKLOC} ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(STRIP "${err}" err)
  string(FIND "${err}" "\n" newline)
  if(rc EQUAL 0 OR NOT rc MATCHES "^[0-9]+$" OR NOT err MATCHES "^vkloc: error: " OR NOT newline EQUAL -1)
    message(FATAL_ERROR "vkloc ${args}: expected a one-line error and exit 1, got rc=${rc} stderr='${err}'")
  endif()
endforeach()
# No Vulkan driver: a one-line error naming the package to install.
execute_process(COMMAND ${CMAKE_COMMAND} -E env VK_ICD_FILENAMES=/nonexistent/icd.json VK_DRIVER_FILES=/nonexistent/icd.json
                ${VKLOC} devices RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(STRIP "${err}" err)
if(rc EQUAL 0 OR NOT err MATCHES "^vkloc: error: .*mesa-vulkan-drivers" OR err MATCHES "\n")
  message(FATAL_ERROR "vkloc devices without a driver: expected a one-line error, got rc=${rc} stderr='${err}'")
endif()
# --help for every verb.
foreach(verb demo render info devices bench export)
  execute_process(COMMAND ${VKLOC} ${verb} --help RESULT_VARIABLE rc OUTPUT_VARIABLE out)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "Usage|OPTIONS|Options")
    message(FATAL_ERROR "vkloc ${verb} --help failed (${rc}): ${out}")
  endif()
endforeach()
