#include "stream/stage.hpp"

namespace qte::stream {

void run_stage(Stage& stage, const std::function<std::optional<Record>()>& next, const Emit& emit) {
  stage.start(emit);
  while (!stage.done()) {
    const std::optional<Record> record = next();
    if (!record) break;
    stage.handle(*record, emit);
  }
  stage.finish(emit);
}

void run_stage(Stage& stage, RecordReader& reader, RecordWriter& writer) {
  run_stage(stage, [&] { return reader.next(); }, [&](const Record& r) { writer.write(r); });
  writer.close();
}

}  // namespace qte::stream
