// Element types of the record stream (formats/record-stream.md, "Data types").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace qte::stream {

// The numeric codes are part of the on-disk format: never renumber, only append.
enum class DType : uint8_t {
  u8 = 1,
  i8 = 2,
  u16 = 3,
  i16 = 4,
  u32 = 5,
  i32 = 6,
  u64 = 7,
  i64 = 8,
  f32 = 9,
  f64 = 10,
  str = 11,  // UTF-8 text, 1-d, shape = [byte count]
};

bool is_known_dtype(uint8_t code);
std::size_t dtype_size(DType dtype);
const char* dtype_name(DType dtype);       // "float32", "uint8", "str", ...
const char* dtype_numpy_descr(DType dtype);  // "<f4", "|u1", ... ("|u1" for str)
DType dtype_from_name(const std::string& name);  // accepts "float32" and "f32"; throws Error

template <class T> constexpr DType dtype_of();
template <> constexpr DType dtype_of<uint8_t>() { return DType::u8; }
template <> constexpr DType dtype_of<int8_t>() { return DType::i8; }
template <> constexpr DType dtype_of<uint16_t>() { return DType::u16; }
template <> constexpr DType dtype_of<int16_t>() { return DType::i16; }
template <> constexpr DType dtype_of<uint32_t>() { return DType::u32; }
template <> constexpr DType dtype_of<int32_t>() { return DType::i32; }
template <> constexpr DType dtype_of<uint64_t>() { return DType::u64; }
template <> constexpr DType dtype_of<int64_t>() { return DType::i64; }
template <> constexpr DType dtype_of<float>() { return DType::f32; }
template <> constexpr DType dtype_of<double>() { return DType::f64; }

}  // namespace qte::stream
