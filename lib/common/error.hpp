// One error path for the whole toolkit: library code throws these, each tool's main catches
// them once (lib/cli) and prints a single line. Stream errors carry where the bad bytes are.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace qte {

// Anything the user can fix: bad input, bad options, a missing file.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bad command-line usage; tools exit with status 2 and point at --help.
class UsageError : public Error {
 public:
  using Error::Error;
};

// The reader of our output went away (EPIPE). Tools exit quietly, as Unix filters do.
class BrokenPipe : public Error {
 public:
  BrokenPipe() : Error("broken pipe") {}
};

// Where in a stream something is: file name ("-" is stdin), record index, byte offset.
struct StreamPosition {
  std::string source = "-";
  uint64_t record_index = 0;
  uint64_t byte_offset = 0;

  // "demos.rec: record 3 at byte 4096"
  std::string describe() const;
};

// A damaged or unexpected stream: "<source>: record <i> at byte <o>: <what was expected>".
class StreamError : public Error {
 public:
  StreamError(const StreamPosition& where, const std::string& what_expected);
  const StreamPosition& where() const { return where_; }

 private:
  StreamPosition where_;
};

// Throws Error("<what>: <strerror(errno)>"); for failed system calls.
[[noreturn]] void throw_system_error(const std::string& what);

}  // namespace qte
