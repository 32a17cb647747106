#include "point_clouds/pcd_file.hpp"

#include <pcl/io/lzf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/error.hpp"

namespace qte::point_clouds {

void write_pcd(const std::string& path, const voxels::CameraCloud& camera) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud(static_cast<uint32_t>(camera.width), static_cast<uint32_t>(camera.height));
  cloud.is_dense = true;
  const auto& in = camera.cloud;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    auto& p = cloud[i];
    p.x = in.xyz[3 * i], p.y = in.xyz[3 * i + 1], p.z = in.xyz[3 * i + 2];
    p.r = in.rgb[3 * i], p.g = in.rgb[3 * i + 1], p.b = in.rgb[3 * i + 2];
    if (!std::isfinite(p.x)) cloud.is_dense = false;
  }
  // PCL writes to a path; write beside it under the temporary name AtomicOutputFile uses (so a
  // killed writer's leftover is recognised and removed), then rename.
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  if (pcl::io::savePCDFileBinary(temp, cloud) != 0) {
    std::remove(temp.c_str());
    throw Error("cannot write " + path);
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw_system_error("cannot rename " + temp + " to " + path);
  }
}

// The reader is our own rather than PCL's: PCL sizes its buffers from the header before checking
// it against the file (gigabytes for a small file), reads fields of one type as another and
// accepts malformed ASCII. Here every header field is checked against the data and the file
// size before anything is allocated, and every failure is one line naming the file.
namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 16;
constexpr uint64_t kMaxPointStep = 1 << 16;
constexpr uint64_t kLzfMaxRatio = 88;  // an LZF back-reference: 3 bytes for at most 264

const char* const kExpectedHeader =
    "expected a PCD header: FIELDS, SIZE, TYPE, [COUNT,] WIDTH, HEIGHT, [VIEWPOINT,] POINTS, then DATA";

struct PcdField {
  std::string name;
  int size = 0;    // bytes per value: 1, 2, 4, 8
  char type = 0;   // I (signed), U (unsigned), F (floating point)
  int count = 1;   // values per point
  uint64_t offset = 0;       // bytes into a point (binary)
  uint64_t first_value = 0;  // values into a line (ascii)
};

struct PcdHeader {
  std::vector<PcdField> fields;
  uint64_t width = 0, height = 0, points = 0;
  uint64_t point_step = 0;   // bytes of one point, all fields
  uint64_t packed_step = 0;  // the same without padding fields '_' (binary_compressed leaves them out)
  uint64_t values_per_point = 0;
  std::string data;          // ascii, binary or binary_compressed
  uint64_t data_start = 0;   // byte offset just after the DATA line
  int x = -1, y = -1, z = -1, colour = -1;  // indices into fields; colour is rgb, else rgba, else -1

  uint64_t bytes() const { return points * point_step; }
};

// A short printable token quoted, or a description when it would garble the message.
std::string quoted(const std::string& token) {
  if (token.size() > 32) return "a " + std::to_string(token.size()) + "-character value";
  for (char c : token)
    if (c < 0x20 || c > 0x7e) return "a value with unprintable characters";
  return "'" + token + "'";
}

// Decimal digits only (no sign, no spaces), below 10^19.
bool parse_unsigned(const std::string& text, uint64_t& value) {
  if (text.empty() || text.size() > 19) return false;
  value = 0;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
    value = 10 * value + uint64_t(c - '0');
  }
  return true;
}

