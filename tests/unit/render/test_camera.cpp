// The ray-cast camera on a tiny real Bullet scene: a 30 cm square slab (top at z = 0) with a
// 10 cm cube on it (top at z = 0.1), seen from 25 cm above the cube.
#include <btBulletCollisionCommon.h>
#include <dirent.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "common/error.hpp"
#include "render/camera.hpp"
#include "render/textures.hpp"

using qte::Error;
using namespace qte::render;

namespace {

constexpr float kCubeHalf = 0.05f;
constexpr float kGroundHalf = 0.15f;
constexpr double kCubeTopZ = 0.1;

struct TinyScene {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &configuration};
  btBoxShape ground_shape{btVector3(kGroundHalf, kGroundHalf, 0.05f)};
  btBoxShape cube_shape{btVector3(kCubeHalf, kCubeHalf, kCubeHalf)};
  btCollisionObject ground, cube;
  Appearance ground_look, cube_look;

  TinyScene() {
    ground_look.colour = {0.2f, 0.6f, 0.3f};
    cube_look.colour = {0.8f, 0.3f, 0.1f};
    add(ground, ground_shape, ground_look, btVector3(0, 0, -0.05f));
    add(cube, cube_shape, cube_look, btVector3(0, 0, kCubeHalf));
    world.updateAabbs();
  }
  ~TinyScene() {
    world.removeCollisionObject(&cube);
    world.removeCollisionObject(&ground);
  }
  TinyScene(const TinyScene&) = delete;
  TinyScene& operator=(const TinyScene&) = delete;

  void add(btCollisionObject& object, btCollisionShape& shape, const Appearance& look,
           const btVector3& position) {
    object.setCollisionShape(&shape);
    object.setWorldTransform(btTransform(btQuaternion::getIdentity(), position));
    object.setUserPointer(const_cast<Appearance*>(&look));
    world.addCollisionObject(&object);
  }
};

CameraIntrinsics small_camera() {
  CameraIntrinsics in;
  in.width = 128;
  in.height = 128;
  in.fov_y_deg = 60.0;
  return in;
}

// Straight down from 25 cm above the cube; image right is +x, image up is +y.
Eigen::Isometry3d top_down() {
  return look_at({0, 0, 0.35}, {0, 0, 0}, Eigen::Vector3d::UnitY());
}

// From the front (-y), right and above: shows the top and two sides of the cube.
Eigen::Isometry3d oblique() { return look_at({0.12, -0.3, 0.35}, {0, 0, 0.03}); }

enum class Surface { none, cube_top, ground_top, other };

Surface surface_of(const cv::Vec3f& p) {
  if (std::isnan(p[0])) return Surface::none;
  const bool on_cube = std::abs(p[0]) <= kCubeHalf + 1e-3 && std::abs(p[1]) <= kCubeHalf + 1e-3;
  if (on_cube && std::abs(p[2] - kCubeTopZ) < 1e-3) return Surface::cube_top;
  const bool on_ground =
      std::abs(p[0]) <= kGroundHalf + 1e-3 && std::abs(p[1]) <= kGroundHalf + 1e-3;
  if (on_ground && !on_cube && std::abs(p[2]) < 1e-3) return Surface::ground_top;
  return Surface::other;
}

// Within 0.1 mm of a face of the box, and not outside it.
bool on_box_surface(const cv::Vec3f& p, const Eigen::Vector3d& centre,
                    const Eigen::Vector3d& half) {
  double outside = 0, closest_face = 1e9;
  for (int i = 0; i < 3; ++i) {
    const double off_centre = std::abs(p[i] - centre[i]);
    outside = std::max(outside, off_centre - half[i]);
    closest_face = std::min(closest_face, std::abs(off_centre - half[i]));
  }
  return outside < 1e-4 && closest_face < 1e-4;
}

// The brightness factor that turns `colour` into `rgb`, or -1 when no single factor does.
double shading_factor(const cv::Vec3b& rgb, const Eigen::Vector3f& colour) {
  const double k = rgb[0] / (255.0 * colour.x());
  for (int c = 0; c < 3; ++c)
    if (std::abs(rgb[c] - k * colour[c] * 255.0) > 1.5) return -1;
  return k;
}

bool same_bytes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

bool same_frames(const CameraFrame& a, const CameraFrame& b) {
  return same_bytes(a.rgb, b.rgb) && same_bytes(a.depth, b.depth) &&
         same_bytes(a.points, b.points);
}

std::string temp_dir() {
  char pattern[] = "/tmp/qte_render_XXXXXX";
  return ::mkdtemp(pattern);
}

