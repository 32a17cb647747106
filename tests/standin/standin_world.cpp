// standin-world: the real world of robot-step played by the simulator, for tests. It speaks the
// robot spool (formats/robot-spool.md) as an arm driver and a camera recorder do: it executes
// each motion file in Bullet, renders the front camera into the colour and 16-bit depth PNGs a
// RealSense recorder writes, and reports the joints reached. A person's part (putting the scene
// back, saying whether the task is done) goes through DIR/standin/, for tests/standin/judge.sh:
//   standin/reset-<k>.request  "task variation seed"  ->  standin/reset-<k>.ready
//   standin/<motion>.outcome   success, failure <reason> or continue, after each motion
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "render/camera.hpp"
#include "robot/xarm_export.hpp"
#include "sim_step/simulator.hpp"
#include "voxels/observation_cloud.hpp"

using namespace qte;
namespace fs = std::filesystem;

namespace {

std::string read_all(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const fs::path& path, const std::string& text) { write_file_atomically(path.string(), text.data(), text.size()); }

struct Motion {
  std::vector<double> time_s, joints;  // radians
  int gripper_after = 850;
};

// An xarm-export file: '#' comments, the header, then time_s, 7 angles (deg), gripper units.
Motion read_motion(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  bool header = false;
  Motion motion;
  int number = 0;
  while (std::getline(in, line)) {
    number += 1;
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      if (line != "time_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,j7_deg,gripper")
        throw Error(path.string() + ": line " + std::to_string(number) + ": expected the header");
      header = true;
      continue;
    }
    std::istringstream cells(line);
    std::string cell;
    std::vector<double> values;
    while (std::getline(cells, cell, ',')) values.push_back(std::stod(cell));
    if (values.size() != 9) throw Error(path.string() + ": line " + std::to_string(number) + ": expected 9 columns");
    motion.time_s.push_back(values[0]);
    for (int k = 1; k <= 7; ++k) motion.joints.push_back(values[k] * M_PI / 180.0);
    motion.gripper_after = static_cast<int>(values[8]);
  }
  if (motion.time_s.empty()) throw Error(path.string() + ": no rows");
  return motion;
}

class StandIn {
 public:
  StandIn(fs::path spool, const robot::RobotModel& robot, sim_step::SimulatorOptions options)
      : spool_(std::move(spool)), robot_(robot), simulator_(robot, std::move(options)) {
    fs::create_directories(spool_ / "standin");
  }

