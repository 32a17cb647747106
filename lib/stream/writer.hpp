// Writes a record stream: to stdout ("-", flushed after every record so pipelines and FIFO
// loops see each record at once), to a file atomically, or appended to a growing file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "stream/record.hpp"

namespace qte::stream {

enum class WriteMode {
  replace,  // the file appears complete on close() (temporary name + rename)
  append,   // each record is appended whole under an exclusive lock (replay logs, many actors);
            // for "-" the same as replace: standard output is a stream either way
};

struct WriteOptions {
  WriteMode mode = WriteMode::replace;
  int zstd_level = 3;  // for fields marked `compress`
  // Append only: cut a torn last record (left by a killed writer) off the file instead of
  // refusing to append behind it.
  bool repair = false;
  // The files this program reads ("-" = stdin): writing straight into one of them (an append,
  // or stdout redirected onto it) is refused, since it would read its own output forever.
  std::vector<std::string> inputs = {};
};

// Where a stream file's whole records end, from walking its record headers.
struct StreamEnd {
  uint64_t whole_bytes = 0;  // the offset after the last whole record
  uint64_t records = 0;      // how many whole records lie before it
  std::string damage;        // empty when the file ends exactly there; else what is wrong there
  bool torn_tail = false;    // the damage is only a last record cut short (or a damaged last
                             // payload): cutting the file back to whole_bytes repairs it
};

// Walks the record headers of the file open at `fd` (readable, `name` for messages) from
// `from`, a record boundary preceded by `records` records, to `size`: each header is checked
// (magic, checksum, version, type, length) and the last record's payload checksum too; the
// other payloads are not read, so a multi-gigabyte replay is walked in milliseconds.
StreamEnd find_stream_end(int fd, const std::string& name, uint64_t from, uint64_t records, uint64_t size);

class RecordWriter {
 public:
  // `path` "-" writes stdout (refused when stdout is a terminal). In append mode the file
  // must be a record stream whose last record is whole (checked here, under the lock) and
  // not one of options.inputs; otherwise a StreamError names the file, the record and the byte
  // offset where it stops being one (with options.repair a torn last record is cut off).
  explicit RecordWriter(const std::string& path, WriteOptions options = {});
  // Without close(), a replaced file is discarded (nothing half-written is left behind).
  ~RecordWriter();
  RecordWriter(const RecordWriter&) = delete;
  RecordWriter& operator=(const RecordWriter&) = delete;

  void write(const Record& record);
  void close();

  const std::string& path() const { return path_; }
  uint64_t records_written() const { return records_; }
  uint64_t bytes_written() const { return bytes_; }

 private:
  void check_append_target();
  void append(const std::vector<uint8_t>& bytes);

  std::string path_;
  WriteOptions options_;
  std::unique_ptr<AtomicOutputFile> atomic_;
  int fd_ = -1;  // stdout or the append file
  bool append_file_ = false;  // fd_ is a regular file appended under the lock
  StreamEnd checked_;         // the part of the append file known to be whole records
  uint64_t records_ = 0;
  uint64_t bytes_ = 0;
};

}  // namespace qte::stream
