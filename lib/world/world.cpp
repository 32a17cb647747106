#include "world/world.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "common/error.hpp"

namespace qte::world {
namespace {

btTransform to_bullet(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  return btTransform(btQuaternion(q.x(), q.y(), q.z(), q.w()),
                     btVector3(pose.translation().x(), pose.translation().y(), pose.translation().z()));
}

Eigen::Isometry3d from_bullet(const btTransform& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const btQuaternion q = t.getRotation();
  pose.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).toRotationMatrix();
  pose.translation() << t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z();
  return pose;
}

std::unique_ptr<btConvexHullShape> make_hull(const std::vector<Eigen::Vector3d>& points) {
  auto hull = std::make_unique<btConvexHullShape>();
  for (const auto& p : points) hull->addPoint(btVector3(p.x(), p.y(), p.z()), false);
  hull->setMargin(kHullMargin);
  hull->initializePolyhedralFeatures();  // faces for SAT and clipping: flat hulls rest flat on each other
  hull->recalcLocalAabb();  // after the margin: the cached box includes it (default 4 cm)
  return hull;
}

// The object's collision shape; a compound's pieces go to `children` (the compound only
// points at them).
std::unique_ptr<btCollisionShape> make_shape(const ObjectSpec& spec,
                                             std::vector<std::unique_ptr<btCollisionShape>>& children) {
  const Eigen::Vector3d& s = spec.size;
  switch (spec.shape) {
    case ObjectSpec::Shape::box:
      return std::make_unique<btBoxShape>(btVector3(s.x() / 2, s.y() / 2, s.z() / 2));
    case ObjectSpec::Shape::cylinder:
      return std::make_unique<btCylinderShapeZ>(btVector3(s.x(), s.x(), s.y() / 2));
    case ObjectSpec::Shape::sphere:
      return std::make_unique<btSphereShape>(s.x());
    case ObjectSpec::Shape::convex_hull:
      return make_hull(spec.hull_points);
    case ObjectSpec::Shape::compound: {
      if (spec.pieces.empty()) throw Error("compound object '" + spec.name + "' has no pieces");
      auto compound = std::make_unique<btCompoundShape>();
      for (const auto& piece : spec.pieces) {
        children.push_back(make_hull(piece));
        compound->addChildShape(btTransform::getIdentity(), children.back().get());
      }
      return compound;
    }
  }
  throw Error("unknown object shape");
}

// Counts contacts deeper than a tolerance between two objects.
struct PenetrationCallback : btCollisionWorld::ContactResultCallback {
  double tolerance_m;
  bool touching = false;
  explicit PenetrationCallback(double tolerance) : tolerance_m(tolerance) {}
  btScalar addSingleResult(btManifoldPoint& point, const btCollisionObjectWrapper*, int, int,
                           const btCollisionObjectWrapper*, int, int) override {
    if (point.getDistance() < -tolerance_m) touching = true;
    return 0;
  }
};

// How far a held object must slip back in the grip (along `back`, the reverse of the
// gripper's approach) to leave what it presses on: the deepest contact, deeper than
// `tolerance_m`, whose obstacle pushes it back along the approach rather than sideways.
struct SlipCallback : btCollisionWorld::ContactResultCallback {
  const btCollisionObject* held;
  std::function<bool(const btCollisionObject*)> is_obstacle;
  btVector3 back;
  double tolerance_m;
  double slip_m = 0;
  SlipCallback(const btCollisionObject* held_object, std::function<bool(const btCollisionObject*)> obstacle,
               const btVector3& back_direction, double tolerance)
      : held(held_object), is_obstacle(std::move(obstacle)), back(back_direction), tolerance_m(tolerance) {}
  btScalar addSingleResult(btManifoldPoint& point, const btCollisionObjectWrapper* a, int, int,
                           const btCollisionObjectWrapper* b, int, int) override {
    const bool held_is_a = a->getCollisionObject() == held;
    if (!is_obstacle(held_is_a ? b->getCollisionObject() : a->getCollisionObject())) return 0;
    // The normal on B points from B to A: turned to point out of the obstacle, into the held object.
    const btVector3 out = held_is_a ? point.m_normalWorldOnB : -point.m_normalWorldOnB;
    const double along = out.dot(back), depth = -point.getDistance();
    if (depth > tolerance_m && along > 0.5) slip_m = std::max(slip_m, depth / along);
    return 0;
  }
};

}  // namespace

