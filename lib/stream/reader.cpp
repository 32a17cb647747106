#include "stream/reader.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "common/standard_streams.hpp"
#include "stream/codec.hpp"

namespace qte::stream {
namespace {

class FdSource : public ByteSource {
 public:
  FdSource(int fd, bool owned, std::string name) : fd_(fd), owned_(owned), name_(std::move(name)) {}
  ~FdSource() override {
    if (owned_) ::close(fd_);
  }
  std::size_t read(uint8_t* buffer, std::size_t n) override {
    for (;;) {
      const ssize_t got = ::read(fd_, buffer, n);
      if (got >= 0) return static_cast<std::size_t>(got);
      if (errno != EINTR) throw_system_error("cannot read " + name_);
    }
  }

 private:
  int fd_;
  bool owned_;
  std::string name_;
};

class MemorySource : public ByteSource {
 public:
  MemorySource(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::size_t read(uint8_t* buffer, std::size_t n) override {
    const std::size_t k = std::min(n, size_ - at_);
    std::memcpy(buffer, data_ + at_, k);
    at_ += k;
    return k;
  }

 private:
  const uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

std::unique_ptr<ByteSource> open_path(const std::string& path) {
  if (path == "-") {
    // A person at a terminal, not a pipe: waiting for a binary stream typed by hand helps nobody.
    if (::isatty(0))
      throw UsageError("standard input is a terminal: give the input file, or pipe a record stream in");
    if (standard_input_was_closed())
      throw UsageError("standard input is closed: give the input file, or pipe a record stream in");
    return std::make_unique<FdSource>(0, false, "<stdin>");
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw_system_error("cannot open " + path);
  return std::make_unique<FdSource>(fd, true, path);
}

}  // namespace

std::unique_ptr<ByteSource> memory_source(const uint8_t* data, std::size_t size) {
  return std::make_unique<MemorySource>(data, size);
}

RecordReader::RecordReader(const std::string& path, ReadOptions options)
    : RecordReader(open_path(path), path, options) {}

RecordReader::RecordReader(std::unique_ptr<ByteSource> source, std::string name,
                           ReadOptions options)
    : source_(std::move(source)), options_(options) {
  position_.source = std::move(name);
}

RecordReader::~RecordReader() = default;

std::size_t RecordReader::read_fully(uint8_t* buffer, std::size_t n) {
  std::size_t have = 0;
  while (have < n) {
    const std::size_t got = source_->read(buffer + have, n - have);
    if (got == 0) break;
    have += got;
  }
  return have;
}

std::optional<Record> RecordReader::next() {
  uint8_t header_bytes[kHeaderBytes];
  const std::size_t got = read_fully(header_bytes, kHeaderBytes);
  if (got == 0) return std::nullopt;
  if (got < kHeaderBytes) require_magic(header_bytes, got, position_);  // not a stream at all, however short
  if (got < kHeaderBytes)
    throw StreamError(position_, "truncated stream: expected a 64-byte record header, got " +
                                     std::to_string(got) + " bytes");
  const RecordHeader header =
      decode_header(header_bytes, options_.max_record_bytes, position_);

  // Grow the buffer while reading, so a damaged length on a short file allocates little.
  const std::size_t total = header.payload_bytes;
  std::size_t capacity = std::min<std::size_t>(std::max<std::size_t>(total, 64), 64u << 20);
  auto* buffer = static_cast<uint8_t*>(std::aligned_alloc(kAlignment, capacity));
  if (!buffer) throw std::bad_alloc();
  std::shared_ptr<uint8_t> payload(buffer, [](uint8_t* p) { std::free(p); });
  std::size_t have = 0;
  while (have < total) {
    if (have == capacity) {
      const std::size_t bigger = std::min(total, capacity * 2);
      auto* grown = static_cast<uint8_t*>(std::aligned_alloc(kAlignment, bigger));
      if (!grown) throw std::bad_alloc();
      std::memcpy(grown, payload.get(), have);
      payload.reset(grown, [](uint8_t* p) { std::free(p); });
      capacity = bigger;
    }
    const std::size_t chunk = read_fully(payload.get() + have, capacity - have);
    if (chunk == 0) break;
    have += chunk;
  }
  if (have < total)
    throw StreamError(position_, "truncated stream: '" + header.type + "' record needs " +
                                     std::to_string(total) + " payload bytes, got " +
                                     std::to_string(have));
  Record record = decode_payload(header, payload, options_.max_record_bytes, position_);
  position_.byte_offset += kHeaderBytes + total;
  position_.record_index += 1;
  return record;
}

}  // namespace qte::stream
