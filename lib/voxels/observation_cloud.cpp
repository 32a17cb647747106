#include "voxels/observation_cloud.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "stream/field_names.hpp"

namespace qte::voxels {

std::vector<uint16_t> depth_in_mm(const float* depth_m, std::size_t count) {
  std::vector<uint16_t> mm(count);
  for (std::size_t i = 0; i < count; ++i)
    mm[i] = static_cast<uint16_t>(std::clamp(std::lround(depth_m[i] * 1000.0), 0L, 65535L));
  return mm;
}

void points_from_depth(const float* depth_m, int width, int height, const double* k, const double* e,
                       float* xyz_out) {
  const double fx = k[0], cx = k[2], fy = k[4], cy = k[5];
  const Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> pose(e);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      const double z = depth_m[i];
      float* out = xyz_out + 3 * i;
      if (!(z > 0)) {
        out[0] = out[1] = out[2] = nan;
        continue;
      }
      const Eigen::Vector4d camera((u - cx) / fx * z, (v - cy) / fy * z, z, 1.0);
      const Eigen::Vector4d world = pose * camera;
      out[0] = static_cast<float>(world.x());
      out[1] = static_cast<float>(world.y());
      out[2] = static_cast<float>(world.z());
    }
}

std::string intrinsics_problem(const double* k) {
  for (int i = 0; i < 9; ++i)
    if (!std::isfinite(k[i])) return "finite values";
  if (!(k[0] > 0 && k[4] > 0)) return "positive focal lengths fx, fy (elements [0, 0] and [1, 1])";
  if (k[6] != 0 || k[7] != 0 || k[8] != 1) return "a pinhole matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]]";
  return "";
}

std::string extrinsics_problem(const double* e) {
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(e[i])) return "finite values";
  const Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> m(e);
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if (!(r.transpose() * r - Eigen::Matrix3d::Identity()).isZero(1e-3) || std::abs(r.determinant() - 1) > 1e-3 ||
      !m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)))
    return "a camera-to-world pose: a proper rotation (orthonormal, determinant +1), a translation, last row 0 0 0 1";
  return "";
}

void check_camera_matrices(const stream::Record& obs, const std::string& camera) {
  if (obs.has(camera + fields::per_camera::intrinsics)) {
    const auto k = obs.array<double>(camera + fields::per_camera::intrinsics);
    if (k.size() != 9) obs.fail(camera + fields::per_camera::intrinsics, "float64 [3, 3]");
    const std::string problem = intrinsics_problem(k.data);
    if (!problem.empty()) obs.fail(camera + fields::per_camera::intrinsics, problem);
  }
  const auto e = obs.array<double>(camera + fields::per_camera::extrinsics);
  if (e.size() != 16) obs.fail(camera + fields::per_camera::extrinsics, "float64 [4, 4]");
  const std::string problem = extrinsics_problem(e.data);
  if (!problem.empty()) obs.fail(camera + fields::per_camera::extrinsics, problem);
}

std::size_t points_inside(const PointCloud& cloud, const GridBounds& bounds) {
  const Eigen::Vector3d lo = bounds.min_corner, hi = bounds.max_corner();
  std::size_t n = 0;
  for (std::size_t i = 0; i < cloud.count; ++i) {
    const float* p = cloud.xyz + 3 * i;
    n += p[0] >= lo.x() && p[0] < hi.x() && p[1] >= lo.y() && p[1] < hi.y() && p[2] >= lo.z() && p[2] < hi.z();
  }
  return n;
}

void require_points_in_scene(const stream::Record& obs, const ObservationCloud& cloud, const GridBounds& scene) {
  const PointCloud view = cloud.view();
  if (points_inside(view, scene) > 0) return;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < view.count; ++i) seen += std::isfinite(view.xyz[3 * i]);
  const Eigen::Vector3d c = scene.min_corner;
  throw StreamError(obs.position, "'" + obs.type() + "' record: none of its " + std::to_string(seen) +
                                      " points lies inside the scene bounds " + std::to_string(c.x()) + "," +
                                      std::to_string(c.y()) + "," + std::to_string(c.z()) + "," +
                                      std::to_string(scene.size_m) +
                                      ": nothing seen; check the cameras' extrinsics (camera-to-world pose) and "
                                      "intrinsics, the depth units, and --bounds");
}