struct World::Impl {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};

  struct Body {
    std::unique_ptr<btCollisionShape> shape;
    std::vector<std::unique_ptr<btCollisionShape>> children;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
    std::unique_ptr<render::Appearance> appearance;
  };
  Body table, floor;
  std::vector<Body> links;    // one per robot link (null body for links without shapes)
  std::vector<Body> objects;  // task objects, by id
  std::vector<ObjectSpec> specs;
  std::vector<std::pair<int, int>> checked_link_pairs;  // for self-collision

  ~Impl() {
    for (auto* list : {&objects, &links})
      for (auto& b : *list)
        if (b.body) world.removeRigidBody(b.body.get());
    for (auto* b : {&table, &floor})
      if (b->body) world.removeRigidBody(b->body.get());
  }

  Body make_body(std::unique_ptr<btCollisionShape> shape, double mass, const btTransform& pose,
                 const render::Appearance& appearance) {
    Body b;
    b.shape = std::move(shape);
    b.motion = std::make_unique<btDefaultMotionState>(pose);
    btVector3 inertia(0, 0, 0);
    if (mass > 0) b.shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo info(mass, b.motion.get(), b.shape.get(), inertia);
    info.m_friction = 0.8;
    info.m_rollingFriction = 0.001;
    info.m_spinningFriction = 0.001;
    b.body = std::make_unique<btRigidBody>(info);
    b.appearance = std::make_unique<render::Appearance>(appearance);
    b.body->setUserPointer(b.appearance.get());
    return b;
  }
};

