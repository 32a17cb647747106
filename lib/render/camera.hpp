// GPU-free RGB-D cameras: one ray per pixel against Bullet's collision world.
//
// Conventions (also in formats/record-stream.md, obs record):
//  - camera frame as in OpenCV: x right, y down, z forward (optical axis);
//  - intrinsics K (3x3, pixels): fx = fy = (H/2) / tan(fov_y/2), cx = W/2 - 0.5, cy = H/2 - 0.5
//    (pixel centres at integer coordinates);
//  - extrinsics: the 4x4 pose of the camera in the world (world_from_camera), as RLBench;
//  - depth: metric distance along the optical axis (camera z), float32; 0 where no surface
//    was hit between near_m and far_m (both measured along the pixel's ray);
//  - points: the world-frame point of each pixel, float32 HxWx3; NaN where depth is 0;
//    world_from_camera * (depth * K^-1 [u, v, 1]), computed in double, stored as float;
//  - rgb: black where nothing was hit.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <string>

class btCollisionWorld;

namespace qte::render {

// How a collision object looks. The renderer finds it through the object's user pointer
// (btCollisionObject::setUserPointer(const Appearance*)); objects without one are grey.
struct Appearance {
  Eigen::Vector3f colour{0.6f, 0.6f, 0.6f};  // RGB in [0, 1]
  // Optional images on the faces of box shapes (CV_8UC3, RGB), indexed by the face's outward
  // normal in the object's own frame: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z. Empty = plain
  // colour. Each image is stretched over its whole face and reads unmirrored from outside.
  // Its "up" is object +z on the side faces (+-x, +-y) and object +y on the top and bottom
  // (+-z). So on the top face image right is +x: a camera above the box whose image up is
  // the box's +y sees the image upright. Images are sampled nearest-neighbour.
  std::array<cv::Mat, 6> box_face_textures;
};

struct CameraIntrinsics {
  int width = 128;
  int height = 128;
  double fov_y_deg = 45.0;
  double near_m = 0.01;
  double far_m = 5.0;

  Eigen::Matrix3d matrix() const;  // K
};

struct CameraFrame {
  std::string name;
  cv::Mat rgb;     // CV_8UC3, RGB order
  cv::Mat depth;   // CV_32FC1, metres along camera z
  cv::Mat points;  // CV_32FC3, world frame
  Eigen::Matrix3d intrinsics;
  Eigen::Isometry3d world_from_camera;
};

// The camera pose that looks from `eye` at `target`, with image "up" closest to `up`.
// Throws Error when eye == target or `up` is parallel to the line of sight.
Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                          const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

// Renders one frame. Rows are split over `threads` (>= 1) threads; the result does not
// depend on the thread count. The world is only read, so renders may run concurrently; poses
// are read at the call (no updateAabbs needed). Boxes, spheres and cylinders, also inside
// compounds, are intersected exactly; other shapes go to Bullet's ray test (ray_caster.hpp).
// Objects whose collision filter rejects Bullet's default ray group are invisible, as to
// rayTest. Shading: Lambert, one fixed light from above, plus ambient. Throws Error on bad
// arguments.
CameraFrame render(const btCollisionWorld& world, const CameraIntrinsics& intrinsics,
                   const Eigen::Isometry3d& world_from_camera, const std::string& name,
                   int threads = 2);

// PNG files a person can look at, written atomically: the RGB image, and depth as a
// colour map (near warm, far cool; no-return black).
void save_rgb_png(const std::string& path, const cv::Mat& rgb);
void save_depth_png(const std::string& path, const cv::Mat& depth);
// Depth as depth cameras save it: 16-bit millimetres, 0 = no return (CV_16UC1).
void save_mm_png(const std::string& path, const cv::Mat& millimetres);

}  // namespace qte::render
