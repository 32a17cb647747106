// obs-pack's logic: frame file patterns, the camera's pose and intrinsics from option values, and
// a recording of PNG frames and a joint log made into observations.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "camera_recordings/recording.hpp"
#include "common/error.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::camera_recordings;

TEST(Recording, FramePatternsTakeOneIntegerConversion) {
  EXPECT_EQ(frame_path("frames/color_%06d.png", 42), "frames/color_000042.png");
  EXPECT_EQ(frame_path("%d.pcd", 7), "7.pcd");
  EXPECT_EQ(frame_path("100%%_%-4u|", 3), "100%_3   |");
  for (const char* bad : {"none.png", "%s.png", "%d_%d.png", "%06.png", "%"})
    EXPECT_THROW(frame_path(bad, 1), UsageError) << bad;
}

TEST(Recording, CameraPosesAndIntrinsicsAreChecked) {
  const Eigen::Isometry3d pose = camera_pose_from_values({1, 2, 3, 0, 0, 0.70710678, 0.70710678}, "camera-pose");
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-6));  // 90 deg about z
  EXPECT_THROW(camera_pose_from_values({0, 0, 0, 0, 0, 0, 2}, "camera-pose"), UsageError);
  EXPECT_THROW(camera_pose_from_values({0, 0, NAN, 0, 0, 0, 1}, "camera-pose"), UsageError);
  std::vector<double> matrix = {1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 1};
  EXPECT_TRUE(camera_pose_from_matrix(matrix, "extrinsics").translation().isApprox(Eigen::Vector3d(0.5, 0, 1)));
  matrix[0] = -1;  // a reflection
  EXPECT_THROW(camera_pose_from_matrix(matrix, "extrinsics"), UsageError);
  const Eigen::Matrix3d k = intrinsics_from_values({600, 610, 320, 240}, "intrinsics");
  EXPECT_EQ(k(0, 0), 600);
  EXPECT_EQ(k(1, 1), 610);
  EXPECT_EQ(k(0, 2), 320);
  EXPECT_EQ(k(1, 2), 240);
  EXPECT_THROW(intrinsics_from_values({0, 610, 320, 240}, "intrinsics"), UsageError);
}

// Three frames 1 m in front of a camera looking down at the table, a joint log: one obs each, in
// order, with the robot's joints from the log; a count the recording does not have is an error
// naming the missing frame, and so is a log shorter than the recording.
TEST(Recording, FramesAndJointsBecomeObservations) {
  const std::string dir = test_support::temp_dir("recording");
  for (int i = 0; i < 3; ++i) {
    cv::imwrite(dir + "/rgb_" + std::to_string(i) + ".png", cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30 + i)));
    cv::imwrite(dir + "/depth_" + std::to_string(i) + ".png", cv::Mat(8, 8, CV_16UC1, cv::Scalar(1000)));
  }
  Recording recording;
  recording.rgb_pattern = dir + "/rgb_%d.png";
  recording.depth_pattern = dir + "/depth_%d.png";
  recording.episode_length = 2;
  recording.task = "reach_target";
  recording.camera.intrinsics = intrinsics_from_values({8, 8, 4, 4}, "intrinsics");
  // 1 m above the table's middle, looking straight down (camera z = world -z).
  recording.camera.camera_to_world = camera_pose_from_values({0, 0, 1.75, 1, 0, 0, 0}, "camera-pose");
  recording.joints_path = "log.csv";
  for (int i = 0; i < 3; ++i) {
    RobotState state;
    state.joints(0) = 0.1 * i;
    recording.states.push_back(state);
  }
  std::vector<stream::Record> records;
  const PackedRecording packed =
      pack_recording(recording, test_support::xarm(), [&](const stream::Record& r) { records.push_back(r); });
  ASSERT_EQ(packed.written, 3);
  EXPECT_EQ(packed.blind, 0);
  ASSERT_EQ(records.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(records[i].scalar<int32_t>("step"), i);
    EXPECT_EQ(records[i].scalar<int32_t>("episode_length"), 2);
    EXPECT_DOUBLE_EQ(records[i].array<double>("joint_positions")[0], 0.1 * i);
    EXPECT_EQ(records[i].array<uint8_t>("front.rgb")[0], 30 + i);  // RGB: the BGR file's red is its third
  }
  recording.count = 4;
  try {
    pack_recording(recording, test_support::xarm(), [](const stream::Record&) {});
    FAIL() << "a fourth frame was found";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/rgb_3.png: no such frame"), std::string::npos) << e.what();
  }
  recording.count = -1;
  recording.states.pop_back();  // a log shorter than the recording
  EXPECT_THROW(pack_recording(recording, test_support::xarm(), [](const stream::Record&) {}), Error);
}
