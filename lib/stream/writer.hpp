// Writes a record stream: to stdout ("-", flushed after every record so pipelines and FIFO
// loops see each record at once), to a file atomically, or appended to a growing file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

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
};

class RecordWriter {
 public:
  // `path` "-" writes stdout (refused when stdout is a terminal).
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
  std::string path_;
  WriteOptions options_;
  std::unique_ptr<AtomicOutputFile> atomic_;
  int fd_ = -1;  // stdout or the append file
  uint64_t records_ = 0;
  uint64_t bytes_ = 0;
};

}  // namespace qte::stream
