// Shared by the per-record-type fuzz targets: the fuzzer's bytes read as a record stream (the
// fuzz build does not enforce checksums, FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION in
// CMakeLists.txt, so mutations reach the records' fields) and every decoded record given to
// `use`. StreamError and Error (a record refused with a message) are the expected outcomes; a
// crash, a sanitizer report, a hang or an allocation past libFuzzer's limit is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>

#include "common/error.hpp"
#include "stream/reader.hpp"

namespace qte::fuzz {

inline void for_each_record(const uint8_t* data, std::size_t size, const std::function<void(const stream::Record&)>& use) {
  stream::ReadOptions options;
  options.max_record_bytes = 8 << 20;  // keeps allocations within libFuzzer's limit; larger is damage
  stream::RecordReader reader(stream::memory_source(data, size), "fuzz", options);
  try {
    while (auto record = reader.next()) {
      try {
        use(*record);
      } catch (const Error&) {  // this record refused with a message: go on with the next
      }
    }
  } catch (const Error&) {  // damage: the stream ends here
  }
}

}  // namespace qte::fuzz
