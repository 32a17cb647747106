// Human- and machine-readable views of records (stream-dump).
#pragma once

#include <cstdint>
#include <ostream>
#include <string>

#include "stream/record.hpp"

namespace qte::stream {

struct InspectOptions {
  int64_t max_values = 6;  // values shown per field; negative = all
};

// One block per record: "#3 @4096 obs (5 fields, 49472 bytes)" then a line per field.
void print_record_text(std::ostream& out, const Record& record, uint64_t record_bytes,
                       const InspectOptions& options);

// One JSON object per line (JSON Lines): index, offset, type, fields with dtype, shape and
// values (flattened, C order; NaN and infinities as the strings "nan", "inf", "-inf").
void print_record_json(std::ostream& out, const Record& record, uint64_t record_bytes,
                       const InspectOptions& options);

// JSON string literal with escapes.
std::string json_quote(const std::string& text);

// Element i of a numeric field as a double (NaN for text fields).
double element_as_double(const Field& field, int64_t i);

}  // namespace qte::stream