std::vector<std::string> words_of(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream in(line);
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

std::string describe(const PcdField& f) {
  return "TYPE " + std::string(1, f.type) + " SIZE " + std::to_string(f.size) + " COUNT " + std::to_string(f.count);
}

// Types and sizes of the fields; x, y, z as 4-byte floats and the colour as 4 packed bytes.
void check_fields(const std::string& path, PcdHeader& h) {
  const std::string where = path + ": ";
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    PcdField& f = h.fields[i];
    if (f.size != 1 && f.size != 2 && f.size != 4 && f.size != 8)
      throw Error(where + "field " + f.name + ": SIZE expected 1, 2, 4 or 8");
    if (f.type != 'I' && f.type != 'U' && f.type != 'F') throw Error(where + "field " + f.name + ": TYPE expected I, U or F");
    if (f.type == 'F' && f.size != 4 && f.size != 8)
      throw Error(where + "field " + f.name + " is " + describe(f) + ", expected SIZE 4 or 8 for TYPE F");
    for (std::size_t j = 0; j < i; ++j)
      if (f.name != "_" && h.fields[j].name == f.name) throw Error(where + "field " + f.name + " appears twice in FIELDS");
    f.offset = h.point_step;
    f.first_value = h.values_per_point;
    h.point_step += uint64_t(f.size) * f.count;
    if (f.name != "_") h.packed_step += uint64_t(f.size) * f.count;
    h.values_per_point += f.count;
    if (h.point_step > kMaxPointStep)
      throw Error(where + "points of more than " + std::to_string(kMaxPointStep) + " bytes; expected x, y, z and a few more fields");
    if (f.name == "x") h.x = static_cast<int>(i);
    if (f.name == "y") h.y = static_cast<int>(i);
    if (f.name == "z") h.z = static_cast<int>(i);
    if (f.name == "rgb" || (f.name == "rgba" && h.colour < 0)) h.colour = static_cast<int>(i);
  }
  for (const int axis : {h.x, h.y, h.z})
    if (axis < 0) throw Error(where + "no field x, y or z; expected a point cloud with x, y, z fields");
  for (const int axis : {h.x, h.y, h.z}) {
    const PcdField& f = h.fields[axis];
    if (f.type != 'F' || f.size != 4 || f.count != 1)
      throw Error(where + "field " + f.name + " is " + describe(f) + ", expected a 4-byte float (TYPE F SIZE 4 COUNT 1)");
  }
  for (const PcdField& f : h.fields)
    if ((f.name == "rgb" || f.name == "rgba") && (f.size != 4 || f.count != 1 || f.type == 'I'))
      throw Error(where + "field " + f.name + " is " + describe(f) +
                  ", expected 8-bit colour packed in 4 bytes (TYPE F or U, SIZE 4, COUNT 1)");
}

void check_point_count(const std::string& path, const PcdHeader& h) {
  const std::string where = path + ": ";
  if (h.points == 0) throw Error(where + "POINTS 0, expected a cloud of at least one point");
  if (h.points > kMaxPcdPoints)
    throw Error(where + "POINTS " + std::to_string(h.points) + ", expected at most " + std::to_string(kMaxPcdPoints) +
                " (one camera frame)");
  // Both factors at most kMaxPcdPoints before multiplying: no overflow.
  if (h.width > kMaxPcdPoints || h.height > kMaxPcdPoints || h.width * h.height != h.points)
    throw Error(where + "WIDTH " + std::to_string(h.width) + " x HEIGHT " + std::to_string(h.height) +
                " does not make POINTS " + std::to_string(h.points) + ", expected them to agree");
}

// The header's per-field lists as written, before they are put together and checked.
struct FieldLists {
  std::vector<std::string> names, sizes, types, counts;
  bool seen_count = false;
};

// The header's lines, from the file's first kMaxHeaderBytes: the per-field lists, the sizes,
// the encoding and where the data starts.
void parse_header_lines(const std::string& path, const std::string& head, PcdHeader& h, FieldLists& lists) {
  const std::string not_pcd = path + ": not a .pcd point cloud (" + kExpectedHeader + ")";
  std::istringstream in(head);
  bool seen_width = false, seen_height = false, seen_points = false;
  std::string line;
  for (int number = 1; h.data.empty(); ++number) {
    if (!std::getline(in, line)) throw Error(not_pcd);
    std::vector<std::string> words = words_of(line);
    if (words.empty() || words[0][0] == '#') continue;
    const std::string key = words[0];
    words.erase(words.begin());
    const std::string at = path + ": header line " + std::to_string(number) + ": ";
    const auto once = [&](bool& seen) {
      if (seen) throw Error(at + key + " appears twice; " + kExpectedHeader);
      seen = true;
    };
    const auto one_number = [&](uint64_t& value, bool& seen) {
      once(seen);
      if (words.size() != 1 || !parse_unsigned(words[0], value)) throw Error(at + key + ": expected one non-negative integer");
    };
    const auto list = [&](std::vector<std::string>& into) {
      if (!into.empty()) throw Error(at + key + " appears twice; " + kExpectedHeader);
      if (words.empty()) throw Error(at + key + ": expected one value per field");
      if (words.size() > 1024) throw Error(at + key + ": more than 1024 fields, expected x, y, z and a few more");
      into = words;
    };
    if (key == "VERSION") {
    } else if (key == "FIELDS") {
      list(lists.names);
    } else if (key == "SIZE") {
      list(lists.sizes);
    } else if (key == "TYPE") {
      list(lists.types);
    } else if (key == "COUNT") {
      once(lists.seen_count);
      lists.counts = words;
    } else if (key == "WIDTH") {
      one_number(h.width, seen_width);
    } else if (key == "HEIGHT") {
      one_number(h.height, seen_height);
    } else if (key == "POINTS") {
      one_number(h.points, seen_points);
    } else if (key == "VIEWPOINT") {
      if (words.size() != 7) throw Error(at + "VIEWPOINT: expected 7 numbers (tx ty tz qw qx qy qz)");
    } else if (key == "DATA") {
      if (words.size() != 1 || (words[0] != "ascii" && words[0] != "binary" && words[0] != "binary_compressed"))
        throw Error(at + "DATA: expected ascii, binary or binary_compressed");
      h.data = words[0];
    } else {
      throw Error(number == 1 ? not_pcd : at + "unknown key; " + kExpectedHeader);
    }
  }
  if (in.eof()) throw Error(path + ": the header's DATA line does not end (expected a newline, then the points)");
  h.data_start = static_cast<uint64_t>(in.tellg());
  if (lists.names.empty() || !seen_width || !seen_height || !seen_points)
    throw Error(path + ": the header lacks FIELDS, WIDTH, HEIGHT or POINTS; " + kExpectedHeader);
}

