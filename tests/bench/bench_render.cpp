// Frame time of the ray-cast camera on a task-sized scene: a table with 8 cylinders and 6
// boxes on it, seen from the front and above as RLBench's front camera sees its table.
// Prints the median over 30 frames after warm-up, per image size and thread count.
#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "render/camera.hpp"

using namespace qte::render;

namespace {

class TableScene {
 public:
  TableScene() {
    add(std::make_unique<btBoxShape>(btVector3(0.6f, 0.5f, 0.02f)), {0, 0, 0.73f},
        {0.55f, 0.4f, 0.25f});
    for (int i = 0; i < 8; ++i) {
      const float angle = static_cast<float>(i) * 0.785f;
      add(std::make_unique<btCylinderShapeZ>(btVector3(0.03f, 0.03f, 0.06f)),
          {0.3f * std::cos(angle), 0.3f * std::sin(angle), 0.81f},
          {0.2f + 0.1f * static_cast<float>(i % 3), 0.3f, 0.8f - 0.08f * static_cast<float>(i)});
    }
    for (int i = 0; i < 6; ++i)
      add(std::make_unique<btBoxShape>(btVector3(0.025f, 0.025f, 0.025f)),
          {-0.15f + 0.06f * static_cast<float>(i), 0.08f * static_cast<float>(i % 2), 0.775f},
          {0.9f, 0.2f + 0.1f * static_cast<float>(i), 0.2f});
    world_.updateAabbs();
  }
  ~TableScene() {
    for (auto& object : objects_) world_.removeCollisionObject(object.get());
  }
  const btCollisionWorld& world() const { return world_; }

 private:
  void add(std::unique_ptr<btCollisionShape> shape, const btVector3& position,
           const Eigen::Vector3f& colour) {
    auto appearance = std::make_unique<Appearance>();
    appearance->colour = colour;
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(shape.get());
    object->setWorldTransform(btTransform(btQuaternion::getIdentity(), position));
    object->setUserPointer(appearance.get());
    world_.addCollisionObject(object.get());
    shapes_.push_back(std::move(shape));
    appearances_.push_back(std::move(appearance));
    objects_.push_back(std::move(object));
  }

  btDefaultCollisionConfiguration configuration_;
  btCollisionDispatcher dispatcher_{&configuration_};
  btDbvtBroadphase broadphase_;
  btCollisionWorld world_{&dispatcher_, &broadphase_, &configuration_};
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<Appearance>> appearances_;
  std::vector<std::unique_ptr<btCollisionObject>> objects_;
};

double median_ms_per_frame(const TableScene& scene, const CameraIntrinsics& intrinsics,
                           const Eigen::Isometry3d& pose, int threads) {
  constexpr int kWarmUp = 3, kFrames = 30;
  for (int i = 0; i < kWarmUp; ++i) render(scene.world(), intrinsics, pose, "front", threads);
  std::vector<double> ms;
  for (int i = 0; i < kFrames; ++i) {
    const auto start = std::chrono::steady_clock::now();
    render(scene.world(), intrinsics, pose, "front", threads);
    const std::chrono::duration<double, std::milli> took = std::chrono::steady_clock::now() - start;
    ms.push_back(took.count());
  }
  std::nth_element(ms.begin(), ms.begin() + kFrames / 2, ms.end());
  return ms[kFrames / 2];
}

}  // namespace

int main() {
  const TableScene scene;
  const Eigen::Isometry3d front = look_at({1.3, 0.0, 1.55}, {0.0, 0.0, 0.75});
  for (int size : {128, 256})
    for (int threads : {1, 2}) {
      CameraIntrinsics intrinsics;
      intrinsics.width = intrinsics.height = size;
      intrinsics.fov_y_deg = 40.0;
      const double ms = median_ms_per_frame(scene, intrinsics, front, threads);
      std::printf("render %dx%d threads=%d: %.1f ms/frame (%.0f fps)\n", size, size, threads, ms,
                  1000.0 / ms);
    }
  return 0;
}
