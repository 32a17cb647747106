// Reading what another process or a person wrote (a driver's answer, a joint log, a file of
// outcomes) with a bound on its size: an endless file (/dev/zero), a huge one, a FIFO nobody
// writes to or a directory is one Error naming the file and the limit, never a hang or a
// process that grows without end.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace qte {

// The whole of `path`, which must be a regular file (a FIFO, a device or a directory is refused
// without waiting on it) of at most `limit_bytes`. `what` says what the file is for, in errors.
std::string read_regular_file(const std::string& path, std::size_t limit_bytes, const std::string& what);

// Lines of `path` (a regular file or a FIFO, not a directory), each at most `line_limit_bytes`
// and all of them at most `total_limit_bytes`; the '\n' (and a '\r' before it) removed.
class BoundedLines {
 public:
  BoundedLines(std::string path, std::size_t line_limit_bytes, uint64_t total_limit_bytes, std::string what);
  bool next(std::string& line);  // false at the end of the file
  int line_number() const { return line_number_; }  // of the line next() returned, from 1
  const std::string& path() const { return path_; }

 private:
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string path_, what_;
  std::size_t line_limit_;
  uint64_t total_limit_, total_ = 0;
  int line_number_ = 0;
  std::unique_ptr<std::FILE, Closer> file_;
};

// `text` as valid UTF-8 without ASCII control characters (each bad byte becomes '?'), cut at a
// character boundary to at most `limit_bytes`: words from outside fit in a record's string.
std::string clean_text(const std::string& text, std::size_t limit_bytes);

}  // namespace qte
