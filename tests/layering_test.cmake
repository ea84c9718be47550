# The module layering of ARCHITECTURE (label "format"): which module's files may include which
# modules' headers. Fails naming each file and include that breaks a rule. -DSOURCE=<repo root>.
#
#   core      : core                                (and Eigen and the standard library only)
#   model     : core model
#   render    : core model render
#   track     : core model render track
#   fusion    : core fusion
#   localize  : core model render track fusion localize
#   io        : core model fusion io
#   sim, eval : everything of the host (not the engine)
#   engine    : core model render track engine       (implements their interfaces)
# Never in host/: Vulkan headers. The umbrella headers vkloc/vkloc.hpp and vkloc/bench.hpp are
# exempt; tools/ and tests/ may include everything.
cmake_minimum_required(VERSION 3.22)

set(allowed_core core)
set(allowed_model core model)
set(allowed_render core model render)
set(allowed_track core model render track)
set(allowed_fusion core fusion)
set(allowed_localize core model render track fusion localize)
set(allowed_io core model fusion io)
set(allowed_sim core model render track fusion localize io sim eval)
set(allowed_eval core model render track fusion localize io sim eval)
set(allowed_engine core model render track engine)
# Third-party headers a module's public headers may not expose (they stay in its .cpp files).
set(public_forbidden "opencv2|yaml-cpp|nlohmann|fmt/|assimp|draco|vulkan|meshoptimizer|CLI/")

set(problems "")
file(GLOB_RECURSE files RELATIVE ${SOURCE}
  ${SOURCE}/host/include/vkloc/*.hpp ${SOURCE}/host/src/*.cpp ${SOURCE}/host/src/*.hpp
  ${SOURCE}/engine/include/*.hpp ${SOURCE}/engine/src/*.cpp ${SOURCE}/engine/src/*.hpp)
foreach(f ${files})
  if(f MATCHES "^host/include/vkloc/(vkloc|bench)\\.hpp$")
    continue()
  endif()
  if(f MATCHES "^engine/")
    set(module engine)
  elseif(f MATCHES "^host/(include/vkloc|src)/([a-z]+)/")
    set(module ${CMAKE_MATCH_2})
  else()
    string(APPEND problems "\n  ${f}: not inside a module folder")
    continue()
  endif()
  if(NOT DEFINED allowed_${module})
    string(APPEND problems "\n  ${f}: unknown module '${module}'")
    continue()
  endif()
  file(STRINGS ${SOURCE}/${f} includes REGEX "^#include [<\"]")
  foreach(line ${includes})
    if(line MATCHES "^#include \"vkloc/([a-z]+)/")
      set(target ${CMAKE_MATCH_1})
    elseif(line MATCHES "^#include \"([a-z]+)/[a-z_]+\\.hpp\"")
      set(target ${CMAKE_MATCH_1})  # a module's private header (host/src/<module>/...)
      if(NOT target MATCHES "^(core|model|render|track|fusion|localize|io|sim|eval)$")
        continue()
      endif()
    else()
      if(f MATCHES "^host/" AND line MATCHES "vulkan")
        string(APPEND problems "\n  ${f}: ${line} (host code never includes Vulkan)")
      endif()
      if(f MATCHES "/include/" AND line MATCHES "<(${public_forbidden})")
        string(APPEND problems "\n  ${f}: ${line} (a public header exposes a third-party library)")
      elseif(module STREQUAL "core" AND line MATCHES "<(${public_forbidden})")
        string(APPEND problems "\n  ${f}: ${line} (core needs Eigen and the standard library only)")
      endif()
      continue()
    endif()
    list(FIND allowed_${module} ${target} at)
    if(at LESS 0)
      string(APPEND problems "\n  ${f}: ${line} (${module} may use: ${allowed_${module}})")
    endif()
  endforeach()
endforeach()
if(problems)
  message(FATAL_ERROR "module layering broken:${problems}")
endif()
list(LENGTH files n)
message(STATUS "layering: ${n} files follow the module rules")
