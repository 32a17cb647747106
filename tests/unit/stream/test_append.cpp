// Appends land only behind a whole record of a record stream (lib/stream/writer.cpp).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>

#include "stream/codec.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::stream;

namespace {

Record numbered(int i) {
  Record r("transition");
  r.set_scalar<int32_t>("i", i);
  r.set<float>("x", {100}, std::vector<float>(100, 0.5f * i));
  return r;
}

void write_bytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

std::vector<uint8_t> stream_of(int n) {
  std::vector<uint8_t> out;
  for (int i = 0; i < n; ++i) {
    const auto r = encode_record(numbered(i));
    out.insert(out.end(), r.begin(), r.end());
  }
  return out;
}

uint64_t file_size(const std::string& path) {
  struct stat info {};
  EXPECT_EQ(::stat(path.c_str(), &info), 0);
  return static_cast<uint64_t>(info.st_size);
}

int count_records(const std::string& path) {
  RecordReader reader(path);
  int n = 0;
  while (reader.next()) ++n;
  return n;
}

WriteOptions appending(bool repair = false) {
  WriteOptions options;
  options.mode = WriteMode::append;
  options.repair = repair;
  return options;
}

std::string append_error(const std::string& path, WriteOptions options = appending()) {
  try {
    RecordWriter w(path, options);
    w.write(numbered(99));
    w.close();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(StreamEnd, WalksHeadersToTheLastWholeRecord) {
  const std::string path = test_support::temp_dir("stream_end") + "/s.rec";
  const auto bytes = stream_of(3);
  const uint64_t one = bytes.size() / 3;
  write_bytes(path, std::vector<uint8_t>(bytes.begin(), bytes.end() - 10));
  const int fd = ::open(path.c_str(), O_RDONLY);
  const StreamEnd end = find_stream_end(fd, path, 0, 0, bytes.size() - 10);
  ::close(fd);
  EXPECT_EQ(end.whole_bytes, 2 * one);
  EXPECT_EQ(end.records, 2u);
  EXPECT_TRUE(end.torn_tail);
  EXPECT_NE(end.damage.find("torn record"), std::string::npos) << end.damage;
}

TEST(Append, RefusesATornTailAndRepairsItOnlyWhenAsked) {
  const std::string path = test_support::temp_dir("append_torn") + "/replay.rec";
  const auto bytes = stream_of(3);
  const uint64_t one = bytes.size() / 3;
  write_bytes(path, std::vector<uint8_t>(bytes.begin(), bytes.begin() + 2 * one + 100));
  const std::string error = append_error(path);
  EXPECT_NE(error.find(path + ": record 2 at byte " + std::to_string(2 * one) + ": cannot append"), std::string::npos)
      << error;
  EXPECT_EQ(file_size(path), 2 * one + 100) << "the refused append changed the file";
  EXPECT_EQ(append_error(path, appending(/*repair=*/true)), "");
  EXPECT_EQ(count_records(path), 3);
}

TEST(Append, RefusesAFileThatIsNotAStream) {
  const std::string path = test_support::temp_dir("append_foreign") + "/notes.txt";
  write_bytes(path, std::vector<uint8_t>(200, 'a'));
  const std::string error = append_error(path, appending(/*repair=*/true));
  EXPECT_NE(error.find(path + ": record 0 at byte 0: cannot append: bad magic"), std::string::npos) << error;
  EXPECT_EQ(file_size(path), 200u);
}

TEST(Append, RefusesAnInputAsTheOutput) {
  const std::string path = test_support::temp_dir("append_self") + "/replay.rec";
  write_bytes(path, stream_of(2));
  WriteOptions options = appending();
  options.inputs = {"/nonexistent/other.rec", path};
  const std::string error = append_error(path, options);
  EXPECT_NE(error.find("it is also an input"), std::string::npos) << error;
  EXPECT_EQ(count_records(path), 2);
}

// Another appender killed mid-record (SIGKILL cannot be deferred) leaves a torn tail behind
// this writer's last check: the next append finds it instead of landing behind it.
TEST(Append, FindsATornRecordLeftByAnotherAppender) {
  const std::string path = test_support::temp_dir("append_other") + "/replay.rec";
  RecordWriter w(path, appending());
  w.write(numbered(0));
  const auto torn = encode_record(numbered(1));
  {
    std::ofstream out(path, std::ios::binary | std::ios::app);
    out.write(reinterpret_cast<const char*>(torn.data()), 100);
  }
  EXPECT_THROW(w.write(numbered(2)), StreamError);
  RecordWriter repairing(path, appending(/*repair=*/true));
  repairing.write(numbered(3));
  repairing.close();
  EXPECT_EQ(count_records(path), 2);
}
