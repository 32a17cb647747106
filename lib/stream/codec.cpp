#include "stream/codec.hpp"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the record stream is little-endian; this reader copies bytes as they are");

namespace qte::stream {
namespace {

#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr bool kVerifyChecksums = false;  // see CMakeLists.txt, QTE_FUZZ
#else
constexpr bool kVerifyChecksums = true;
#endif

constexpr std::size_t kDescriptorFixedBytes = 16;

std::size_t pad64(std::size_t n) { return (n + kAlignment - 1) / kAlignment * kAlignment; }

template <class T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <class T>
void store(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

std::string hex_bytes(const uint8_t* p, std::size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    if (i) s += ' ';
    s += digits[p[i] >> 4];
    s += digits[p[i] & 15];
  }
  return s;
}

std::string hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

}  // namespace

uint32_t crc32_of(const uint8_t* bytes, std::size_t n) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (n > 0) {  // zlib takes uInt lengths
    const uInt chunk = n > (1u << 30) ? (1u << 30) : static_cast<uInt>(n);
    crc = crc32(crc, bytes, chunk);
    bytes += chunk;
    n -= chunk;
  }
  return static_cast<uint32_t>(crc);
}

void require_magic(const uint8_t* bytes, std::size_t n, const StreamPosition& where) {
  n = std::min(n, sizeof kMagic);
  if (std::memcmp(bytes, kMagic, n) != 0)
    throw StreamError(where, "bad magic: expected 89 51 54 45 0d 0a 1a 0a (a QTE record "
                             "stream), got " + hex_bytes(bytes, n));
}

RecordHeader decode_header(const uint8_t* h, uint64_t max_payload_bytes,
                           const StreamPosition& where) {
  require_magic(h, sizeof kMagic, where);
  const uint32_t stored_crc = load<uint32_t>(h + 60);
  const uint32_t actual_crc = crc32_of(h, 60);
  if (kVerifyChecksums && stored_crc != actual_crc)
    throw StreamError(where, "header checksum mismatch: header says " + hex32(stored_crc) +
                                 ", header bytes give " + hex32(actual_crc) +
                                 " (damaged header)");
  RecordHeader header;
  header.version_major = load<uint16_t>(h + 8);
  header.version_minor = load<uint16_t>(h + 10);
  if (header.version_major != kVersionMajor)
    throw StreamError(where, "unsupported format version " +
                                 std::to_string(header.version_major) + "." +
                                 std::to_string(header.version_minor) + ": this reader reads " +
                                 std::to_string(kVersionMajor) + ".x");
  header.field_count = load<uint32_t>(h + 12);
  const char* type = reinterpret_cast<const char*>(h + 16);
  header.type.assign(type, strnlen(type, 16));
  for (std::size_t i = header.type.size(); i < 16; ++i)
    if (h[16 + i] != 0) throw StreamError(where, "record type not NUL-padded");
  if (!is_valid_record_type(header.type))
    throw StreamError(where, "invalid record type '" + header.type +
                                 "': expected 1-16 characters of [a-z0-9_]");
  header.payload_bytes = load<uint64_t>(h + 32);
  header.payload_crc32 = load<uint32_t>(h + 40);
  if (header.payload_bytes % kAlignment != 0)
    throw StreamError(where, "payload length " + std::to_string(header.payload_bytes) +
                                 " is not a multiple of 64");
  if (header.payload_bytes > max_payload_bytes)
    throw StreamError(where, "absurd payload length " + std::to_string(header.payload_bytes) +
                                 " bytes: expected at most " + std::to_string(max_payload_bytes) +
                                 " (raise it with --max-record-bytes if this is real)");
  if (header.field_count > header.payload_bytes / kAlignment)
    throw StreamError(where, "field count " + std::to_string(header.field_count) +
                                 " cannot fit in a payload of " +
                                 std::to_string(header.payload_bytes) + " bytes");
  return header;
}