std::vector<std::string> files_in(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  while (dirent* e = ::readdir(d))
    if (std::strcmp(e->d_name, ".") != 0 && std::strcmp(e->d_name, "..") != 0)
      names.push_back(e->d_name);
  ::closedir(d);
  return names;
}

}  // namespace

TEST(RenderIntrinsics, MatrixFollowsTheDocumentedFormula) {
  CameraIntrinsics in;
  in.width = 640;
  in.height = 480;
  in.fov_y_deg = 90.0;
  const Eigen::Matrix3d k = in.matrix();
  EXPECT_NEAR(k(0, 0), 240.0, 1e-9);  // (480/2) / tan(45 deg)
  EXPECT_NEAR(k(1, 1), 240.0, 1e-9);
  EXPECT_DOUBLE_EQ(k(0, 2), 319.5);
  EXPECT_DOUBLE_EQ(k(1, 2), 239.5);
  EXPECT_DOUBLE_EQ(k(0, 1), 0.0);
  EXPECT_DOUBLE_EQ(k(1, 0), 0.0);
  EXPECT_EQ(k.row(2), Eigen::RowVector3d(0, 0, 1));
}

TEST(RenderIntrinsics, RejectsNonsense) {
  CameraIntrinsics in;
  in.width = 0;
  EXPECT_THROW(in.matrix(), Error);
  in = CameraIntrinsics{};
  in.fov_y_deg = 180;
  EXPECT_THROW(in.matrix(), Error);
  in = CameraIntrinsics{};
  in.near_m = 2.0;
  in.far_m = 1.0;
  EXPECT_THROW(in.matrix(), Error);
}

TEST(RenderLookAt, PutsTheTargetOnTheOpticalAxisWithImageUpAlongUp) {
  const Eigen::Vector3d eyes[] = {{1, 2, 3}, {0.5, -0.2, 1.4}, {-1, 0, 0.1}};
  const Eigen::Vector3d target(0.1, 0.2, 0.75);
  for (const Eigen::Vector3d& eye : eyes) {
    const Eigen::Isometry3d pose = look_at(eye, target);
    const Eigen::Vector3d in_camera = pose.inverse() * target;
    EXPECT_NEAR(in_camera.x(), 0.0, 1e-12);
    EXPECT_NEAR(in_camera.y(), 0.0, 1e-12);
    EXPECT_NEAR(in_camera.z(), (target - eye).norm(), 1e-12);
    const Eigen::Matrix3d r = pose.linear();
    EXPECT_TRUE((r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    EXPECT_NEAR(r.col(0).dot(Eigen::Vector3d::UnitZ()), 0.0, 1e-12);  // horizon level
    EXPECT_LT(r.col(1).dot(Eigen::Vector3d::UnitZ()), 0.0);            // image y points down
  }
}

TEST(RenderLookAt, RejectsDegenerateViews) {
  EXPECT_THROW(look_at({1, 1, 1}, {1, 1, 1}), Error);
  EXPECT_THROW(look_at({0, 0, 1}, {0, 0, 0}, Eigen::Vector3d::UnitZ()), Error);
}

TEST(RenderFrame, DepthAtTheCentreIsTheDistanceToTheCubeTop) {
  TinyScene scene;
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 2);
  EXPECT_EQ(frame.name, "top");
  EXPECT_EQ(frame.rgb.type(), CV_8UC3);
  EXPECT_EQ(frame.depth.type(), CV_32FC1);
  EXPECT_EQ(frame.points.type(), CV_32FC3);
  EXPECT_EQ(frame.rgb.size(), cv::Size(128, 128));
  EXPECT_NEAR(frame.depth.at<float>(64, 64), 0.35 - kCubeTopZ, 1e-3);
  EXPECT_NEAR(frame.depth.at<float>(63, 63), 0.35 - kCubeTopZ, 1e-3);
  EXPECT_TRUE(frame.intrinsics.isApprox(small_camera().matrix()));
  EXPECT_TRUE(frame.world_from_camera.isApprox(top_down()));
}

TEST(RenderFrame, PointsAreBackProjectedDepthsAndLieOnTheSurfaces) {
  TinyScene scene;
  for (const Eigen::Isometry3d& pose : {top_down(), oblique()}) {
    const CameraFrame frame = render(scene.world, small_camera(), pose, "cam", 2);
    const Eigen::Matrix3d k_inverse = frame.intrinsics.inverse();
    int valid = 0;
    for (int v = 0; v < frame.depth.rows; ++v)
      for (int u = 0; u < frame.depth.cols; ++u) {
        const float depth = frame.depth.at<float>(v, u);
        const cv::Vec3f p = frame.points.at<cv::Vec3f>(v, u);
        if (depth == 0.0f) continue;
        ++valid;
        const Eigen::Vector3d expected = pose * (depth * (k_inverse * Eigen::Vector3d(u, v, 1)));
        EXPECT_NEAR(p[0], expected.x(), 1e-4);
        EXPECT_NEAR(p[1], expected.y(), 1e-4);
        EXPECT_NEAR(p[2], expected.z(), 1e-4);
        // Every point is on a face of one of the boxes.
        EXPECT_TRUE(on_box_surface(p, {0, 0, kCubeHalf}, {kCubeHalf, kCubeHalf, kCubeHalf}) ||
                    on_box_surface(p, {0, 0, -0.05}, {kGroundHalf, kGroundHalf, 0.05}))
            << "pixel " << u << "," << v << " at " << p;
      }
    EXPECT_GT(valid, 128 * 128 / 4);
  }
}

TEST(RenderFrame, CubeTopPixelsAreAllAtTheSameDepth) {
  TinyScene scene;
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 1);
  int cube_pixels = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u)
      if (surface_of(frame.points.at<cv::Vec3f>(v, u)) == Surface::cube_top) {
        ++cube_pixels;
        EXPECT_NEAR(frame.depth.at<float>(v, u), 0.35 - kCubeTopZ, 1e-3);
      }
  EXPECT_GT(cube_pixels, 30 * 30);  // about 44 x 44 pixels
}

