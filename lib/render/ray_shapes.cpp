#include "render/ray_shapes.hpp"

#include <btBulletCollisionCommon.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace qte::render {
namespace {

Eigen::Vector3d to_eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

// Slab test: the ray enters the box when it has entered all three slabs.
bool intersect_box(const Eigen::Vector3d& half, const Eigen::Vector3d& o,
                   const Eigen::Vector3d& d, ShapeHit& hit) {
  double enter = -std::numeric_limits<double>::infinity();
  double leave = std::numeric_limits<double>::infinity();
  int enter_axis = 0;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {
      if (std::abs(o[i]) > half[i]) return false;
      continue;
    }
    double low = (-half[i] - o[i]) / d[i], high = (half[i] - o[i]) / d[i];
    if (low > high) std::swap(low, high);
    if (low > enter) {
      enter = low;
      enter_axis = i;
    }
    leave = std::min(leave, high);
  }
  if (enter < 0 || enter > leave) return false;
  hit.distance = enter;
  hit.normal = Eigen::Vector3d::Zero();
  hit.normal[enter_axis] = d[enter_axis] < 0 ? 1.0 : -1.0;
  return true;
}

bool intersect_sphere(double radius, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      ShapeHit& hit) {
  const double b = o.dot(d), c = o.squaredNorm() - radius * radius;
  const double discriminant = b * b - c;
  if (c < 0 || discriminant < 0) return false;
  const double t = -b - std::sqrt(discriminant);
  if (t < 0) return false;
  hit.distance = t;
  hit.normal = (o + t * d) / radius;
  return true;
}

// A cylinder along `axis`: entered through its side or, from beyond its ends, a cap.
bool intersect_cylinder(int axis, double radius, double half_height, const Eigen::Vector3d& o,
                        const Eigen::Vector3d& d, ShapeHit& hit) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const double radial_squared = o[i] * o[i] + o[j] * o[j];
  const bool beyond_ends = std::abs(o[axis]) > half_height;
  if (radial_squared <= radius * radius && !beyond_ends) return false;  // starts inside

  hit.distance = std::numeric_limits<double>::infinity();
  const double a = d[i] * d[i] + d[j] * d[j];
  if (a > 0) {
    const double b = o[i] * d[i] + o[j] * d[j], c = radial_squared - radius * radius;
    const double discriminant = b * b - a * c;
    if (discriminant >= 0) {
      const double t = (-b - std::sqrt(discriminant)) / a;
      if (t >= 0 && std::abs(o[axis] + t * d[axis]) <= half_height) {
        hit.distance = t;
        hit.normal = o + t * d;
        hit.normal[axis] = 0;
        hit.normal /= radius;
      }
    }
  }
  if (beyond_ends && d[axis] != 0) {
    const double cap = o[axis] > 0 ? half_height : -half_height;
    const double t = (cap - o[axis]) / d[axis];
    const Eigen::Vector3d p = o + t * d;
    if (t >= 0 && t < hit.distance && p[i] * p[i] + p[j] * p[j] <= radius * radius) {
      hit.distance = t;
      hit.normal = Eigen::Vector3d::Zero();
      hit.normal[axis] = cap > 0 ? 1.0 : -1.0;
    }
  }
  return std::isfinite(hit.distance);
}

}  // namespace

bool is_primitive(const btCollisionShape& shape) {
  const int type = shape.getShapeType();
  return type == BOX_SHAPE_PROXYTYPE || type == SPHERE_SHAPE_PROXYTYPE ||
         type == CYLINDER_SHAPE_PROXYTYPE;
}

bool intersect_primitive(const btCollisionShape& shape, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& direction, double max_distance, ShapeHit& hit) {
  bool found = false;
  switch (shape.getShapeType()) {
    case BOX_SHAPE_PROXYTYPE: {
      const auto& box = static_cast<const btBoxShape&>(shape);
      found = intersect_box(to_eigen(box.getHalfExtentsWithMargin()), origin, direction, hit);
      break;
    }
    case SPHERE_SHAPE_PROXYTYPE:
      found = intersect_sphere(static_cast<const btSphereShape&>(shape).getRadius(), origin,
                               direction, hit);
      break;
    case CYLINDER_SHAPE_PROXYTYPE: {
      const auto& cylinder = static_cast<const btCylinderShape&>(shape);
      const int axis = cylinder.getUpAxis();
      found = intersect_cylinder(axis, cylinder.getRadius(),
                                 cylinder.getHalfExtentsWithMargin()[axis], origin, direction,
                                 hit);
      break;
    }
    default:
      return false;
  }
  return found && hit.distance <= max_distance;
}

std::vector<Eigen::Vector4d> hull_planes(const btConvexHullShape& hull) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < hull.getNumPoints(); ++i) v.push_back(to_eigen(hull.getUnscaledPoints()[i]));
  double size = 0;
  for (const auto& p : v) size = std::max(size, (p - v.front()).norm());
  const double tolerance = 1e-9 * std::max(size, 1e-3);
  // Every plane through three vertices with all the vertices on one side is a face's.
  std::vector<Eigen::Vector4d> planes;
  const int n = static_cast<int>(v.size());
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        Eigen::Vector3d normal = (v[j] - v[i]).cross(v[k] - v[i]);
        if (normal.norm() < tolerance * size) continue;  // (nearly) collinear
        normal.normalize();
        double offset = -normal.dot(v[i]);
        bool in_front = false, behind = false;
        for (const auto& p : v) {
          const double d = normal.dot(p) + offset;
          in_front |= d > tolerance;
          behind |= d < -tolerance;
        }
        if (in_front && behind) continue;
        if (in_front) normal = -normal, offset = -offset;  // outward: every vertex behind
        const Eigen::Vector4d plane(normal.x(), normal.y(), normal.z(), offset);
        const bool known = std::any_of(planes.begin(), planes.end(), [&](const Eigen::Vector4d& q) {
          return (q - plane).cwiseAbs().maxCoeff() < 1e-9;
        });
        if (!known) planes.push_back(plane);
      }
  return planes;
}

bool intersect_planes(const std::vector<Eigen::Vector4d>& planes, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& direction, double max_distance, ShapeHit& hit) {
  // The ray inside every half-space at once: entering through the last plane it enters,
  // before leaving through the first it leaves.
  double enter = 0, leave = max_distance, last_entered = -std::numeric_limits<double>::infinity();
  bool outside = false;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const Eigen::Vector4d& plane : planes) {
    const Eigen::Vector3d n = plane.head<3>();
    const double height = n.dot(origin) + plane.w(), along = n.dot(direction);
    outside |= height > 0;
    if (along == 0) {
      if (height > 0) return false;  // parallel, outside this face
      continue;
    }
    const double t = -height / along;
    if (along < 0) {
      if (t > last_entered) last_entered = t, normal = n;
      enter = std::max(enter, t);
    } else {
      leave = std::min(leave, t);
    }
    if (enter > leave) return false;
  }
  if (!outside) return false;  // starts inside: not seen, as with the primitives
  hit.distance = enter;
  hit.normal = normal;
  return true;
}

}  // namespace qte::render
