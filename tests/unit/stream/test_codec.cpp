// Round trips and every kind of damage the format document lists.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "stream/codec.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace qte;
using namespace qte::stream;

namespace {

Record sample_record() {
  Record r("obs");
  r.set_string("task", "reach_target");
  r.set_scalar<int32_t>("step", 3);
  r.set<uint8_t>("rgb", {2, 2, 3}, std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  r.set<float>("depth", {2, 2}, std::vector<float>{0.5f, NAN, INFINITY, -1e-30f});
  r.set<double>("pose", {7}, std::vector<double>{0.1, 0.2, 0.3, 1, 0, 0, 0});
  r.set<int64_t>("ids", {0}, std::vector<int64_t>{});
  return r;
}

std::vector<Record> read_all(const std::vector<uint8_t>& bytes) {
  RecordReader reader(memory_source(bytes.data(), bytes.size()), "mem");
  std::vector<Record> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  return out;
}

// The error message of reading `bytes` to the end ("" when it reads cleanly).
std::string read_error(const std::vector<uint8_t>& bytes) {
  try {
    read_all(bytes);
  } catch (const StreamError& e) {
    return e.what();
  }
  return "";
}

void reseal_header(std::vector<uint8_t>& bytes, std::size_t at = 0) {
  const uint32_t crc = crc32_of(bytes.data() + at, 60);
  std::memcpy(bytes.data() + at + 60, &crc, 4);
}

void reseal_payload(std::vector<uint8_t>& bytes) {
  uint64_t len;
  std::memcpy(&len, bytes.data() + 32, 8);
  const uint32_t crc = crc32_of(bytes.data() + 64, len);
  std::memcpy(bytes.data() + 40, &crc, 4);
  reseal_header(bytes);
}

}  // namespace

TEST(Codec, RoundTripsEveryFieldBitForBit) {
  const Record in = sample_record();
  const auto bytes = encode_record(in);
  ASSERT_EQ(bytes.size() % 64, 0u);
  const auto out = read_all(bytes);
  ASSERT_EQ(out.size(), 1u);
  const Record& r = out[0];
  EXPECT_EQ(r.type(), "obs");
  ASSERT_EQ(r.fields().size(), in.fields().size());
  for (std::size_t i = 0; i < in.fields().size(); ++i) {
    const Field &a = in.fields()[i], &b = r.fields()[i];
    EXPECT_EQ(a.name(), b.name());
    EXPECT_EQ(a.dtype(), b.dtype());
    EXPECT_EQ(a.shape(), b.shape());
    ASSERT_EQ(a.byte_count(), b.byte_count());
    EXPECT_EQ(std::memcmp(a.bytes(), b.bytes(), a.byte_count()), 0) << a.name();
    EXPECT_EQ(reinterpret_cast<uintptr_t>(b.bytes()) % 64, 0u) << "field data not aligned";
  }
  EXPECT_EQ(r.string("task"), "reach_target");
  EXPECT_EQ(r.scalar<int32_t>("step"), 3);
  EXPECT_TRUE(std::isnan(r.array<float>("depth")[1]));
}

TEST(Codec, EncodingIsDeterministic) {
  EXPECT_EQ(encode_record(sample_record()), encode_record(sample_record()));
}

TEST(Codec, CompressedFieldsRoundTripAndShrink) {
  Record r("obs");
  std::vector<uint16_t> depth(128 * 128);
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<uint16_t>(800 + i / 128);
  r.set<uint16_t>("depth_mm", {128, 128}, depth, /*compress=*/true);
  const auto bytes = encode_record(r);
  EXPECT_LT(bytes.size(), depth.size() * 2 / 4);
  const auto out = read_all(bytes);
  const auto view = out.at(0).array<uint16_t>("depth_mm");
  EXPECT_TRUE(std::equal(view.begin(), view.end(), depth.begin()));
  EXPECT_TRUE(out[0].field("depth_mm").compress);
}

// A field read compressed is written again with the frame it came in, not compressed anew:
// the same bytes at the same level, and (shown with a frame of another level) no new frame.
TEST(Codec, CompressedFieldsPassedOnKeepTheirFrame) {
  Record r("obs");
  std::vector<uint16_t> depth(128 * 128);
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<uint16_t>(800 + (i * 7919) % 1000);
  r.set<uint16_t>("depth_mm", {128, 128}, depth, /*compress=*/true);
  r.set_string("task", "reach_prism");
  const auto level3 = encode_record(r);
  EXPECT_EQ(encode_record(read_all(level3).at(0)), level3);
  const auto other = encode_record(r, -5);  // zstd's fast mode: another frame for the same elements
  ASSERT_NE(other, level3);
  Record passed = read_all(other).at(0);
  EXPECT_NE(passed.field("depth_mm").encoded(), nullptr);
  EXPECT_EQ(encode_record(passed, 3), other);  // written as it came
  passed.set_string("task", "pick_and_lift");  // other fields may change around it
  const auto changed = read_all(encode_record(passed, 3)).at(0);
  const auto view = changed.array<uint16_t>("depth_mm");
  EXPECT_TRUE(std::equal(view.begin(), view.end(), depth.begin()));
  // Elements made anew (set) are compressed anew.
  Record fresh = passed;
  fresh.set<uint16_t>("depth_mm", {128, 128}, depth, /*compress=*/true);
  EXPECT_EQ(fresh.field("depth_mm").encoded(), nullptr);
  EXPECT_EQ(encode_record(fresh, 3).size(), encode_record([&] {
              Record x = r;
              x.set_string("task", "pick_and_lift");
              return x;
            }(), 3).size());
}

TEST(Codec, ReadsConsecutiveRecordsWithOffsets) {
  auto bytes = encode_record(sample_record());
  const std::size_t first = bytes.size();
  const auto second = encode_record(Record("reset"));
  bytes.insert(bytes.end(), second.begin(), second.end());
  RecordReader reader(memory_source(bytes.data(), bytes.size()), "mem");
  auto a = reader.next();
  auto b = reader.next();
  ASSERT_TRUE(a && b);
  EXPECT_FALSE(reader.next());
  EXPECT_EQ(a->position.byte_offset, 0u);
  EXPECT_EQ(b->position.byte_offset, first);
  EXPECT_EQ(b->position.record_index, 1u);
  EXPECT_EQ(b->type(), "reset");
}

TEST(Damage, TruncatedHeader) {
  auto bytes = encode_record(sample_record());
  bytes.resize(30);
  EXPECT_NE(read_error(bytes).find("mem: record 0 at byte 0: truncated stream"),
            std::string::npos);
}

TEST(Damage, TruncatedPayloadNamesTheSecondRecord) {
  auto bytes = encode_record(sample_record());
  const std::size_t first = bytes.size();
  const auto second = encode_record(sample_record());
  bytes.insert(bytes.end(), second.begin(), second.end() - 100);
  const std::string e = read_error(bytes);
  EXPECT_NE(e.find("record 1 at byte " + std::to_string(first) + ": truncated"),
            std::string::npos) << e;
}

TEST(Damage, WrongMagic) {
  auto bytes = encode_record(sample_record());
  bytes[1] = 'X';
  EXPECT_NE(read_error(bytes).find("bad magic"), std::string::npos);
}

TEST(Damage, UnsupportedVersion) {
  auto bytes = encode_record(sample_record());
  bytes[8] = 2;
  reseal_header(bytes);
  EXPECT_NE(read_error(bytes).find("unsupported format version 2.0"), std::string::npos);
}

TEST(Damage, NewerMinorVersionIsRead) {
  auto bytes = encode_record(sample_record());
  bytes[10] = 7;
  reseal_header(bytes);
  EXPECT_EQ(read_error(bytes), "");
}

TEST(Damage, HeaderChecksum) {
  auto bytes = encode_record(sample_record());
  bytes[20] ^= 1;
  EXPECT_NE(read_error(bytes).find("header checksum mismatch"), std::string::npos);
}

TEST(Damage, PayloadChecksum) {
  auto bytes = encode_record(sample_record());
  bytes[bytes.size() - 70] ^= 0x40;
  EXPECT_NE(read_error(bytes).find("payload checksum mismatch"), std::string::npos);
}

TEST(Damage, AbsurdPayloadLength) {
  auto bytes = encode_record(sample_record());
  const uint64_t huge = uint64_t(1) << 50;
  std::memcpy(bytes.data() + 32, &huge, 8);
  reseal_header(bytes);
  EXPECT_NE(read_error(bytes).find("absurd payload length"), std::string::npos);
}

TEST(Damage, UnknownDtype) {
  auto bytes = encode_record(sample_record());
  bytes[64] = 99;  // dtype code of the first field
  reseal_payload(bytes);
  const std::string e = read_error(bytes);
  EXPECT_NE(e.find("unknown dtype code 99"), std::string::npos) << e;
  EXPECT_NE(e.find("at byte 64"), std::string::npos) << e;
}

TEST(Damage, ShapeDoesNotMatchByteCount) {
  Record r("obs");
  r.set<float>("depth", {4}, std::vector<float>{1, 2, 3, 4});
  auto bytes = encode_record(r);
  const int64_t wrong = 5;
  std::memcpy(bytes.data() + 64 + 16, &wrong, 8);  // first extent of the first field
  reseal_payload(bytes);
  const std::string e = read_error(bytes);
  EXPECT_NE(e.find("needs 20 bytes, stored 16"), std::string::npos) << e;
}

TEST(Damage, MissingFieldNamesRecordAndOffset) {
  const auto out = read_all(encode_record(sample_record()));
  try {
    out[0].array<float>("point_cloud");
    FAIL() << "expected an error";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("mem: record 0 at byte 0: 'obs' record has no field "
                                         "'point_cloud'"),
              std::string::npos) << e.what();
  }
}