namespace {

// A zstd-encoded field's data, checked to hold exactly one frame of the size its shape needs
// (`raw_bytes`), decompressed into 64-byte-aligned memory. `what` prefixes the errors.
std::shared_ptr<uint8_t> decompressed(const uint8_t* data, uint64_t stored, uint64_t raw_bytes, uint64_t max_field_bytes,
                                      const std::string& what,
                                      const std::function<StreamError(const std::string&)>& bad) {
  if (raw_bytes > max_field_bytes)
    throw bad(what + "decompressed size " + std::to_string(raw_bytes) + " exceeds the limit of " +
              std::to_string(max_field_bytes));
  const unsigned long long content = ZSTD_getFrameContentSize(data, stored);
  if (content >= ZSTD_CONTENTSIZE_ERROR)
    throw bad(what + "zstd frame without a content size (expected " + std::to_string(raw_bytes) + " bytes)");
  if (content != raw_bytes)
    throw bad(what + "zstd frame declares " + std::to_string(content) + " bytes, shape needs " +
              std::to_string(raw_bytes));
  if (ZSTD_findFrameCompressedSize(data, stored) != stored)
    throw bad(what + "expected exactly one zstd frame in " + std::to_string(stored) + " bytes");
  const std::size_t padded = pad64(raw_bytes ? raw_bytes : 1);
  auto* out = static_cast<uint8_t*>(std::aligned_alloc(kAlignment, padded));
  if (!out) throw std::bad_alloc();
  std::shared_ptr<uint8_t> owner(out, [](uint8_t* q) { std::free(q); });
  const std::size_t got = ZSTD_decompress(out, padded, data, stored);
  if (ZSTD_isError(got) || got != raw_bytes)
    throw bad(what + "zstd data does not decompress to " + std::to_string(raw_bytes) + " bytes" +
              (ZSTD_isError(got) ? std::string(" (") + ZSTD_getErrorName(got) + ")" : ""));
  return owner;
}

}  // namespace

Record decode_payload(const RecordHeader& header, std::shared_ptr<const uint8_t> payload,
                      uint64_t max_field_bytes, const StreamPosition& where) {
  const uint8_t* base = payload.get();
  const uint64_t size = header.payload_bytes;
  const uint32_t crc = crc32_of(base, size);
  if (kVerifyChecksums && crc != header.payload_crc32)
    throw StreamError(where, "payload checksum mismatch: header says " +
                                 hex32(header.payload_crc32) + ", payload bytes give " +
                                 hex32(crc) + " (damaged payload)");
  Record record(header.type);
  record.position = where;
  uint64_t at = 0;
  for (uint32_t i = 0; i < header.field_count; ++i) {
    StreamPosition field_where = where;
    field_where.byte_offset = where.byte_offset + kHeaderBytes + at;
    auto bad = [&](const std::string& what) -> StreamError {
      return StreamError(field_where, "field " + std::to_string(i) + ": " + what);
    };
    if (size - at < kDescriptorFixedBytes) throw bad("descriptor runs past the payload end");
    const uint8_t* d = base + at;
    const uint8_t dtype_code = d[0];
    const uint8_t ndim = d[1];
    const uint8_t encoding = d[2];
    const uint16_t name_len = load<uint16_t>(d + 4);
    const uint64_t stored = load<uint64_t>(d + 8);
    if (!is_known_dtype(dtype_code))
      throw bad("unknown dtype code " + std::to_string(dtype_code) + " (expected 1-11)");
    if (ndim > kMaxDims) throw bad("ndim " + std::to_string(ndim) + " (expected at most 8)");
    if (encoding > 1)
      throw bad("unknown encoding " + std::to_string(encoding) + " (expected 0 raw or 1 zstd)");
    if (name_len == 0 || name_len > 255)
      throw bad("name length " + std::to_string(name_len) + " (expected 1-255)");
    const uint64_t descriptor_bytes = pad64(kDescriptorFixedBytes + 8 * ndim + name_len);
    if (size - at < descriptor_bytes) throw bad("descriptor runs past the payload end");
    Shape shape(ndim);
    for (int k = 0; k < ndim; ++k) shape[k] = load<int64_t>(d + kDescriptorFixedBytes + 8 * k);
    if (const std::string why = shape_problem(shape); !why.empty()) throw bad(why);
    const int64_t count = element_count(shape);
    std::string name(reinterpret_cast<const char*>(d + kDescriptorFixedBytes + 8 * ndim),
                     name_len);
    if (!is_valid_field_name(name)) throw bad("invalid field name (expected [A-Za-z0-9_.-])");
    if (record.has(name)) throw bad("duplicate field name '" + name + "'");
    const DType dtype = static_cast<DType>(dtype_code);
    if (dtype == DType::str && ndim != 1) throw bad("'" + name + "': str fields are 1-d");
    const uint64_t raw_bytes = static_cast<uint64_t>(count) * dtype_size(dtype);
    at += descriptor_bytes;
    if (stored > size - at)
      throw bad("'" + name + "': data of " + std::to_string(stored) +
                " bytes runs past the payload end");
    const uint8_t* data = base + at;
    if (encoding == static_cast<uint8_t>(Encoding::raw)) {
      if (stored != raw_bytes)
        throw bad("'" + name + "': shape " + shape_to_string(shape) + " of " +
                  dtype_name(dtype) + " needs " + std::to_string(raw_bytes) +
                  " bytes, stored " + std::to_string(stored));
      record.add(Field(name, dtype, shape, payload, data));
    } else {
      const std::shared_ptr<uint8_t> owner =
          decompressed(data, stored, raw_bytes, max_field_bytes, "'" + name + "': ", bad);
      Field field(name, dtype, shape, owner, owner.get());
      field.compress = true;  // written again compressed when passed through: this very frame
      field.keep_encoded(payload, data, stored);
      record.add(std::move(field));
    }
    at += pad64(stored);  // within the payload: stored <= size - at and sizes are 64-multiples
  }
  if (at != size)
    throw StreamError(where, std::to_string(size - at) +
                                 " bytes after the last field: expected the payload to end "
                                 "there (field count too small?)");
  return record;
}