namespace {

// Appends one camera's pixels to xyz/rgb: its stored points, or points rebuilt from its depth.
// Returns the image's (height, width).
std::pair<int, int> append_camera(const stream::Record& obs, const std::string& camera, std::vector<float>& xyz,
                                  std::vector<uint8_t>& rgb_out) {
  const std::string name = camera + fields::per_camera::rgb;
  const auto rgb = obs.array<uint8_t>(name);
  if (rgb.shape.size() != 3 || rgb.shape[2] != 3) obs.fail(name, "uint8 [H, W, 3]");
  const int h = static_cast<int>(rgb.shape[0]), w = static_cast<int>(rgb.shape[1]);
  const std::size_t n = static_cast<std::size_t>(h) * w, at = rgb_out.size() / 3;
  rgb_out.insert(rgb_out.end(), rgb.begin(), rgb.end());
  xyz.resize(3 * (at + n));
  float* out = xyz.data() + 3 * at;
  if (obs.has(camera + fields::per_camera::extrinsics)) check_camera_matrices(obs, camera);
  if (obs.has(camera + fields::per_camera::points)) {
    const auto points = obs.array<float>(camera + fields::per_camera::points);
    if (points.shape != stream::Shape{h, w, 3})
      obs.fail(camera + fields::per_camera::points, "float32 [H, W, 3] like " + name);
    std::copy(points.begin(), points.end(), out);
    return {h, w};
  }
  std::vector<float> depth(n);
  if (obs.has(camera + fields::per_camera::depth_mm)) {
    const auto mm = obs.array<uint16_t>(camera + fields::per_camera::depth_mm);
    if (mm.shape != stream::Shape{h, w}) obs.fail(camera + fields::per_camera::depth_mm, "uint16 [H, W] like " + name);
    for (std::size_t i = 0; i < n; ++i) depth[i] = mm[i] * 0.001f;
  } else {
    const auto d = obs.array<float>(camera + fields::per_camera::depth);
    if (d.shape != stream::Shape{h, w}) obs.fail(camera + fields::per_camera::depth, "float32 [H, W] like " + name);
    std::copy(d.begin(), d.end(), depth.begin());
  }
  check_camera_matrices(obs, camera);  // depth needs both
  if (!obs.has(camera + fields::per_camera::intrinsics))
    obs.fail(camera + fields::per_camera::intrinsics, "float64 [3, 3] (depth needs it)");
  const auto k = obs.array<double>(camera + fields::per_camera::intrinsics);
  const auto e = obs.array<double>(camera + fields::per_camera::extrinsics);
  points_from_depth(depth.data(), w, h, k.data, e.data, out);
  return {h, w};
}

[[noreturn]] void no_camera(const stream::Record& obs) {
  throw StreamError(obs.position, "'" + obs.type() + "' record has no camera image (<camera>.rgb with "
                                  "<camera>.points or <camera>.depth): nothing to voxelize");
}

}  // namespace

ObservationCloud observation_cloud(const stream::Record& obs) {
  ObservationCloud cloud;
  const std::vector<std::string> cameras = obs.prefixes(fields::per_camera::rgb);
  if (cameras.empty()) no_camera(obs);
  for (const std::string& camera : cameras) append_camera(obs, camera, cloud.xyz, cloud.rgb);
  return cloud;
}

std::vector<CameraCloud> camera_clouds(const stream::Record& obs) {
  std::vector<CameraCloud> clouds;
  for (const std::string& camera : obs.prefixes(fields::per_camera::rgb)) {
    CameraCloud c;
    c.camera = camera;
    std::tie(c.height, c.width) = append_camera(obs, camera, c.cloud.xyz, c.cloud.rgb);
    clouds.push_back(std::move(c));
  }
  if (clouds.empty()) no_camera(obs);
  return clouds;
}

}  // namespace qte::voxels
