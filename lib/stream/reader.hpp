// Reads a record stream one record at a time, from a file, a pipe ("-" = stdin) or memory.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "stream/record.hpp"

namespace qte::stream {

// Where bytes come from. read() returns how many bytes it put in `buffer` (0 only at the end).
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual std::size_t read(uint8_t* buffer, std::size_t n) = 0;
};

struct ReadOptions {
  // Larger payload lengths are treated as damage rather than allocated.
  uint64_t max_record_bytes = uint64_t(4) << 30;
};

class RecordReader {
 public:
  // `path` "-" reads stdin. Throws Error when the file cannot be opened.
  explicit RecordReader(const std::string& path, ReadOptions options = {});
  RecordReader(std::unique_ptr<ByteSource> source, std::string name, ReadOptions options = {});
  ~RecordReader();
  RecordReader(const RecordReader&) = delete;
  RecordReader& operator=(const RecordReader&) = delete;

  // The next record, or nothing at a clean end of stream. Throws StreamError on damage,
  // naming the source, the record index and the byte offset.
  std::optional<Record> next();

  const std::string& name() const { return position_.source; }
  uint64_t records_read() const { return position_.record_index; }
  uint64_t byte_offset() const { return position_.byte_offset; }

 private:
  std::size_t read_fully(uint8_t* buffer, std::size_t n);

  std::unique_ptr<ByteSource> source_;
  ReadOptions options_;
  StreamPosition position_;
};

// A source over bytes in memory (tests, the fuzz target).
std::unique_ptr<ByteSource> memory_source(const uint8_t* data, std::size_t size);

}  // namespace qte::stream
