// vkloc: command-line entry point. One verb per file in tools/.
#include <algorithm>
#include <cstdio>
#include <opencv2/core/utils/logger.hpp>

#include "common.hpp"

#if defined(__SANITIZE_ADDRESS__)
// Processes that load a Vulkan driver run without leak checking: lavapipe and the validation
// layer leave small allocations that LeakSanitizer reports from already unloaded modules, which
// are not vkloc's. Address and UB checks stay on; host-only tests keep leak checking.
extern "C" const char* __asan_default_options() { return "detect_leaks=0"; }
#endif

int main(int argc, char** argv) {
  // Errors are reported once, as one line, by vkloc itself.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  CLI::App app{"vkloc: model-based camera localization with Vulkan"};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every command");
  auto verbs = vkloc::cli::verbRegistry();
  std::stable_sort(verbs.begin(), verbs.end(), [](const auto& a, const auto& b) { return a.order < b.order; });
  for (const auto& verb : verbs) verb.add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "vkloc: error: %s (see 'vkloc --help')\n", e.what());
    return 2;
  } catch (const vkloc::cli::Failure& f) {
    std::fprintf(stderr, "vkloc: error: %s\n", f.message.c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vkloc: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
