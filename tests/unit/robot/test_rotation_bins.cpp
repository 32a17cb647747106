// The action encoding's rotation bins: a round trip stays within half a bin on every axis, and
// the gripper pointing down has the bins the experts' poses give.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "robot/rotation_bins.hpp"

using namespace qte::robot;

TEST(RotationBins, RoundTripWithinHalfABin) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), pitch(-1.4, 1.4);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d a(angle(rng), pitch(rng), angle(rng));
    const Eigen::Vector3i bins = rotation_bins(from_euler_xyz(a));
    ASSERT_TRUE((bins.array() >= 0).all() && (bins.array() < kRotationBins).all());
    const Eigen::Vector3d back = euler_xyz(rotation_from_bins(bins));
    for (int k = 0; k < 3; ++k) {
      const double difference = std::remainder(back[k] - a[k], 2 * M_PI) * 180 / M_PI;
      EXPECT_LE(std::abs(difference), 2.5 + 1e-9) << "axis " << k;
    }
  }
  // The top-down grasp: x = +-180 deg falls in bin 0 either way.
  const Eigen::Matrix3d down = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_EQ(rotation_bins(down), Eigen::Vector3i(0, 36, 36));
}