  // One pass over the spool; false once `stop` is there.
  bool serve() {
    if (fs::exists(spool_ / "stop")) return false;
    std::map<std::pair<long, long>, std::string> requests;  // (session, n) -> name, in order
    for (const auto& entry : fs::directory_iterator(spool_)) {
      const std::string file = entry.path().filename().string();
      for (const std::string suffix : {".xarm.csv", ".request"}) {
        if (file.size() <= suffix.size() || file.compare(file.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
        const std::string name = file.substr(0, file.size() - suffix.size());
        long session = 0, n = 0;
        if (answered_.count(name) || std::sscanf(name.c_str(), "%*[a-z]-%ld-%ld", &session, &n) != 2) continue;
        requests[{session, n}] = name;
      }
    }
    for (const auto& [key, name] : requests) {
      if (fs::exists(spool_ / "stop")) return false;
      if (name.rfind("motion-", 0) == 0) move(name);
      else capture(name);
      answered_.insert(name);
    }
    for (const auto& entry : fs::directory_iterator(spool_ / "standin")) {
      const std::string file = entry.path().filename().string();
      if (file.size() > 8 && file.compare(file.size() - 8, 8, ".request") == 0 && !answered_.count(file)) {
        reset(entry.path());
        answered_.insert(file);
      }
    }
    return true;
  }

 private:
  void reset(const fs::path& request) {
    std::istringstream words(read_all(request));
    std::string task;
    int32_t variation = 0;
    int64_t seed = 0;
    words >> task >> variation >> seed;
    stream::Record record("reset");
    record.set_string("task", task);
    record.set_scalar<int32_t>("variation", variation);
    record.set_scalar<int64_t>("seed", seed);
    simulator_.handle(record, [&](const stream::Record& obs) { last_ = obs; });
    fs::path ready = request;
    ready.replace_extension(".ready");
    write_text(ready, "");
  }

  void move(const std::string& name) {
    const fs::path answer = spool_ / (name + ".done");
    if (!last_) return write_text(spool_ / (name + ".fault"), "no scene: the stand-in world was never reset\n");
    Motion motion;
    try {
      motion = read_motion(spool_ / (name + ".xarm.csv"));
    } catch (const std::exception& e) {
      return write_text(spool_ / (name + ".fault"), std::string(e.what()) + "\n");
    }
    const robot::JointVector now = simulator_.world()->joint_positions();
    const Eigen::Map<const robot::JointVector> first(motion.joints.data());
    std::string outcome = "continue";
    if (motion.time_s.size() == 1 && (first - now).cwiseAbs().maxCoeff() < 1e-6) {
      // A move to where the arm is (the start pose after a reset): nothing to do.
    } else if (motion.time_s.size() == 1) {
      return write_text(spool_ / (name + ".fault"), "the stand-in world starts episodes at the simulation's ready pose only\n");
    } else if (simulator_.episode_over()) {
      return write_text(spool_ / (name + ".fault"), "the stand-in's episode is over: reset the scene first\n");
    } else {
      // A driver reaches the first row slowly from wherever the arm is: here at 0.5 rad/s.
      if ((first - now).cwiseAbs().maxCoeff() > 1e-3) {
        const double approach = std::max(0.1, (first - now).cwiseAbs().maxCoeff() / 0.5);
        for (double& t : motion.time_s) t += approach;
        motion.time_s.insert(motion.time_s.begin(), 0.0);
        motion.joints.insert(motion.joints.begin(), now.data(), now.data() + 7);
      }
      const int64_t n = static_cast<int64_t>(motion.time_s.size());
      stream::Record trajectory("trajectory");
      trajectory.set<double>("time_s", {n}, motion.time_s);
      trajectory.set<double>("joint_positions", {n, 7}, motion.joints);
      trajectory.set_scalar<uint8_t>("gripper_open", motion.gripper_after > robot::kXarmGripperOpenUnits / 2);
      simulator_.handle(trajectory, [&](const stream::Record& obs) { last_ = obs; });
      if (last_->scalar<uint8_t>("success")) outcome = "success";
      else if (last_->has("failure")) outcome = "failure " + last_->string("failure");
    }
    const robot::JointVector q = simulator_.world()->joint_positions();
    std::string done;
    char number[32];
    for (int k = 0; k < 7; ++k) {
      std::snprintf(number, sizeof number, "%.6f,", q[k] * 180.0 / M_PI);
      done += number;
    }
    done += std::to_string(robot::xarm_gripper_units(simulator_.world()->finger_opening_m(), robot_)) + "\n";
    write_text(spool_ / "standin" / (name + ".outcome"), outcome + "\n");
    write_text(answer, done);
  }

  void capture(const std::string& name) {
    if (!last_) return write_text(spool_ / (name + ".fault"), "no scene: the stand-in world was never reset\n");
    const auto rgb = last_->array<uint8_t>("front.rgb");
    const auto depth = last_->array<float>("front.depth");
    const int h = static_cast<int>(rgb.shape[0]), w = static_cast<int>(rgb.shape[1]);
    render::save_rgb_png((spool_ / (name + ".color.png")).string(),
                         cv::Mat(h, w, CV_8UC3, const_cast<uint8_t*>(rgb.data)));
    const std::vector<uint16_t> mm = voxels::depth_in_mm(depth.data, static_cast<std::size_t>(h) * w);
    render::save_mm_png((spool_ / (name + ".depth.png")).string(),
                        cv::Mat(h, w, CV_16UC1, const_cast<uint16_t*>(mm.data())));
    write_text(spool_ / (name + ".ready"), "");
  }

  fs::path spool_;
  const robot::RobotModel& robot_;
  sim_step::Simulator simulator_;
  std::optional<stream::Record> last_;
  std::set<std::string> answered_;
};

cli::Usage usage() {
  cli::Usage u;
  u.name = "standin-world";
  u.summary = "the simulator behind a robot spool, standing in for a real arm, camera and person (tests)";
  u.description = {"Serves the robot spool DIR (formats/robot-spool.md) until DIR/stop appears."};
  u.options = {
      {"spool", "DIR", "the spool directory", ""},
      {"image-size", "WxH", "the camera's resolution", "128x128"},
  };
  return u;
}

void run(const cli::Arguments& args) {
  const auto [width, height] = args.size("image-size", 8, 8, 4096, 4096);
  sim_step::SimulatorOptions options = sim_step::options_for_cameras({"front"}, width, height);
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  StandIn world(args.text("spool"), robot, options);
  while (world.serve()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  std::cerr << "standin-world: stopped\n";
}

}  // namespace

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
