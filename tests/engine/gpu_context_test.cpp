// Vulkan context: device listing and selection, validation hook, missing-driver error.
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "context.hpp"
#include "support/gpu_test_support.hpp"

namespace vkloc::test {
namespace {

using GpuContextTest = GpuTest;

TEST_F(GpuContextTest, ListsDevicesAndSelectsByIndexAndName) {
  auto devices = GpuContext::listDevices();
  ASSERT_TRUE(devices.ok()) << devices.error().message;
  ASSERT_FALSE(devices->empty());
  const GpuDeviceInfo& first = devices->front();
  EXPECT_FALSE(first.name.empty());
  EXPECT_FALSE(first.api_version.empty());

  GpuOptions by_index;
  by_index.device = std::to_string(context_->device().index);
  by_index.validation = 1;
  auto a = GpuContext::create(by_index);
  ASSERT_TRUE(a.ok()) << a.error().message;
  EXPECT_EQ((*a)->device().name, context_->device().name);

  GpuOptions by_name;
  by_name.device = context_->device().name.substr(0, 4);  // case-insensitive substring
  for (char& c : by_name.device) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  by_name.validation = 1;
  auto b = GpuContext::create(by_name);
  ASSERT_TRUE(b.ok()) << b.error().message;
  EXPECT_EQ((*b)->device().index, context_->device().index);

  GpuOptions missing;
  missing.device = "no-such-device-xyz";
  auto c = GpuContext::create(missing);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().code, ErrorCode::kNotFound);
  EXPECT_NE(c.error().message.find("no-such-device-xyz"), std::string::npos);
}

TEST_F(GpuContextTest, ValidationMessagesAreCounted) {
  // A deliberately invalid call (zero-sized buffer) must reach the counter, proving that the
  // "no validation message" check of every GPU test can fail.
  GpuOptions options;
  options.validation = 1;
  std::vector<std::string> messages;
  options.on_validation_message = [&messages](const std::string& m) { messages.push_back(m); };
  auto ctx = GpuContext::create(options);
  ASSERT_TRUE(ctx.ok());
  const uint64_t before = (*ctx)->validationMessages();
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = 0;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  const VkDevice device = (*ctx)->impl().device;
  if (vkCreateBuffer(device, &bci, nullptr, &buffer) == VK_SUCCESS) vkDestroyBuffer(device, buffer, nullptr);
  EXPECT_GT((*ctx)->validationMessages(), before);
  // The library does not print: the message reached the handler, on one line.
  ASSERT_FALSE(messages.empty());
  EXPECT_EQ(messages.front().find('\n'), std::string::npos);
}

TEST(GpuNoDriver, MissingDriverIsAOneLineErrorNamingThePackage) {
  // Point the loader at a driver manifest that does not exist: no device, no crash. Both the
  // current (VK_DRIVER_FILES) and the older (VK_ICD_FILENAMES) variable are set, since the
  // current one wins when the environment already names a driver; VK_ADD_DRIVER_FILES is
  // cleared for the same reason.
  const char* kVariables[3] = {"VK_DRIVER_FILES", "VK_ICD_FILENAMES", "VK_ADD_DRIVER_FILES"};
  std::optional<std::string> saved[3];
  for (int i = 0; i < 3; ++i) {
    if (const char* v = std::getenv(kVariables[i])) saved[i] = v;
  }
  setenv("VK_DRIVER_FILES", "/nonexistent/vkloc_icd.json", 1);
  setenv("VK_ICD_FILENAMES", "/nonexistent/vkloc_icd.json", 1);
  unsetenv("VK_ADD_DRIVER_FILES");
  auto devices = GpuContext::listDevices();
  GpuOptions options;
  options.validation = 0;
  auto ctx = GpuContext::create(options);
  for (int i = 0; i < 3; ++i) {
    if (saved[i])
      setenv(kVariables[i], saved[i]->c_str(), 1);
    else
      unsetenv(kVariables[i]);
  }
  ASSERT_FALSE(devices.ok());
  ASSERT_FALSE(ctx.ok());
  EXPECT_EQ(ctx.error().code, ErrorCode::kNoDevice);
  EXPECT_NE(ctx.error().message.find("mesa-vulkan-drivers"), std::string::npos) << ctx.error().message;
  EXPECT_EQ(ctx.error().message.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace vkloc::test
