// A calibrated camera on the command line: the options obs-pack and robot-step share, so a
// camera is given, documented and checked the same way wherever its frames are read.
#pragma once

#include <vector>

#include "camera_recordings/camera_recordings.hpp"
#include "cli/command.hpp"

namespace qte::camera_recordings {

// --camera, --intrinsics, --camera-pose, --extrinsics, --depth-unit, --no-points.
std::vector<cli::OptionSpec> camera_setup_options();
// The camera they give; UsageError naming the option that is wrong (its pose is required).
CameraSetup camera_setup_from(const cli::Arguments& args);

}  // namespace qte::camera_recordings
