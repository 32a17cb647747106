#include "stream/stage.hpp"

#include "common/error.hpp"
#include "stream/record_types.hpp"

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

void require_record_types(const RecordReader& reader, const std::map<std::string, int64_t>& counts,
                          const std::vector<std::string>& wanted) {
  if (counts.empty() || wanted.empty()) return;
  for (const std::string& type : wanted)
    if (counts.count(type)) return;
  std::string expected, held;
  for (const std::string& type : wanted) {
    const RecordType* t = find_record_type(type);
    expected += (expected.empty() ? "'" : " or '") + type + "' records" +
                (t ? std::string(" (") + t->what + ", written by " + t->written_by + ")" : "");
  }
  for (const auto& [type, n] : counts) {
    const RecordType* t = find_record_type(type);
    if (t) held += (held.empty() ? "" : "; ") + std::string("'") + type + "': " + t->what + ", from " + t->written_by;
  }
  throw StreamError({reader.name(), reader.records_read(), reader.byte_offset()},
                    "expected " + expected + "; the stream held " + describe_counts(counts) +
                        (held.empty() ? std::string() : " (" + held + ")"));
}

void run_stage(Stage& stage, RecordReader& reader, const Emit& emit) {
  std::map<std::string, int64_t> counts;
  run_stage(
      stage,
      [&]() -> std::optional<Record> {
        std::optional<Record> record = reader.next();
        if (record) ++counts[record->type()];
        return record;
      },
      emit);
  if (!stage.done()) require_record_types(reader, counts, stage.reads());
}

void run_stage(Stage& stage, RecordReader& reader, RecordWriter& writer) {
  run_stage(stage, reader, [&](const Record& r) { writer.write(r); });
  writer.close();
}

}  // namespace qte::stream
