// libFuzzer target: the camera recordings' other readers (obs-pack --rgb, --depth, --joints,
// --joint-log, --frame-times). The first byte picks the reader (0: colour PNG, 1: depth PNG,
// 2: joint CSV, 3: joint log, then the state halfway through it, 4: frame times), the rest is the
// file. Error naming the file is the expected outcome. Run: make fuzz FUZZ_TARGETS=camera_recordings.
#include "camera_recordings/camera_recordings.hpp"
#include "camera_recordings/joint_log.hpp"
#include "camera_recordings/png_frames.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const qte::robot::RobotModel robot = qte::robot::RobotModel::xarm7();
  if (size == 0) return 0;
  const std::string& path = qte::fuzz::as_file(data + 1, size - 1);
  try {
    switch (data[0] % 5) {
      case 0: (void)qte::camera_recordings::read_colour_png(path); break;
      case 1: (void)qte::camera_recordings::read_depth_png(path); break;
      case 2: (void)qte::camera_recordings::read_joint_csv(path, robot); break;
      case 3: {
        const auto log = qte::camera_recordings::read_joint_log(path, robot);
        (void)qte::camera_recordings::state_at(log, (log.times_s.front() + log.times_s.back()) / 2);
        break;
      }
      default: (void)qte::camera_recordings::read_frame_times(path); break;
    }
  } catch (const qte::Error&) {
  }
  return 0;
}
