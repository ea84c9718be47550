#include "support/test_support.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <opencv2/core/utility.hpp>
#include <random>

namespace vkloc::test {

#if defined(__SANITIZE_THREAD__)
namespace {
// OpenCV's parallel loops run on TBB's threads, which ThreadSanitizer cannot see synchronise
// (TBB is not instrumented): under TSan they run on the calling thread, leaving vkloc's own
// threads (the keyframe worker) to check.
const bool kOpenCvSerial = [] {
  cv::setNumThreads(0);
  return true;
}();
}  // namespace
#endif

TempDir::TempDir(const std::string& tag) {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          (tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

bool writeFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(f);
}

bool writeFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  return static_cast<bool>(f);
}

std::vector<uint8_t> readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

}  // namespace vkloc::test
