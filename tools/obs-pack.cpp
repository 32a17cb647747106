// obs-pack: saved RGB-D camera frames (colour + 16-bit depth PNGs, or .pcd clouds) to 'obs' records.
#include <iostream>

#include "camera_recordings/camera_options.hpp"
#include "camera_recordings/recording.hpp"
#include "cli/command.hpp"
#include "robot/robot_model.hpp"
#include "cli/stream_options.hpp"
#include "stream/writer.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "obs-pack";
  u.summary = "turn saved RGB-D camera frames into observation records";
  u.description = {
      "Reads a real camera's saved frames and writes one 'obs' record per frame, the records "
      "sim-step writes, so voxelize, qte-select and plan-path run on them as on simulated ones. "
      "A frame is a colour PNG (--rgb) with a 16-bit depth PNG (--depth; counts of --depth-unit "
      "metres, 0 = no return; a RealSense saves millimetres), or a .pcd point cloud (--pcd) in the "
      "camera frame. File names are printf patterns with one integer conversion "
      "(frames/color_%06d.png); frames are read from --start until the first index whose files "
      "are missing, or --count of them.",
      "The camera is given by --intrinsics (fx, fy, cx, cy in pixels; needed for depth images) "
      "and its pose: --camera-pose (x, y, z, qx, qy, qz, qw) or --extrinsics (the 4x4 "
      "camera-to-world matrix, row by row), camera axes as OpenCV's (x right, y down, z forward). "
      "The world frame is the simulation's: the robot's base at (-0.3, 0, 0.752), facing +x; "
      "express the camera's calibration there, so scene bounds and networks trained in "
      "simulation apply.",
      "With --joints each frame's robot state comes from a CSV row: 7 joint angles in radians "
      "and optionally the gripper opening in metres (the xArm gripper's 0-850 units are 0-0.085 "
      "m); the gripper pose follows by forward kinematics. Without it the records carry no joint "
      "state and plan-path refuses them; qte-select needs only the gripper opening (open). "
      "Records are written whole or not at all; a bad file stops with one line naming it.",
      "A tele-operated or kinesthetic demonstration gives --joint-log instead of --joints: the arm "
      "driver's log, one row per time stamp: time (s), 7 joint angles (rad), the gripper opening "
      "(m) and optionally 1 (gripper open) or 0 (closed); without that column a gripper more than "
      "half open is open, which a gripper closed on a wide object may be. --frame-times gives each "
      "frame's time on the log's clock, one row per frame from --start; the frames packed are the "
      "ones it times. A frame's joints and opening are the log's interpolated linearly, its joint "
      "velocities the slope of the log over the row interval leading to the frame, its gripper "
      "state the last row's at or before it.",
      "With --success 1 (or 0) the recording is one whole demonstration, as demo-record writes "
      "one: frames numbered from 0, steps counted as demo-record counts motions (0, then 1 + the "
      "keyframes before the frame), the last frame terminal with the success given (reward 100 "
      "on success). keyframe takes it as it is; it finds the key poses where the gripper acts and "
      "where the arm stands still (every joint within 0.1 rad/s), so the log must be faster than "
      "the camera or the arm pause at each key pose. Several demonstrations go into one file with "
      "--append, which reads every frame once before the first record is appended, so that a bad "
      "frame leaves the file as it was.",
      "Files are checked before they are decoded. PNGs: at most 32768 pixels on a side and 50 "
      "million in all; the colour PNG of any colour type (reduced to 8-bit RGB), the depth PNG "
      "16-bit greyscale. .pcd files (DATA ascii, binary or binary_compressed): x, y, z 4-byte "
      "floats (TYPE F SIZE 4 COUNT 1), rgb or rgba 4 packed bytes (TYPE F or U), WIDTH x HEIGHT "
      "equal to POINTS (at most 50 million), and the file as long as the header says: ASCII "
      "data exactly POINTS lines of one number per value, each of its field's type. The joint "
      "CSV, joint log and frame times: every cell a finite number (a row of nan is refused, not "
      "taken for a header); times increasing row by row, frame times within the log's.",
  };
  u.options = {
      {"rgb", "PATTERN", "colour PNGs, e.g. frames/color_%06d.png", ""},
      {"depth", "PATTERN", "16-bit depth PNGs matching --rgb, e.g. frames/depth_%06d.png", ""},
      {"pcd", "PATTERN", "instead of --rgb/--depth: point clouds (.pcd, camera frame, with rgb if any)", ""},
      cli::integer_option("start", "N", "index of the first frame", "0", 0, 1000000000),
      cli::integer_option("count", "N",
                          "frames to read (default: until the first missing index; with --frame-times, its rows)", "",
                          1, 1000000000),
      {"joints", "FILE.csv", "robot state per frame: 7 joint angles (rad)[, gripper opening (m)]", ""},
      {"joint-log", "FILE.csv", "instead of --joints: time (s), 7 joint angles (rad), gripper opening (m)[, open 1/0]",
       ""},
      {"frame-times", "FILE.csv", "each frame's time (s) on the joint log's clock, one row per frame", ""},
      cli::integer_option("success", "0|1",
                          "the recording is one demonstration, successful (1) or not (0); needs --joint-log", "", 0, 1),
      {"task", "NAME", "the records' task name", "real"},
      cli::integer_option("episode-length", "N", "next-best poses per episode (the networks' time input scales by it)",
                          "10", 1, 1000),
  };
  u.add_options(camera_recordings::camera_setup_options());
  u.options.push_back(cli::output_file());
  u.add_options(cli::append_options());
  u.examples = {
      {"obs-pack --rgb rec/color_%06d.png --depth rec/depth_%06d.png --intrinsics 615.2,615.0,320.5,240.1 "
       "--camera-pose 1.05,0,1.602,-0.63365,-0.63365,0.31383,0.31383 --joints rec/joints.csv > real.rec",
       "a RealSense recording with the arm's joint log"},
      {"obs-pack --rgb demo1/color_%06d.png --depth demo1/depth_%06d.png --intrinsics 615.2,615.0,320.5,240.1 "
       "--camera-pose 1.05,0,1.602,-0.63365,-0.63365,0.31383,0.31383 --joint-log demo1/joints.csv "
       "--frame-times demo1/frames.csv --success 1 --task reach_prism --append --output demos.rec",
       "one tele-operated demonstration added to demos.rec, for keyframe"},
      {"obs-pack ... < /dev/null | qte-select --checkpoint run/latest.rec --k 10 --png q/ | plan-path | stream-dump --type trajectory",
       "what the learned agent would do on each saved frame"},
      {"obs-pack --pcd clouds/%06d.pcd --camera-pose 1.05,0,1.602,-0.63365,-0.63365,0.31383,0.31383 | voxelize --png grids/",
       "voxelize saved clouds and look at the grids"},
  };
  u.see_also = {"sim-step(1)", "voxelize(1)", "qte-select(1)", "plan-path(1)", "keyframe(1)", "qte-stream(5)"};
  u.environment = robot::kDataDirEnvironment;
  return u;
}

