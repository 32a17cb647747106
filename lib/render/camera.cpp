#include "render/camera.hpp"

#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <thread>
#include <vector>

#include "common/png_file.hpp"
#include "common/error.hpp"
#include "render/ray_caster.hpp"

namespace qte::render {
namespace {

constexpr float kAmbientLight = 0.35f;
// Light from above, tilted towards +x and +y so that the faces of a box differ in brightness.
const Eigen::Vector3f kTowardsLight = Eigen::Vector3f(0.5f, 0.3f, 1.0f).normalized();
const Appearance kNoAppearance{};

void check_intrinsics(const CameraIntrinsics& in) {
  if (in.width <= 0 || in.height <= 0)
    throw Error("camera image size must be positive, got " + std::to_string(in.width) + "x" +
                std::to_string(in.height));
  if (!(in.fov_y_deg > 0 && in.fov_y_deg < 180))
    throw Error("camera fov_y_deg must be in (0, 180), got " + std::to_string(in.fov_y_deg));
  if (!(in.near_m >= 0 && in.far_m > in.near_m && std::isfinite(in.far_m)))
    throw Error("camera needs 0 <= near_m < far_m (finite), got " + std::to_string(in.near_m) +
                " and " + std::to_string(in.far_m));
}

void check_pose(const Eigen::Isometry3d& world_from_camera) {
  const Eigen::Matrix3d r = world_from_camera.linear();
  if (!world_from_camera.matrix().allFinite() ||
      !(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || r.determinant() < 0)
    throw Error("camera pose must be a rigid transform (rotation and translation)");
}

// Worker threads must not throw, so the textures' layout is checked once, up front.
void check_textures(const btCollisionWorld& world) {
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const auto* appearance = static_cast<const Appearance*>(objects[i]->getUserPointer());
    if (appearance == nullptr) continue;
    for (const cv::Mat& texture : appearance->box_face_textures)
      if (!texture.empty() && texture.type() != CV_8UC3)
        throw Error("box face textures must be 8-bit RGB images (CV_8UC3)");
  }
}

// Where a point on a box face falls in that face's image: (u right, v down), both in [0, 1].
// The image reads unmirrored from outside; its up is +z on side faces and +y on the top and
// bottom (object frame), as documented on Appearance::box_face_textures.
Eigen::Vector2f face_uv(int axis, float sign, const Eigen::Vector3f& point_in_box,
                        const Eigen::Vector3f& half_extents) {
  Eigen::Vector3f outward = Eigen::Vector3f::Zero();
  outward[axis] = sign;
  const Eigen::Vector3f up = axis == 2 ? Eigen::Vector3f::UnitY() : Eigen::Vector3f::UnitZ();
  const Eigen::Vector3f right = up.cross(outward);  // right x up = outward, towards the viewer
  const Eigen::Vector3f scaled = point_in_box.cwiseQuotient(half_extents);  // box is [-1, 1]^3
  return {0.5f + 0.5f * right.dot(scaled), 0.5f - 0.5f * up.dot(scaled)};
}

// The texel (RGB in [0, 1]) where a ray hit a face of a box that has an image there.
bool box_texel(const RayHit& hit, const Eigen::Vector3d& world_point, Eigen::Vector3f& texel) {
  const ScenePart& part = *hit.part;
  // Images belong to the object's own box, not to the children of a compound.
  if (part.shape != part.object->getCollisionShape() ||
      part.shape->getShapeType() != BOX_SHAPE_PROXYTYPE)
    return false;
  const auto* appearance = static_cast<const Appearance*>(part.object->getUserPointer());
  if (appearance == nullptr) return false;
  const Eigen::Vector3f normal = (part.shape_from_world.linear() * hit.normal).cast<float>();
  int axis;
  normal.cwiseAbs().maxCoeff(&axis);
  const float sign = normal[axis] < 0 ? -1.0f : 1.0f;
  const cv::Mat& texture = appearance->box_face_textures[2 * axis + (sign < 0 ? 1 : 0)];
  if (texture.empty()) return false;

  const btVector3 half = static_cast<const btBoxShape*>(part.shape)->getHalfExtentsWithMargin();
  const Eigen::Vector3f point_in_box = (part.shape_from_world * world_point).cast<float>();
  const Eigen::Vector2f uv = face_uv(axis, sign, point_in_box, {half.x(), half.y(), half.z()});
  const int column = std::clamp(static_cast<int>(uv.x() * texture.cols), 0, texture.cols - 1);
  const int row = std::clamp(static_cast<int>(uv.y() * texture.rows), 0, texture.rows - 1);
  const cv::Vec3b& rgb = texture.at<cv::Vec3b>(row, column);
  texel = Eigen::Vector3f(rgb[0], rgb[1], rgb[2]) / 255.0f;
  return true;
}

// What one frame's rays share; every pixel depends only on this and its own coordinates,
// which is what makes the image independent of the thread count.
struct FrameSetup {
  const RayCaster* caster;
  Eigen::Matrix3d camera_from_pixel;  // K^-1
  Eigen::Isometry3d world_from_camera;
  double near_m, far_m;
};

void render_pixel(const FrameSetup& setup, int u, int v, cv::Vec3b& rgb, float& depth,
                  cv::Vec3f& point) {
  const Eigen::Vector3d ray_camera = setup.camera_from_pixel * Eigen::Vector3d(u, v, 1.0);
  const double ray_length = ray_camera.norm();  // its camera z is 1
  const Eigen::Vector3d direction = setup.world_from_camera.linear() * ray_camera / ray_length;
  const Eigen::Vector3d eye = setup.world_from_camera.translation();
  RayHit hit;
  if (!setup.caster->cast(eye + setup.near_m * direction, direction,
                          setup.far_m - setup.near_m, hit)) {
    rgb = cv::Vec3b(0, 0, 0);
    depth = 0.0f;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    point = cv::Vec3f(nan, nan, nan);
    return;
  }

  const double depth_m = (setup.near_m + hit.distance) / ray_length;
  const Eigen::Vector3d world_point = setup.world_from_camera * (depth_m * ray_camera);
  depth = static_cast<float>(depth_m);
  point = cv::Vec3f(float(world_point.x()), float(world_point.y()), float(world_point.z()));

  const auto* appearance = static_cast<const Appearance*>(hit.part->object->getUserPointer());
  Eigen::Vector3f colour = (appearance != nullptr ? *appearance : kNoAppearance).colour;
  box_texel(hit, world_point, colour);
  const float facing = std::max(0.0f, hit.normal.cast<float>().dot(kTowardsLight));
  const Eigen::Vector3f shaded = colour * (kAmbientLight + (1.0f - kAmbientLight) * facing);
  for (int c = 0; c < 3; ++c) rgb[c] = cv::saturate_cast<uchar>(shaded[c] * 255.0f);
}

}  // namespace

Eigen::Matrix3d CameraIntrinsics::matrix() const {
  check_intrinsics(*this);
  const double focal = (height / 2.0) / std::tan(fov_y_deg * M_PI / 360.0);
  Eigen::Matrix3d k;
  k << focal, 0, width / 2.0 - 0.5,  //
      0, focal, height / 2.0 - 0.5,  //
      0, 0, 1;
  return k;
}

Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                          const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward = target - eye;
  if (!(forward.norm() > 1e-12)) throw Error("look_at: the eye is at the target");
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d up_in_image_plane = up - up.dot(z) * z;
  if (!(up_in_image_plane.norm() > 1e-9 * std::max(1.0, up.norm())))
    throw Error("look_at: `up` is parallel to the line of sight");
  const Eigen::Vector3d y = -up_in_image_plane.normalized();  // image y points down
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << x, y, z;
  pose.translation() = eye;
  return pose;
}