// One field from each list (COUNT 1 each when the header has no COUNT).
void put_fields_together(const std::string& path, FieldLists& lists, PcdHeader& h) {
  const std::string where = path + ": ";
  const std::size_t n = lists.names.size();
  if (!lists.seen_count) lists.counts.assign(n, "1");
  if (lists.sizes.size() != n || lists.types.size() != n || lists.counts.size() != n)
    throw Error(where + std::to_string(n) + " FIELDS with " + std::to_string(lists.sizes.size()) + " SIZE, " +
                std::to_string(lists.types.size()) + " TYPE and " + std::to_string(lists.counts.size()) +
                " COUNT values, expected one of each per field");
  for (std::size_t i = 0; i < n; ++i) {
    PcdField f;
    f.name = lists.names[i];
    uint64_t size = 0, count = 0;
    if (!parse_unsigned(lists.sizes[i], size) || size > 8) size = 0;  // refused by check_fields
    if (!parse_unsigned(lists.counts[i], count) || count == 0 || count > kMaxPointStep)
      throw Error(where + "field " + f.name + " has COUNT " + quoted(lists.counts[i]) + ", expected a positive integer");
    f.size = static_cast<int>(size);
    f.count = static_cast<int>(count);
    f.type = lists.types[i].size() == 1 ? lists.types[i][0] : '?';
    h.fields.push_back(f);
  }
}

