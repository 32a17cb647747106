// Bytes <-> records: the byte layout of formats/record-stream.md, in one place.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "stream/record.hpp"

namespace qte::stream {

constexpr uint8_t kMagic[8] = {0x89, 'Q', 'T', 'E', '\r', '\n', 0x1a, '\n'};
constexpr uint16_t kVersionMajor = 1;
constexpr uint16_t kVersionMinor = 0;
constexpr std::size_t kHeaderBytes = 64;
constexpr std::size_t kAlignment = 64;

enum class Encoding : uint8_t { raw = 0, zstd = 1 };

struct RecordHeader {
  uint16_t version_major = kVersionMajor;
  uint16_t version_minor = kVersionMinor;
  uint32_t field_count = 0;
  std::string type;
  uint64_t payload_bytes = 0;
  uint32_t payload_crc32 = 0;
};

// Parses and checks the 64 header bytes (magic, header CRC, version, type, length).
// Throws StreamError ("bad magic ... a QTE record stream") unless the first min(n, 8) bytes are
// the magic: a file too short for a header is told apart from a short stream alike.
void require_magic(const uint8_t* bytes, std::size_t n, const StreamPosition& where);
RecordHeader decode_header(const uint8_t* bytes, uint64_t max_payload_bytes,
                           const StreamPosition& where);

// Checks the payload CRC and parses its fields; the fields point into `payload` (no copy
// unless a field is compressed). `payload` must be 64-byte aligned.
Record decode_payload(const RecordHeader& header, std::shared_ptr<const uint8_t> payload,
                      uint64_t max_field_bytes, const StreamPosition& where);

// The whole record (header + payload), ready to write. zstd_level applies to fields marked
// `compress`.
std::vector<uint8_t> encode_record(const Record& record, int zstd_level = 3);

uint32_t crc32_of(const uint8_t* bytes, std::size_t n);

}  // namespace qte::stream
