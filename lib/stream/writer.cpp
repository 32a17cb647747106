#include "stream/writer.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <limits>

#include "stream/codec.hpp"

namespace qte::stream {
namespace {

void read_at(int fd, uint8_t* buffer, std::size_t n, uint64_t offset, const std::string& name) {
  std::size_t have = 0;
  while (have < n) {
    const ssize_t got = ::pread(fd, buffer + have, n - have, static_cast<off_t>(offset + have));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw_system_error("cannot read " + name);
    if (got == 0) throw Error("cannot read " + name + ": it shrank while being checked");
    have += static_cast<std::size_t>(got);
  }
}

uint32_t crc32_at(int fd, uint64_t offset, uint64_t n, const std::string& name) {
  std::vector<uint8_t> chunk(std::min<uint64_t>(n, 1u << 20));
  uLong crc = crc32(0L, Z_NULL, 0);
  while (n > 0) {
    const std::size_t k = static_cast<std::size_t>(std::min<uint64_t>(n, chunk.size()));
    read_at(fd, chunk.data(), k, offset, name);
    crc = crc32(crc, chunk.data(), static_cast<uInt>(k));
    offset += k;
    n -= k;
  }
  return static_cast<uint32_t>(crc);
}

struct stat stat_of(const std::string& path) {
  struct stat info {};
  const int failed = path == "-" ? ::fstat(0, &info) : ::stat(path.c_str(), &info);
  if (failed != 0) info.st_ino = 0;  // an input that is not there is the reader's to report
  return info;
}

// Termination signals wait while a record is appended, so SIGTERM or Ctrl-C (the learning
// loop stopping its actors) never leaves a torn record; only SIGKILL can, and the next
// append finds it.
class DeferTerminationSignals {
 public:
  DeferTerminationSignals() {
    sigset_t block;
    sigemptyset(&block);
    for (int s : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) sigaddset(&block, s);
    ::pthread_sigmask(SIG_BLOCK, &block, &saved_);
  }
  ~DeferTerminationSignals() { ::pthread_sigmask(SIG_SETMASK, &saved_, nullptr); }

 private:
  sigset_t saved_;
};

class FileLock {
 public:
  FileLock(int fd, const std::string& name) : fd_(fd) {
    while (::flock(fd_, LOCK_EX) != 0)
      if (errno != EINTR) throw_system_error("cannot lock " + name);
  }
  ~FileLock() { ::flock(fd_, LOCK_UN); }

 private:
  int fd_;
};

}  // namespace

StreamEnd find_stream_end(int fd, const std::string& name, uint64_t from, uint64_t records, uint64_t size) {
  StreamEnd end;
  end.whole_bytes = from;
  end.records = records;
  while (end.whole_bytes < size) {
    const StreamPosition at{name, end.records, end.whole_bytes};
    const uint64_t left = size - end.whole_bytes;
    uint8_t h[kHeaderBytes];
    const std::size_t n = static_cast<std::size_t>(std::min<uint64_t>(left, kHeaderBytes));
    read_at(fd, h, n, end.whole_bytes, name);
    if (n < kHeaderBytes) {
      end.torn_tail = std::memcmp(h, kMagic, std::min<std::size_t>(n, sizeof kMagic)) == 0;
      end.damage = "expected a 64-byte record header, the file ends after " + std::to_string(n) +
                   " bytes" + (end.torn_tail ? " (a torn record, left by a killed writer)" : " (not a record stream)");
      return end;
    }
    RecordHeader header;
    try {
      header = decode_header(h, std::numeric_limits<uint64_t>::max(), at);
    } catch (const StreamError& e) {
      end.damage = std::string(e.what()).substr(at.describe().size() + 2);  // without the position
      return end;
    }
    if (header.payload_bytes > left - kHeaderBytes) {
      end.torn_tail = true;
      end.damage = "expected " + std::to_string(header.payload_bytes) + " payload bytes of a '" + header.type +
                   "' record, the file ends after " + std::to_string(left - kHeaderBytes) +
                   " (a torn record, left by a killed writer)";
      return end;
    }
    const uint64_t record_bytes = kHeaderBytes + header.payload_bytes;
    if (record_bytes == left && crc32_at(fd, end.whole_bytes + kHeaderBytes, header.payload_bytes, name) != header.payload_crc32) {
      end.torn_tail = true;
      end.damage = "payload checksum mismatch in the last record, a '" + header.type + "' (a damaged or torn record)";
      return end;
    }
    end.whole_bytes += record_bytes;
    end.records += 1;
  }
  return end;
}

RecordWriter::RecordWriter(const std::string& path, WriteOptions options)
    : path_(path), options_(std::move(options)) {
  if (path.empty()) throw UsageError("an empty output path: name a file, or '-' for standard output");
  if (path == "-") {
    if (::isatty(1))
      throw Error("refusing to write a binary stream to a terminal: redirect stdout to a file "
                  "or pipe it into another tool (e.g. stream-dump)");
    fd_ = 1;
  } else if (options_.mode == WriteMode::append) {
    // Readable too: the file is checked before anything is appended to it.
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0) fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);  // a device or FIFO
    if (fd_ < 0) throw_system_error("cannot open " + path + " for appending");
  } else {
    atomic_ = std::make_unique<AtomicOutputFile>(path);
  }
  if (fd_ < 0) return;
  struct stat info {};
  if (::fstat(fd_, &info) != 0 || !S_ISREG(info.st_mode)) return;
  const std::string shown = path == "-" ? "standard output" : path;
  for (const std::string& input : options_.inputs) {
    const struct stat in = stat_of(input);
    if (in.st_ino != 0 && in.st_dev == info.st_dev && in.st_ino == info.st_ino)
      throw Error("cannot write " + shown + ": it is also an input (" + (input == "-" ? "standard input" : input) +
                  "), which would read its own records forever; write to another file");
  }
  if (fd_ != 1) {
    append_file_ = true;
    const FileLock lock(fd_, path_);
    check_append_target();
  }
}

