// The record types of the stream format (formats/record-stream.md, section 12, which a test
// holds equal to this list): what each is and which programs write it, so that a program given
// records of another kind can say so and name the program that makes the right ones.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace qte::stream {

struct RecordType {
  const char* name;        // "obs"
  const char* what;        // "observations"
  const char* written_by;  // "sim-step, robot-step, obs-pack or demo-record"
};

const std::vector<RecordType>& record_types();
// The type of that name, or nullptr.
const RecordType* find_record_type(const std::string& name);
// "reset, obs, voxels, ...": for a usage error that lists them.
std::string record_type_names();
// How many records of each type a stream held, as "3 'frame', 2 'transition'" (most first).
std::string describe_counts(const std::map<std::string, int64_t>& counts);

}  // namespace qte::stream
