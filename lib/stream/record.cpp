#include "stream/record.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace qte::stream {
namespace {

// 64-byte aligned, zero-padded copy that owns itself through a shared_ptr.
std::shared_ptr<uint8_t> aligned_copy(const void* data, std::size_t n) {
  const std::size_t padded = std::max<std::size_t>(64, (n + 63) / 64 * 64);
  auto* p = static_cast<uint8_t*>(std::aligned_alloc(64, padded));
  if (!p) throw std::bad_alloc();
  if (n) std::memcpy(p, data, n);
  std::memset(p + n, 0, padded - n);
  return std::shared_ptr<uint8_t>(p, [](uint8_t* q) { std::free(q); });
}

}  // namespace

int64_t element_count(const Shape& shape) {
  int64_t n = 1;
  for (int64_t d : shape) n *= d;
  return n;
}

std::string shape_problem(const Shape& shape) {
  constexpr int64_t kMaxElements = int64_t(1) << 40;
  if (shape.size() > static_cast<std::size_t>(kMaxDims))
    return "ndim " + std::to_string(shape.size()) + " (expected at most " + std::to_string(kMaxDims) + ")";
  int64_t count = 1;
  for (std::size_t k = 0; k < shape.size(); ++k) {
    if (shape[k] < 0 || shape[k] > kMaxElements)
      return "extent " + std::to_string(shape[k]) + " in dimension " + std::to_string(k);
    if (shape[k] != 0 && count > kMaxElements / shape[k]) return "more than 2^40 elements";
    count *= shape[k];
  }
  return "";
}

std::string shape_to_string(const Shape& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

bool is_valid_record_type(const std::string& type) {
  if (type.empty() || type.size() > 16) return false;
  return std::all_of(type.begin(), type.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

bool is_valid_field_name(const std::string& name) {
  if (name.empty() || name.size() > 255) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           c == '_' || c == '.' || c == '-';
  });
}

Field::Field(std::string name, DType dtype, Shape shape, std::shared_ptr<const void> owner,
             const uint8_t* bytes)
    : name_(std::move(name)),
      dtype_(dtype),
      shape_(std::move(shape)),
      owner_(std::move(owner)),
      bytes_(bytes) {}

Record::Record(std::string type) : type_(std::move(type)) {
  if (!is_valid_record_type(type_))
    throw Error("invalid record type '" + type_ + "' (expected 1-16 characters of [a-z0-9_])");
}

void Record::check_count(const std::string& name, const Shape& shape, std::size_t count) {
  if (const std::string why = shape_problem(shape); !why.empty())
    throw Error("field '" + name + "': shape " + shape_to_string(shape) + ": " + why);
  if (element_count(shape) != static_cast<int64_t>(count))
    throw Error("field '" + name + "': shape " + shape_to_string(shape) + " needs " +
                std::to_string(element_count(shape)) + " values, got " + std::to_string(count));
}

void Record::set_raw(const std::string& name, DType dtype, const Shape& shape, const void* data,
                     bool compress) {
  if (!is_valid_field_name(name))
    throw Error("invalid field name '" + name + "' (expected 1-255 characters of [A-Za-z0-9_.-])");
  if (const std::string why = shape_problem(shape); !why.empty())
    throw Error("field '" + name + "': shape " + shape_to_string(shape) + ": " + why);
  auto storage = aligned_copy(data, element_count(shape) * dtype_size(dtype));
  Field field(name, dtype, shape, storage, storage.get());
  field.compress = compress;
  add(std::move(field));
}

void Record::set_string(const std::string& name, const std::string& text) {
  set_raw(name, DType::str, {static_cast<int64_t>(text.size())}, text.data());
}

void Record::add(Field field) {
  for (auto& f : fields_)
    if (f.name() == field.name()) {
      f = std::move(field);
      return;
    }
  fields_.push_back(std::move(field));
}

bool Record::remove(const std::string& name) {
  auto it = std::find_if(fields_.begin(), fields_.end(),
                         [&](const Field& f) { return f.name() == name; });
  if (it == fields_.end()) return false;
  fields_.erase(it);
  return true;
}

const Field* Record::find(const std::string& name) const {
  for (const auto& f : fields_)
    if (f.name() == name) return &f;
  return nullptr;
}

void Record::fail(const std::string& field_name, const std::string& expected) const {
  throw StreamError(position, "'" + type_ + "' record, field '" + field_name + "': expected " +
                                  expected);
}

void Record::require_finite(const std::string& name) const {
  const Field& f = field(name);
  for (int64_t i = 0; i < f.element_count(); ++i) {
    double x = 0;
    if (f.dtype() == DType::f32) x = reinterpret_cast<const float*>(f.bytes())[i];
    else if (f.dtype() == DType::f64) x = reinterpret_cast<const double*>(f.bytes())[i];
    else fail(name, "float32 or float64, got " + std::string(dtype_name(f.dtype())));
    if (!std::isfinite(x))
      fail(name, "finite values, element " + std::to_string(i) + " is " + (std::isnan(x) ? "nan" : x > 0 ? "inf" : "-inf"));
  }
}

const Field& Record::field(const std::string& name) const {
  const Field* f = find(name);
  if (!f) throw StreamError(position, "'" + type_ + "' record has no field '" + name + "'");
  return *f;
}

const Field& Record::typed_field(const std::string& name, DType dtype) const {
  const Field& f = field(name);
  if (f.dtype() != dtype)
    fail(name, std::string(dtype_name(dtype)) + ", got " + dtype_name(f.dtype()));
  return f;
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() > suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::vector<std::string> Record::prefixes(const std::string& suffix) const {
  std::vector<std::string> out;
  for (const auto& f : fields_)
    if (ends_with(f.name(), suffix)) out.push_back(f.name().substr(0, f.name().size() - suffix.size()));
  return out;
}

std::string Record::string(const std::string& name) const {
  const Field& f = typed_field(name, DType::str);
  return std::string(reinterpret_cast<const char*>(f.bytes()), f.byte_count());
}

}  // namespace qte::stream