RecordWriter::~RecordWriter() {
  if (fd_ > 1) ::close(fd_);
}

// Called under the lock: checks what was added to the file since it was last checked (by
// other appenders, or all of it when the file is new to us or shrank), so an append lands
// only behind a whole record. A torn tail is cut off when options_.repair asks for it.
void RecordWriter::check_append_target() {
  struct stat info {};
  if (::fstat(fd_, &info) != 0) throw_system_error("cannot stat " + path_);
  const uint64_t size = static_cast<uint64_t>(info.st_size);
  if (size == checked_.whole_bytes) return;
  const StreamEnd end = size > checked_.whole_bytes
                            ? find_stream_end(fd_, path_, checked_.whole_bytes, checked_.records, size)
                            : find_stream_end(fd_, path_, 0, 0, size);
  const StreamPosition at{path_, end.records, end.whole_bytes};
  if (!end.damage.empty()) {
    if (!end.torn_tail)
      throw StreamError(at, "cannot append: " + end.damage + "; expected a record stream ending in a whole record");
    if (!options_.repair)
      throw StreamError(at, "cannot append: " + end.damage +
                                "; --repair cuts the file back to its last whole record");
    if (::ftruncate(fd_, static_cast<off_t>(end.whole_bytes)) != 0) throw_system_error("cannot repair " + path_);
    std::cerr << "repaired " << at.describe() << ": cut off " << (size - end.whole_bytes) << " bytes: " << end.damage
              << "\n";
  }
  checked_ = end;
  checked_.damage.clear();
  checked_.torn_tail = false;
}

// One lock per record keeps records of concurrent appenders from interleaving. A record is
// appended whole or not at all: a failed write (a full disk, the file-size limit) is cut back
// to where the file ended, so the next append does not land behind a torn record that every
// reader would stop at.
void RecordWriter::append(const std::vector<uint8_t>& bytes) {
  const DeferTerminationSignals defer;
  const FileLock lock(fd_, path_);
  check_append_target();
  try {
    write_all(fd_, bytes.data(), bytes.size(), path_);
  } catch (...) {
    if (::ftruncate(fd_, static_cast<off_t>(checked_.whole_bytes)) != 0) {
      // Nothing more to do: the write's own error is the one to report.
    }
    throw;
  }
  checked_.whole_bytes += bytes.size();
  checked_.records += 1;
}

void RecordWriter::write(const Record& record) {
  const std::vector<uint8_t> bytes = encode_record(record, options_.zstd_level);
  if (atomic_) {
    atomic_->write(bytes.data(), bytes.size());
  } else if (fd_ < 0) {
    throw Error("write to " + path_ + " after close");
  } else if (append_file_) {
    append(bytes);
  } else {
    write_all(fd_, bytes.data(), bytes.size(), fd_ == 1 ? "standard output" : path_);
  }
  records_ += 1;
  bytes_ += bytes.size();
}

void RecordWriter::close() {
  if (atomic_) {
    atomic_->commit();
    atomic_.reset();
  }
  if (fd_ > 1 && ::close(fd_) != 0) throw_system_error("cannot close " + path_);
  fd_ = -1;
}

}  // namespace qte::stream
