// voxelize: observations to coarse-to-fine voxel grids (C2F-ARM's 10 channels).

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "point_clouds/cloud_filters.hpp"
#include "stream/reader.hpp"
#include "stream/stage.hpp"
#include "stream/writer.hpp"
#include "voxels/hierarchy_options.hpp"
#include "voxel_occupancy/voxels_record.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "voxelize";
  u.summary = "turn observations into C2F-ARM voxel grids";
  u.description = {
      "Reads a record stream and passes every record through; after each 'obs' record it writes "
      "a 'voxels' record holding the depth-0 grid over the scene bounds and, for every --centre, "
      "a deeper grid of centre +- --offset (the crops coarse-to-fine attention zooms into). The "
      "point cloud is every camera's <camera>.points with <camera>.rgb (or points rebuilt from "
      "<camera>.depth / depth_mm and the camera's intrinsics and extrinsics); points outside a "
      "grid, and pixels without a return, are ignored. An observation with no point inside the scene "
      "bounds is refused (exit 1, naming the record), as qte-select and qattn-train refuse it: its "
      "grid would be empty.",
      "Each voxel has 10 channels, channels last: the mean x, y, z of its points (world frame, "
      "metres), their mean r, g, b scaled to [-1, 1], the voxel's index divided by the grid "
      "size for x, y, z, and occupancy (1 when it holds a point); empty voxels are zero but "
      "for their index channels. A voxel's coordinate is its centre: min + (index + 0.5) * size.",
      "With --octomap-channels two channels follow those 10: 'free' (the voxel centre was "
      "crossed by a camera ray) and 'unknown' (no ray reached it: hidden or out of view), from "
      "an OctoMap of the observation at 1 cm. Points alone cannot tell empty space from hidden "
      "space. Off by default until it is shown to help learning; it costs about 0.2 s per "
      "observation.",
      "With --png DIR a picture of every grid is saved (occupied voxels as cubes in their "
      "colour): the way to see what the attention sees.",
  };
  u.arguments = {cli::input_file()};
  u.options = {
      {"centre", "X,Y,Z", "also voxelize centre +- offset at depth 1 (repeat for several: one batched pass)", "", true},
      cli::real_option("offset", "M", "half edge of the deeper grids, metres",
                       cli::default_text(voxels::CoarseToFine{}.offsets_m.front()), 0.001, 10),
      {"octomap-channels", "", "add the free and unknown channels (12 in all)", ""},
      {"png", "DIR", "save a picture of every grid as DIR/<record>.depth<d>[.<k>].png (all at the end, or none)", ""},
  };
  u.options.push_back(cli::output_file());
  u.add_options(voxels::scene_options());
  u.add_options(point_clouds::cloud_filter_options());
  u.examples = {
      {"sim-step --task reach_target < /dev/null | voxelize --png grids/ | stream-dump --type voxels",
       "voxelize the first observation and look at it"},
      {"voxelize --centre 0.2,0,0.8 --centre 0.1,0.2,0.8 < obs.rec > with_voxels.rec",
       "two deeper crops of each observation in one pass over its points"},
  };
  u.see_also = {"qte-select(1)", "keyframe(1)", "qte-stream(5)"};
  return u;
}

static void run(const cli::Arguments& args) {
  const voxels::GridBounds scene = voxels::parse_scene(args);
  const double offset = args.real("offset");
  std::vector<voxels::GridBounds> crops;
  for (const auto& c : args.all("centre")) {
    const auto p = cli::parse_reals("centre", c, 3);
    crops.push_back(voxels::GridBounds::around({p[0], p[1], p[2]}, offset, scene.voxels));
  }
  std::unique_ptr<OutputDirectory> pictures;  // all or none
  if (args.has("png")) pictures = std::make_unique<OutputDirectory>(args.text("png"));

  voxel_occupancy::VoxelizeStage stage({scene, crops, args.flag("octomap-channels")}, pictures ? pictures->staging() : "",
                              point_clouds::observation_filter(point_clouds::parse_cloud_filters(args)));
  stream::RecordReader reader(args.input());
  stream::RecordWriter writer(args.text("output"));
  stream::run_stage(stage, reader, writer);
  if (pictures) pictures->commit();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
