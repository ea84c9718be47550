// vkloc devices: list Vulkan devices and which one vkloc would pick.
#include <cstdio>

#include "common.hpp"

namespace vkloc::cli {

static void addDevicesVerb(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("devices", "List Vulkan devices (select one with --device or VKLOC_DEVICE)");
  cmd->callback([] {
    const auto devices = take(GpuContext::listDevices());
    GpuOptions options;
    options.validation = 0;
    auto chosen = GpuContext::create(options);
    for (const auto& d : devices) {
      const bool is_default = chosen.ok() && (*chosen)->device().index == d.index;
      std::printf("%c %d: %s [%s, Vulkan %s] %s%s%s\n", is_default ? '*' : ' ', d.index, d.name.c_str(), d.type.c_str(),
                  d.api_version.c_str(), d.driver.c_str(), d.usable ? "" : " -- unusable: ", d.why_unusable.c_str());
    }
    if (!chosen.ok()) throw Failure{chosen.error().message};
  });
}

VKLOC_REGISTER_VERB(80, addDevicesVerb);

}  // namespace vkloc::cli
