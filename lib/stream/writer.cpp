#include "stream/writer.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "stream/codec.hpp"

namespace qte::stream {

RecordWriter::RecordWriter(const std::string& path, WriteOptions options)
    : path_(path), options_(options) {
  if (path.empty()) throw UsageError("an empty output path: name a file, or '-' for standard output");
  if (path == "-") {
    if (::isatty(1))
      throw Error("refusing to write a binary stream to a terminal: redirect stdout to a file "
                  "or pipe it into another tool (e.g. stream-dump)");
    fd_ = 1;
  } else if (options_.mode == WriteMode::append) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0) throw_system_error("cannot open " + path + " for appending");
  } else {
    atomic_ = std::make_unique<AtomicOutputFile>(path);
  }
}

RecordWriter::~RecordWriter() {
  if (fd_ > 1) ::close(fd_);
}

void RecordWriter::write(const Record& record) {
  const std::vector<uint8_t> bytes = encode_record(record, options_.zstd_level);
  if (atomic_) {
    atomic_->write(bytes.data(), bytes.size());
  } else if (fd_ < 0) {
    throw Error("write to " + path_ + " after close");
  } else if (options_.mode == WriteMode::append && fd_ != 1) {
    // One lock per record keeps records of concurrent appenders from interleaving. A record
    // is appended whole or not at all: a failed write (a full disk) is cut back to where the
    // file ended, so the next append does not land behind a torn record that every reader
    // would stop at.
    if (::flock(fd_, LOCK_EX) != 0) throw_system_error("cannot lock " + path_);
    struct stat before {};
    const bool sized = ::fstat(fd_, &before) == 0;
    try {
      write_all(fd_, bytes.data(), bytes.size(), path_);
    } catch (...) {
      if (sized && ::ftruncate(fd_, before.st_size) != 0) {
        // Nothing more to do: the write's own error is the one to report.
      }
      ::flock(fd_, LOCK_UN);
      throw;
    }
    ::flock(fd_, LOCK_UN);
  } else {
    write_all(fd_, bytes.data(), bytes.size(), "standard output");
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
