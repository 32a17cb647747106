#include "stream/record_types.hpp"

#include <algorithm>

namespace qte::stream {

const std::vector<RecordType>& record_types() {
  static const std::vector<RecordType> types = {
      {"reset", "episode starts", "the actor loop (sim-step --task writes its own)"},
      {"obs", "observations", "sim-step, robot-step, obs-pack or demo-record"},
      {"voxels", "voxel grids", "voxelize"},
      {"action", "next-best poses", "qte-select"},
      {"trajectory", "planned motions", "plan-path"},
      {"episode", "ends of recorded demonstrations", "demo-record or obs-pack"},
      {"frame", "replay frames", "keyframe"},
      {"transition", "replay transitions", "keyframe"},
      {"checkpoint", "network weights", "qattn-train"},
      {"learner", "a training run's state", "qattn-train"},
      {"metrics", "figures of a run", "qattn-train"},
  };
  return types;
}

const RecordType* find_record_type(const std::string& name) {
  for (const RecordType& t : record_types())
    if (name == t.name) return &t;
  return nullptr;
}

std::string record_type_names() {
  std::string names;
  for (const RecordType& t : record_types()) names += (names.empty() ? "" : ", ") + std::string(t.name);
  return names;
}

std::string describe_counts(const std::map<std::string, int64_t>& counts) {
  std::vector<std::pair<std::string, int64_t>> sorted(counts.begin(), counts.end());
  std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string text;
  for (const auto& [name, n] : sorted) text += (text.empty() ? "" : ", ") + std::to_string(n) + " '" + name + "'";
  return text;
}

}  // namespace qte::stream
