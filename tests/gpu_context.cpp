// Vulkan context: device listing and selection, validation hook, missing-driver error.
#include <gtest/gtest.h>

#include <cstdlib>

#include "context.hpp"
#include "gpu_test_support.hpp"

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
  options.print_validation = false;
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
}

TEST(GpuNoDriver, MissingDriverIsAOneLineErrorNamingThePackage) {
  // Point the loader at a driver manifest that does not exist: no device, no crash.
  const char* saved = std::getenv("VK_ICD_FILENAMES");
  const std::string saved_value = saved ? saved : "";
  setenv("VK_ICD_FILENAMES", "/nonexistent/vkloc_icd.json", 1);
  auto devices = GpuContext::listDevices();
  GpuOptions options;
  options.validation = 0;
  auto ctx = GpuContext::create(options);
  if (saved)
    setenv("VK_ICD_FILENAMES", saved_value.c_str(), 1);
  else
    unsetenv("VK_ICD_FILENAMES");
  ASSERT_FALSE(devices.ok());
  ASSERT_FALSE(ctx.ok());
  EXPECT_EQ(ctx.error().code, ErrorCode::kNoDevice);
  EXPECT_NE(ctx.error().message.find("mesa-vulkan-drivers"), std::string::npos) << ctx.error().message;
  EXPECT_EQ(ctx.error().message.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace vkloc::test
