#include "robot/robot_model.hpp"

#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "common/error.hpp"

#ifndef QTE_INSTALLED_DATA_DIR
#define QTE_INSTALLED_DATA_DIR ""
#endif
#ifndef QTE_SOURCE_DATA_DIR
#define QTE_SOURCE_DATA_DIR ""
#endif

namespace qte::robot {
namespace {

Eigen::Isometry3d to_eigen(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << pose.position.x, pose.position.y, pose.position.z;
  t.linear() = Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y,
                                  pose.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  return t;
}

bool file_exists(const std::string& path) { return std::ifstream(path).good(); }

// One collision element of a link: a box, cylinder or sphere placed in the link's frame.
Shape shape_from(const urdf::Collision& collision, const std::string& path, const std::string& link) {
  Shape shape;
  shape.link_from_shape = to_eigen(collision.origin);
  const auto& g = collision.geometry;
  if (g->type == urdf::Geometry::BOX) {
    auto box = std::static_pointer_cast<urdf::Box>(g);
    shape.kind = Shape::Kind::box;
    shape.size << box->dim.x, box->dim.y, box->dim.z;
  } else if (g->type == urdf::Geometry::CYLINDER) {
    auto c = std::static_pointer_cast<urdf::Cylinder>(g);
    shape.kind = Shape::Kind::cylinder;
    shape.size << c->radius, c->length, 0;
  } else if (g->type == urdf::Geometry::SPHERE) {
    shape.kind = Shape::Kind::sphere;
    shape.size << std::static_pointer_cast<urdf::Sphere>(g)->radius, 0, 0;
  } else {
    throw Error(path + ": link " + link + ": only box, cylinder and sphere collision shapes are supported");
  }
  return shape;
}

// A joint's type, origin in its parent link, axis and limits (its links are set by the caller).
Joint joint_from(const urdf::Joint& joint, const std::string& path) {
  Joint j;
  j.name = joint.name;
  j.origin = to_eigen(joint.parent_to_joint_origin_transform);
  j.axis << joint.axis.x, joint.axis.y, joint.axis.z;
  if (joint.type == urdf::Joint::REVOLUTE) j.type = Joint::Type::revolute;
  else if (joint.type == urdf::Joint::PRISMATIC) j.type = Joint::Type::prismatic;
  else if (joint.type == urdf::Joint::FIXED) j.type = Joint::Type::fixed;
  else throw Error(path + ": joint " + j.name + ": unsupported joint type");
  if (joint.limits) {
    j.lower = joint.limits->lower;
    j.upper = joint.limits->upper;
    j.max_velocity = joint.limits->velocity;
  }
  j.finger = j.type == Joint::Type::prismatic && j.name.find("finger") != std::string::npos;
  return j;
}

}  // namespace

const char* const kDataDirEnvironment =
    "QTE_DATA_DIR: the directory that holds xarm7.urdf, the robot description. Unset, the program looks in "
    "share/qte beside its own directory: PREFIX/share/qte for an install (make install PREFIX=...), BUILD/share/qte "
    "in a build tree; an install can be moved as a whole.";

std::string default_data_dir() {
  if (const char* env = std::getenv("QTE_DATA_DIR")) {
    if (!file_exists(std::string(env) + "/xarm7.urdf"))
      throw Error("QTE_DATA_DIR=" + std::string(env) + " holds no xarm7.urdf (the toolkit's robot description)");
    return env;
  }
  // share/qte beside the program's own directory or one or two above it: PREFIX/bin/x finds
  // PREFIX/share/qte, BUILD/tools/x and BUILD/tests/bench/x find BUILD/share/qte.
  std::error_code error;
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
  std::filesystem::path dir = error ? std::filesystem::path() : program.parent_path();
  for (int up = 0; up < 3 && !dir.empty(); ++up, dir = dir.parent_path()) {
    const std::filesystem::path data = dir.parent_path() / "share" / "qte";
    if (file_exists((data / "xarm7.urdf").string())) return data.string();
    if (dir == dir.parent_path()) break;
  }
  throw Error("cannot find the robot description xarm7.urdf in share/qte beside " +
              (program.empty() ? std::string("the program") : program.parent_path().string()) +
              " (an install puts it in PREFIX/share/qte): set QTE_DATA_DIR to the directory that holds it");
}

RobotModel RobotModel::xarm7() { return load_urdf(default_data_dir() + "/xarm7.urdf"); }

RobotModel RobotModel::load_urdf(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open robot description " + path);
  std::stringstream text;
  text << in.rdbuf();
  urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(text.str());
  if (!urdf) throw Error(path + ": not a valid URDF robot description");

  RobotModel model;
  std::map<std::string, int> link_ids;
  // Depth-first from the root so parents always precede children.
  std::function<void(const urdf::LinkConstSharedPtr&, int)> visit =
      [&](const urdf::LinkConstSharedPtr& link, int parent_joint) {
        Link out;
        out.name = link->name;
        out.parent_joint = parent_joint;
        for (const auto& collision : link->collision_array) out.shapes.push_back(shape_from(*collision, path, link->name));
        if (link->visual && link->visual->material)
          out.colour << link->visual->material->color.r, link->visual->material->color.g,
              link->visual->material->color.b;
        const int id = static_cast<int>(model.links_.size());
        link_ids[out.name] = id;
        model.links_.push_back(out);
        for (const auto& child_joint : link->child_joints) {
          Joint j = joint_from(*child_joint, path);
          j.parent_link = id;
          const int joint_id = static_cast<int>(model.joints_.size());
          model.joints_.push_back(j);
          const auto child = urdf->getLink(child_joint->child_link_name);
          model.joints_[joint_id].child_link = static_cast<int>(model.links_.size());
          visit(child, joint_id);
        }
      };
  visit(urdf->getRoot(), -1);

  auto tcp = link_ids.find("tcp");
  if (tcp == link_ids.end()) throw Error(path + ": no link named 'tcp' (the tool centre point)");
  model.tcp_link_ = tcp->second;
  // The arm joints are the revolute joints on the chain from the root to the TCP.
  std::vector<int> chain;
  for (int j = model.links_[model.tcp_link_].parent_joint; j >= 0;
       j = model.links_[model.joints_[j].parent_link].parent_joint)
    if (model.joints_[j].type == Joint::Type::revolute) chain.insert(chain.begin(), j);
  if (chain.size() != kArmJoints)
    throw Error(path + ": expected 7 revolute joints from the root to 'tcp', found " +
                std::to_string(chain.size()));
  for (int i = 0; i < kArmJoints; ++i) model.joints_[chain[i]].arm_index = i;
  for (const auto& j : model.joints_)
    if (j.finger) model.max_opening_m_ += j.upper;
  return model;
}

int RobotModel::link_index(const std::string& name) const {
  for (std::size_t i = 0; i < links_.size(); ++i)
    if (links_[i].name == name) return static_cast<int>(i);
  throw Error("robot has no link '" + name + "'");
}

JointVector RobotModel::lower_limits() const {
  JointVector v;
  for (const auto& j : joints_)
    if (j.arm_index >= 0) v[j.arm_index] = j.lower;
  return v;
}

JointVector RobotModel::upper_limits() const {
  JointVector v;
  for (const auto& j : joints_)
    if (j.arm_index >= 0) v[j.arm_index] = j.upper;
  return v;
}

JointVector RobotModel::max_velocities() const {
  JointVector v;
  for (const auto& j : joints_)
    if (j.arm_index >= 0) v[j.arm_index] = j.max_velocity;
  return v;
}

std::vector<std::pair<int, int>> RobotModel::self_collision_pairs() const {
  auto moving_joints_above = [&](int link) {
    int depth = 0;
    for (int j = links_[link].parent_joint; j >= 0; j = links_[joints_[j].parent_link].parent_joint)
      if (joints_[j].type != Joint::Type::fixed && !joints_[j].finger) ++depth;
    return depth;
  };
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < static_cast<int>(links_.size()); ++a)
    for (int b = a + 1; b < static_cast<int>(links_.size()); ++b)
      if (!links_[a].shapes.empty() && !links_[b].shapes.empty() &&
          std::abs(moving_joints_above(a) - moving_joints_above(b)) > 2)
        pairs.emplace_back(a, b);
  return pairs;
}

