#include "stream/record_filter.hpp"

#include <cstdlib>

#include "stream/inspect.hpp"

namespace qte::stream {

bool field_equals(const Record& record, const std::string& name, const std::string& value) {
  const Field* field = record.find(name);
  if (field == nullptr) return false;
  if (field->dtype() == DType::str) return record.string(name) == value;
  if (field->element_count() != 1) return false;
  char* end = nullptr;
  const double wanted = std::strtod(value.c_str(), &end);
  if (end == value.c_str() || *end != '\0') return false;
  return element_as_double(*field, 0) == wanted;
}

void RecordFilter::handle(const Record& record, const Emit& emit) {
  if (done()) return;
  if (!selection_.keep_types.empty() && !selection_.keep_types.count(record.type())) return;
  if (selection_.drop_types.count(record.type())) return;
  for (const auto& [name, value] : selection_.fields_equal)
    if (!field_equals(record, name, value)) return;
  emit(record);
  ++passed_;
}

}  // namespace qte::stream
