// NumPy .npy files (format 1.0, C order, little-endian) <-> fields, so arrays move between
// the stream and Python without our reader.
#pragma once

#include <string>

#include "stream/record.hpp"

namespace qte::stream {

// Writes one field atomically. `str` fields become a 0-d bytes array (dtype |S<n>).
void write_npy(const std::string& path, const Field& field);

// Reads a .npy file of one of our dtypes into `record` as field `name`.
void read_npy_into(Record& record, const std::string& name, const std::string& path);

}  // namespace qte::stream
