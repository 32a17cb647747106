#include "stream/dtype.hpp"

#include "common/error.hpp"

namespace qte::stream {
namespace {

struct DTypeInfo {
  DType dtype;
  std::size_t size;
  const char* name;
  const char* short_name;
  const char* numpy_descr;
};

constexpr DTypeInfo kTypes[] = {
    {DType::u8, 1, "uint8", "u8", "|u1"},     {DType::i8, 1, "int8", "i8", "|i1"},
    {DType::u16, 2, "uint16", "u16", "<u2"},  {DType::i16, 2, "int16", "i16", "<i2"},
    {DType::u32, 4, "uint32", "u32", "<u4"},  {DType::i32, 4, "int32", "i32", "<i4"},
    {DType::u64, 8, "uint64", "u64", "<u8"},  {DType::i64, 8, "int64", "i64", "<i8"},
    {DType::f32, 4, "float32", "f32", "<f4"}, {DType::f64, 8, "float64", "f64", "<f8"},
    {DType::str, 1, "str", "str", "|u1"},
};

const DTypeInfo& info(DType dtype) {
  for (const auto& t : kTypes)
    if (t.dtype == dtype) return t;
  throw Error("unknown dtype code " + std::to_string(static_cast<int>(dtype)));
}

}  // namespace

bool is_known_dtype(uint8_t code) {
  for (const auto& t : kTypes)
    if (static_cast<uint8_t>(t.dtype) == code) return true;
  return false;
}

std::size_t dtype_size(DType dtype) { return info(dtype).size; }
const char* dtype_name(DType dtype) { return info(dtype).name; }
const char* dtype_numpy_descr(DType dtype) { return info(dtype).numpy_descr; }

DType dtype_from_name(const std::string& name) {
  for (const auto& t : kTypes)
    if (name == t.name || name == t.short_name) return t.dtype;
  throw Error("unknown dtype '" + name +
              "' (expected one of uint8 int8 uint16 int16 uint32 int32 uint64 int64 float32 "
              "float64 str)");
}

}  // namespace qte::stream
