# The installed package from a consumer's side (label "install"): installs the build tree into a
# prefix, moves the prefix (the package must be relocatable), configures and builds the consumer
# in tests/install/consumer from a copy outside the source tree, and runs it; also runs the
# installed `vkloc` tool. Arguments: -DBUILD=<build tree> -DSOURCE=<consumer folder>
# -DWORK=<scratch folder outside the source tree> [-DGENERATOR=Ninja].
cmake_minimum_required(VERSION 3.22)
include(${CMAKE_CURRENT_LIST_DIR}/../support/script_helpers.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
run("install" ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/staging)
foreach(f include/vkloc/vkloc.hpp include/vkloc/engine/gpu.hpp include/vkloc/localize/localizer.hpp
          lib/cmake/vkloc/vklocConfig.cmake lib/cmake/vkloc/vklocTargets.cmake bin/vkloc)
  if(NOT EXISTS ${WORK}/staging/${f})
    message(FATAL_ERROR "the install lacks ${f}")
  endif()
endforeach()
# Relocatable: the package works from wherever the prefix is moved to.
file(RENAME ${WORK}/staging ${WORK}/prefix)
file(COPY ${SOURCE}/ DESTINATION ${WORK}/src)
if(NOT GENERATOR)
  set(GENERATOR "Ninja")
endif()
run("configure the consumer" ${CMAKE_COMMAND} -S ${WORK}/src -B ${WORK}/build -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${WORK}/prefix)
run("build the consumer" ${CMAKE_COMMAND} --build ${WORK}/build)
run("run the consumer" ${WORK}/build/vkloc_consumer ${WORK}/data)
message(STATUS "${out}")
if(NOT out MATCHES "state tracking")
  message(FATAL_ERROR "the consumer did not localize its frame:\n${out}")
endif()
run("the installed tool" ${WORK}/prefix/bin/vkloc --help)
if(NOT out MATCHES "track")
  message(FATAL_ERROR "the installed vkloc tool does not list its verbs:\n${out}")
endif()
file(REMOVE_RECURSE ${WORK})
