# Compiles GLSL to SPIR-V at build time and generates one C++ file embedding the words.
#
# vkloc_compile_shaders(<out_var> <shader files...>) sets <out_var> to the generated C++ file,
# which defines `const vkloc::engine::ShaderBlob* findShader(std::string_view)` (declared in
# engine/src/shader_registry.hpp); add it to the engine's sources. Each shader is compiled by glslc
# (or glslangValidator) with dependency tracking, so editing a shader or any file it #includes
# rebuilds it. Nothing is written into the source tree.
find_program(VKLOC_GLSLC glslc)
find_program(VKLOC_GLSLANG glslangValidator)
if(NOT VKLOC_GLSLC AND NOT VKLOC_GLSLANG)
  message(FATAL_ERROR "No GLSL compiler: install glslc or glslang-tools (scripts/install-deps.sh)")
endif()

function(vkloc_compile_shaders out_var)
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/shaders)
  file(MAKE_DIRECTORY ${out_dir})
  set(spv_files)
  set(names)
  foreach(src ${ARGN})
    get_filename_component(fname ${src} NAME)
    set(spv ${out_dir}/${fname}.spv)
    set(dep ${out_dir}/${fname}.d)
    if(VKLOC_GLSLC)
      set(werror "")
      if(VKLOC_WERROR)
        set(werror -Werror)
      endif()
      add_custom_command(OUTPUT ${spv}
        COMMAND ${VKLOC_GLSLC} --target-env=vulkan1.2 -O ${werror}
                -I ${CMAKE_CURRENT_SOURCE_DIR}/shaders/include
                -MD -MF ${dep} -o ${spv} ${src}
        DEPENDS ${src}
        DEPFILE ${dep}
        COMMENT "glslc ${fname}"
        VERBATIM)
    else()
      add_custom_command(OUTPUT ${spv}
        COMMAND ${VKLOC_GLSLANG} --target-env vulkan1.2 -I${CMAKE_CURRENT_SOURCE_DIR}/shaders/include
                --depfile ${dep} -o ${spv} ${src}
        DEPENDS ${src}
        DEPFILE ${dep}
        COMMENT "glslangValidator ${fname}"
        VERBATIM)
    endif()
    list(APPEND spv_files ${spv})
    list(APPEND names ${fname})
  endforeach()
  set(gen_cpp ${out_dir}/vkloc_shaders_generated.cpp)
  add_custom_command(OUTPUT ${gen_cpp}
    COMMAND ${CMAKE_COMMAND} -DOUT=${gen_cpp} "-DSPV_FILES=${spv_files}" "-DNAMES=${names}"
            -P ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/EmbedSpirv.cmake
    DEPENDS ${spv_files} ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/EmbedSpirv.cmake
    COMMENT "Embedding SPIR-V"
    VERBATIM)
  set(${out_var} ${gen_cpp} PARENT_SCOPE)
endfunction()
