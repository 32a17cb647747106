#include "camera_recordings/camera_options.hpp"

#include "camera_recordings/recording.hpp"
#include "cli/stream_options.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::camera_recordings {

std::vector<cli::OptionSpec> camera_setup_options() {
  return {
      {"camera", "NAME", "camera name, the records' field prefix", "front"},
      {"intrinsics", "FX,FY,CX,CY", "pinhole intrinsics in pixels (needed for depth images)", ""},
      {"camera-pose", "X,Y,Z,QX,QY,QZ,QW", "camera-to-world pose, metres and unit quaternion", ""},
      {"extrinsics", "M00,...,M33", "camera-to-world 4x4 matrix, 16 numbers row by row (instead of --camera-pose)", ""},
      cli::real_option("depth-unit", "M", "metres per depth count", cli::default_text(CameraSetup{}.depth_unit_m), 1e-6, 1.0),
      cli::no_points_option(),
  };
}

CameraSetup camera_setup_from(const cli::Arguments& args) {
  CameraSetup camera;
  camera.name = args.text("camera");
  // The name prefixes the records' fields (NAME.rgb): empty or dotted, it would name other fields.
  if (camera.name.empty() || camera.name.find('.') != std::string::npos || !stream::is_valid_field_name(camera.name))
    throw UsageError("--camera: '" + camera.name + "' is not a camera name, expected letters, digits, '_' or '-'");
  if (args.has("intrinsics")) camera.intrinsics = intrinsics_from_values(args.reals("intrinsics", 4), "intrinsics");
  if (args.has("camera-pose") == args.has("extrinsics"))
    throw UsageError("give the camera's pose: one of --camera-pose and --extrinsics");
  camera.camera_to_world = args.has("camera-pose") ? camera_pose_from_values(args.reals("camera-pose", 7), "camera-pose")
                                                   : camera_pose_from_matrix(args.reals("extrinsics", 16), "extrinsics");
  camera.depth_unit_m = args.real("depth-unit");
  camera.store_points = !args.flag("no-points");
  return camera;
}

}  // namespace qte::camera_recordings