static void run(const cli::Arguments& args) {
  camera_recordings::Recording recording;
  const bool images = args.has("rgb") || args.has("depth");
  if (images == args.has("pcd")) throw UsageError("give --rgb and --depth, or --pcd");
  if (images && !(args.has("rgb") && args.has("depth"))) throw UsageError("--rgb and --depth go together");
  recording.rgb_pattern = args.text("rgb");
  recording.depth_pattern = args.text("depth");
  recording.pcd_pattern = args.text("pcd");
  recording.camera = camera_recordings::camera_setup_from(args);
  if (images && !recording.camera.intrinsics) throw UsageError("depth images need --intrinsics");
  recording.start = args.integer("start");
  recording.count = args.has("count") ? args.integer("count") : -1;
  recording.episode_length = static_cast<int>(args.integer("episode-length"));
  recording.task = args.text("task");
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  if (args.has("joints") && args.has("joint-log")) throw UsageError("give --joints or --joint-log, not both");
  if (args.has("joint-log") != args.has("frame-times")) throw UsageError("--joint-log and --frame-times go together");
  if (args.has("success") && !args.has("joint-log"))
    throw UsageError("--success needs --joint-log and --frame-times (keyframes are found from the joint velocities)");
  if (args.has("joints")) {
    recording.joints_path = args.text("joints");
    recording.states = camera_recordings::read_joint_csv(recording.joints_path, robot);
  }
  if (args.has("joint-log"))
    camera_recordings::add_joint_log(recording, camera_recordings::read_joint_log(args.text("joint-log"), robot),
                                     camera_recordings::read_frame_times(args.text("frame-times")));
  if (args.has("success")) recording.demonstration_success = args.integer("success") == 1;

  std::vector<std::string> inputs;
  for (const char* file : {"joints", "joint-log", "frame-times"})
    if (args.has(file)) inputs.push_back(args.text(file));
  const stream::WriteOptions write_options = cli::write_options_from(args, inputs);
  // An append is record by record: every frame is read and checked once before, so that a bad
  // one leaves the file as it was rather than half a demonstration in it.
  if (write_options.mode == stream::WriteMode::append && args.text("output") != "-")
    camera_recordings::pack_recording(recording, robot, [](const stream::Record&) {});
  stream::RecordWriter writer(args.text("output"), write_options);
  const auto packed = camera_recordings::pack_recording(recording, robot, [&](const stream::Record& obs) { writer.write(obs); });
  writer.close();
  // Not an error here (other bounds may suit), but qte-select and qattn-train refuse such frames.
  if (packed.blind > 0)
    std::cerr << "obs-pack: warning: " << packed.blind << " of " << packed.written
              << " frames have no point inside the default scene bounds -0.3,-0.5,0.6,1.0: check the camera pose "
                 "(--camera-pose, --extrinsics), --intrinsics and --depth-unit\n";
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
