#include "fuzz_common.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

#include "vkloc/core/pose.hpp"

namespace vkloc::fuzz {

namespace fs = std::filesystem;

namespace {

std::string makeScratchDir() {
  std::error_code ec;
  // A fixed folder (run_fuzzer.cmake) keeps the paths the target compares the same from run to
  // run, so that a seeded run repeats itself.
  if (const char* fixed = std::getenv("VKLOC_FUZZ_SCRATCH"); fixed && *fixed) {
    fs::remove_all(fixed, ec);
    fs::create_directories(fixed, ec);
    if (ec) {
      std::fprintf(stderr, "vkloc fuzz: cannot create %s: %s\n", fixed, ec.message().c_str());
      std::abort();
    }
    return fixed;
  }
  std::string base = "/dev/shm";
  if (access(base.c_str(), W_OK) != 0) {
    const char* tmp = std::getenv("TMPDIR");
    base = tmp && *tmp ? tmp : "/tmp";
  }
  // Folders of earlier runs that crashed (atexit does not run on abort) are removed here.
  const std::string prefix = "vkloc_fuzz_";
  for (const fs::directory_entry& e : fs::directory_iterator(base, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid > 0 && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
  }
  const std::string dir = base + "/" + prefix + std::to_string(getpid());
  fs::remove_all(dir, ec);
  fs::create_directories(dir, ec);
  if (ec) {
    std::fprintf(stderr, "vkloc fuzz: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
    std::abort();
  }
  return dir;
}

void removeScratchDir() {
  std::error_code ec;
  fs::remove_all(scratchDir(), ec);
}

const std::set<std::string>& knownFindings() {
  static const std::set<std::string> known = [] {
    std::set<std::string> ids;
    const char* env = std::getenv("VKLOC_FUZZ_KNOWN");
    std::istringstream in(env ? env : "");
    std::string id;
    while (std::getline(in, id, ',')) {
      id.erase(0, id.find_first_not_of(" \t"));
      id.erase(id.find_last_not_of(" \t") + 1);
      if (!id.empty()) ids.insert(id);
    }
    return ids;
  }();
  return known;
}

}  // namespace

const std::string& scratchDir() {
  // Never destroyed: removeScratchDir reads it at exit.
  static const std::string* dir = [] {
    auto* d = new std::string(makeScratchDir());
    std::atexit(removeScratchDir);
    return d;
  }();
  return *dir;
}

std::string scratchPath(const std::string& name) { return scratchDir() + "/" + name; }

void writeInput(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || (size > 0 && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
    std::fprintf(stderr, "vkloc fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
}

void writeInput(const std::string& path, std::string_view text) {
  writeInput(path, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

void check(bool condition, const char* id, const std::string& details) {
  if (condition) return;
  if (knownFindings().count(id)) {
    static std::set<std::string> reported;
    if (reported.insert(id).second) {
      std::fprintf(stderr, "vkloc fuzz: known finding '%s' (not aborting): %s\n", id, escaped(details).c_str());
    }
    return;
  }
  std::fprintf(stderr, "vkloc fuzz: property '%s' violated: %s\n", id, escaped(details).c_str());
  std::abort();
}

bool noControlCharacters(std::string_view text) {
  return std::none_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 0x20 || u == 0x7f;
  });
}

std::string escaped(std::string_view text) {
  std::string out;
  for (char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7f || c == '\\') {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", u);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out;
}

void checkErrorMessage(const Error& error, const std::string& path, const char* target) {
  const std::string& m = error.message;
  check(!m.empty() && noControlCharacters(m), (std::string(target) + ".error_one_line").c_str(),
        "message is empty or has a line break or control character: " + m);
  if (!path.empty()) {
    check(m.find(path) != std::string::npos, (std::string(target) + ".error_names_file").c_str(),
          "message does not name " + path + ": " + m);
  }
}

bool nearRelative(double a, double b, double tol) {
  if (a == b) return true;
  return std::abs(a - b) <= tol * std::max({1.0, std::abs(a), std::abs(b)});
}

std::string cameraDifference(const SequenceCamera& a, const SequenceCamera& b) {
  if (a.model != b.model) return "model";
  const PinholeCamera &k = a.intrinsics, &l = b.intrinsics;
  if (k.fx != l.fx || k.fy != l.fy || k.cx != l.cx || k.cy != l.cy) return "fx, fy, cx or cy";
  if (k.width != l.width || k.height != l.height) return "width or height";
  if (a.distortion != b.distortion) return "distortion";
  if (a.xi != b.xi) return "xi";
  if (a.alpha != b.alpha) return "alpha";
  if (a.max_angle_deg != b.max_angle_deg) return "max_angle_deg";
  if (!(a.T_body_camera.matrix() == b.T_body_camera.matrix())) return "T_body_camera";
  return {};
}

void checkCamera(const SequenceCamera& camera, const char* target,
                 Result<SequenceCamera> (*reload)(const std::string& path)) {
  const std::string t(target);
  const auto lens = lensCamera(camera);
  check(lens.ok(), (t + ".valid").c_str(), lens.ok() ? "" : lens.error().message);
  check(isValidPose(camera.T_body_camera), (t + ".valid").c_str(), "T_body_camera is not rigid");
  static const std::string saved = scratchPath("saved_camera.yaml");
  const Status st = saveSequenceCamera(camera, saved);
  check(st.ok(), (t + ".save_accepts_loaded").c_str(), st.ok() ? "" : st.error().message);
  if (!st.ok()) return;
  const auto again = reload(saved);
  check(again.ok(), (t + ".roundtrip").c_str(), again.ok() ? "" : again.error().message);
  if (!again.ok()) return;
  const std::string differs = cameraDifference(camera, *again);
  check(differs.empty(), (t + ".roundtrip").c_str(), differs + " differs after save and load");
}

}  // namespace vkloc::fuzz
