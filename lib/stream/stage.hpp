// A pipeline stage in PDAL's sense: records in, records out. Every program that filters a
// stream (sim-step, plan-path, voxelize, qte-select, keyframe) is a stage plus its options,
// and run_stage() is the record loop they share, so each stage is unit-tested on records.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "stream/reader.hpp"
#include "stream/record.hpp"
#include "stream/writer.hpp"

namespace qte::stream {

using Emit = std::function<void(const Record&)>;

class Stage {
 public:
  virtual ~Stage() = default;
  // Before the first record (sim-step's first observation must go out before any input
  // arrives: in the actor loop the input is made from it).
  virtual void start(const Emit&) {}
  // One record in; what it produces (the record itself, for stages that pass records on) to `emit`.
  virtual void handle(const Record& record, const Emit& emit) = 0;
  // After the last record: what the stage still holds (an episode not yet converted).
  virtual void finish(const Emit&) {}
  // True when the stage wants no more input (sim-step after its planned episodes).
  virtual bool done() const { return false; }
  // The record types it acts on (empty: any, or none needed). Given records, but none of these
  // (a replay where observations belong), run_stage refuses the stream at its end, naming what
  // it held and which programs write the right ones.
  virtual std::vector<std::string> reads() const { return {}; }
};

// start, each record of `next` (until it returns nothing or the stage is done), finish.
void run_stage(Stage& stage, const std::function<std::optional<Record>()>& next, const Emit& emit);
// The same from a reader, with the check of Stage::reads() at the end of its stream.
void run_stage(Stage& stage, RecordReader& reader, const Emit& emit);
// The same to a writer, which is closed at the end (not when the input is refused).
void run_stage(Stage& stage, RecordReader& reader, RecordWriter& writer);
// Throws StreamError at the reader's position when `counts` (records read, by type) holds
// records but none of a type in `wanted`: "expected 'obs' records (observations, written by ...);
// the stream held 3 'frame', 2 'transition' (...)".
void require_record_types(const RecordReader& reader, const std::map<std::string, int64_t>& counts,
                          const std::vector<std::string>& wanted);

}  // namespace qte::stream
