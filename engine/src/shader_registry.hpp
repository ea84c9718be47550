// SPIR-V embedded at build time from shaders/ (see cmake/VklocShaders.cmake).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace vkloc::engine {

struct ShaderBlob {
  const char* name;  ///< Source file name, e.g. "model.vert".
  const uint32_t* words;
  size_t word_count;
};

/// Returns the compiled shader for a source file name, or nullptr.
const ShaderBlob* findShader(std::string_view name);

}  // namespace vkloc::engine
