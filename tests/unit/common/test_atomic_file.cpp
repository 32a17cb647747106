#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

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
