#include "vkloc/core/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>

#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

namespace fs = std::filesystem;
using text::cat;

Error ioError(const std::string& path, const std::string& what) {
  return makeError(ErrorCode::kIoError, cat(path, ": ", what));
}

std::string systemReason(int error) { return std::strerror(error); }

/// Where to write for `path`: the file itself (direct, for devices and pipes) or the regular
/// file to replace (the target of a symbolic link). kIoError for a folder.
struct Target {
  std::string file;
  bool direct = false;
};

Result<Target> resolveTarget(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!ec && fs::exists(status)) {
    if (fs::is_directory(status)) return ioError(path, "is a folder, not a file");
    if (!fs::is_regular_file(status)) return Target{path, true};
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
      const fs::path resolved = fs::canonical(path, ec);
      if (!ec) return Target{resolved.string(), false};
    }
  }
  return Target{path, false};
}

/// The writer's process id of a temporary name "<name>.tmp-<pid>-<n>", or -1 for another name.
long temporaryOwner(const std::string& name) {
  const size_t at = name.rfind(".tmp-");
  if (at == std::string::npos || at == 0) return -1;
  const char* p = name.data() + at + 5;
  const char* end = name.data() + name.size();
  long pid = 0;
  uint64_t n = 0;
  auto [after_pid, e1] = std::from_chars(p, end, pid);
  if (e1 != std::errc() || after_pid == p || after_pid == end || *after_pid != '-' || pid <= 0) return -1;
  auto [after_n, e2] = std::from_chars(after_pid + 1, end, n);
  if (e2 != std::errc() || after_n == after_pid + 1 || after_n != end) return -1;
  return pid;
}

/// Removes the temporaries in `folder` whose writer no longer runs (a kill -9 or a power cut
/// between writing and renaming): kill(pid, 0) says ESRCH. A live process's, or one that cannot
/// be asked (EPERM: another user's), is left alone. Once per folder and process: a folder written
/// into many times (a sequence's images) is listed once.
void sweepStaleTemporaries(const std::string& file) {
  static std::mutex mutex;
  static std::set<std::string> swept;
  std::error_code ec;
  const fs::path folder = fs::absolute(fs::path(file), ec).parent_path();
  if (ec) return;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (swept.size() >= 4096) swept.clear();  // bounded for a process that writes into many folders
    if (!swept.insert(folder.string()).second) return;
  }
  const long self = static_cast<long>(::getpid());
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = temporaryOwner(it->path().filename().string());
    if (pid <= 0 || pid == self) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    if (it->is_regular_file(ignored)) fs::remove(it->path(), ignored);
  }
}

std::string temporaryName(const std::string& file) {
  static std::atomic<uint64_t> counter{0};
  sweepStaleTemporaries(file);
  return cat(file, ".tmp-", static_cast<long>(::getpid()), "-", counter.fetch_add(1));
}

/// Writes bytes with stdio and reports the system's reason for a failure (fclose included:
/// buffered data meets a full disk there).
Status writeWhole(const std::string& file, const std::string& shown_path, std::string_view bytes) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (!f) return ioError(shown_path, cat("cannot open for writing (", systemReason(errno), ")"));
  const size_t written = bytes.empty() ? 0 : std::fwrite(bytes.data(), 1, bytes.size(), f);
  int error = written == bytes.size() ? 0 : errno;
  if (std::fflush(f) != 0 && error == 0) error = errno;
  if (std::fclose(f) != 0 && error == 0) error = errno;
  if (written != bytes.size() && error == 0) error = EIO;
  if (error != 0) return ioError(shown_path, cat("write failed (", systemReason(error), ")"));
  return Status::success();
}

Status renameInto(const std::string& tmp, const std::string& target, const std::string& shown_path) {
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return ioError(shown_path, cat("cannot replace the file (", ec.message(), ")"));
  }
  return Status::success();
}

}  // namespace

Status writeFileAtomically(const std::string& path, std::string_view bytes) {
  Result<Target> target = resolveTarget(path);
  if (!target.ok()) return target.error();
  if (target->direct) return writeWhole(target->file, path, bytes);
  const std::string tmp = temporaryName(target->file);
  Status written = writeWhole(tmp, path, bytes);
  if (!written.ok()) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return written;
  }
  return renameInto(tmp, target->file, path);
}

AtomicFileSet::~AtomicFileSet() {
  for (const Pending& p : pending_) {
    if (p.tmp.empty()) continue;
    std::error_code ec;
    fs::remove(p.tmp, ec);
  }
}

Status AtomicFileSet::write(const std::string& path, std::string_view bytes) {
  Result<Target> target = resolveTarget(path);
  if (!target.ok()) return target.error();
  if (target->direct) {
    pending_.push_back({"", target->file});
    return writeWhole(target->file, path, bytes);
  }
  pending_.push_back({temporaryName(target->file), target->file});
  return writeWhole(pending_.back().tmp, path, bytes);
}

Status AtomicFileSet::write(const std::string& path, const std::function<bool(std::ostream&)>& writer) {
  Result<Target> target = resolveTarget(path);
  if (!target.ok()) return target.error();
  const bool direct = target->direct;
  pending_.push_back({direct ? "" : temporaryName(target->file), target->file});
  const std::string& file = direct ? target->file : pending_.back().tmp;
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) return ioError(path, cat("cannot open for writing (", systemReason(errno), ")"));
  const bool ok = writer(out);
  out.close();
  if (!ok || out.fail()) return ioError(path, "write failed (disk full?)");
  return Status::success();
}

Status AtomicFileSet::commit() {
  for (Pending& p : pending_) {
    if (p.tmp.empty()) continue;
    VKLOC_TRY_STATUS(renameInto(p.tmp, p.target, p.target));
    p.tmp.clear();
  }
  pending_.clear();
  return Status::success();
}

Result<std::unique_ptr<PartialFileWriter>> PartialFileWriter::open(const std::string& path) {
  Result<Target> target = resolveTarget(path);
  if (!target.ok()) return target.error();
  std::unique_ptr<PartialFileWriter> w(new PartialFileWriter());
  w->path_ = path;
  w->direct_ = target->direct;
  w->partial_ = target->direct ? target->file : target->file + ".partial";
  w->file_ = std::fopen(w->partial_.c_str(), "wb");
  if (!w->file_) return ioError(w->partial_, cat("cannot open for writing (", systemReason(errno), ")"));
  return w;
}

PartialFileWriter::~PartialFileWriter() { keep(); }

Status PartialFileWriter::appendLine(std::string_view line) {
  if (!file_) return ioError(partial_, "already closed");
  if ((!line.empty() && std::fwrite(line.data(), 1, line.size(), file_) != line.size()) ||
      std::fputc('\n', file_) == EOF || std::fflush(file_) != 0) {
    return ioError(partial_, cat("write failed (", systemReason(errno), ")"));
  }
  ++lines_;
  return Status::success();
}

Status PartialFileWriter::commit() {
  if (!file_) return ioError(partial_, "already closed");
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (closed != 0) return ioError(partial_, cat("write failed (", systemReason(errno), ")"));
  if (direct_) return Status::success();
  std::error_code ec;
  const std::string target = partial_.substr(0, partial_.size() - std::string(".partial").size());
  fs::rename(partial_, target, ec);
  if (ec) return ioError(path_, cat("cannot move ", partial_, " into place (", ec.message(), ")"));
  return Status::success();
}

void PartialFileWriter::keep() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
}

}  // namespace vkloc