World::World(const robot::RobotModel& robot, const SceneLayout& layout)
    : impl_(std::make_unique<Impl>()), robot_(robot), layout_(layout) {
  auto& w = impl_->world;
  w.setGravity(btVector3(0, 0, -9.81));
  // Hull pairs by separating axes and face clipping (several contact points per face) rather
  // than GJK's one point a step: stacked thin hulls (checkers) otherwise sink into each other.
  w.getDispatchInfo().m_enableSatConvex = true;

  render::Appearance wood, ground;
  wood.colour << 0.72f, 0.56f, 0.40f;
  ground.colour << 0.35f, 0.35f, 0.38f;
  const double thickness = 0.05;
  btTransform table_pose(btQuaternion::getIdentity(),
                         btVector3(layout.table_centre.x(), layout.table_centre.y(),
                                   layout.table_height_m - thickness / 2));
  impl_->table = impl_->make_body(
      std::make_unique<btBoxShape>(btVector3(layout.table_extent_m.x() / 2,
                                             layout.table_extent_m.y() / 2, thickness / 2)),
      0, table_pose, wood);
  impl_->floor = impl_->make_body(std::make_unique<btBoxShape>(btVector3(5, 5, 0.05)), 0,
                                  btTransform(btQuaternion::getIdentity(), btVector3(0, 0, -0.05)),
                                  ground);
  w.addRigidBody(impl_->table.body.get());
  w.addRigidBody(impl_->floor.body.get());

  // Robot links: kinematic bodies made of their primitive shapes.
  for (const auto& link : robot.links()) {
    Impl::Body body;
    if (!link.shapes.empty()) {
      auto compound = std::make_unique<btCompoundShape>();
      std::vector<std::unique_ptr<btCollisionShape>> children;
      for (const auto& s : link.shapes) {
        std::unique_ptr<btCollisionShape> child;
        if (s.kind == robot::Shape::Kind::box)
          child = std::make_unique<btBoxShape>(btVector3(s.size.x() / 2, s.size.y() / 2, s.size.z() / 2));
        else if (s.kind == robot::Shape::Kind::cylinder)
          child = std::make_unique<btCylinderShapeZ>(btVector3(s.size.x(), s.size.x(), s.size.y() / 2));
        else
          child = std::make_unique<btSphereShape>(s.size.x());
        compound->addChildShape(to_bullet(s.link_from_shape), child.get());
        children.push_back(std::move(child));
      }
      render::Appearance look;
      look.colour = link.colour;
      body = impl_->make_body(std::move(compound), 0, btTransform::getIdentity(), look);
      body.children = std::move(children);
      body.body->setCollisionFlags(body.body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      body.body->setActivationState(DISABLE_DEACTIVATION);
      w.addRigidBody(body.body.get());
    }
    impl_->links.push_back(std::move(body));
  }
  impl_->checked_link_pairs = robot.self_collision_pairs();

  set_robot_state(SceneLayout::ready_joints(), robot.max_finger_opening_m());
}

World::~World() = default;

int World::add_object(const ObjectSpec& spec) {
  if (spec.name.empty()) throw Error("an object needs a name");
  for (const auto& s : impl_->specs)
    if (s.name == spec.name) throw Error("two objects named '" + spec.name + "'");
  std::vector<std::unique_ptr<btCollisionShape>> children;
  auto shape = make_shape(spec, children);
  Impl::Body body = impl_->make_body(std::move(shape), spec.mass_kg, to_bullet(spec.pose), spec.appearance);
  body.children = std::move(children);
  if (!spec.collides)
    body.body->setCollisionFlags(body.body->getCollisionFlags() | btCollisionObject::CF_NO_CONTACT_RESPONSE);
  impl_->world.addRigidBody(body.body.get());
  impl_->objects.push_back(std::move(body));
  impl_->specs.push_back(spec);
  return static_cast<int>(impl_->objects.size()) - 1;
}

int World::object_count() const { return static_cast<int>(impl_->objects.size()); }
const ObjectSpec& World::object_spec(int id) const { return impl_->specs.at(id); }

int World::object_id(const std::string& name) const {
  for (std::size_t i = 0; i < impl_->specs.size(); ++i)
    if (impl_->specs[i].name == name) return static_cast<int>(i);
  throw Error("the scene has no object '" + name + "'");
}

Eigen::Isometry3d World::object_pose(int id) const {
  return from_bullet(impl_->objects.at(id).body->getWorldTransform());
}

Eigen::AlignedBox3d World::object_box(int id) const {
  const ObjectSpec& spec = object_spec(id);
  const Eigen::Vector3d& s = spec.size;
  Eigen::AlignedBox3d box;
  switch (spec.shape) {
    case ObjectSpec::Shape::box:
      return {-s / 2, s / 2};
    case ObjectSpec::Shape::cylinder:  // about z: (radius, height)
      return {Eigen::Vector3d(-s.x(), -s.x(), -s.y() / 2), Eigen::Vector3d(s.x(), s.x(), s.y() / 2)};
    case ObjectSpec::Shape::sphere:
      return {Eigen::Vector3d::Constant(-s.x()), Eigen::Vector3d::Constant(s.x())};
    case ObjectSpec::Shape::convex_hull:
      for (const auto& p : spec.hull_points) box.extend(p);
      return box;
    case ObjectSpec::Shape::compound:
      for (const auto& piece : spec.pieces)
        for (const auto& p : piece) box.extend(p);
      return box;
  }
  return box;
}

Eigen::Isometry3d World::link_pose(int link) const {
  return robot_base_pose() * robot_.link_poses(q_, opening_m_)[link];
}

Eigen::Isometry3d World::tcp_pose() const { return link_pose(robot_.tcp_link()); }

void World::place_robot_links() {
  const auto poses = robot_.link_poses(q_, opening_m_);
  const Eigen::Isometry3d base = robot_base_pose();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    auto& body = impl_->links[i].body;
    if (!body) continue;
    const btTransform t = to_bullet(base * poses[i]);
    body->getMotionState()->setWorldTransform(t);
    body->setWorldTransform(t);
  }
  if (held_ >= 0) {
    auto& body = impl_->objects[held_].body;
    const Eigen::Isometry3d tcp = base * poses[robot_.tcp_link()];
    const btTransform t = to_bullet(tcp * held_from_tcp_);
    body->getMotionState()->setWorldTransform(t);
    body->setWorldTransform(t);
    slip_held_object(tcp);
  }
}

void World::slip_held_object(const Eigen::Isometry3d& tcp) {
  auto& body = *impl_->objects[held_].body;
  const auto is_obstacle = [this](const btCollisionObject* other) {
    if (other == impl_->table.body.get()) return true;
    for (int id = 0; id < object_count(); ++id)
      if (other == impl_->objects[id].body.get()) return id != held_ && impl_->specs[id].collides;
    return false;  // robot links: the fingers hold it
  };
  const Eigen::Vector3d back = -tcp.linear().col(2);
  double slipped = 0;
  for (int pass = 0; pass < 3; ++pass) {  // a slip out of one obstacle may press into another
    SlipCallback contacts(&body, is_obstacle, btVector3(back.x(), back.y(), back.z()), kSlipTolerance_m);
    impl_->world.contactTest(&body, contacts);
    if (contacts.slip_m == 0 || slipped + contacts.slip_m > kMaxSlip_m) break;
    slipped += contacts.slip_m;
    const Eigen::Isometry3d moved = Eigen::Translation3d(contacts.slip_m * back) * object_pose(held_);
    held_from_tcp_ = tcp.inverse() * moved;
    const btTransform t = to_bullet(moved);
    body.getMotionState()->setWorldTransform(t);
    body.setWorldTransform(t);
  }
}

