// Tests of the atomic writers (core/atomic_file.hpp): replacement only by complete files, devices
// and pipes written directly, symbolic links kept, partial files kept after failures.
#include "vkloc/core/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "support/test_support.hpp"
#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

namespace fs = std::filesystem;

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

size_t entries(const fs::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(AtomicFile, ReplacesARegularFileAndLeavesNoTemporary) {
  test::TempDir dir;
  const std::string path = dir.file("a.txt");
  ASSERT_TRUE(writeFileAtomically(path, "first").ok());
  ASSERT_TRUE(writeFileAtomically(path, "second").ok());
  EXPECT_EQ(readAll(path), "second");
  EXPECT_EQ(entries(dir.path()), 1u);
}

// A writer killed between writing and renaming leaves "<name>.tmp-<pid>-<n>": the next process
// to write into that folder removes it when that process no longer runs, and leaves a live
// process's temporaries and other files alone.
TEST(AtomicFile, TemporariesOfWritersThatNoLongerRunAreRemoved) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // `child` is now a process id nobody runs
  test::TempDir dir;
  const std::string dead = dir.file(text::cat("a.txt.tmp-", static_cast<long>(child), "-3"));
  const std::string live = dir.file(text::cat("b.txt.tmp-", static_cast<long>(::getppid()), "-0"));
  const std::string other = dir.file(text::cat("c.tmp-", static_cast<long>(child), "-x"));
  for (const std::string& f : {dead, live, other}) std::ofstream(f) << "half";
  ASSERT_TRUE(writeFileAtomically(dir.file("a.txt"), "whole").ok());
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(other));
  EXPECT_EQ(readAll(dir.file("a.txt")), "whole");
}

TEST(AtomicFile, FollowsASymbolicLinkAndKeepsIt) {
  test::TempDir dir;
  const std::string target = dir.file("target.txt");
  const std::string link = dir.file("link.txt");
  ASSERT_TRUE(writeFileAtomically(target, "old").ok());
  fs::create_symlink(target, link);
  ASSERT_TRUE(writeFileAtomically(link, "new").ok());
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(readAll(target), "new");
}

TEST(AtomicFile, WritesDevicesDirectlyAndReportsTheirErrors) {
  // /dev/null stays a device (replacing it with a regular file was the old behaviour as root).
  ASSERT_TRUE(writeFileAtomically("/dev/null", "gone").ok());
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  if (fs::exists("/dev/full")) {
    const Status full = writeFileAtomically("/dev/full", std::string(1 << 16, 'x'));
    ASSERT_FALSE(full.ok());
    EXPECT_EQ(full.error().code, ErrorCode::kIoError);
    EXPECT_NE(full.error().message.find("/dev/full"), std::string::npos);
    EXPECT_TRUE(fs::is_character_file("/dev/full"));
  }
}

TEST(AtomicFile, WritesAPipeDirectly) {
  test::TempDir dir;
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = readAll(fifo); });
  ASSERT_TRUE(writeFileAtomically(fifo, "through the pipe").ok());
  reader.join();
  EXPECT_EQ(received, "through the pipe");
  struct stat st {};
  ASSERT_EQ(stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST(AtomicFile, AFolderOrAMissingFolderIsAnError) {
  test::TempDir dir;
  const Status folder = writeFileAtomically(dir.path().string(), "x");
  ASSERT_FALSE(folder.ok());
  EXPECT_NE(folder.error().message.find("folder"), std::string::npos);
  const Status missing = writeFileAtomically(dir.file("no/such/dir.txt"), "x");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kIoError);
}

TEST(AtomicFile, FileSetCommitsTogetherOrNotAtAll) {
  test::TempDir dir;
  ASSERT_TRUE(writeFileAtomically(dir.file("a"), "old a").ok());
  {
    AtomicFileSet files;
    ASSERT_TRUE(files.write(dir.file("a"), "new a").ok());
    ASSERT_TRUE(files.write(dir.file("b"), [](std::ostream& out) { return static_cast<bool>(out << "new b"); }).ok());
    // Not committed: nothing changes, no temporary is left.
  }
  EXPECT_EQ(readAll(dir.file("a")), "old a");
  EXPECT_FALSE(fs::exists(dir.file("b")));
  EXPECT_EQ(entries(dir.path()), 1u);
  AtomicFileSet files;
  ASSERT_TRUE(files.write(dir.file("a"), "new a").ok());
  ASSERT_TRUE(files.write(dir.file("b"), "new b", 5).ok());
  ASSERT_TRUE(files.commit().ok());
  EXPECT_EQ(readAll(dir.file("a")), "new a");
  EXPECT_EQ(readAll(dir.file("b")), "new b");
}

TEST(AtomicFile, PartialWriterKeepsThePreviousFileUntilCommit) {
  test::TempDir dir;
  const std::string path = dir.file("traj.txt");
  ASSERT_TRUE(writeFileAtomically(path, "previous run\n").ok());
  {
    auto w = PartialFileWriter::open(path);
    ASSERT_TRUE(w.ok()) << w.error().message;
    ASSERT_TRUE((*w)->appendLine("1").ok());
    ASSERT_TRUE((*w)->appendLine("2").ok());
    EXPECT_EQ((*w)->lines(), 2u);
    EXPECT_EQ((*w)->partialPath(), path + ".partial");
    // The lines are on disk as they are written (an interrupted run keeps them).
    EXPECT_EQ(readAll(path + ".partial"), "1\n2\n");
    EXPECT_EQ(readAll(path), "previous run\n");
    // Destroyed without commit (a failed run): the partial file stays beside the old one.
  }
  EXPECT_EQ(readAll(path), "previous run\n");
  EXPECT_EQ(readAll(path + ".partial"), "1\n2\n");
  auto w = PartialFileWriter::open(path);
  ASSERT_TRUE(w.ok());
  ASSERT_TRUE((*w)->appendLine("3").ok());
  ASSERT_TRUE((*w)->commit().ok());
  EXPECT_EQ(readAll(path), "3\n");
  EXPECT_FALSE(fs::exists(path + ".partial"));
  // A non-regular target is written directly, with no partial file.
  auto null = PartialFileWriter::open("/dev/null");
  ASSERT_TRUE(null.ok());
  EXPECT_EQ((*null)->partialPath(), "/dev/null");
  ASSERT_TRUE((*null)->appendLine("x").ok());
  ASSERT_TRUE((*null)->commit().ok());
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_FALSE(PartialFileWriter::open(dir.file("no/such/dir/t.txt")).ok());
}

}  // namespace
}  // namespace vkloc
