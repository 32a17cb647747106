// The PCL filters checked against brute-force references written here, and observations
// through them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <tuple>

#include "common/error.hpp"
#include "point_clouds/cloud_filters.hpp"
#include "sim_step/simulator.hpp"

using namespace qte;
using point_clouds::CloudFilters;
using voxels::ObservationCloud;

namespace {

using Point = std::array<float, 3>;

std::vector<Point> points_of(const ObservationCloud& c) {
  std::vector<Point> out;
  for (std::size_t i = 0; i + 2 < c.xyz.size(); i += 3) out.push_back({c.xyz[i], c.xyz[i + 1], c.xyz[i + 2]});
  std::sort(out.begin(), out.end());
  return out;
}

ObservationCloud cloud_of(const std::vector<Point>& points) {
  ObservationCloud c;
  for (std::size_t i = 0; i < points.size(); ++i) {
    c.xyz.insert(c.xyz.end(), points[i].begin(), points[i].end());
    c.rgb.insert(c.rgb.end(), {uint8_t(i % 256), uint8_t(3 * i % 256), uint8_t(7 * i % 256)});
  }
  return c;
}

// A 40 x 40 table-top patch 5 mm apart, a little noise, and a few points floating far away.
std::vector<Point> noisy_patch(unsigned seed, int floaters) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 0.0005f);
  std::uniform_real_distribution<float> anywhere(-0.5f, 0.5f);
  std::vector<Point> points;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) points.push_back({0.005f * i, 0.005f * j, 0.75f + noise(rng)});
  for (int k = 0; k < floaters; ++k) points.push_back({anywhere(rng), anywhere(rng), 1.2f + anywhere(rng)});
  return points;
}

double distance(const Point& a, const Point& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

TEST(CloudFilters, CropKeepsExactlyThePointsInsideTheBoxAndDropsNaN) {
  std::vector<Point> points = noisy_patch(1, 30);
  points.push_back({NAN, NAN, NAN});
  CloudFilters f;
  f.crop = Eigen::AlignedBox3f(Eigen::Vector3f(0.02f, 0.0f, 0.7f), Eigen::Vector3f(0.1f, 0.05f, 0.8f));
  std::vector<Point> expected;
  for (const Point& p : points)
    if (p[0] >= 0.02f && p[0] <= 0.1f && p[1] >= 0.0f && p[1] <= 0.05f && p[2] >= 0.7f && p[2] <= 0.8f) expected.push_back(p);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(points_of(point_clouds::filter_cloud(cloud_of(points), f)), expected);
  EXPECT_GT(expected.size(), 100u);
}

// Statistical outlier removal as its definition says: a point's mean distance to its K nearest
// neighbours, kept when at most mean + S * (sample) standard deviation of those means.
TEST(CloudFilters, OutlierRemovalMatchesTheDefinitionByBruteForce) {
  const std::vector<Point> points = noisy_patch(2, 12);
  const int k = 8;
  const double s = 1.5;
  std::vector<double> mean_distance(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::vector<double> d;
    for (std::size_t j = 0; j < points.size(); ++j)
      if (j != i) d.push_back(distance(points[i], points[j]));
    std::partial_sort(d.begin(), d.begin() + k, d.end());
    mean_distance[i] = std::accumulate(d.begin(), d.begin() + k, 0.0) / k;
  }
  const double n = double(points.size());
  const double mu = std::accumulate(mean_distance.begin(), mean_distance.end(), 0.0) / n;
  double sq = 0;
  for (double m : mean_distance) sq += (m - mu) * (m - mu);
  const double threshold = mu + s * std::sqrt(sq / (n - 1));
  std::vector<Point> expected;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (mean_distance[i] <= threshold) expected.push_back(points[i]);
  std::sort(expected.begin(), expected.end());

  CloudFilters f;
  f.outlier_neighbours = k;
  f.outlier_stddevs = s;
  const std::vector<Point> kept = points_of(point_clouds::filter_cloud(cloud_of(points), f));
  EXPECT_EQ(kept, expected);
  for (std::size_t i = 1600; i < points.size(); ++i)  // every floater is gone
    EXPECT_FALSE(std::binary_search(kept.begin(), kept.end(), points[i]));
}

// Voxel-grid downsampling: one point per occupied M-metre cube of the world grid (cubes at
// multiples of M), the centroid of its points, with their mean colour.
TEST(CloudFilters, DownsamplingGivesEachCubesCentroidAndMeanColour) {
  const std::vector<Point> points = noisy_patch(3, 20);
  const ObservationCloud in = cloud_of(points);
  const float leaf = 0.012f;
  struct Sum { double x = 0, y = 0, z = 0, r = 0, g = 0, b = 0; int n = 0; };
  std::map<std::tuple<int, int, int>, Sum> cubes;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    Sum& s = cubes[{int(std::floor(p[0] * (1 / leaf))), int(std::floor(p[1] * (1 / leaf))), int(std::floor(p[2] * (1 / leaf)))}];
    s.x += p[0], s.y += p[1], s.z += p[2], s.n += 1;
    s.r += in.rgb[3 * i], s.g += in.rgb[3 * i + 1], s.b += in.rgb[3 * i + 2];
  }
  CloudFilters f;
  f.downsample_m = leaf;
  const ObservationCloud out = point_clouds::filter_cloud(in, f);
  ASSERT_EQ(out.rgb.size() / 3, cubes.size());
  for (std::size_t i = 0; i < out.rgb.size() / 3; ++i) {
    const float* p = &out.xyz[3 * i];  // a centroid lies in its own cube
    const auto it = cubes.find({int(std::floor(p[0] * (1 / leaf))), int(std::floor(p[1] * (1 / leaf))),
                                int(std::floor(p[2] * (1 / leaf)))});
    ASSERT_NE(it, cubes.end()) << "point " << i;
    const Sum& s = it->second;
    EXPECT_NEAR(p[0], s.x / s.n, 1e-5);
    EXPECT_NEAR(p[1], s.y / s.n, 1e-5);
    EXPECT_NEAR(p[2], s.z / s.n, 1e-5);
    EXPECT_NEAR(out.rgb[3 * i], s.r / s.n, 1.0);
    EXPECT_NEAR(out.rgb[3 * i + 1], s.g / s.n, 1.0);
    EXPECT_NEAR(out.rgb[3 * i + 2], s.b / s.n, 1.0);
  }
}