CameraFrame render(const btCollisionWorld& world, const CameraIntrinsics& intrinsics,
                   const Eigen::Isometry3d& world_from_camera, const std::string& name,
                   int threads) {
  check_intrinsics(intrinsics);
  check_pose(world_from_camera);
  if (threads < 1) throw Error("render needs at least one thread, got " + std::to_string(threads));
  check_textures(world);

  CameraFrame frame;
  frame.name = name;
  frame.intrinsics = intrinsics.matrix();
  frame.world_from_camera = world_from_camera;
  frame.rgb.create(intrinsics.height, intrinsics.width, CV_8UC3);
  frame.depth.create(intrinsics.height, intrinsics.width, CV_32FC1);
  frame.points.create(intrinsics.height, intrinsics.width, CV_32FC3);

  const RayCaster caster(world);
  const FrameSetup setup{&caster, frame.intrinsics.inverse(), world_from_camera,
                         intrinsics.near_m, intrinsics.far_m};
  const int workers = std::min(threads, intrinsics.height);
  // Interleaved rows, so that every worker gets a similar share of table and background.
  auto render_rows = [&](int first_row) {
    for (int v = first_row; v < intrinsics.height; v += workers) {
      auto* rgb = frame.rgb.ptr<cv::Vec3b>(v);
      auto* depth = frame.depth.ptr<float>(v);
      auto* points = frame.points.ptr<cv::Vec3f>(v);
      for (int u = 0; u < intrinsics.width; ++u)
        render_pixel(setup, u, v, rgb[u], depth[u], points[u]);
    }
  };

  std::vector<std::thread> helpers;
  try {
    for (int k = 1; k < workers; ++k) helpers.emplace_back(render_rows, k);
  } catch (const std::system_error& e) {
    for (std::thread& t : helpers) t.join();
    throw Error(std::string("cannot start render threads: ") + e.what());
  }
  render_rows(0);
  for (std::thread& t : helpers) t.join();
  return frame;
}

void save_rgb_png(const std::string& path, const cv::Mat& rgb) {
  if (rgb.empty() || rgb.type() != CV_8UC3)
    throw Error("save_rgb_png: " + path + ": need an 8-bit RGB image (CV_8UC3)");
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);  // OpenCV's codecs take BGR
  write_png(path, bgr);
}

void save_mm_png(const std::string& path, const cv::Mat& millimetres) {
  if (millimetres.empty() || millimetres.type() != CV_16UC1)
    throw Error("save_mm_png: " + path + ": need a 16-bit depth image (CV_16UC1)");
  write_png(path, millimetres);
}

void save_depth_png(const std::string& path, const cv::Mat& depth) {
  if (depth.empty() || depth.type() != CV_32FC1)
    throw Error("save_depth_png: " + path + ": need a float depth image (CV_32FC1)");
  // NaN compares false, so it counts as no return too.
  const cv::Mat valid = (depth > 0) & (depth < std::numeric_limits<float>::infinity());
  double nearest = 0, farthest = 0;
  cv::minMaxLoc(depth, &nearest, &farthest, nullptr, nullptr, valid);
  // Near maps to the warm (high) end of the colour map.
  const double span = farthest > nearest ? farthest - nearest : 1.0;
  cv::Mat level;
  depth.convertTo(level, CV_8U, -255.0 / span, 255.0 * farthest / span);
  cv::Mat bgr;
  cv::applyColorMap(level, bgr, cv::COLORMAP_TURBO);
  bgr.setTo(cv::Scalar::all(0), ~valid);
  write_png(path, bgr);
}

}  // namespace qte::render
