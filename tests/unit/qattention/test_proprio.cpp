// The networks' time input runs from 1 at the first next-best pose to -1 at the last of the
// record's episode_length (10 where a record has none, as streams recorded before had).
#include <gtest/gtest.h>

#include "qattention/proprio.hpp"

using namespace qte;

namespace {

stream::Record observation(double opening_m, bool open, int episode_length) {
  stream::Record r("obs");
  r.set_scalar<uint8_t>("gripper_open", open);
  r.set_scalar<double>("gripper_opening_m", opening_m);
  if (episode_length > 0) r.set_scalar<int32_t>("episode_length", episode_length);
  return r;
}

}  // namespace

TEST(Proprio, TimeRunsOverTheRecordsEpisodeLength) {
  const auto first = qattention::proprio_of(observation(0.08, true, 30), 0);
  EXPECT_EQ(first, (std::vector<float>{1.0f, 0.04f, 0.04f, 1.0f}));
  EXPECT_FLOAT_EQ(qattention::proprio_of(observation(0.0, false, 30), 29)[3], -1.0f);
  EXPECT_FLOAT_EQ(qattention::proprio_of(observation(0.0, false, 30), 9)[3], 1.0f - 18.0f / 29.0f);
  // Without the field: the published 10 (step 9 is the last).
  EXPECT_FLOAT_EQ(qattention::proprio_of(observation(0.0, false, 0), 9)[3], -1.0f);
  EXPECT_FLOAT_EQ(qattention::proprio_of(observation(0.0, false, 0), 3)[3], 1.0f - 6.0f / 9.0f);
  EXPECT_FLOAT_EQ(qattention::proprio_of(observation(0.0, false, 10), 12)[3], -1.0f);  // clamped
}
