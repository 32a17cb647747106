#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "common/error.hpp"
#include "point_clouds/pcd_file.hpp"

using namespace qte;

namespace {

voxels::CameraCloud small_camera() {
  voxels::CameraCloud c;
  c.camera = "front";
  c.width = 4, c.height = 3;
  for (int i = 0; i < 12; ++i) {
    const bool none = i == 5;
    c.cloud.xyz.insert(c.cloud.xyz.end(), {none ? NAN : 0.1f * i, none ? NAN : -0.03f * i, none ? NAN : 0.7f + 0.001f * i});
    c.cloud.rgb.insert(c.cloud.rgb.end(), {uint8_t(20 * i), uint8_t(255 - i), uint8_t(i)});
  }
  return c;
}

std::string temp_path(const char* name) { return ::testing::TempDir() + name; }

}  // namespace

// What we write, PCL reads back: the same points bit for bit, colours, and the image's layout.
TEST(PcdFile, PclLoadsTheSamePointsColoursAndLayout) {
  const voxels::CameraCloud c = small_camera();
  const std::string path = temp_path("camera.pcd");
  point_clouds::write_pcd(path, c);
  pcl::PointCloud<pcl::PointXYZRGB> loaded;
  ASSERT_EQ(pcl::io::loadPCDFile(path, loaded), 0);
  EXPECT_EQ(loaded.width, 4u);
  EXPECT_EQ(loaded.height, 3u);
  EXPECT_FALSE(loaded.is_dense);
  ASSERT_EQ(loaded.size(), 12u);
  for (int i = 0; i < 12; ++i) {
    const auto& p = loaded[i];
    if (i == 5) {
      EXPECT_TRUE(std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z));
    } else {
      EXPECT_EQ(std::memcmp(&p.x, &c.cloud.xyz[3 * i], 4), 0);
      EXPECT_EQ(p.y, c.cloud.xyz[3 * i + 1]);
      EXPECT_EQ(p.z, c.cloud.xyz[3 * i + 2]);
    }
    EXPECT_EQ(p.r, c.cloud.rgb[3 * i]);
    EXPECT_EQ(p.g, c.cloud.rgb[3 * i + 1]);
    EXPECT_EQ(p.b, c.cloud.rgb[3 * i + 2]);
  }
  const voxels::CameraCloud back = point_clouds::read_pcd(path);
  EXPECT_EQ(back.width, 4);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.cloud.rgb, c.cloud.rgb);
  for (std::size_t i = 0; i < c.cloud.xyz.size(); ++i)
    EXPECT_TRUE(back.cloud.xyz[i] == c.cloud.xyz[i] || (std::isnan(back.cloud.xyz[i]) && std::isnan(c.cloud.xyz[i])));
  std::remove(path.c_str());
}

TEST(PcdFile, AnUnorganizedCloudWithoutColourReadsAsOneRowOfWhite) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back({0.1f, 0.2f, 0.3f});
  cloud.push_back({0.4f, 0.5f, 0.6f});
  const std::string path = temp_path("plain.pcd");
  ASSERT_EQ(pcl::io::savePCDFileASCII(path, cloud), 0);
  const voxels::CameraCloud back = point_clouds::read_pcd(path);
  EXPECT_EQ(back.height, 1);
  EXPECT_EQ(back.width, 2);
  EXPECT_EQ(back.cloud.xyz, (std::vector<float>{0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}));
  EXPECT_EQ(back.cloud.rgb, std::vector<uint8_t>(6, 255));
  std::remove(path.c_str());
}

TEST(PcdFile, ANonPcdFileIsAnErrorNamingIt) {
  const std::string path = temp_path("not.pcd");
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs("hello\n", f);
  std::fclose(f);
  try {
    point_clouds::read_pcd(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::remove(path.c_str());
}