TEST(CloudFilters, ALeafTooSmallForTheCloudIsAnErrorNotASilentNoOp) {
  ObservationCloud c = cloud_of({{-50, -50, -50}, {50, 50, 50}});
  CloudFilters f;
  f.downsample_m = 0.001;
  EXPECT_THROW(point_clouds::filter_cloud(c, f), Error);
}

TEST(CloudFilters, FilteredObservationIsUnorganizedWithoutDepthAndKeepsTheRest) {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  sim_step::SimulatorOptions options;
  options.render_threads = 1;
  options = sim_step::options_for_cameras({"front"}, 64, 64);
  options.render_threads = 1;
  sim_step::Simulator sim(robot, options);
  stream::Record obs("obs");
  sim.handle(sim_step::plan_reset({"pick_and_lift", 0, 1, 2}, 0), [&](const stream::Record& r) { obs = r; });
  CloudFilters f;
  f.crop = Eigen::AlignedBox3f(Eigen::Vector3f(-0.3f, -0.5f, 0.76f), Eigen::Vector3f(0.7f, 0.5f, 1.6f));  // above the table
  const stream::Record out = point_clouds::filter_observation(obs, f);
  const auto points = out.array<float>("front.points");
  const auto rgb = out.array<uint8_t>("front.rgb");
  ASSERT_EQ(points.shape.size(), 3u);
  EXPECT_EQ(points.shape[0], 1);
  EXPECT_EQ(rgb.shape, points.shape);
  EXPECT_FALSE(out.has("front.depth"));
  EXPECT_TRUE(out.has("front.extrinsics"));
  EXPECT_TRUE(out.has("joint_positions"));
  // Exactly the finite original points inside the box, in pixel order.
  const auto original = obs.array<float>("front.points");
  std::vector<float> expected;
  for (int64_t i = 0; i < original.size(); i += 3)
    if (f.crop->contains(Eigen::Vector3f(original[i], original[i + 1], original[i + 2])))
      expected.insert(expected.end(), {original[i], original[i + 1], original[i + 2]});
  EXPECT_EQ(std::vector<float>(points.begin(), points.end()), expected);
  EXPECT_GT(expected.size(), 30u);
  EXPECT_LT(expected.size(), std::size_t(original.size()));
  // A box that holds nothing leaves an empty cloud, which the voxelizer still takes.
  f.crop = Eigen::AlignedBox3f(Eigen::Vector3f(5, 5, 5), Eigen::Vector3f(6, 6, 6));
  EXPECT_EQ(point_clouds::filter_observation(obs, f).array<float>("front.points").size(), 0);
  EXPECT_EQ(voxels::observation_cloud(point_clouds::filter_observation(obs, f)).xyz.size(), 0u);
}
