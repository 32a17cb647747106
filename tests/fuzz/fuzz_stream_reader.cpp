// libFuzzer target: any bytes given to the stream reader must end in records or a StreamError,
// never a crash, a hang, a sanitizer report or an unbounded allocation. Run: make fuzz.
#include <cstddef>
#include <cstdint>

#include "stream/inspect.hpp"
#include "stream/reader.hpp"
#include "stream/codec.hpp"

#include <sstream>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qte::stream::ReadOptions options;
  options.max_record_bytes = 1 << 20;  // keeps allocations small; larger is rejected as damage
  qte::stream::RecordReader reader(qte::stream::memory_source(data, size), "fuzz", options);
  try {
    while (auto record = reader.next()) {
      // Touch every field the way stream-dump and pass-through tools do.
      std::ostringstream sink;
      qte::stream::print_record_json(sink, *record, 0, {-1});
      const auto again = qte::stream::encode_record(*record);
      (void)again;
    }
  } catch (const qte::Error&) {
  }
  return 0;
}
