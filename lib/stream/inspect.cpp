#include "stream/inspect.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>


namespace qte::stream {
namespace {

template <class T>
T element(const Field& f, int64_t i) {
  T v;
  std::memcpy(&v, f.bytes() + i * sizeof(T), sizeof(T));
  return v;
}

std::string format_float(double v, int digits) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (v == 0 && std::signbit(v)) return "-0.0";  // "-0" would read back as the integer 0
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

}  // namespace

double element_as_double(const Field& f, int64_t i) {
  switch (f.dtype()) {
    case DType::u8: return element<uint8_t>(f, i);
    case DType::i8: return element<int8_t>(f, i);
    case DType::u16: return element<uint16_t>(f, i);
    case DType::i16: return element<int16_t>(f, i);
    case DType::u32: return element<uint32_t>(f, i);
    case DType::i32: return element<int32_t>(f, i);
    case DType::u64: return static_cast<double>(element<uint64_t>(f, i));
    case DType::i64: return static_cast<double>(element<int64_t>(f, i));
    case DType::f32: return element<float>(f, i);
    case DType::f64: return element<double>(f, i);
    case DType::str: break;
  }
  return std::nan("");
}

namespace {

// Value i as text; `for_json` quotes non-finite floats so the line stays valid JSON.
std::string value_text(const Field& f, int64_t i, bool for_json) {
  auto real = [&](double v, int digits) {
    std::string s = format_float(v, digits);
    return (for_json && !std::isfinite(v)) ? "\"" + s + "\"" : s;
  };
  switch (f.dtype()) {
    case DType::u8: return std::to_string(element<uint8_t>(f, i));
    case DType::i8: return std::to_string(element<int8_t>(f, i));
    case DType::u16: return std::to_string(element<uint16_t>(f, i));
    case DType::i16: return std::to_string(element<int16_t>(f, i));
    case DType::u32: return std::to_string(element<uint32_t>(f, i));
    case DType::i32: return std::to_string(element<int32_t>(f, i));
    case DType::u64: return std::to_string(element<uint64_t>(f, i));
    case DType::i64: return std::to_string(element<int64_t>(f, i));
    case DType::f32: return real(element<float>(f, i), 9);   // 9 digits round-trip float32
    case DType::f64: return real(element<double>(f, i), 17);  // 17 digits round-trip float64
    case DType::str: break;
  }
  return "?";
}

std::string text_of(const Field& f) {
  return std::string(reinterpret_cast<const char*>(f.bytes()), f.byte_count());
}

// Length of the valid UTF-8 sequence starting at text[i], or 0 when it is invalid.
std::size_t utf8_sequence_length(const std::string& text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(i);
  const std::size_t n = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
  if (n == 0 || i + n > text.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((byte(i + k) >> 6) != 2) return 0;
  return n;
}

}  // namespace

std::string json_quote(const std::string& text) {
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x80) {  // JSON must be UTF-8: invalid bytes become U+FFFD
      const std::size_t n = utf8_sequence_length(text, i);
      if (n == 0) {
        out += "\ufffd";
      } else {
        out.append(text, i, n);
        i += n - 1;
      }
      continue;
    }
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

void print_record_text(std::ostream& out, const Record& record, uint64_t record_bytes,
                       const InspectOptions& options) {
  out << "#" << record.position.record_index << " @" << record.position.byte_offset << " "
      << record.type() << " (" << record.fields().size() << " fields, " << record_bytes
      << " bytes)\n";
  for (const Field& f : record.fields()) {
    out << "  " << f.name() << "  " << dtype_name(f.dtype()) << " "
        << shape_to_string(f.shape());
    if (f.dtype() == DType::str) {
      out << "  " << json_quote(text_of(f)) << "\n";
      continue;
    }
    const int64_t n = f.element_count();
    const int64_t shown = options.max_values < 0 ? n : std::min(n, options.max_values);
    if (shown > 0) {
      out << "  " << (f.shape().empty() ? "" : "[");
      for (int64_t i = 0; i < shown; ++i) out << (i ? " " : "") << value_text(f, i, false);
      if (shown < n) out << " ...";
      out << (f.shape().empty() ? "" : "]");
    }
    out << "\n";
  }
}

void print_record_json(std::ostream& out, const Record& record, uint64_t record_bytes,
                       const InspectOptions& options) {
  out << "{\"index\":" << record.position.record_index
      << ",\"offset\":" << record.position.byte_offset << ",\"type\":" << json_quote(record.type())
      << ",\"bytes\":" << record_bytes << ",\"fields\":[";
  bool first = true;
  for (const Field& f : record.fields()) {
    out << (first ? "" : ",") << "{\"name\":" << json_quote(f.name()) << ",\"dtype\":\""
        << dtype_name(f.dtype()) << "\",\"shape\":[";
    for (std::size_t k = 0; k < f.shape().size(); ++k) out << (k ? "," : "") << f.shape()[k];
    out << "]";
    if (f.dtype() == DType::str) {
      out << ",\"value\":" << json_quote(text_of(f));
    } else {
      const int64_t n = f.element_count();
      const int64_t shown = options.max_values < 0 ? n : std::min(n, options.max_values);
      out << ",\"values\":[";
      for (int64_t i = 0; i < shown; ++i) out << (i ? "," : "") << value_text(f, i, true);
      out << "],\"complete\":" << (shown == n ? "true" : "false");
    }
    out << "}";
    first = false;
  }
  out << "]}\n";
}

}  // namespace qte::stream
