// Exact ray intersections with boxes, spheres and cylinders, and rays through compounds.
#include <btBulletCollisionCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "render/ray_caster.hpp"
#include "render/ray_shapes.hpp"

using namespace qte::render;

namespace {

// How far outside the shape a point is (negative inside): box, sphere, Z cylinder.
double box_excess(const Eigen::Vector3d& p, const Eigen::Vector3d& half) {
  return (p.cwiseAbs() - half).maxCoeff();
}
double sphere_excess(const Eigen::Vector3d& p, double r) { return p.norm() - r; }
double cylinder_excess(const Eigen::Vector3d& p, double r, double half_height) {
  return std::max(std::hypot(p.x(), p.y()) - r, std::abs(p.z()) - half_height);
}

// Random rays from outside towards the neighbourhood of the origin: the hit must be on the
// surface, and the ray must stay outside up to it (it is the first hit).
template <class Excess>
void check_random_rays(const btCollisionShape& shape, Excess excess) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> around(-0.15, 0.15);
  int hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d origin = Eigen::Vector3d(around(random), around(random), around(random))
                                       .normalized() * 0.5;
    const Eigen::Vector3d aim(around(random), around(random), around(random));
    const Eigen::Vector3d direction = (aim - origin).normalized();
    ShapeHit hit;
    if (!intersect_primitive(shape, origin, direction, 2.0, hit)) {
      for (double t = 0; t < 1.0; t += 0.001) ASSERT_GT(excess(origin + t * direction), -1e-7);
      continue;
    }
    ++hits;
    const Eigen::Vector3d p = origin + hit.distance * direction;
    EXPECT_NEAR(excess(p), 0.0, 1e-7);  // float extents, double maths
    EXPECT_NEAR(hit.normal.norm(), 1.0, 1e-9);
    EXPECT_LT(hit.normal.dot(direction), 0.0);  // outward, against the ray
    EXPECT_GT(excess(p + 1e-6 * hit.normal), 0.0);
    for (double t = 0; t < hit.distance - 1e-6; t += 0.001)
      ASSERT_GT(excess(origin + t * direction), -1e-7);
  }
  EXPECT_GT(hits, 300);
}

}  // namespace

TEST(RenderRayShapes, BoxHitsAreOnTheSurface) {
  const btBoxShape box(btVector3(0.05f, 0.08f, 0.03f));  // Bullet's margin must not matter
  check_random_rays(box, [](const Eigen::Vector3d& p) {
    return box_excess(p, {0.05f, 0.08f, 0.03f});
  });
}

TEST(RenderRayShapes, SphereHitsAreOnTheSurface) {
  const btSphereShape sphere(0.07f);
  check_random_rays(sphere, [](const Eigen::Vector3d& p) { return sphere_excess(p, 0.07f); });
}

TEST(RenderRayShapes, CylinderHitsAreOnTheSurface) {
  const btCylinderShapeZ cylinder(btVector3(0.04f, 0.04f, 0.09f));
  check_random_rays(cylinder, [](const Eigen::Vector3d& p) {
    return cylinder_excess(p, 0.04f, 0.09f);
  });
}

TEST(RenderRayShapes, CylindersAlongXAndYToo) {
  const btCylinderShapeX along_x(btVector3(0.09f, 0.04f, 0.04f));
  check_random_rays(along_x, [](const Eigen::Vector3d& p) {
    return cylinder_excess({p.y(), p.z(), p.x()}, 0.04f, 0.09f);
  });
  const btCylinderShape along_y(btVector3(0.04f, 0.09f, 0.04f));
  check_random_rays(along_y, [](const Eigen::Vector3d& p) {
    return cylinder_excess({p.z(), p.x(), p.y()}, 0.04f, 0.09f);
  });
}