PcdHeader read_header(const std::string& path, std::istream& in) {
  std::string head(kMaxHeaderBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  in.clear();
  PcdHeader h;
  FieldLists lists;
  parse_header_lines(path, head, h, lists);
  put_fields_together(path, lists, h);
  check_fields(path, h);
  check_point_count(path, h);
  in.seekg(static_cast<std::streamoff>(h.data_start));
  return h;
}

// Where one field's values are: the first point's, and bytes from one point's to the next.
struct Column {
  const char* first = nullptr;
  uint64_t stride = 0;
};

void append_point(voxels::CameraCloud& out, float x, float y, float z, bool has_colour, uint32_t packed) {
  const bool finite = std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.cloud.xyz.insert(out.cloud.xyz.end(), {finite ? x : nan, finite ? y : nan, finite ? z : nan});
  if (has_colour) out.cloud.rgb.insert(out.cloud.rgb.end(), {uint8_t(packed >> 16), uint8_t(packed >> 8), uint8_t(packed)});
  else out.cloud.rgb.insert(out.cloud.rgb.end(), {255, 255, 255});
}

// `column(field)` says where a field's values are; x, y, z and colour are 4 bytes each.
template <typename ColumnOf>
void decode_points(const PcdHeader& h, const ColumnOf& column, voxels::CameraCloud& out) {
  const Column x = column(h.x), y = column(h.y), z = column(h.z);
  const Column colour = h.colour >= 0 ? column(h.colour) : Column{};
  out.cloud.xyz.reserve(3 * h.points);
  out.cloud.rgb.reserve(3 * h.points);
  for (uint64_t i = 0; i < h.points; ++i) {
    float p[3];
    uint32_t packed = 0;
    std::memcpy(&p[0], x.first + i * x.stride, 4);
    std::memcpy(&p[1], y.first + i * y.stride, 4);
    std::memcpy(&p[2], z.first + i * z.stride, 4);
    if (colour.first) std::memcpy(&packed, colour.first + i * colour.stride, 4);
    append_point(out, p[0], p[1], p[2], colour.first != nullptr, packed);
  }
}

std::vector<char> read_exactly(const std::string& path, std::istream& in, uint64_t bytes, const std::string& what) {
  std::vector<char> buffer(bytes);
  if (!in.read(buffer.data(), static_cast<std::streamsize>(bytes)))
    throw Error(path + ": cannot read the " + what + " (" + std::to_string(bytes) + " bytes)");
  return buffer;
}

// binary: one point after another, point_step bytes each (padding fields '_' included).
void read_binary(const std::string& path, std::istream& in, const PcdHeader& h, uint64_t file_size,
                 voxels::CameraCloud& out) {
  if (h.data_start + h.bytes() > file_size)
    throw Error(path + ": POINTS " + std::to_string(h.points) + " of " + std::to_string(h.point_step) + " bytes need " +
                std::to_string(h.bytes()) + " bytes of binary data, the file has " + std::to_string(file_size - h.data_start));
  const std::vector<char> data = read_exactly(path, in, h.bytes(), "binary data");
  decode_points(h, [&](int f) { return Column{data.data() + h.fields[f].offset, h.point_step}; }, out);
}

// binary_compressed: the compressed and uncompressed sizes (uint32 each), then LZF data that
// unpacks to each field's values for all points in turn (x x x ... y y y ...), padding left out.
void read_compressed(const std::string& path, std::istream& in, const PcdHeader& h, uint64_t file_size,
                     voxels::CameraCloud& out) {
  const std::string where = path + ": binary_compressed data: ";
  if (h.data_start + 8 > file_size) throw Error(where + "the file ends before its two sizes");
  uint32_t sizes[2];
  std::memcpy(sizes, read_exactly(path, in, 8, "compressed data's sizes").data(), 8);
  const uint64_t compressed = sizes[0], uncompressed = sizes[1], expected = h.points * h.packed_step;
  if (uncompressed != expected)
    throw Error(where + "unpacks to " + std::to_string(uncompressed) + " bytes, expected " + std::to_string(expected) +
                " (POINTS " + std::to_string(h.points) + " of " + std::to_string(h.packed_step) + " bytes)");
  if (h.data_start + 8 + compressed > file_size)
    throw Error(where + std::to_string(compressed) + " compressed bytes claimed, the file has " +
                std::to_string(file_size - h.data_start - 8));
  if (uncompressed > kLzfMaxRatio * compressed)
    throw Error(where + std::to_string(compressed) + " compressed bytes cannot unpack to " + std::to_string(uncompressed) +
                " (LZF packs at most " + std::to_string(kLzfMaxRatio) + " to 1)");
  const std::vector<char> packed = read_exactly(path, in, compressed, "compressed data");
  std::vector<char> columns(uncompressed);
  const unsigned int got = pcl::lzfDecompress(packed.data(), static_cast<unsigned int>(compressed), columns.data(),
                                              static_cast<unsigned int>(uncompressed));
  if (got != uncompressed)
    throw Error(where + "damaged LZF data, expected it to unpack to " + std::to_string(uncompressed) + " bytes");
  std::vector<uint64_t> column_start(h.fields.size());
  for (std::size_t f = 0, at = 0; f < h.fields.size(); ++f) {
    column_start[f] = at;
    if (h.fields[f].name != "_") at += uint64_t(h.fields[f].size) * h.fields[f].count * h.points;
  }
  decode_points(h, [&](int f) { return Column{columns.data() + column_start[f], 4}; }, out);
}

// One ASCII value as its field's type: false unless the whole text is a number of that type.
// `bits` gets a 4-byte value's bits (the packed colour), `value` a number's value.
bool parse_value(const std::string& text, const PcdField& f, double& value, uint32_t& bits) {
  const bool colour = f.name == "rgb" || f.name == "rgba";
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  if (f.type == 'U' || (f.type == 'F' && colour && text.find_first_not_of("0123456789") == std::string::npos)) {
    // PCL writes a packed colour as an unsigned integer whatever its TYPE.
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) return false;
    const unsigned long long u = std::strtoull(s, &end, 10);
    if (errno == ERANGE || (f.size < 8 && u >> (8 * f.size))) return false;
    value = static_cast<double>(u), bits = static_cast<uint32_t>(u);
    return true;
  }
  if (f.type == 'I') {
    if (text.empty() || text.find_first_not_of("+-0123456789") != std::string::npos) return false;
    const long long v = std::strtoll(s, &end, 10);
    const long long half = f.size < 8 ? 1LL << (8 * f.size - 1) : 0;
    if (end == s || *end != '\0' || errno == ERANGE || (f.size < 8 && (v < -half || v >= half))) return false;
    value = static_cast<double>(v), bits = static_cast<uint32_t>(v);
    return true;
  }
  value = std::strtod(s, &end);
  if (end == s || *end != '\0' || (std::isinf(value) && errno == ERANGE)) return false;
  if (f.size == 4) {
    if (std::isfinite(value) && std::abs(value) > std::numeric_limits<float>::max()) return false;
    const float single = static_cast<float>(value);
    std::memcpy(&bits, &single, 4);
  }
  return true;
}