void World::set_robot_state(const robot::JointVector& q, double finger_opening_m) {
  q_ = q;
  opening_m_ = std::clamp(finger_opening_m, 0.0, robot_.max_finger_opening_m());
  place_robot_links();
  // Kinematic bodies must not carry the teleport as a velocity into the next step.
  for (auto& link : impl_->links)
    if (link.body) link.body->saveKinematicState(kPhysicsStep);
  impl_->world.updateAabbs();
}

void World::physics_substep() { impl_->world.stepSimulation(kPhysicsStep, 1, kPhysicsStep); }

void World::step_towards(const robot::JointVector& q, double finger_opening_m, double dt_s) {
  const int steps = std::max(1, static_cast<int>(std::lround(dt_s / kPhysicsStep)));
  const robot::JointVector q0 = q_;
  const double opening0 = opening_m_;
  for (int i = 1; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    q_ = q0 + t * (q - q0);
    opening_m_ = opening0 + t * (finger_opening_m - opening0);
    place_robot_links();
    physics_substep();
  }
}

void World::settle(double seconds) {
  const int steps = std::max(1, static_cast<int>(std::lround(seconds / kPhysicsStep)));
  for (int i = 0; i < steps; ++i) {
    place_robot_links();
    physics_substep();
  }
}

namespace {

// Where a box (centre and rotation in the TCP frame, half extents in its own) reaches along the
// closing axis (TCP y) within the finger pads' band |x| <= half_band, as {lowest, highest}; empty
// if the band misses it. The fingers meet only that part: a phone turned 10 degrees is 7.5 cm
// across the pads, though its whole 14 cm length spans 9.3 cm along the closing axis. The
// extremes of a box cut by two planes lie at its corners inside the band or where its edges
// cross the planes.
std::optional<std::pair<double, double>> closing_extent(const Eigen::Isometry3d& in_tcp, const Eigen::Vector3d& half,
                                                        double half_band) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int i = 0; i < 8; ++i)
    corners[i] = in_tcp * Eigen::Vector3d((i & 1 ? 1 : -1) * half.x(), (i & 2 ? 1 : -1) * half.y(), (i & 4 ? 1 : -1) * half.z());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto take = [&](const Eigen::Vector3d& p) {
    lo = std::min(lo, p.y());
    hi = std::max(hi, p.y());
  };
  for (const auto& p : corners)
    if (std::abs(p.x()) <= half_band) take(p);
  for (int i = 0; i < 8; ++i)
    for (int axis = 0; axis < 3; ++axis) {
      const int j = i | (1 << axis);  // the edge from corner i along one axis
      if (j == i) continue;
      const Eigen::Vector3d &a = corners[i], &b = corners[j];
      for (double plane : {-half_band, half_band})
        if ((a.x() - plane) * (b.x() - plane) < 0) take(a + (b - a) * ((plane - a.x()) / (b.x() - a.x())));
    }
  if (lo > hi) return std::nullopt;
  return std::make_pair(lo, hi);
}

}  // namespace

