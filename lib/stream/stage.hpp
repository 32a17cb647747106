// A pipeline stage in PDAL's sense: records in, records out. Every program that filters a
// stream (sim-step, plan-path, voxelize, qte-select, keyframe) is a stage plus its options,
// and run_stage() is the record loop they share, so each stage is unit-tested on records.
#pragma once

#include <functional>
#include <optional>

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
};

// start, each record of `next` (until it returns nothing or the stage is done), finish.
void run_stage(Stage& stage, const std::function<std::optional<Record>()>& next, const Emit& emit);
// The same from a reader to a writer, which is closed at the end.
void run_stage(Stage& stage, RecordReader& reader, RecordWriter& writer);

}  // namespace qte::stream