TEST(RenderFrame, SurfacesCarryTheirObjectsShadedColour) {
  TinyScene scene;
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 2);
  double cube_k = -1, ground_k = -1;
  int cube_pixels = 0, ground_pixels = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u) {
      const cv::Vec3b rgb = frame.rgb.at<cv::Vec3b>(v, u);
      const Surface surface = surface_of(frame.points.at<cv::Vec3f>(v, u));
      if (surface == Surface::cube_top) {
        const double k = shading_factor(rgb, scene.cube_look.colour);
        ASSERT_GT(k, 0) << "pixel " << u << "," << v << " is " << rgb << ", not cube colour";
        if (cube_k < 0) cube_k = k;
        EXPECT_NEAR(k, cube_k, 0.01);  // one flat face, one brightness
        ++cube_pixels;
      } else if (surface == Surface::ground_top) {
        const double k = shading_factor(rgb, scene.ground_look.colour);
        ASSERT_GT(k, 0) << "pixel " << u << "," << v << " is " << rgb << ", not ground colour";
        if (ground_k < 0) ground_k = k;
        EXPECT_NEAR(k, ground_k, 0.01);
        ++ground_pixels;
      }
    }
  EXPECT_GT(cube_pixels, 900);
  EXPECT_GT(ground_pixels, 2000);
  // Both tops face the same way, so the light treats them alike; lit beyond ambient alone.
  EXPECT_NEAR(cube_k, ground_k, 0.01);
  EXPECT_GT(cube_k, 0.5);
  EXPECT_LE(cube_k, 1.0);
}

TEST(RenderFrame, FacesTurnedAwayFromTheLightAreDarker) {
  TinyScene scene;
  scene.cube_look.colour = {0.9f, 0.9f, 0.9f};
  const CameraFrame frame = render(scene.world, small_camera(), oblique(), "oblique", 2);
  int top = 0, front = 0;
  double top_sum = 0, front_sum = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u) {
      const cv::Vec3f p = frame.points.at<cv::Vec3f>(v, u);
      const double brightness = frame.rgb.at<cv::Vec3b>(v, u)[0];
      if (surface_of(p) == Surface::cube_top) {
        top_sum += brightness;
        ++top;
      } else if (std::abs(p[1] + kCubeHalf) < 1e-3 && p[2] > 0.01 && p[2] < 0.09) {
        front_sum += brightness;  // the -y side, facing the camera
        ++front;
      }
    }
  ASSERT_GT(top, 50);
  ASSERT_GT(front, 50);
  EXPECT_GT(top_sum / top, front_sum / front + 20);
}