int World::close_gripper() {
  gripper_open_ = false;
  if (held_ >= 0) return held_;
  // Look for the graspable object nearest the TCP that the pads meet (more of it than
  // robot::kHoldingOpening_m across) and that fits between the fingers.
  const Eigen::Isometry3d tcp = tcp_pose();
  const double finger_length = 0.055, finger_width = 0.02;
  int best = -1;
  double best_distance = 1e9, best_width = 0;
  for (int id = 0; id < object_count(); ++id) {
    const ObjectSpec& spec = impl_->specs[id];
    if (!spec.graspable || spec.mass_kg <= 0) continue;
    // The grasped part's centre in the TCP frame and its half extents (object frame): the
    // grasp region, or else the object's bounding box about its origin.
    Eigen::Isometry3d in_tcp = tcp.inverse() * object_pose(id);
    Eigen::Vector3d half;
    if (spec.grasp_region.isEmpty()) {
      btVector3 lo, hi;
      impl_->objects[id].shape->getAabb(btTransform::getIdentity(), lo, hi);
      half << (hi - lo).x() / 2, (hi - lo).y() / 2, (hi - lo).z() / 2;
    } else {
      in_tcp = in_tcp * Eigen::Translation3d(spec.grasp_region.center());
      half = spec.grasp_region.sizes() / 2;
    }
    const double half_y = (in_tcp.linear().row(1).cwiseAbs()) * half;
    const Eigen::Vector3d c = in_tcp.translation();
    const auto across = closing_extent(in_tcp, half, finger_width / 2);  // what the pads meet
    const bool between = across && across->second - across->first > robot::kHoldingOpening_m &&
                         std::max(-across->first, across->second) <= opening_m_ / 2 + 0.002 &&
                         c.z() >= -finger_length - 0.01 && c.z() <= 0.01 + half_y;
    if (between && c.norm() < best_distance) {
      best = id;
      best_distance = c.norm();
      best_width = across->second - across->first;
    }
  }
  const double closed = best >= 0 ? best_width : 0.0;
  // Close over a quarter second so the motion is visible in recorded demonstrations.
  step_towards(q_, std::max(closed, 0.0), 0.25);
  if (best >= 0) {
    held_ = best;
    auto& body = *impl_->objects[best].body;
    impl_->world.removeRigidBody(&body);
    body.setMassProps(0, btVector3(0, 0, 0));
    body.setCollisionFlags(body.getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body.setActivationState(DISABLE_DEACTIVATION);
    body.setLinearVelocity(btVector3(0, 0, 0));
    body.setAngularVelocity(btVector3(0, 0, 0));
    impl_->world.addRigidBody(&body);
    held_from_tcp_ = tcp_pose().inverse() * object_pose(best);
  }
  return held_;
}

void World::open_gripper() {
  gripper_open_ = true;
  if (held_ >= 0) {
    auto& body = *impl_->objects[held_].body;
    const double mass = impl_->specs[held_].mass_kg;
    impl_->world.removeRigidBody(&body);
    btVector3 inertia(0, 0, 0);
    body.getCollisionShape()->calculateLocalInertia(mass, inertia);
    body.setCollisionFlags(body.getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
    body.setMassProps(mass, inertia);
    body.updateInertiaTensor();
    body.setLinearVelocity(btVector3(0, 0, 0));
    body.setAngularVelocity(btVector3(0, 0, 0));
    body.forceActivationState(ACTIVE_TAG);
    impl_->world.addRigidBody(&body);
    held_ = -1;
  }
  step_towards(q_, robot_.max_finger_opening_m(), 0.25);
}

std::string World::robot_collision() const {
  auto& w = const_cast<btDiscreteDynamicsWorld&>(impl_->world);  // contactPairTest is not const
  const auto& links = robot_.links();
  for (std::size_t i = 0; i < impl_->links.size(); ++i) {
    if (!impl_->links[i].body) continue;
    PenetrationCallback table(0.002);
    w.contactPairTest(impl_->links[i].body.get(), impl_->table.body.get(), table);
    if (table.touching) return "collision:" + links[i].name + "-table";
  }
  for (const auto& [a, b] : impl_->checked_link_pairs) {
    PenetrationCallback self(0.002);
    w.contactPairTest(impl_->links[a].body.get(), impl_->links[b].body.get(), self);
    if (self.touching) return "collision:" + links[a].name + "-" + links[b].name;
  }
  return "";
}

std::string World::robot_object_contact(double tolerance_m) const {
  auto& w = const_cast<btDiscreteDynamicsWorld&>(impl_->world);  // contactPairTest is not const
  for (std::size_t i = 0; i < impl_->links.size(); ++i) {
    if (!impl_->links[i].body) continue;
    for (int id = 0; id < object_count(); ++id) {
      if (id == held_ || !impl_->specs[id].collides) continue;
      PenetrationCallback contact(tolerance_m);
      w.contactPairTest(impl_->links[i].body.get(), impl_->objects[id].body.get(), contact);
      if (contact.touching) return robot_.links()[i].name + "-" + impl_->specs[id].name;
    }
  }
  return "";
}

const btCollisionWorld& World::collision_world() const { return impl_->world; }

}  // namespace qte::world
