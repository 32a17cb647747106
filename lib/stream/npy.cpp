#include "stream/npy.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <regex>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/indexed_name.hpp"

namespace qte::stream {

namespace {

// The magic, version and header of a .npy file of `descr` and `shape` (version 1.0: the
// header padded with spaces so the data starts at a multiple of 64 bytes).
std::vector<uint8_t> npy_header(const std::string& descr, const Shape& shape) {
  std::string dims = "(";
  for (std::size_t k = 0; k < shape.size(); ++k) dims += (k ? ", " : "") + std::to_string(shape[k]);
  if (shape.size() == 1) dims += ",";  // Python's one-element tuple
  dims += ")";
  std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + dims + ", }";
  // magic(6) + version(2) + length(2) + header + '\n', padded with spaces to 64 bytes.
  const std::size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header += '\n';
  std::vector<uint8_t> bytes = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0,
                                static_cast<uint8_t>(header.size() & 0xff),
                                static_cast<uint8_t>(header.size() >> 8)};
  bytes.insert(bytes.end(), header.begin(), header.end());
  return bytes;
}

}  // namespace

void write_npy(const std::string& path, const Field& field) {
  const bool text = field.dtype() == DType::str;
  std::vector<uint8_t> bytes =
      text ? npy_header("|S" + std::to_string(field.byte_count()), {})
           : npy_header(dtype_numpy_descr(field.dtype()), field.shape());
  bytes.insert(bytes.end(), field.bytes(), field.bytes() + field.byte_count());
  write_file_atomically(path, bytes.data(), bytes.size());
}

namespace {

// The shape tuple of a .npy header ("2, 3" or "4," or ""). Each dimension a non-negative
// integer, and the element count within what a record holds: (-1,) is not [1], and
// (2^32, 2^32, 4) does not wrap to a small array.
Shape npy_shape(const std::string& dims, const std::string& path) {
  auto bad = [&](const std::string& what) { return Error(path + ": " + what); };
  Shape shape;
  const std::regex item("\\s*([^,]*?)\\s*(,|$)");
  double elements = 1;
  for (std::sregex_iterator it(dims.begin(), dims.end(), item), end; it != end; ++it) {
    const std::string dim = (*it)[1];
    if (dim.empty()) {
      if ((*it)[2].length() == 0) break;  // the end (after a trailing comma)
      throw bad("shape (" + dims + "): an empty dimension");
    }
    if (!std::regex_match(dim, std::regex("\\d{1,15}"))) throw bad("shape (" + dims + "): '" + dim + "' is not a size");
    shape.push_back(std::stoll(dim));
    elements *= static_cast<double>(shape.back());
    if (shape.size() > static_cast<std::size_t>(kMaxDims)) throw bad("shape (" + dims + "): more than 8 dimensions");
  }
  if (elements > 1e12) throw bad("shape (" + dims + ") is larger than a record field can hold");
  return shape;
}

}  // namespace

void read_npy_into(Record& record, const std::string& name, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open " + path);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto bad = [&](const std::string& what) { return Error(path + ": " + what); };
  static const uint8_t magic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
  if (bytes.size() < 10 || std::memcmp(bytes.data(), magic, 6) != 0)
    throw bad("not a .npy file (expected the magic \\x93NUMPY)");
  const int major = bytes[6];
  std::size_t header_len, at;
  if (major == 1) {
    header_len = bytes[8] | (bytes[9] << 8);
    at = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw bad("truncated .npy header");
    header_len = bytes[8] | (bytes[9] << 8) | (bytes[10] << 16) | (std::size_t(bytes[11]) << 24);
    at = 12;
  } else {
    throw bad(".npy version " + std::to_string(major) + " (expected 1, 2 or 3)");
  }
  if (bytes.size() < at + header_len) throw bad("truncated .npy header");
  const std::string header(bytes.begin() + at, bytes.begin() + at + header_len);
  std::smatch m;
  if (!std::regex_search(header, m, std::regex("'descr':\\s*'([^']*)'")))
    throw bad("no 'descr' in the .npy header");
  const std::string descr = m[1];
  if (std::regex_search(header, std::regex("'fortran_order':\\s*True")))
    throw bad("Fortran-order arrays are not supported (save with np.ascontiguousarray)");
  if (!std::regex_search(header, m, std::regex("'shape':\\s*\\(([^)]*)\\)")))
    throw bad("no 'shape' in the .npy header");
  const Shape shape = npy_shape(m[1], path);
  DType dtype = DType::u8;
  bool found = false;
  for (DType d : {DType::u8, DType::i8, DType::u16, DType::i16, DType::u32, DType::i32, DType::u64,
                  DType::i64, DType::f32, DType::f64}) {
    std::string want = dtype_numpy_descr(d);
    if (descr == want || (want[0] == '<' && descr == "=" + want.substr(1)) ||
        (want[0] == '|' && descr == "<" + want.substr(1))) {
      dtype = d;
      found = true;
    }
  }
  if (!found && descr.size() > 2 && descr.compare(0, 2, "|S") == 0 && shape.empty()) {
    const std::size_t n = bytes.size() - at - header_len;
    std::string text(bytes.begin() + at + header_len, bytes.end());
    text = text.substr(0, std::min(n, text.find('\0') == std::string::npos ? n : text.find('\0')));
    record.set_string(name, text);
    return;
  }
  if (!found) throw bad("unsupported dtype '" + descr + "' (expected little-endian numbers)");
  const std::size_t need = element_count(shape) * dtype_size(dtype);
  if (bytes.size() - at - header_len != need)
    throw bad("shape " + shape_to_string(shape) + " needs " + std::to_string(need) +
              " data bytes, file has " + std::to_string(bytes.size() - at - header_len));
  record.set_raw(name, dtype, shape, bytes.data() + at + header_len);
}

