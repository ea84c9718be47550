// Main of the GPU tests: one shared Vulkan context with validation on; a test that triggers any
// validation message fails.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "support/gpu_test_support.hpp"

namespace vkloc::test {
namespace {
std::shared_ptr<GpuContext> g_context;
std::string g_context_error;

}  // namespace

std::shared_ptr<GpuContext> gpuContext() {
  if (!g_context && g_context_error.empty()) {
    GpuOptions options;
    options.validation = 1;
    options.on_validation_message = [](const std::string& m) {
      std::fprintf(stderr, "Vulkan validation: %s\n", m.c_str());
    };
    auto r = GpuContext::create(options);
    if (r.ok()) {
      g_context = *r;
      std::printf("[vkloc] device %s, validation %s\n", g_context->device().name.c_str(),
                  g_context->validationEnabled() ? "on" : "off");
    } else {
      g_context_error = r.error().message;
    }
  }
  return g_context;
}

const std::string& gpuContextError() { return g_context_error; }

void releaseGpuContext() { g_context.reset(); }

void GpuTest::SetUp() {
  context_ = gpuContext();
  ASSERT_TRUE(context_) << "Vulkan context: " << gpuContextError();
  ASSERT_TRUE(context_->validationEnabled());
  validation_before_ = context_->validationMessages();
}

void GpuTest::TearDown() {
  if (context_) {
    EXPECT_EQ(context_->validationMessages(), validation_before_)
        << "Vulkan validation messages were reported during this test (see stderr)";
  }
}

}  // namespace vkloc::test

#if defined(__SANITIZE_ADDRESS__)
// Processes that load a Vulkan driver run without leak checking: lavapipe and the validation
// layer leave small allocations that LeakSanitizer reports from already unloaded modules, which
// are not vkloc's. Address and UB checks stay on; host-only tests keep leak checking.
extern "C" const char* __asan_default_options() { return "detect_leaks=0"; }
#endif

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  const int rc = RUN_ALL_TESTS();
  vkloc::test::releaseGpuContext();
  return rc;
}