std::vector<Eigen::Isometry3d> RobotModel::link_poses(const JointVector& q,
                                                      double opening_m) const {
  std::vector<Eigen::Isometry3d> poses(links_.size(), Eigen::Isometry3d::Identity());
  for (const Joint& j : joints_) {
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    if (j.type == Joint::Type::revolute && j.arm_index >= 0)
      motion.linear() = Eigen::AngleAxisd(q[j.arm_index], j.axis).toRotationMatrix();
    else if (j.finger)
      motion.translation() = j.axis * std::clamp(opening_m / 2, 0.0, j.upper);
    poses[j.child_link] = poses[j.parent_link] * j.origin * motion;
  }
  return poses;
}

Eigen::Isometry3d RobotModel::tcp_pose(const JointVector& q) const {
  return link_poses(q, 0)[tcp_link_];
}

Eigen::Matrix<double, 6, kArmJoints> RobotModel::tcp_jacobian(const JointVector& q) const {
  const auto poses = link_poses(q, 0);
  const Eigen::Vector3d tip = poses[tcp_link_].translation();
  Eigen::Matrix<double, 6, kArmJoints> jacobian = Eigen::Matrix<double, 6, kArmJoints>::Zero();
  for (const Joint& j : joints_) {
    if (j.arm_index < 0) continue;
    // The child link frame coincides with the joint frame (motion is a pure rotation).
    const Eigen::Isometry3d& frame = poses[j.child_link];
    const Eigen::Vector3d axis = frame.linear() * j.axis;
    jacobian.block<3, 1>(0, j.arm_index) = axis.cross(tip - frame.translation());
    jacobian.block<3, 1>(3, j.arm_index) = axis;
  }
  return jacobian;
}

}  // namespace qte::robot
