// vkloc: writing files so that nothing already written is ever lost or half-replaced.
//
// Regular files are written under a temporary name in the same folder ("<name>.tmp-<pid>-<n>")
// and renamed over the target when complete, so a reader (or a crash, or kill -9) sees the old
// file or the new one, never a mixture. The temporaries a killed writer left (its process no
// longer runs) are removed from a folder the first time a process writes into it. A target that
// exists and is not a regular file (a device such as /dev/null or /dev/full, a pipe, /dev/stdout)
// is written directly: replacing it with a regular file would be wrong, and errors on it (ENOSPC
// on /dev/full) are reported. A symbolic link to a regular file is followed: the file it points
// to is replaced, the link stays. Errors are kIoError with one line naming the file and the
// system's reason. Standard library and POSIX only. Functions are safe to call from several
// threads on different paths.
#pragma once

#include <cstdio>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "vkloc/core/status.hpp"

namespace vkloc {

/// Writes `bytes` to `path` atomically (see above). The folder must exist.
Status writeFileAtomically(const std::string& path, std::string_view bytes);

/// Several files that appear together or not at all (a model and its material and textures):
/// each write() goes to a temporary file, commit() renames them all into place in the order
/// written. Temporary files not committed are removed by the destructor. Not thread-safe.
class AtomicFileSet {
 public:
  AtomicFileSet() = default;
  ~AtomicFileSet();
  AtomicFileSet(const AtomicFileSet&) = delete;
  AtomicFileSet& operator=(const AtomicFileSet&) = delete;

  /// Stages `bytes` as the new content of `path`.
  Status write(const std::string& path, std::string_view bytes);
  Status write(const std::string& path, const void* data, size_t size) {
    return write(path, std::string_view(static_cast<const char*>(data), size));
  }
  /// Stages the content `writer` streams (it returns false on failure) as the new content of `path`.
  Status write(const std::string& path, const std::function<bool(std::ostream&)>& writer);
  /// Moves every staged file into place. On error the files not yet moved keep their old content.
  Status commit();

 private:
  struct Pending {
    std::string tmp;     ///< Temporary file; empty when the target is written directly.
    std::string target;  ///< File replaced by commit().
  };
  std::vector<Pending> pending_;
};

/// A text file made line by line over a long run (a tracked trajectory, a per-frame log) that
/// must not destroy the previous file of that name before the new one is complete, and must
/// keep what was made when the run fails. Lines go to "<path>.partial", flushed after each
/// append() so that an interrupted run keeps every line written; commit() renames it to `path`.
/// Destroyed without commit(), the ".partial" file stays (keep() says where); the previous file
/// at `path` is untouched. A non-regular target (/dev/stdout, a pipe) is written directly.
/// Not thread-safe.
class PartialFileWriter {
 public:
  /// Opens "<path>.partial" (truncating a stale one) or the non-regular target. kIoError when it
  /// cannot be created (missing folder, no permission).
  static Result<std::unique_ptr<PartialFileWriter>> open(const std::string& path);
  ~PartialFileWriter();
  PartialFileWriter(const PartialFileWriter&) = delete;
  PartialFileWriter& operator=(const PartialFileWriter&) = delete;

  /// Appends `text` and a line break, then flushes. kIoError (disk full, ...) naming the file.
  Status appendLine(std::string_view text);
  /// Closes the file and renames it to the target path.
  Status commit();
  /// Closes the file and leaves it at partialPath() (e.g. after a failed run).
  void keep();
  /// Lines appended so far.
  size_t lines() const { return lines_; }
  /// Where the lines are while the file is open: "<path>.partial", or the target when direct.
  const std::string& partialPath() const { return partial_; }
  /// The final path.
  const std::string& path() const { return path_; }

 private:
  PartialFileWriter() = default;
  std::string path_, partial_;
  std::FILE* file_ = nullptr;
  bool direct_ = false;
  size_t lines_ = 0;
};

}  // namespace vkloc
