#include "stream/npy.hpp"

#include <cstdint>
#include <fstream>
#include <iterator>
#include <regex>
#include <vector>

#include "common/atomic_file.hpp"

namespace qte::stream {

void write_npy(const std::string& path, const Field& field) {
  std::string descr = dtype_numpy_descr(field.dtype());
  std::string shape = "(";
  if (field.dtype() == DType::str) {
    descr = "|S" + std::to_string(field.byte_count());
  } else {
    for (std::size_t k = 0; k < field.shape().size(); ++k)
      shape += (k ? ", " : "") + std::to_string(field.shape()[k]);
    if (field.shape().size() == 1) shape += ",";  // Python's one-element tuple
  }
  shape += ")";
  std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape +
                       ", }";
  // magic(6) + version(2) + length(2) + header + '\n', padded with spaces to 64 bytes.
  const std::size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header += '\n';
  std::vector<uint8_t> bytes = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0,
                                static_cast<uint8_t>(header.size() & 0xff),
                                static_cast<uint8_t>(header.size() >> 8)};
  bytes.insert(bytes.end(), header.begin(), header.end());
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

}  // namespace qte::stream
