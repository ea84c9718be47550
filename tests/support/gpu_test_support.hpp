// Fixture for GPU tests: a shared validated Vulkan context.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "vkloc/engine/gpu.hpp"

namespace vkloc::test {

/// The process-wide context (validation on); null with gpuContextError() set on failure.
std::shared_ptr<GpuContext> gpuContext();
const std::string& gpuContextError();
/// Destroys the shared context (before static destruction).
void releaseGpuContext();

/// Fails the test if the context is missing or any validation message appears during it.
class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;
  std::shared_ptr<GpuContext> context_;
  uint64_t validation_before_ = 0;
};

}  // namespace vkloc::test