std::string type_name(const PcdField& f) {
  if (f.type == 'F') return f.size == 4 ? "a 4-byte float" : "an 8-byte float";
  return std::string(f.type == 'U' ? "an unsigned" : "a signed") + " " + std::to_string(f.size) + "-byte integer";
}

// ascii: exactly POINTS lines (blank lines after the last allowed), each with exactly one value
// per field and COUNT, each value wholly a number of its field's type.
void read_ascii(const std::string& path, std::istream& in, const PcdHeader& h, uint64_t file_size,
                voxels::CameraCloud& out) {
  const uint64_t data_bytes = file_size - h.data_start;
  if (2 * h.points * h.values_per_point - 1 > data_bytes)  // a value and its separator: two bytes at least
    throw Error(path + ": POINTS " + std::to_string(h.points) + " of " + std::to_string(h.values_per_point) +
                " values cannot fit in the " + std::to_string(data_bytes) + " bytes of ASCII data");
  std::vector<const PcdField*> field_of_value;
  for (const PcdField& f : h.fields)
    for (int c = 0; c < f.count; ++c) field_of_value.push_back(&f);
  const int axes[3] = {h.x, h.y, h.z};
  uint64_t read = 0;
  std::string line;
  for (uint64_t number = 1; std::getline(in, line); ++number) {
    const std::string at = path + ": data line " + std::to_string(number) + ": ";
    const std::vector<std::string> values = words_of(line);
    if (read == h.points) {
      if (values.empty()) continue;
      throw Error(at + "more data lines than POINTS " + std::to_string(h.points));
    }
    if (values.size() != h.values_per_point)
      throw Error(at + std::to_string(values.size()) + " values, expected " + std::to_string(h.values_per_point) +
                  " (one per field and COUNT)");
    double number_of[3] = {0, 0, 0};
    uint32_t packed = 0;
    for (std::size_t k = 0; k < values.size(); ++k) {
      const PcdField& f = *field_of_value[k];
      double value = 0;
      uint32_t bits = 0;
      if (!parse_value(values[k], f, value, bits))
        throw Error(at + "value " + std::to_string(k + 1) + " (field " + f.name + ") is " + quoted(values[k]) +
                    ", expected " + type_name(f));
      for (int axis = 0; axis < 3; ++axis)
        if (&f == &h.fields[axes[axis]]) number_of[axis] = value;
      if (h.colour >= 0 && &f == &h.fields[h.colour]) packed = bits;
    }
    append_point(out, static_cast<float>(number_of[0]), static_cast<float>(number_of[1]),
                 static_cast<float>(number_of[2]), h.colour >= 0, packed);
    ++read;
  }
  if (read != h.points) throw Error(path + ": " + std::to_string(read) + " data lines, expected POINTS " + std::to_string(h.points));
}

}  // namespace

voxels::CameraCloud read_pcd(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_system_error("cannot open " + path);
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  in.seekg(0);
  if (end < 0) throw Error(path + ": cannot tell its size, expected a regular .pcd file");
  const uint64_t file_size = static_cast<uint64_t>(end);
  const PcdHeader h = read_header(path, in);
  voxels::CameraCloud out;
  out.width = static_cast<int>(h.width);
  out.height = static_cast<int>(h.height);
  if (h.data == "binary") read_binary(path, in, h, file_size, out);
  else if (h.data == "binary_compressed") read_compressed(path, in, h, file_size, out);
  else read_ascii(path, in, h, file_size, out);
  return out;
}

}  // namespace qte::point_clouds
