// Closest-hit rays against a snapshot of a Bullet collision world, safe from many threads.
//
// Why not btCollisionWorld::rayTest: Debian's Bullet is built without BT_THREADSAFE, and then
// btDbvtBroadphase::rayTest walks its trees with one shared stack (m_rayTestStacks[0]), so
// concurrent calls race; and its convex casts are approximate (see ray_shapes.hpp). Instead the
// snapshot lists every object's primitive parts (compounds flattened) with their world AABBs;
// each ray tests those boxes, then intersects the parts exactly (primitives, and convex hulls
// by their faces' planes). Other shapes go to btCollisionWorld::rayTestSingle, which keeps all
// its state in locals.
// Linear in the part count, which suits the tens of parts of a task scene.
#pragma once

#include <Eigen/Geometry>
#include <vector>

class btCollisionObject;
class btCollisionShape;
class btCollisionWorld;

namespace qte::render {

// One piece of an object: its own shape, or a child of its compound shape.
struct ScenePart {
  const btCollisionObject* object;
  const btCollisionShape* shape;
  Eigen::Isometry3d world_from_shape;
  Eigen::Isometry3d shape_from_world;
  Eigen::AlignedBox3d bounds;  // world frame
  std::vector<Eigen::Vector4d> planes;  // a convex hull's faces (ray_shapes.hpp), shape frame
};

struct RayHit {
  double distance;         // along the ray, from its start
  Eigen::Vector3d normal;  // world frame, unit, facing back along the ray
  const ScenePart* part;
};

class RayCaster {
 public:
  // Takes the parts and their poses now; the world must not change while casting. Objects
  // whose collision filter rejects Bullet's default ray group are left out, as rayTest would.
  explicit RayCaster(const btCollisionWorld& world);

  // The closest surface on start + t * direction (direction a unit vector, 0 <= t <= length).
  bool cast(const Eigen::Vector3d& start, const Eigen::Vector3d& direction, double length,
            RayHit& hit) const;

 private:
  std::vector<ScenePart> parts_;
};

}  // namespace qte::render
