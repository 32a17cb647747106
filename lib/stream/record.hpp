// A record: a type name plus named, typed n-d arrays (formats/record-stream.md).
// Scalars are 0-d arrays and text is a 1-d `str` array, so everything is a field.
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "stream/dtype.hpp"

namespace qte::stream {

using Shape = std::vector<int64_t>;

// Number of elements of a shape (1 for a scalar).
int64_t element_count(const Shape& shape);
// Why `shape` cannot be a field's (more than 8 dimensions, an extent below 0 or above 2^40, more
// than 2^40 elements), or "" when it can: one rule for the writers and the decoder.
std::string shape_problem(const Shape& shape);
std::string shape_to_string(const Shape& shape);  // "[128, 128, 3]"

// Read-only typed view of a field's elements, stored C order (row-major).
template <class T>
struct ArrayView {
  const T* data = nullptr;
  Shape shape;
  int64_t size() const { return element_count(shape); }
  const T& operator[](int64_t i) const { return data[i]; }
  const T* begin() const { return data; }
  const T* end() const { return data + size(); }
};

class Field {
 public:
  Field(std::string name, DType dtype, Shape shape, std::shared_ptr<const void> owner,
        const uint8_t* bytes);

  const std::string& name() const { return name_; }
  DType dtype() const { return dtype_; }
  const Shape& shape() const { return shape_; }
  int64_t element_count() const { return stream::element_count(shape_); }
  std::size_t byte_count() const { return element_count() * dtype_size(dtype_); }
  const uint8_t* bytes() const { return bytes_; }  // 64-byte aligned

  // Ask the writer to zstd-compress this array (kept raw when that does not shrink it).
  bool compress = false;

  // The zstd frame these elements were read from (null when they were stored raw or made
  // here). A writer asked to compress them writes this frame again instead of compressing
  // anew: the same bytes when it was written at the writer's level (every program here
  // writes level 3), and no work in the programs that pass observations on.
  void keep_encoded(std::shared_ptr<const void> owner, const uint8_t* frame, std::size_t size) {
    encoded_owner_ = std::move(owner);
    encoded_ = frame;
    encoded_size_ = size;
  }
  const uint8_t* encoded() const { return encoded_; }
  std::size_t encoded_size() const { return encoded_size_; }

 private:
  std::string name_;
  DType dtype_;
  Shape shape_;
  std::shared_ptr<const void> owner_;  // keeps `bytes_` alive (a read payload or own buffer)
  const uint8_t* bytes_;
  std::shared_ptr<const void> encoded_owner_;  // keeps `encoded_` alive (the read payload)
  const uint8_t* encoded_ = nullptr;
  std::size_t encoded_size_ = 0;
};

class Record {
 public:
  explicit Record(std::string type);

  const std::string& type() const { return type_; }
  const std::vector<Field>& fields() const { return fields_; }

  // Where this record was read from; used to name file, record and offset in errors.
  StreamPosition position;

  // --- building ---------------------------------------------------------------------------
  // Adds or replaces a field, copying the elements.
  void set_raw(const std::string& name, DType dtype, const Shape& shape, const void* data,
               bool compress = false);
  template <class T>
  void set(const std::string& name, const Shape& shape, const T* data, bool compress = false) {
    set_raw(name, dtype_of<T>(), shape, data, compress);
  }
  template <class T>
  void set(const std::string& name, const Shape& shape, const std::vector<T>& values,
           bool compress = false) {
    check_count(name, shape, values.size());
    set_raw(name, dtype_of<T>(), shape, values.data(), compress);
  }
  template <class T>
  void set_scalar(const std::string& name, T value) {
    set_raw(name, dtype_of<T>(), {}, &value);
  }
  void set_string(const std::string& name, const std::string& text);
  // Adds an already-built field (used by the reader and by tools that pass fields through).
  void add(Field field);
  bool remove(const std::string& name);

  // --- reading (throw StreamError naming this record's position when absent or mistyped) ---
  bool has(const std::string& name) const { return find(name) != nullptr; }
  const Field* find(const std::string& name) const;
  const Field& field(const std::string& name) const;
  template <class T>
  ArrayView<T> array(const std::string& name) const {
    const Field& f = typed_field(name, dtype_of<T>());
    return {reinterpret_cast<const T*>(f.bytes()), f.shape()};
  }
  template <class T>
  T scalar(const std::string& name) const {
    const Field& f = typed_field(name, dtype_of<T>());
    if (f.element_count() != 1) fail(name, "a scalar, got shape " + shape_to_string(f.shape()));
    T value;
    std::memcpy(&value, f.bytes(), sizeof(T));
    return value;
  }
  std::string string(const std::string& name) const;

  [[noreturn]] void fail(const std::string& field_name, const std::string& expected) const;
  // Fails (naming this record and the field) unless every element of the float32 or float64
  // field is finite: for values written on (poses, bounds, rewards, camera matrices).
  void require_finite(const std::string& name) const;

  // The X of every field named X<suffix>, in field order: e.g. the cameras of an observation,
  // prefixes(".rgb") -> {"front", "wrist"}.
  std::vector<std::string> prefixes(const std::string& suffix) const;

 private:
  const Field& typed_field(const std::string& name, DType dtype) const;
  static void check_count(const std::string& name, const Shape& shape, std::size_t count);

  std::string type_;
  std::vector<Field> fields_;
};

bool ends_with(const std::string& text, const std::string& suffix);

// Rules for names, shared by reader and writer so both reject the same things.
bool is_valid_record_type(const std::string& type);  // 1..16 chars of [a-z0-9_]
bool is_valid_field_name(const std::string& name);   // 1..255 chars of [A-Za-z0-9_.-]
constexpr int kMaxDims = 8;

}  // namespace qte::stream