TEST(RenderRayShapes, RaysStartingInsideOrTooShortSeeNothing) {
  const btBoxShape box(btVector3(0.1f, 0.1f, 0.1f));
  const btSphereShape sphere(0.1f);
  const btCylinderShapeZ cylinder(btVector3(0.1f, 0.1f, 0.1f));
  ShapeHit hit;
  for (const btCollisionShape* shape : {static_cast<const btCollisionShape*>(&box),
                                        static_cast<const btCollisionShape*>(&sphere),
                                        static_cast<const btCollisionShape*>(&cylinder)}) {
    EXPECT_FALSE(intersect_primitive(*shape, {0, 0, 0}, {0, 0, 1}, 1.0, hit));
    EXPECT_FALSE(intersect_primitive(*shape, {0, 0, 1}, {0, 0, -1}, 0.85, hit));
    ASSERT_TRUE(intersect_primitive(*shape, {0, 0, 1}, {0, 0, -1}, 0.95, hit));
    EXPECT_NEAR(hit.distance, 0.9, 1e-7);
    EXPECT_FALSE(intersect_primitive(*shape, {0.2, 0, 1}, {0, 0, -1}, 2.0, hit));
  }
}

TEST(RenderRayShapes, CompoundChildrenAreHitWhereTheyAre) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btCollisionWorld world(&dispatcher, &broadphase, &configuration);
  btCompoundShape compound;
  btBoxShape plate(btVector3(0.1f, 0.1f, 0.01f));
  btSphereShape knob(0.03f);
  compound.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 0)), &plate);
  compound.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0.05f, 0, 0.04f)),
                         &knob);
  btCollisionObject object;
  object.setCollisionShape(&compound);
  object.setWorldTransform(
      btTransform(btQuaternion(btVector3(0, 0, 1), 0.5f), btVector3(1.0f, 2.0f, 0.5f)));
  world.addCollisionObject(&object);

  const RayCaster caster(world);
  const Eigen::Vector3d above(1.0, 2.0, 1.5);
  RayHit hit;
  // Straight down onto the plate's centre, beside the knob.
  ASSERT_TRUE(caster.cast(above, {0, 0, -1}, 2.0, hit));
  EXPECT_NEAR(hit.distance, 1.0 - 0.01, 1e-6);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-6);
  EXPECT_EQ(hit.part->shape, &plate);
  EXPECT_EQ(hit.part->object, &object);
  // Onto the knob's top: the knob sits 5 cm along the object's rotated x axis.
  const Eigen::Vector3d knob_centre(1.0 + 0.05 * std::cos(0.5), 2.0 + 0.05 * std::sin(0.5), 0.54);
  ASSERT_TRUE(caster.cast({knob_centre.x(), knob_centre.y(), 1.5}, {0, 0, -1}, 2.0, hit));
  EXPECT_NEAR(hit.distance, 1.5 - 0.54 - 0.03, 1e-6);
  EXPECT_EQ(hit.part->shape, &knob);
  // Past the edge: nothing.
  EXPECT_FALSE(caster.cast({1.3, 2.0, 1.5}, {0, 0, -1}, 2.0, hit));
  world.removeCollisionObject(&object);
}

TEST(RenderRayShapes, OtherShapesGoToBulletsRayTest) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btCollisionWorld world(&dispatcher, &broadphase, &configuration);
  btConvexHullShape hull;  // a 10 cm cube as a hull, with the simulator's 1 mm margin
  for (int corner = 0; corner < 8; ++corner)
    hull.addPoint(btVector3(corner & 1 ? 0.05f : -0.05f, corner & 2 ? 0.05f : -0.05f,
                            corner & 4 ? 0.05f : -0.05f),
                  false);
  hull.recalcLocalAabb();
  hull.setMargin(0.001f);
  btCollisionObject object;
  object.setCollisionShape(&hull);
  world.addCollisionObject(&object);

  const RayCaster caster(world);
  RayHit hit;
  ASSERT_TRUE(caster.cast({0.01, 0.02, 1.0}, {0, 0, -1}, 2.0, hit));
  EXPECT_NEAR(hit.distance, 1.0 - 0.05, 2e-3);  // the margin adds up to 1 mm
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-3);
  EXPECT_EQ(hit.part->shape, &hull);
  EXPECT_FALSE(caster.cast({0.2, 0.0, 1.0}, {0, 0, -1}, 2.0, hit));
  world.removeCollisionObject(&object);
}
