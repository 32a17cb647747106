// NumPy .npy files (format 1.0, C order, little-endian) <-> fields, so arrays move between
// the stream and Python without our reader.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "stream/record.hpp"

namespace qte::stream {

// Writes one field atomically. `str` fields become a 0-d bytes array (dtype |S<n>).
void write_npy(const std::string& path, const Field& field);

// Reads a .npy file of one of our dtypes into `record` as field `name`.
void read_npy_into(Record& record, const std::string& name, const std::string& path);

// Exports the fields of many records into the directory `dir`, as NumPy users expect: one
// stacked array per record type and field, `dir/<type>.<field>.npy` of shape [N, ...] over
// the N records of that type (a `str` field: a 1-d |S<longest> array). Rows are spooled to an
// unlinked scratch file in `dir` as records arrive, so memory holds one record, not the stream.
// A field that is missing from some records of its type, or whose dtype or shape changes,
// cannot be stacked: it is written per record instead, as `dir/<index>.<type>.<field>.npy`
// (the record's index zero-padded to 6 digits), which is what `per_record` asks for every field.
class NpyExport {
 public:
  NpyExport(std::string dir, bool per_record);
  ~NpyExport();
  NpyExport(const NpyExport&) = delete;
  NpyExport& operator=(const NpyExport&) = delete;

  void add(const Record& record);
  // Writes the stacked files (each atomically). Call once, after the last add().
  void finish();

 private:
  struct Stack {  // the rows of one (type, field) so far
    DType dtype = DType::u8;
    Shape shape;                          // of one row
    std::vector<uint64_t> record_indices;  // of each row, for the per-record names
    std::vector<uint64_t> offsets;         // of each row in the spool (numbers)
    std::vector<std::string> texts;        // each row (str fields)
    bool per_record = false;
  };
  using Key = std::pair<std::string, std::string>;  // (record type, field name)

  std::string per_record_path(uint64_t record_index, const Key& key) const;
  bool fits(const Stack& stack, const Field& field) const;
  void append(Stack& stack, const Field& field, uint64_t record_index);
  void write_rows_per_record(const Key& key, Stack& stack);
  std::vector<uint8_t> spooled(const Stack& stack, std::size_t i) const;

  std::string dir_;
  bool per_record_;
  int spool_fd_ = -1;
  uint64_t spool_bytes_ = 0;
  std::map<Key, Stack> stacks_;
  std::map<std::string, uint64_t> records_of_type_;
};

}  // namespace qte::stream
