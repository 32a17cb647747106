// run_stage: start before the first record is asked for, records in order until the input ends
// or the stage is done, finish last; from a reader to a writer, the writer closed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "stream/reader.hpp"
#include "stream/stage.hpp"
#include "stream/writer.hpp"

using namespace qte;
using namespace qte::stream;

namespace {

Record numbered(const std::string& type, int32_t n) {
  Record r(type);
  r.set_scalar<int32_t>("n", n);
  return r;
}

// Emits "start" at once, each record's n doubled as "twice", and "finish" with the count of
// records seen; done after `stop_after` records.
struct Doubler : Stage {
  int seen = 0, stop_after = 1000;
  void start(const Emit& emit) override { emit(numbered("start", 0)); }
  void handle(const Record& r, const Emit& emit) override {
    ++seen;
    emit(numbered("twice", 2 * r.scalar<int32_t>("n")));
  }
  void finish(const Emit& emit) override { emit(numbered("finish", seen)); }
  bool done() const override { return seen >= stop_after; }
};

}  // namespace

TEST(Stage, StartsBeforeTheFirstReadAndFinishesAfterTheLast) {
  std::vector<std::string> log;
  Doubler stage;
  int next = 0;
  std::vector<Record> out;
  run_stage(
      stage,
      [&]() -> std::optional<Record> {
        log.push_back("read " + std::to_string(next));
        // The first read comes after start() emitted (the actor loop's input is made from it).
        EXPECT_FALSE(out.empty());
        if (next == 3) return std::nullopt;
        return numbered("in", next++);
      },
      [&](const Record& r) { out.push_back(r); });
  ASSERT_EQ(out.size(), 5u);
  EXPECT_EQ(out.front().type(), "start");
  for (int i = 0; i < 3; ++i) EXPECT_EQ(out[1 + i].scalar<int32_t>("n"), 2 * i);
  EXPECT_EQ(out.back().type(), "finish");
  EXPECT_EQ(out.back().scalar<int32_t>("n"), 3);
  EXPECT_EQ(log.size(), 4u);  // three records and the end
}

TEST(Stage, ADoneStageReadsNoMore) {
  Doubler stage;
  stage.stop_after = 2;
  int reads = 0;
  std::vector<Record> out;
  run_stage(
      stage, [&]() -> std::optional<Record> { return numbered("in", reads++); },
      [&](const Record& r) { out.push_back(r); });
  EXPECT_EQ(reads, 2);  // an endless input: the stage ended it
  EXPECT_EQ(out.back().type(), "finish");
  EXPECT_EQ(out.back().scalar<int32_t>("n"), 2);
}

TEST(Stage, FromAReaderToAWriter) {
  const std::string in = ::testing::TempDir() + "stage_in_" + std::to_string(::getpid()) + ".rec";
  const std::string out = ::testing::TempDir() + "stage_out_" + std::to_string(::getpid()) + ".rec";
  {
    RecordWriter writer(in);
    for (int i = 0; i < 4; ++i) writer.write(numbered("in", i));
    writer.close();
  }
  Doubler stage;
  RecordReader reader(in);
  RecordWriter writer(out);
  run_stage(stage, reader, writer);
  RecordReader check(out);  // closed: the file is complete under its name
  std::vector<int32_t> values;
  while (auto r = check.next()) values.push_back(r->scalar<int32_t>("n"));
  EXPECT_EQ(values, (std::vector<int32_t>{0, 0, 2, 4, 6, 4}));
  std::remove(in.c_str());
  std::remove(out.c_str());
}