// --- stacked export ----------------------------------------------------------------------

NpyExport::NpyExport(std::string dir, bool per_record) : dir_(std::move(dir)), per_record_(per_record) {
  if (per_record_) return;
  std::string name = dir_ + "/.npy-spool.XXXXXX";
  spool_fd_ = mkstemp(name.data());
  if (spool_fd_ < 0) throw_system_error("cannot make a scratch file in " + dir_);
  unlink(name.c_str());  // gone with the descriptor, whatever ends the program
}

NpyExport::~NpyExport() {
  if (spool_fd_ >= 0) close(spool_fd_);
}

std::string NpyExport::per_record_path(uint64_t record_index, const Key& key) const {
  return dir_ + "/" + indexed_name(record_index, key.first + "." + key.second + ".npy");
}

bool NpyExport::fits(const Stack& stack, const Field& field) const {
  if (field.dtype() != stack.dtype) return false;
  return field.dtype() == DType::str || field.shape() == stack.shape;  // texts are padded
}

void NpyExport::append(Stack& stack, const Field& field, uint64_t record_index) {
  stack.record_indices.push_back(record_index);
  if (field.dtype() == DType::str) {
    stack.texts.emplace_back(reinterpret_cast<const char*>(field.bytes()), field.byte_count());
    return;
  }
  stack.offsets.push_back(spool_bytes_);
  write_all(spool_fd_, field.bytes(), field.byte_count(), dir_ + " (scratch file)");
  spool_bytes_ += field.byte_count();
}

// The bytes of row i of a stack of numbers, read back from the spool.
std::vector<uint8_t> NpyExport::spooled(const Stack& stack, std::size_t i) const {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(element_count(stack.shape)) * dtype_size(stack.dtype));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = pread(spool_fd_, bytes.data() + done, bytes.size() - done,
                            static_cast<off_t>(stack.offsets[i] + done));
    if (n <= 0) throw_system_error("cannot read back the scratch file in " + dir_);
    done += static_cast<std::size_t>(n);
  }
  return bytes;
}

// A stack that turned out not to be stackable: its rows so far become per-record files.
void NpyExport::write_rows_per_record(const Key& key, Stack& stack) {
  for (std::size_t i = 0; i < stack.record_indices.size(); ++i) {
    Record row(key.first);
    if (stack.dtype == DType::str) row.set_string(key.second, stack.texts[i]);
    else row.set_raw(key.second, stack.dtype, stack.shape, spooled(stack, i).data());
    write_npy(per_record_path(stack.record_indices[i], key), row.field(key.second));
  }
  stack = Stack{};
  stack.per_record = true;
}

void NpyExport::add(const Record& record) {
  const std::string& type = record.type();
  const uint64_t before = records_of_type_[type]++;  // records of this type before this one
  const uint64_t index = record.position.record_index;
  for (const Field& field : record.fields()) {
    const Key key(type, field.name());
    auto [it, fresh] = stacks_.try_emplace(key);
    Stack& stack = it->second;
    if (fresh) {
      stack.dtype = field.dtype();
      stack.shape = field.shape();
      stack.per_record = per_record_ || before > 0;  // the earlier records lacked it
    } else if (!stack.per_record && (stack.record_indices.size() != before || !fits(stack, field))) {
      write_rows_per_record(key, stack);
    }
    if (stack.per_record) write_npy(per_record_path(index, key), field);
    else append(stack, field, index);
  }
  // Fields of this type that this record lacks cannot be stacked either.
  for (auto it = stacks_.lower_bound(Key(type, "")); it != stacks_.end() && it->first.first == type; ++it)
    if (!it->second.per_record && it->second.record_indices.size() != before + 1)
      write_rows_per_record(it->first, it->second);
}

void NpyExport::finish() {
  for (auto& [key, stack] : stacks_) {
    if (stack.per_record) continue;
    const int64_t rows = static_cast<int64_t>(stack.record_indices.size());
    AtomicOutputFile out(dir_ + "/" + key.first + "." + key.second + ".npy");
    if (stack.dtype == DType::str) {
      std::size_t width = 1;  // NumPy has no |S0
      for (const std::string& text : stack.texts) width = std::max(width, text.size());
      const std::vector<uint8_t> header = npy_header("|S" + std::to_string(width), {rows});
      out.write(header.data(), header.size());
      for (const std::string& text : stack.texts) {
        std::string padded = text;
        padded.resize(width, '\0');
        out.write(padded.data(), padded.size());
      }
    } else {
      Shape shape = {rows};
      shape.insert(shape.end(), stack.shape.begin(), stack.shape.end());
      const std::vector<uint8_t> header = npy_header(dtype_numpy_descr(stack.dtype), shape);
      out.write(header.data(), header.size());
      for (std::size_t i = 0; i < stack.offsets.size(); ++i) {
        const std::vector<uint8_t> bytes = spooled(stack, i);
        out.write(bytes.data(), bytes.size());
      }
    }
    out.commit();
  }
}

}  // namespace qte::stream