std::vector<uint8_t> encode_record(const Record& record, int zstd_level) {
  // Compress first, so the payload size is known before anything is laid out.
  struct Piece {
    const Field* field;
    Encoding encoding = Encoding::raw;
    std::vector<uint8_t> compressed;  // a frame made here
    const uint8_t* data = nullptr;    // what is stored: the field's bytes, its kept frame or `compressed`
    std::size_t stored = 0;
  };
  std::vector<Piece> pieces(record.fields().size());
  std::size_t payload = 0;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const Field& f = record.fields()[k];
    Piece& piece = pieces[k];
    piece.field = &f;
    piece.data = f.bytes();
    piece.stored = f.byte_count();
    if (f.compress && f.encoded()) {  // read compressed and passed on: its frame as it was
      piece.encoding = Encoding::zstd;
      piece.data = f.encoded();
      piece.stored = f.encoded_size();
    } else if (f.compress && f.byte_count() >= 256) {
      piece.compressed.resize(ZSTD_compressBound(f.byte_count()));
      const std::size_t n = ZSTD_compress(piece.compressed.data(), piece.compressed.size(),
                                          f.bytes(), f.byte_count(), zstd_level);
      if (!ZSTD_isError(n) && n < f.byte_count()) {  // kept raw when that does not shrink it
        piece.encoding = Encoding::zstd;
        piece.data = piece.compressed.data();
        piece.stored = n;
      }
    }
    payload += pad64(kDescriptorFixedBytes + 8 * f.shape().size() + f.name().size()) + pad64(piece.stored);
  }

  std::vector<uint8_t> out(kHeaderBytes + payload, 0);
  uint8_t* p = out.data() + kHeaderBytes;
  for (const Piece& piece : pieces) {
    const Field& f = *piece.field;
    const std::size_t stored = piece.stored;
    p[0] = static_cast<uint8_t>(f.dtype());
    p[1] = static_cast<uint8_t>(f.shape().size());
    p[2] = static_cast<uint8_t>(piece.encoding);
    store<uint16_t>(p + 4, static_cast<uint16_t>(f.name().size()));
    store<uint64_t>(p + 8, stored);
    for (std::size_t k = 0; k < f.shape().size(); ++k)
      store<int64_t>(p + kDescriptorFixedBytes + 8 * k, f.shape()[k]);
    std::memcpy(p + kDescriptorFixedBytes + 8 * f.shape().size(), f.name().data(),
                f.name().size());
    p += pad64(kDescriptorFixedBytes + 8 * f.shape().size() + f.name().size());
    if (stored) std::memcpy(p, piece.data, stored);
    p += pad64(stored);
  }

  uint8_t* h = out.data();
  std::memcpy(h, kMagic, sizeof kMagic);
  store<uint16_t>(h + 8, kVersionMajor);
  store<uint16_t>(h + 10, kVersionMinor);
  store<uint32_t>(h + 12, static_cast<uint32_t>(record.fields().size()));
  std::memcpy(h + 16, record.type().data(), record.type().size());
  store<uint64_t>(h + 32, payload);
  store<uint32_t>(h + 40, crc32_of(out.data() + kHeaderBytes, payload));
  store<uint32_t>(h + 60, crc32_of(h, 60));
  return out;
}

}  // namespace qte::stream
