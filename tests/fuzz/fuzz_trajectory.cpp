// libFuzzer target: 'reset' and 'trajectory' records through sim-step's simulator (one Bullet
// world per reset, 16x16 images; trajectories capped at 1 s so that an input stays fast).
// Run: make fuzz.
#include "fuzz_support.hpp"
#include "robot/robot_model.hpp"
#include "sim_step/simulator.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const qte::robot::RobotModel robot = qte::robot::RobotModel::xarm7();
  qte::sim_step::SimulatorOptions options = qte::sim_step::options_for_cameras({"front"}, 16, 16);
  options.max_trajectory_s = 1.0;
  options.render_threads = 1;
  qte::sim_step::Simulator simulator(robot, options);
  qte::fuzz::for_each_record(data, size, [&](const qte::stream::Record& record) {
    simulator.handle(record, [](const qte::stream::Record&) {});
  });
  return 0;
}