TEST(RenderFrame, RaysThatHitNothingGiveZeroDepthNanPointsAndBlack) {
  TinyScene scene;
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 2);
  int background = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u) {
      const float depth = frame.depth.at<float>(v, u);
      const cv::Vec3f p = frame.points.at<cv::Vec3f>(v, u);
      EXPECT_EQ(depth == 0.0f, std::isnan(p[0]) && std::isnan(p[1]) && std::isnan(p[2]));
      if (depth == 0.0f) {
        ++background;
        EXPECT_EQ(frame.rgb.at<cv::Vec3b>(v, u), cv::Vec3b(0, 0, 0));
      }
    }
  // The slab spans about 47 pixels either side of the centre; the corners see nothing.
  EXPECT_EQ(frame.depth.at<float>(0, 0), 0.0f);
  EXPECT_EQ(frame.depth.at<float>(127, 127), 0.0f);
  EXPECT_GT(background, 128 * 128 / 4);
}

TEST(RenderFrame, FarLimitHidesWhatIsBeyondIt) {
  TinyScene scene;
  CameraIntrinsics in = small_camera();
  in.far_m = 0.3;  // reaches the cube top (0.25 away) but not the ground (0.35)
  const CameraFrame frame = render(scene.world, in, top_down(), "top", 2);
  EXPECT_NEAR(frame.depth.at<float>(64, 64), 0.25, 1e-3);
  EXPECT_EQ(frame.depth.at<float>(64, 10), 0.0f);
}

TEST(RenderFrame, ThreadCountDoesNotChangeAByte) {
  TinyScene scene;
  scene.cube_look.box_face_textures[4] = text_texture("2", 64, {1, 1, 1}, {0, 0, 0});
  for (const Eigen::Isometry3d& pose : {top_down(), oblique()}) {
    const CameraFrame one = render(scene.world, small_camera(), pose, "cam", 1);
    for (int threads : {2, 3, 7, 500})
      EXPECT_TRUE(same_frames(one, render(scene.world, small_camera(), pose, "cam", threads)))
          << threads << " threads";
  }
}

TEST(RenderFrame, ConcurrentRendersOfOneWorldMatchSerialOnes) {
  TinyScene scene;
  const CameraFrame expected = render(scene.world, small_camera(), oblique(), "cam", 1);
  CameraFrame a, b;
  std::thread other([&] { a = render(scene.world, small_camera(), oblique(), "cam", 2); });
  b = render(scene.world, small_camera(), oblique(), "cam", 2);
  other.join();
  EXPECT_TRUE(same_frames(expected, a));
  EXPECT_TRUE(same_frames(expected, b));
}

TEST(RenderFrame, RejectsBadArguments) {
  TinyScene scene;
  EXPECT_THROW(render(scene.world, small_camera(), top_down(), "top", 0), Error);
  CameraIntrinsics in = small_camera();
  in.height = -1;
  EXPECT_THROW(render(scene.world, in, top_down(), "top", 1), Error);
  Eigen::Isometry3d squashed = top_down();
  squashed.linear() *= 2.0;
  EXPECT_THROW(render(scene.world, small_camera(), squashed, "top", 1), Error);
  scene.cube_look.box_face_textures[4] = cv::Mat(8, 8, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(render(scene.world, small_camera(), top_down(), "top", 1), Error);
}

TEST(RenderFrame, ObjectsWithoutAppearanceAreGrey) {
  TinyScene scene;
  scene.cube.setUserPointer(nullptr);
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 2);
  const cv::Vec3b centre = frame.rgb.at<cv::Vec3b>(64, 64);
  EXPECT_EQ(centre[0], centre[1]);
  EXPECT_EQ(centre[1], centre[2]);
  EXPECT_GT(centre[0], 0);
}

TEST(RenderTexture, DigitOnTheCubeTopIsInkedThereAndNowhereElse) {
  TinyScene scene;
  const cv::Mat digit = text_texture("2", 64, {1, 1, 1}, {0.05f, 0.05f, 0.4f});
  scene.cube_look.box_face_textures[4] = digit;  // +z
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 2);
  auto is_ink = [](const cv::Vec3b& c) { return c[0] < 40 && c[1] < 40 && c[2] > 50; };
  int ink_on_top = 0, paper_on_top = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u) {
      const cv::Vec3b rgb = frame.rgb.at<cv::Vec3b>(v, u);
      const Surface surface = surface_of(frame.points.at<cv::Vec3f>(v, u));
      if (surface == Surface::cube_top)
        (is_ink(rgb) ? ink_on_top : paper_on_top)++;
      else
        EXPECT_FALSE(is_ink(rgb)) << "ink at pixel " << u << "," << v;
    }
  EXPECT_GT(ink_on_top, 100);
  EXPECT_GT(paper_on_top, ink_on_top);
}

