#include "replay/growing_stream.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <cstdlib>

#include "stream/codec.hpp"

namespace qte::replay {
namespace {

void read_at(int fd, uint8_t* buffer, std::size_t n, uint64_t offset, const std::string& path) {
  std::size_t have = 0;
  while (have < n) {
    const ssize_t got = ::pread(fd, buffer + have, n - have, static_cast<off_t>(offset + have));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) throw_system_error("cannot read " + path);
    have += static_cast<std::size_t>(got);
  }
}

}  // namespace

GrowingStream::GrowingStream(std::string path, stream::ReadOptions options) : options_(options) {
  position_.source = std::move(path);
  fd_ = ::open(position_.source.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw_system_error("cannot open " + position_.source);
}

GrowingStream::~GrowingStream() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<stream::Record> GrowingStream::poll() {
  std::vector<stream::Record> records;
  struct stat info {};
  if (::fstat(fd_, &info) != 0) throw_system_error("cannot stat " + position_.source);
  const uint64_t size = static_cast<uint64_t>(info.st_size);
  while (size - position_.byte_offset >= stream::kHeaderBytes) {
    uint8_t header_bytes[stream::kHeaderBytes];
    read_at(fd_, header_bytes, sizeof header_bytes, position_.byte_offset, position_.source);
    const stream::RecordHeader header = stream::decode_header(header_bytes, options_.max_record_bytes, position_);
    if (size - position_.byte_offset - stream::kHeaderBytes < header.payload_bytes) break;  // still being written
    auto* buffer = static_cast<uint8_t*>(std::aligned_alloc(stream::kAlignment, std::max<std::size_t>(header.payload_bytes, 64)));
    if (!buffer) throw std::bad_alloc();
    std::shared_ptr<uint8_t> payload(buffer, [](uint8_t* p) { std::free(p); });
    if (header.payload_bytes)
      read_at(fd_, payload.get(), header.payload_bytes, position_.byte_offset + stream::kHeaderBytes, position_.source);
    records.push_back(stream::decode_payload(header, payload, options_.max_record_bytes, position_));
    position_.byte_offset += stream::kHeaderBytes + header.payload_bytes;
    position_.record_index += 1;
  }
  return records;
}

}  // namespace qte::replay
