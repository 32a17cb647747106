// The compact 'frame' record keeps a camera's depth in millimetres whether the observation had
// it in metres (the simulator's) or in millimetres already (a depth camera's, obs-pack's).
#include <gtest/gtest.h>

#include "keyframes/transitions.hpp"

using namespace qte;

namespace {

stream::Record observation() {
  stream::Record obs("obs");
  obs.set<uint8_t>("front.rgb", {1, 2, 3}, std::vector<uint8_t>(6, 7));
  obs.set<double>("front.intrinsics", {3, 3}, std::vector<double>{2, 0, 1, 0, 2, 0.5, 0, 0, 1});
  std::vector<double> identity(16, 0.0);
  for (int i = 0; i < 4; ++i) identity[5 * i] = 1;
  obs.set<double>("front.extrinsics", {4, 4}, identity);
  obs.set_scalar<int32_t>("frame", 3);
  return obs;
}

}  // namespace

TEST(FrameRecord, DepthInMillimetresFromMetresOrAsSaved) {
  stream::Record metres = observation();
  metres.set<float>("front.depth", {1, 2}, std::vector<float>{0.5f, 1.2344f});
  stream::Record millimetres = observation();
  millimetres.set<uint16_t>("front.depth_mm", {1, 2}, std::vector<uint16_t>{500, 1234});
  for (const stream::Record& obs : {metres, millimetres}) {
    const stream::Record frame = keyframes::frame_record(obs, 42);
    ASSERT_TRUE(frame.has("front.depth_mm"));
    const auto mm = frame.array<uint16_t>("front.depth_mm");
    EXPECT_EQ(mm[0], 500);
    EXPECT_EQ(mm[1], 1234);
    EXPECT_TRUE(frame.field("front.depth_mm").compress);
    EXPECT_EQ(frame.scalar<int64_t>("episode_key"), 42);
  }
}
