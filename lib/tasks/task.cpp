#include "tasks/task.hpp"

#include <algorithm>
#include <utility>

#include "common/error.hpp"
#include "tasks/catalogue.hpp"

namespace qte::tasks {

// Every task, in the order usage texts list them: the one place a task is registered, a line
// each (tasks/<name>.cpp defines make_<name>()).
#define QTE_EVERY_TASK(TASK)              \
  TASK(reach_target)                      \
  TASK(pick_and_lift)                     \
  TASK(lift_numbered_block)               \
  TASK(reach_prism)                       \
  TASK(pick_and_lift_small)               \
  TASK(stack_blocks)                      \
  TASK(setup_checkers)                    \
  TASK(take_lid_off_saucepan)             \
  TASK(pick_up_cup)                       \
  TASK(put_rubbish_in_bin)                \
  TASK(stack_wine)                        \
  TASK(phone_on_base)                     \
  TASK(take_umbrella_out_of_umbrella_stand)

#define QTE_DECLARE_TASK(name) std::unique_ptr<Task> make_##name();
QTE_EVERY_TASK(QTE_DECLARE_TASK)

namespace {

const std::vector<std::pair<std::string, std::unique_ptr<Task> (*)()>>& registry() {
#define QTE_REGISTER_TASK(name) {#name, make_##name},
  static const std::vector<std::pair<std::string, std::unique_ptr<Task> (*)()>> tasks = {QTE_EVERY_TASK(QTE_REGISTER_TASK)};
  return tasks;
}

}  // namespace

std::vector<std::string> task_names() {
  std::vector<std::string> names;
  for (const auto& [name, make] : registry()) names.push_back(name);
  return names;
}

std::unique_ptr<Task> make_task(const std::string& name) {
  for (const auto& [known, make] : registry())
    if (known == name) return make();
  throw Error("unknown task '" + name + "' (known tasks: " + task_list() + ")");
}

std::string task_list() {
  std::string list;
  for (const auto& n : task_names()) list += (list.empty() ? "" : ", ") + n;
  return list;
}

Eigen::Matrix3d top_down(double yaw_rad) {
  // TCP z down (rotate pi about x), then yaw about world z; TCP y is the closing axis.
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

const std::vector<NamedColour>& colours() {
  // RLBench's colour list, so variations mean the same thing.
  static const std::vector<NamedColour> list = {
      {"red", {1.0f, 0.0f, 0.0f}},      {"maroon", {0.5f, 0.0f, 0.0f}},
      {"lime", {0.0f, 1.0f, 0.0f}},     {"green", {0.0f, 0.5f, 0.0f}},
      {"blue", {0.0f, 0.0f, 1.0f}},     {"navy", {0.0f, 0.0f, 0.5f}},
      {"yellow", {1.0f, 1.0f, 0.0f}},   {"cyan", {0.0f, 1.0f, 1.0f}},
      {"magenta", {1.0f, 0.0f, 1.0f}},  {"silver", {0.75f, 0.75f, 0.75f}},
      {"gray", {0.5f, 0.5f, 0.5f}},     {"orange", {1.0f, 0.5f, 0.0f}},
      {"olive", {0.5f, 0.5f, 0.0f}},    {"purple", {0.5f, 0.0f, 0.5f}},
      {"teal", {0.0f, 0.5f, 0.5f}},     {"azure", {0.0f, 0.5f, 1.0f}},
      {"violet", {0.5f, 0.0f, 1.0f}},   {"rose", {1.0f, 0.0f, 0.5f}},
      {"black", {0.0f, 0.0f, 0.0f}},    {"white", {1.0f, 1.0f, 1.0f}},
  };
  return list;
}

std::vector<Eigen::Vector3d> sample_separated(std::mt19937_64& rng, int count,
                                              const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                              double min_distance_m) {
  for (int attempt = 0; attempt < 1000; ++attempt) {
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < count; ++i) {
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = std::uniform_real_distribution<double>(lo[k], hi[k])(rng);
      points.push_back(p);
    }
    bool ok = true;
    for (int i = 0; i < count && ok; ++i)
      for (int j = i + 1; j < count && ok; ++j) ok = (points[i] - points[j]).norm() >= min_distance_m;
    if (ok) return points;
  }
  throw Error("cannot place " + std::to_string(count) + " objects " +
              std::to_string(min_distance_m) + " m apart in the task region");
}

std::vector<Eigen::Vector3d> place_one_by_one(std::mt19937_64& rng, int count, const Eigen::Vector3d& lo,
                                              const Eigen::Vector3d& hi, double min_distance_m) {
  for (int layout = 0; layout < 100; ++layout) {
    std::vector<Eigen::Vector3d> points;
    try {
      while (static_cast<int>(points.size()) < count) points.push_back(sample_away_from(rng, points, lo, hi, min_distance_m));
      return points;
    } catch (const Error&) {  // boxed in: start the layout again
    }
  }
  throw Error("cannot place " + std::to_string(count) + " objects " + std::to_string(min_distance_m) +
              " m apart in the task region");
}

Eigen::Vector3d sample_away_from(std::mt19937_64& rng, const std::vector<Eigen::Vector3d>& others,
                                 const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double min_distance_m) {
  for (int attempt = 0; attempt < 1000; ++attempt) {
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) p[k] = std::uniform_real_distribution<double>(lo[k], hi[k])(rng);
    if (std::all_of(others.begin(), others.end(), [&](const Eigen::Vector3d& o) { return (p - o).norm() >= min_distance_m; }))
      return p;
  }
  throw Error("cannot place an object " + std::to_string(min_distance_m) + " m from the others in the task region");
}

std::vector<int> pick_distinct(std::mt19937_64& rng, int count, int range, int excluded) {
  std::vector<int> out;
  while (static_cast<int>(out.size()) < count) {
    const int c = std::uniform_int_distribution<int>(0, range - 1)(rng);
    if (c != excluded && std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
  }
  return out;
}

}  // namespace qte::tasks
