// Exact ray intersections with boxes, spheres, cylinders and convex hulls, and rays through compounds.
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
template <class Intersect, class Excess>
void check_random_rays_of(Intersect intersect, Excess excess, double around_m = 0.15) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> around(-around_m, around_m);
  int hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d origin = Eigen::Vector3d(around(random), around(random), around(random))
                                       .normalized() * 0.5;
    const Eigen::Vector3d aim(around(random), around(random), around(random));
    const Eigen::Vector3d direction = (aim - origin).normalized();
    ShapeHit hit;
    if (!intersect(origin, direction, hit)) {
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

template <class Excess>
void check_random_rays(const btCollisionShape& shape, Excess excess) {
  check_random_rays_of([&](const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           ShapeHit& hit) { return intersect_primitive(shape, o, d, 2.0, hit); },
                       excess);
}

// A regular prism as a hull: `sides` vertices on a circle of radius r, height h, about z.
btConvexHullShape regular_prism(int sides, double r, double h) {
  btConvexHullShape hull;
  for (double z : {-h / 2, h / 2})
    for (int i = 0; i < sides; ++i)
      hull.addPoint(btVector3(btScalar(r * std::cos(2 * M_PI * i / sides)), btScalar(r * std::sin(2 * M_PI * i / sides)),
                              btScalar(z)),
                    false);
  hull.recalcLocalAabb();
  hull.setMargin(0.001f);  // the simulator's: not drawn
  return hull;
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

// Convex hulls by the planes of their faces: a pentagonal prism against its own definition
// (inside every edge's half-plane at the apothem, within the height), and a cube's corners
// against the box primitive.
TEST(RenderRayShapes, ConvexHullHitsAreOnTheSurface) {
  const int sides = 5;
  const double r = 0.02, h = 0.03;
  const btConvexHullShape prism = regular_prism(sides, r, h);
  const std::vector<Eigen::Vector4d> planes = hull_planes(prism);
  EXPECT_EQ(planes.size(), static_cast<std::size_t>(sides + 2));  // one per face, however many triangles
  const float rf = static_cast<float>(r), hf = static_cast<float>(h);  // the hull holds floats
  const auto excess = [&](const Eigen::Vector3d& p) {
    double e = std::abs(p.z()) - hf / 2;
    for (int i = 0; i < sides; ++i) {
      const double angle = 2 * M_PI * (i + 0.5) / sides;  // an edge's outward normal
      e = std::max(e, p.x() * std::cos(angle) + p.y() * std::sin(angle) - rf * std::cos(M_PI / sides));
    }
    return e;
  };
  check_random_rays_of([&](const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           ShapeHit& hit) { return intersect_planes(planes, o, d, 2.0, hit); },
                       excess, 0.03);

  btConvexHullShape cube;
  for (int corner = 0; corner < 8; ++corner)
    cube.addPoint(btVector3(corner & 1 ? 0.05f : -0.05f, corner & 2 ? 0.04f : -0.04f, corner & 4 ? 0.03f : -0.03f),
                  false);
  const std::vector<Eigen::Vector4d> faces = hull_planes(cube);
  EXPECT_EQ(faces.size(), 6u);
  check_random_rays_of([&](const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           ShapeHit& hit) { return intersect_planes(faces, o, d, 2.0, hit); },
                       [](const Eigen::Vector3d& p) { return box_excess(p, {0.05f, 0.04f, 0.03f}); });
}

TEST(RenderRayShapes, HullsInAWorldAreHitExactlyAndOtherShapesGoToBullet) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btCollisionWorld world(&dispatcher, &broadphase, &configuration);
  btConvexHullShape hull = regular_prism(3, 0.05, 0.1);  // a triangular prism
  btCapsuleShapeZ capsule(0.05f, 0.1f);                 // no exact test: Bullet's
  btCollisionObject prism_object, capsule_object;
  prism_object.setCollisionShape(&hull);
  capsule_object.setCollisionShape(&capsule);
  capsule_object.getWorldTransform().setOrigin(btVector3(0.5f, 0, 0));
  world.addCollisionObject(&prism_object);
  world.addCollisionObject(&capsule_object);

  const RayCaster caster(world);
  RayHit hit;
  ASSERT_TRUE(caster.cast({0.01, 0.0, 1.0}, {0, 0, -1}, 2.0, hit));
  EXPECT_NEAR(hit.distance, 1.0 - 0.05, 1e-7);  // the top face, exactly: no margin
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-9);
  EXPECT_EQ(hit.part->shape, &hull);
  // The slanted side facing -x: the edge midpoint is at x = -r cos(60 deg) = -0.025.
  ASSERT_TRUE(caster.cast({-1.0, 0.0, 0.0}, {1, 0, 0}, 2.0, hit));
  EXPECT_NEAR(hit.distance, 1.0 - 0.025, 1e-7);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-7);
  EXPECT_FALSE(caster.cast({0.2, 0.0, 1.0}, {0, 0, -1}, 2.0, hit));
  ASSERT_TRUE(caster.cast({0.5, 0.0, 1.0}, {0, 0, -1}, 2.0, hit));
  EXPECT_NEAR(hit.distance, 1.0 - 0.1, 2e-3);  // the cap's top: radius + half height
  EXPECT_EQ(hit.part->shape, &capsule);
  world.removeCollisionObject(&prism_object);
  world.removeCollisionObject(&capsule_object);
}
