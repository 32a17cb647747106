#include <gtest/gtest.h>
#include <unistd.h>

#include <sys/stat.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "common/atomic_file.hpp"
#include "stream/writer.hpp"

using namespace qte;

namespace {
bool exists(const std::string& p) { return ::access(p.c_str(), F_OK) == 0; }
std::string temp_dir() {
  char tmpl[] = "/tmp/qte_atomic_XXXXXX";
  return ::mkdtemp(tmpl);
}
}  // namespace

TEST(AtomicFile, AppearsOnlyOnCommit) {
  const std::string dir = temp_dir(), path = dir + "/out.bin";
  {
    AtomicOutputFile f(path);
    f.write("abc", 3);
    EXPECT_FALSE(exists(path));
    f.commit();
  }
  EXPECT_TRUE(exists(path));
  std::ifstream in(path);
  std::string s;
  in >> s;
  EXPECT_EQ(s, "abc");
}

TEST(AtomicFile, AbandonedWriteLeavesNothing) {
  const std::string dir = temp_dir(), path = dir + "/out.rec";
  {
    stream::RecordWriter w(path);
    w.write(stream::Record("reset"));
    // no close(): as if the tool failed half-way
  }
  EXPECT_FALSE(exists(path));
  EXPECT_FALSE(exists(path + ".tmp." + std::to_string(::getpid())));
}

TEST(AtomicFile, AbandonedWriteKeepsTheOldFile) {
  const std::string dir = temp_dir(), path = dir + "/ckpt.rec";
  {
    stream::RecordWriter w(path);
    w.write(stream::Record("checkpoint"));
    w.close();
  }
  const auto size_before = std::ifstream(path, std::ios::ate).tellg();
  {
    stream::RecordWriter w(path);
    w.write(stream::Record("checkpoint"));
    w.write(stream::Record("checkpoint"));
  }
  EXPECT_EQ(std::ifstream(path, std::ios::ate).tellg(), size_before);
}

TEST(AtomicFile, DevicesAndPipesAreWrittenInPlaceNotReplaced) {
  {
    stream::RecordWriter w("/dev/null");
    w.write(stream::Record("reset"));
    w.close();
  }
  struct stat info {};
  ASSERT_EQ(::stat("/dev/null", &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode)) << "/dev/null was replaced by a file";
  const std::string dir = temp_dir(), fifo = dir + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread reader([&] {
    std::ifstream in(fifo, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(bytes.size(), 64u);  // one record with no fields: its header
  });
  {
    stream::RecordWriter w(fifo);
    w.write(stream::Record("reset"));
    w.close();
  }
  reader.join();
  ASSERT_EQ(::stat(fifo.c_str(), &info), 0);
  EXPECT_TRUE(S_ISFIFO(info.st_mode));
}

// A SIGKILL leaves NAME.tmp.PID behind; the next writer of NAME removes it (and a checkpoint
// directory all of them), but never one whose process still runs.
TEST(AtomicFile, StaleTemporariesOfDeadWritersAreRemoved) {
  const std::string dir = temp_dir();
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);  // a pid whose process is gone
  const std::string dead = std::to_string(child), alive = std::to_string(::getppid());
  for (const std::string& name : {"out.rec.tmp." + dead, "out.rec.tmp." + alive, "other.rec.tmp." + dead,
                                 "step-00000003.rec.tmp." + dead, std::string("notes.tmp.txt")})
    std::ofstream(dir + "/" + name) << "x";
  {
    AtomicOutputFile f(dir + "/out.rec");
    f.write("abc", 3);
    f.commit();
  }
  EXPECT_FALSE(exists(dir + "/out.rec.tmp." + dead));
  EXPECT_TRUE(exists(dir + "/out.rec.tmp." + alive));
  EXPECT_TRUE(exists(dir + "/other.rec.tmp." + dead));  // another output's: not this writer's to judge
  EXPECT_EQ(remove_stale_temporaries(dir), 2);         // a checkpoint directory: every dead writer's
  EXPECT_FALSE(exists(dir + "/step-00000003.rec.tmp." + dead));
  EXPECT_TRUE(exists(dir + "/out.rec.tmp." + alive));
  EXPECT_TRUE(exists(dir + "/notes.tmp.txt"));
}

// An output directory that exists is used; a file in its place is an error naming it.
TEST(OutputDirectory, MadeOrReusedButNeverAFile) {
  const std::string dir = temp_dir();
  make_output_directory(dir + "/out");
  make_output_directory(dir + "/out");  // again: already there
  EXPECT_TRUE(std::filesystem::is_directory(dir + "/out"));
  std::ofstream(dir + "/file").put('x');
  try {
    make_output_directory(dir + "/file");
    FAIL() << "a file taken for a directory";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/file: exists and is not a directory"), std::string::npos) << e.what();
  }
}