TEST(Damage, WrongDtypeIsNamed) {
  const auto out = read_all(encode_record(sample_record()));
  try {
    out[0].array<double>("depth");
    FAIL() << "expected an error";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("expected float64, got float32"), std::string::npos);
  }
}

TEST(Damage, CorruptZstdData) {
  Record r("obs");
  std::vector<uint8_t> img(4096, 7);
  r.set<uint8_t>("rgb", {4096}, img, true);
  auto bytes = encode_record(r);
  bytes[64 + 64 + 6] ^= 0xff;  // inside the zstd frame, after its header
  reseal_payload(bytes);
  EXPECT_NE(read_error(bytes).find("'rgb': zstd"), std::string::npos) << read_error(bytes);
}

TEST(Damage, EveryTruncationIsAnErrorNotACrash) {
  auto bytes = encode_record(sample_record());
  for (std::size_t n = 1; n < bytes.size(); n += 7) {
    std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + n);
    EXPECT_NE(read_error(cut), "") << n;
  }
}

// A failed append (here a file-size limit standing in for a full disk) leaves the file as it
// was: the next append lands behind the last whole record and every record reads back.
TEST(Append, AFailedAppendLeavesNoTornRecord) {
  char tmpl[] = "/tmp/qte_append_XXXXXX";
  const std::string path = std::string(::mkdtemp(tmpl)) + "/replay.rec";
  {
    RecordWriter w(path, {WriteMode::append});
    w.write(sample_record());
    w.close();
  }
  struct stat before {};
  ASSERT_EQ(::stat(path.c_str(), &before), 0);
  const pid_t child = ::fork();
  if (child == 0) {  // a writer whose disk fills up half-way through a large record
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{static_cast<rlim_t>(before.st_size + 100), static_cast<rlim_t>(before.st_size + 100)};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    Record big("transition");
    big.set<float>("payload", {100000}, std::vector<float>(100000, 1.5f));
    try {
      RecordWriter w(path, {WriteMode::append});
      w.write(big);
      ::_exit(0);  // should not get here
    } catch (const Error&) {
      ::_exit(3);
    }
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3) << "the append did not fail";
  struct stat after {};
  ASSERT_EQ(::stat(path.c_str(), &after), 0);
  EXPECT_EQ(after.st_size, before.st_size) << "a torn record was left behind";
  {
    RecordWriter w(path, {WriteMode::append});
    w.write(sample_record());
    w.close();
  }
  RecordReader reader(path);
  int records = 0;
  while (reader.next()) ++records;
  EXPECT_EQ(records, 2);
}
