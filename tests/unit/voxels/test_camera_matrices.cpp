// Camera matrices are checked where they are read; a scene with no point inside is refused.
#include <gtest/gtest.h>

#include <cmath>

#include "voxels/observation_cloud.hpp"

using namespace qte;
using namespace qte::voxels;

namespace {

const std::vector<double> kGoodIntrinsics = {100, 0, 32, 0, 100, 32, 0, 0, 1};
const std::vector<double> kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// A 4x4 camera at `position` looking along +z, every pixel 1 m away.
stream::Record camera_obs(const std::vector<double>& intrinsics, std::vector<double> extrinsics,
                          double x = 0.2, double y = 0, double z = 0.5) {
  extrinsics[3] += x, extrinsics[7] += y, extrinsics[11] += z;
  stream::Record obs("obs");
  obs.set<uint8_t>("front.rgb", {4, 4, 3}, std::vector<uint8_t>(48, 100));
  obs.set<float>("front.depth", {4, 4}, std::vector<float>(16, 1.0f));
  obs.set<double>("front.intrinsics", {3, 3}, intrinsics);
  obs.set<double>("front.extrinsics", {4, 4}, extrinsics);
  obs.position = {"obs.rec", 5, 320};
  return obs;
}

std::string cloud_error(const stream::Record& obs) {
  try {
    require_points_in_scene(obs, observation_cloud(obs), GridBounds{});
  } catch (const StreamError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CameraMatrices, GoodMatricesPassAndSeeTheScene) {
  EXPECT_EQ(intrinsics_problem(kGoodIntrinsics.data()), "");
  EXPECT_EQ(extrinsics_problem(kIdentity.data()), "");
  EXPECT_EQ(cloud_error(camera_obs(kGoodIntrinsics, kIdentity)), "");
}

TEST(CameraMatrices, BadIntrinsicsAreRefusedNamingRecordAndField) {
  for (const std::vector<double>& k : {std::vector<double>{0, 0, 32, 0, 0, 32, 0, 0, 1},
                                       std::vector<double>{-100, 0, 32, 0, 100, 32, 0, 0, 1},
                                       std::vector<double>{NAN, 0, 32, 0, 100, 32, 0, 0, 1},
                                       std::vector<double>{100, 0, 32, 0, 100, 32, 0, 0, 0}}) {
    EXPECT_NE(intrinsics_problem(k.data()), "");
    const std::string error = cloud_error(camera_obs(k, kIdentity));
    EXPECT_NE(error.find("obs.rec: record 5 at byte 320: 'obs' record, field 'front.intrinsics': expected"),
              std::string::npos)
        << error;
  }
}

TEST(CameraMatrices, ExtrinsicsMustBeAProperRigidTransform) {
  std::vector<double> singular = kIdentity, mirror = kIdentity, scaled = kIdentity, infinite = kIdentity,
                      last_row = kIdentity;
  singular[10] = 0;
  mirror[0] = -1;  // orthonormal, determinant -1: a mirror image of the scene
  scaled[0] = scaled[5] = scaled[10] = 2;
  infinite[3] = INFINITY;
  last_row[12] = 1;
  for (const auto& e : {singular, mirror, scaled, infinite, last_row}) {
    EXPECT_NE(extrinsics_problem(e.data()), "");
    const std::string error = cloud_error(camera_obs(kGoodIntrinsics, e));
    EXPECT_NE(error.find("'obs' record, field 'front.extrinsics': expected"), std::string::npos) << error;
  }
}

TEST(EmptyScene, NoPointInsideTheBoundsIsAnErrorSayingWhatToCheck) {
  const std::string error = cloud_error(camera_obs(kGoodIntrinsics, kIdentity, 10, 10, 10));
  EXPECT_NE(error.find("obs.rec: record 5 at byte 320: 'obs' record: none of its 16 points lies inside the scene bounds"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("extrinsics"), std::string::npos) << error;
  stream::Record no_depth = camera_obs(kGoodIntrinsics, kIdentity);
  no_depth.set<float>("front.depth", {4, 4}, std::vector<float>(16, 0.0f));
  EXPECT_NE(cloud_error(no_depth).find("none of its 0 points"), std::string::npos);
}
