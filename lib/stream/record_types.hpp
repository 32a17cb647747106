// The record types of the stream format and their fields (formats/record-stream.md, section 12,
// which tests/tools/test_record_schema.py holds equal to this registry, as it holds the Python
// reader's records to it): what each type is and which programs write it, so that a program
// given records of another kind can say so and name the program that makes the right ones, and
// every field with its dtype, shape and meaning (`stream-dump --schema` prints them).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace qte::stream {

// One field of a record type, written as the specification's tables write it.
struct FieldSchema {
  // "joint_positions"; per camera "<camera>.rgb", per depth "depth<d>.index", and "<parameter>"
  // or "<name>" where the name is the network's or the figure's own.
  const char* name;
  const char* dtype;    // "uint8", "int32", "float64", "str", ...
  const char* shape;    // "[H, W, 3]", "[7]", "[]" (a scalar), "[n]" (a str's bytes), "its shape"
  bool optional;        // the specification marks it optional: it may be absent
  const char* meaning;  // the specification's words
};

struct RecordType {
  const char* name;        // "obs"
  const char* what;        // "observations"
  const char* written_by;  // "sim-step, robot-step, obs-pack or demo-record"
  std::vector<FieldSchema> fields;  // in the specification's order
};

const std::vector<RecordType>& record_types();
// The type of that name, or nullptr.
const RecordType* find_record_type(const std::string& name);
// "reset, obs, voxels, ...": for a usage error that lists them.
std::string record_type_names();
// The registry as text (`stream-dump --schema`): per type a line "TYPE<tab>WHAT<tab>written by
// WRITTEN_BY", then one line per field "<tab>NAME<tab>DTYPE<tab>SHAPE<tab>optional|required<tab>MEANING".
std::string schema_text(const RecordType& type);
// How many records of each type a stream held, as "3 'frame', 2 'transition'" (most first).
std::string describe_counts(const std::map<std::string, int64_t>& counts);

}  // namespace qte::stream
