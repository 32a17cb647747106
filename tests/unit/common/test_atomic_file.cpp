#include <gtest/gtest.h>
#include <unistd.h>

#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>
#include <vector>

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

namespace {
std::string listing(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  std::string text;
  for (const auto& name : names) text += name + " ";
  return text;
}
std::string contents(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
}  // namespace

// Several files appear all or none: before commit() nothing is in DIR; abandoned, DIR keeps what
// it had (an old file of the same name included) and a DIR the run created goes again.
TEST(OutputDirectory, FilesAppearAllOrNone) {
  const std::string dir = temp_dir(), out = dir + "/pictures";
  {
    OutputDirectory pictures(out);
    pictures.write_file("0.png", "a", 1);
    write_file_atomically(pictures.path("1.png"), "b", 1);  // as a library given a path writes
    EXPECT_EQ(listing(out), ".qte-staging.tmp." + std::to_string(::getpid()) + " ");
  }
  EXPECT_FALSE(exists(out)) << "a directory this run created stays behind a failure";
  make_output_directory(out);
  std::ofstream(out + "/0.png") << "old";
  {
    OutputDirectory pictures(out);
    pictures.write_file("0.png", "new", 3);
    pictures.write_file("2.png", "c", 1);
  }
  EXPECT_EQ(listing(out), "0.png ");
  EXPECT_EQ(contents(out + "/0.png"), "old");
  {
    OutputDirectory pictures(out);
    pictures.write_file("0.png", "new", 3);
    pictures.write_file("2.png", "c", 1);
    pictures.commit();
  }
  EXPECT_EQ(listing(out), "0.png 2.png ");
  EXPECT_EQ(contents(out + "/0.png"), "new");
}

// A signal while files are staged removes them and the directory the run made; a SIGKILL's
// staging directory is removed by the next writer into DIR.
TEST(OutputDirectory, SignalsAndKillsLeaveNothing) {
  const std::string dir = temp_dir(), out = dir + "/signalled";
  for (int signal_number : {SIGTERM, SIGKILL}) {
    int ready[2];
    ASSERT_EQ(::pipe(ready), 0);
    const pid_t child = ::fork();
    if (child == 0) {
      OutputDirectory pictures(out);
      for (int i = 0; i < 100; ++i) pictures.write_file(std::to_string(i) + ".png", "x", 1);
      (void)!::write(ready[1], "r", 1);
      ::pause();
      ::_exit(0);
    }
    char c;
    ASSERT_EQ(::read(ready[0], &c, 1), 1);
    ::close(ready[0]), ::close(ready[1]);
    ::kill(child, signal_number);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status));
    if (signal_number == SIGTERM) {
      EXPECT_FALSE(exists(out)) << listing(out);
    } else {
      ASSERT_EQ(listing(out), ".qte-staging.tmp." + std::to_string(child) + " ");
      OutputDirectory next(out);
      next.write_file("a.png", "y", 1);
      next.commit();
      EXPECT_EQ(listing(out), "a.png ");
    }
  }
}

// An output that is a symbolic link is followed: its target gets the bytes, the link stays (a
// dangling link's target is made).
TEST(AtomicFile, SymbolicLinksAreFollowed) {
  const std::string dir = temp_dir();
  std::filesystem::create_directory(dir + "/disk");
  std::filesystem::create_symlink("disk/replay.rec", dir + "/replay.rec");
  for (const char* text : {"first", "second"}) {
    write_file_atomically(dir + "/replay.rec", text, std::strlen(text));
    EXPECT_TRUE(std::filesystem::is_symlink(dir + "/replay.rec"));
    EXPECT_EQ(contents(dir + "/disk/replay.rec"), text);
  }
  EXPECT_EQ(listing(dir + "/disk"), "replay.rec ");
}
