#include "qattention/proprio.hpp"

#include <algorithm>

#include "stream/field_names.hpp"

namespace qte::qattention {

std::vector<float> proprio_of(const stream::Record& observation, int step) {
  const float open = observation.scalar<uint8_t>(fields::gripper_open) != 0 ? 1.0f : 0.0f;
  const float finger = static_cast<float>(observation.scalar<double>(fields::gripper_opening_m) / 2);
  // Records made before tasks had lengths of their own carry none: the published length.
  const int length = observation.has(fields::episode_length) ? observation.scalar<int32_t>(fields::episode_length)
                                                             : tasks::kPublishedEpisodeLength;
  const float time = std::clamp(1.0f - 2.0f * static_cast<float>(step) / std::max(length - 1, 1), -1.0f, 1.0f);
  return {open, finger, finger, time};
}

}  // namespace qte::qattention