TEST(RenderTexture, TopFaceFollowsTheDocumentedOrientation) {
  // On the +z face, image right is +x and image up is +y (camera.hpp, Appearance).
  TinyScene scene;
  const cv::Mat digit = text_texture("2", 64, {1, 1, 1}, {0, 0, 0});
  scene.cube_look.box_face_textures[4] = digit;
  const CameraFrame frame = render(scene.world, small_camera(), top_down(), "top", 2);
  int paper_level = 0;  // white paper as lit: the brightness factor of this face
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u)
      if (surface_of(frame.points.at<cv::Vec3f>(v, u)) == Surface::cube_top)
        paper_level = std::max<int>(paper_level, frame.rgb.at<cv::Vec3b>(v, u)[0]);
  int agree = 0, total = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u) {
      const cv::Vec3f p = frame.points.at<cv::Vec3f>(v, u);
      if (surface_of(p) != Surface::cube_top) continue;
      const double tu = 0.5 + p[0] / (2 * kCubeHalf), tv = 0.5 - p[1] / (2 * kCubeHalf);
      const int column = std::clamp(static_cast<int>(tu * digit.cols), 0, digit.cols - 1);
      const int row = std::clamp(static_cast<int>(tv * digit.rows), 0, digit.rows - 1);
      const double expected = digit.at<cv::Vec3b>(row, column)[0] * paper_level / 255.0;
      ++total;
      agree += std::abs(frame.rgb.at<cv::Vec3b>(v, u)[0] - expected) <= 2.0;
    }
  ASSERT_GT(total, 900);
  EXPECT_GT(agree, total * 97 / 100);
  // With this camera (image up = +y) the digit is upright: its image matches the texture.
  cv::Mat top = frame.rgb(cv::Rect(64 - 22, 64 - 22, 44, 44)).clone(), resized;
  cv::resize(digit, resized, top.size(), 0, 0, cv::INTER_AREA);
  cv::Mat top_grey, digit_grey, flipped_grey;
  cv::cvtColor(top, top_grey, cv::COLOR_RGB2GRAY);
  cv::cvtColor(resized, digit_grey, cv::COLOR_RGB2GRAY);
  cv::flip(digit_grey, flipped_grey, 0);
  const double upright = cv::norm(top_grey, digit_grey * (paper_level / 255.0), cv::NORM_L1);
  const double upside_down = cv::norm(top_grey, flipped_grey * (paper_level / 255.0), cv::NORM_L1);
  EXPECT_LT(upright * 2, upside_down);
}

TEST(RenderPng, RgbRoundTripsThroughImreadInRgbOrder) {
  const std::string dir = temp_dir(), path = dir + "/frame.png";
  cv::Mat rgb(3, 4, CV_8UC3);
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 4; ++u) rgb.at<cv::Vec3b>(v, u) = cv::Vec3b(200, 10 * u, 30 * v);
  save_rgb_png(path, rgb);
  const cv::Mat read = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(read.type(), CV_8UC3);
  EXPECT_EQ(read.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 200));  // imread gives BGR
  cv::Mat back;
  cv::cvtColor(read, back, cv::COLOR_BGR2RGB);
  EXPECT_TRUE(same_bytes(back, rgb));
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"frame.png"});  // no temporary left
}

TEST(RenderPng, DepthMapIsBlackWhereNothingWasHitAndWarmNear) {
  const std::string dir = temp_dir(), path = dir + "/depth.png";
  cv::Mat depth(2, 3, CV_32FC1, cv::Scalar(0));
  depth.at<float>(0, 0) = 0.5f;  // near
  depth.at<float>(0, 1) = 2.0f;  // far
  depth.at<float>(0, 2) = NAN;
  save_depth_png(path, depth);
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_EQ(bgr.size(), depth.size());
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 2), cv::Vec3b(0, 0, 0));
  const cv::Vec3b near = bgr.at<cv::Vec3b>(0, 0), far = bgr.at<cv::Vec3b>(0, 1);
  EXPECT_GT(near[2], near[0]);  // red over blue
  EXPECT_GT(far[0], far[2]);    // blue over red
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"depth.png"});
}

TEST(RenderPng, RejectsWrongImageTypes) {
  const std::string dir = temp_dir();
  EXPECT_THROW(save_rgb_png(dir + "/a.png", cv::Mat(2, 2, CV_32FC3)), Error);
  EXPECT_THROW(save_depth_png(dir + "/b.png", cv::Mat(2, 2, CV_8UC1)), Error);
  EXPECT_THROW(save_rgb_png(dir + "/missing/c.png", cv::Mat(2, 2, CV_8UC3)), Error);
  EXPECT_TRUE(files_in(dir).empty());
}
