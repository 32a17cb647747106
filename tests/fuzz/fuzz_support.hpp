// Shared by the fuzz targets: the fuzzer's bytes read as a record stream (the fuzz build does
// not enforce checksums, FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION in CMakeLists.txt, so
// mutations reach the records' fields) and every decoded record given to `use`, or written to a
// file for the readers that take a path. StreamError and Error (a record or file refused with a
// message) are the expected outcomes; a crash, a sanitizer report, a hang or an allocation past
// libFuzzer's limit is a finding.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>

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

// For readers that take a path (the camera recordings' files): the fuzzer's bytes as an
// in-memory file (memfd, so nothing is left on disk however the fuzzer stops), and its path.
inline const std::string& as_file(const uint8_t* data, std::size_t size) {
  static const int fd = ::memfd_create("qte_fuzz_input", 0);
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  if (fd < 0 || ::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) std::abort();
  return path;
}

}  // namespace qte::fuzz
