#include "render/ray_caster.hpp"

#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <btBulletCollisionCommon.h>

#include <algorithm>

#include "render/ray_shapes.hpp"

namespace qte::render {
namespace {

Eigen::Vector3d to_eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

btVector3 to_bullet(const Eigen::Vector3d& v) {
  return {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())};
}

Eigen::Isometry3d to_eigen(const btTransform& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column) pose(row, column) = t.getBasis()[row][column];
  pose.translation() = to_eigen(t.getOrigin());
  return pose;
}

btTransform to_bullet(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d& r = pose.linear();
  const btMatrix3x3 basis(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)),
                          btScalar(r(1, 0)), btScalar(r(1, 1)), btScalar(r(1, 2)),
                          btScalar(r(2, 0)), btScalar(r(2, 1)), btScalar(r(2, 2)));
  return btTransform(basis, to_bullet(pose.translation()));
}

void add_parts(const btCollisionObject& object, const btCollisionShape& shape,
               const btTransform& world_from_shape, std::vector<ScenePart>& parts) {
  if (shape.isCompound()) {
    const auto& compound = static_cast<const btCompoundShape&>(shape);
    for (int i = 0; i < compound.getNumChildShapes(); ++i)
      add_parts(object, *compound.getChildShape(i),
                world_from_shape * compound.getChildTransform(i), parts);
    return;
  }
  btVector3 low, high;
  shape.getAabb(world_from_shape, low, high);
  const Eigen::Isometry3d pose = to_eigen(world_from_shape);
  parts.push_back({&object, &shape, pose, pose.inverse(),
                   Eigen::AlignedBox3d(to_eigen(low), to_eigen(high)), {}});
  if (shape.getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE)
    parts.back().planes = hull_planes(static_cast<const btConvexHullShape&>(shape));
}

// Whether the ray's first `length` metres pass through the box (slab test). A zero direction
// component gives infinite slab bounds, or NaN right on a face, which min and max then skip.
bool ray_meets_box(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& start,
                   const Eigen::Vector3d& inverse_direction, double length) {
  double enter = 0, leave = length;
  for (int i = 0; i < 3; ++i) {
    double low = (box.min()[i] - start[i]) * inverse_direction[i];
    double high = (box.max()[i] - start[i]) * inverse_direction[i];
    if (low > high) std::swap(low, high);
    enter = std::max(enter, low);
    leave = std::min(leave, high);
  }
  return enter <= leave;
}

// Shapes without an exact test (meshes, planes) go to Bullet. Its GJK cast is
// far closer to the surface than the default subsimplex one (ray_shapes.hpp). Normal: world.
bool bullet_ray_test(const ScenePart& part, const Eigen::Vector3d& start,
                     const Eigen::Vector3d& direction, double length, ShapeHit& hit) {
  const btVector3 from = to_bullet(start), to = to_bullet(start + length * direction);
  btCollisionWorld::ClosestRayResultCallback closest(from, to);
  closest.m_flags |= btTriangleRaycastCallback::kF_UseGjkConvexCastRaytest;
  // rayTestSingle only reads the object; it takes a non-const pointer for its callbacks' sake.
  btCollisionWorld::rayTestSingle(btTransform(btMatrix3x3::getIdentity(), from),
                                  btTransform(btMatrix3x3::getIdentity(), to),
                                  const_cast<btCollisionObject*>(part.object), part.shape,
                                  to_bullet(part.world_from_shape), closest);
  if (!closest.hasHit()) return false;
  hit.distance = double(closest.m_closestHitFraction) * length;
  hit.normal = to_eigen(closest.m_hitNormalWorld).normalized();
  return true;
}

}  // namespace

RayCaster::RayCaster(const btCollisionWorld& world) {
  // Filtering as rayTest does it, with the default groups of a ray result callback.
  const btCollisionWorld::ClosestRayResultCallback default_ray(btVector3(0, 0, 0),
                                                               btVector3(0, 0, 0));
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    btCollisionObject* object = objects[i];
    if (object->getBroadphaseHandle() == nullptr ||
        !default_ray.needsCollision(object->getBroadphaseHandle()))
      continue;
    add_parts(*object, *object->getCollisionShape(), object->getWorldTransform(), parts_);
  }
}

bool RayCaster::cast(const Eigen::Vector3d& start, const Eigen::Vector3d& direction,
                     double length, RayHit& hit) const {
  const Eigen::Vector3d inverse_direction = direction.cwiseInverse();
  hit.part = nullptr;
  hit.distance = length;
  for (const ScenePart& part : parts_) {
    // Only parts that could be closer than the closest hit so far.
    if (!ray_meets_box(part.bounds, start, inverse_direction, hit.distance)) continue;
    ShapeHit found;
    if (!part.planes.empty()) {
      if (!intersect_planes(part.planes, part.shape_from_world * start, part.shape_from_world.linear() * direction,
                            hit.distance, found))
        continue;
      found.normal = part.world_from_shape.linear() * found.normal;
    } else if (is_primitive(*part.shape)) {
      if (!intersect_primitive(*part.shape, part.shape_from_world * start,
                               part.shape_from_world.linear() * direction, hit.distance, found))
        continue;
      found.normal = part.world_from_shape.linear() * found.normal;
    } else if (!bullet_ray_test(part, start, direction, hit.distance, found)) {
      continue;
    }
    hit.distance = found.distance;
    hit.normal = found.normal;
    hit.part = &part;
  }
  if (hit.part == nullptr) return false;
  if (hit.normal.dot(direction) > 0) hit.normal = -hit.normal;  // a mesh seen from behind
  return true;
}

}  // namespace qte::render
