#include "stream/field_spec.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <vector>

#include "stream/npy.hpp"

namespace qte::stream {
namespace {

template <class T>
void add_numbers(Record& record, const std::string& name, const Shape& shape,
                 const std::vector<std::string>& items, const std::string& spec) {
  std::vector<T> values;
  for (const auto& item : items) {
    try {
      std::size_t used = 0;
      if constexpr (std::is_floating_point_v<T>) {
        // strtof/strtod round correctly for the target type and keep subnormals.
        errno = 0;
        char* end = nullptr;
        const T v = std::is_same_v<T, float> ? static_cast<T>(std::strtof(item.c_str(), &end))
                                             : static_cast<T>(std::strtod(item.c_str(), &end));
        used = static_cast<std::size_t>(end - item.c_str());
        if (item.empty() || (errno == ERANGE && std::isinf(v))) throw std::out_of_range(item);
        values.push_back(v);
      } else if constexpr (std::is_signed_v<T>) {
        const long long v = std::stoll(item, &used, 10);
        if (v < std::numeric_limits<T>::min() || v > std::numeric_limits<T>::max())
          throw std::out_of_range(item);
        values.push_back(static_cast<T>(v));
      } else {
        if (item.find('-') != std::string::npos) throw std::out_of_range(item);
        const unsigned long long v = std::stoull(item, &used, 10);
        if (v > std::numeric_limits<T>::max()) throw std::out_of_range(item);
        values.push_back(static_cast<T>(v));
      }
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error("field spec '" + spec + "': '" + item + "' is not a valid " +
                  dtype_name(dtype_of<T>()));
    }
  }
  if (const std::string why = shape_problem(shape); !why.empty())
    throw Error("field spec '" + spec + "': shape " + shape_to_string(shape) + ": " + why);
  if (element_count(shape) != static_cast<int64_t>(values.size()))
    throw Error("field spec '" + spec + "': shape " + shape_to_string(shape) + " needs " +
                std::to_string(element_count(shape)) + " values, got " +
                std::to_string(values.size()));
  record.set<T>(name, shape, values);
}

}  // namespace

void add_field_from_spec(Record& record, const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos)
    throw Error("field spec '" + spec + "': expected NAME=TEXT, NAME:DTYPE[SHAPE]=VALUES or "
                "NAME=@FILE.npy");
  std::string left = spec.substr(0, eq);
  const std::string value = spec.substr(eq + 1);
  const auto colon = left.find(':');
  if (colon == std::string::npos) {
    if (!value.empty() && value[0] == '@') read_npy_into(record, left, value.substr(1));
    else record.set_string(left, value);
    return;
  }
  const std::string name = left.substr(0, colon);
  std::string type = left.substr(colon + 1);
  Shape shape;
  bool shaped = false;
  if (const auto bracket = type.find('['); bracket != std::string::npos) {
    if (type.back() != ']') throw Error("field spec '" + spec + "': unclosed '[' in the shape");
    std::stringstream dims(type.substr(bracket + 1, type.size() - bracket - 2));
    for (std::string d; std::getline(dims, d, ',');) {
      try {
        shape.push_back(std::stoll(d));
      } catch (const std::exception&) {
        throw Error("field spec '" + spec + "': bad extent '" + d + "'");
      }
    }
    type = type.substr(0, bracket);
    shaped = true;
  }
  const DType dtype = dtype_from_name(type);
  std::vector<std::string> items;
  std::stringstream list(value);
  for (std::string item; std::getline(list, item, ',');) items.push_back(item);
  if (dtype == DType::str) {
    record.set_string(name, value);
    return;
  }
  if (!shaped && items.size() != 1) shape = {static_cast<int64_t>(items.size())};
  switch (dtype) {
    case DType::u8: return add_numbers<uint8_t>(record, name, shape, items, spec);
    case DType::i8: return add_numbers<int8_t>(record, name, shape, items, spec);
    case DType::u16: return add_numbers<uint16_t>(record, name, shape, items, spec);
    case DType::i16: return add_numbers<int16_t>(record, name, shape, items, spec);
    case DType::u32: return add_numbers<uint32_t>(record, name, shape, items, spec);
    case DType::i32: return add_numbers<int32_t>(record, name, shape, items, spec);
    case DType::u64: return add_numbers<uint64_t>(record, name, shape, items, spec);
    case DType::i64: return add_numbers<int64_t>(record, name, shape, items, spec);
    case DType::f32: return add_numbers<float>(record, name, shape, items, spec);
    case DType::f64: return add_numbers<double>(record, name, shape, items, spec);
    case DType::str: break;
  }
}

}  // namespace qte::stream
