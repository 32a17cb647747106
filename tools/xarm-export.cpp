// xarm-export: plan-path's trajectories as files a real xArm 7 plays.

#include <cstdio>
#include <iostream>

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "common/indexed_name.hpp"
#include "robot/robot_model.hpp"
#include "robot/xarm_export.hpp"
#include "stream/field_names.hpp"
#include "stream/reader.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "xarm-export";
  u.summary = "write planned trajectories as xArm 7 joint files at a fixed control rate";
  u.description = {
      "Reads record streams holding 'trajectory' records (plan-path's output, or a whole "
      "episode) and writes each planned motion as DIR/<record index>.xarm.csv, ready for a real "
      "xArm 7: a few '#' comment lines (source, rate, units), a header, then one row per control "
      "tick: time_s, the 7 joint angles j1_deg..j7_deg in degrees, and gripper, the xArm "
      "gripper's position to hold (0 closed .. 850 open). Rows are the path sampled every "
      "1/--rate seconds and at its end, linearly between the planned waypoints (as sim-step "
      "follows them); the gripper holds its state from before the motion (the last observation's "
      "opening, open when none came before), and one last row --settle seconds later commands "
      "the trajectory's gripper_open (850 or 0).",
      "Every path is checked before its file is written, on the waypoints and on the sampled "
      "rows: finite, time starting at 0 and increasing, at most 60 s, within the xArm 7's joint "
      "limits, and no joint faster than its 180 deg/s limit. A path that fails is an error "
      "naming the record and the reason; a 'trajectory' that holds only a planner failure has no "
      "motion and is skipped with a line on standard error. examples/robot/xarm_play.py plays the "
      "files on the arm with UFACTORY's Python SDK.",
      "The files appear all or none: a run that fails (a path refused, damaged input) leaves DIR "
      "as it was, so no arm is given the first moves of an episode whose later ones were refused.",
  };
  u.arguments = {cli::input_files("record streams")};
  const robot::XarmTiming timing;
  u.options = {
      {"dir", "DIR", "where the files go (created if missing)", "."},
      cli::real_option("rate", "HZ", "control rate of the rows (the xArm's servo mode takes up to 250 Hz)",
                       cli::default_text(timing.rate_hz), robot::XarmTiming::kMinRate_hz, robot::XarmTiming::kMaxRate_hz),
      cli::real_option("settle", "S", "seconds after a motion's end before its gripper command",
                       cli::default_text(timing.settle_s), robot::XarmTiming::kMinSettle_s,
                       robot::XarmTiming::kMaxSettle_s),
  };
  u.examples = {
      {"plan-path < episode.rec | xarm-export --dir moves/", "plan each action of a saved episode for the arm"},
      {"python3 examples/robot/xarm_play.py --ip 192.168.1.185 moves/000004.xarm.csv", "play one move on the robot"},
  };
  u.see_also = {"plan-path(1)", "sim-step(1)", "qte-stream(5)"};
  u.environment = robot::kDataDirEnvironment;
  return u;
}

static void run(const cli::Arguments& args) {
  const std::vector<std::string> files = args.inputs();
  const std::string dir = args.text("dir");
  const double rate = args.real("rate"), settle = args.real("settle");
  OutputDirectory out(dir);
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  robot::XarmEpisode episode(robot, rate, settle);
  for (const std::string& file : files) {
    stream::RecordReader reader(file);
    while (auto record = reader.next()) {
      if (record->type() == record_type::obs && record->has(fields::gripper_opening_m))
        episode.observe_gripper(record->scalar<double>(fields::gripper_opening_m));
      if (record->type() != record_type::trajectory) continue;
      const auto index = static_cast<unsigned long long>(record->position.record_index);
      if (record->has(fields::failure) && !record->has(fields::time_s)) {
        std::cerr << "xarm-export: " << file << ": record " << index << ": no motion ("
                  << record->string(fields::failure) << ")\n";
        continue;
      }
      const auto times = record->array<double>(fields::time_s);
      const auto joints = record->array<double>(fields::joint_positions);
      if (times.shape.size() != 1 || joints.shape != stream::Shape{times.size(), robot::kArmJoints})
        record->fail(fields::joint_positions, "float64 [N, 7] with N the length of time_s");
      const bool open = !record->has(fields::gripper_open) || record->scalar<uint8_t>(fields::gripper_open) != 0;
      std::vector<robot::XarmRow> rows;
      try {
        rows = episode.motion(times.data, joints.data, times.size(), open);
      } catch (const Error& e) {
        throw StreamError(record->position, e.what());
      }
      const std::string name = indexed_name(index, "xarm.csv");
      const std::string comment = "# xArm 7 joint trajectory: " + file + ", record " + std::to_string(index) +
                                  "\n# rows every " + std::to_string(1.0 / rate) +
                                  " s; joints in degrees; gripper 0 (closed) .. 850 (open)\n";
      const std::string csv = robot::xarm_csv(rows, comment);
      out.write_file(name, csv.data(), csv.size());
    }
  }
  out.commit();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
