// stream-png: save the camera images of a stream as PNG files, or an episode as a video.

#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "common/indexed_name.hpp"
#include "render/camera.hpp"
#include "stream/field_names.hpp"
#include "stream/reader.hpp"
#include "video/episode_video.hpp"
#include "voxels/observation_cloud.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "stream-png";
  u.summary = "save the images of a record stream as PNG files, or as a video";
  u.description = {
      "Reads record streams and writes every image field as a PNG into DIR: uint8 fields of "
      "shape [H, W, 3] named *.rgb as colour images, and with --depth float32 [H, W] fields "
      "named *.depth as colour-mapped depth (near warm, far cool, no return black). With "
      "--depth-mm depth is also saved as a 16-bit PNG in millimetres (0 = no return), the form "
      "depth cameras save and obs-pack reads. Files are named <record index>.<field>.png (index "
      "zero-padded to 6 digits), and they appear all or none: a run that fails leaves DIR as it was.",
      "With --video FILE.mp4 (or FILE.gif, an animated GIF for web pages) the camera's images "
      "become the frames of one video instead, at --fps. With --attention DIR, the pictures "
      "qte-select --png DIR saved for its actions (DIR/<n>.depth<d>.png, n from 0) are shown "
      "beside the camera: on the observation the action was chosen on and, in a stream of every "
      "control step (sim-step --every-step, replaying the episode's trajectories), on the frames "
      "of the motion that carries it out. qte-select acts on the last observation of each step "
      "that is not terminal; before the first action there is black.",
  };
  u.arguments = {cli::input_files("record streams")};
  u.options = {
      {"dir", "DIR", "where the PNG files go (created if missing)", "."},
      {"type", "T", "only records of type T", record_type::obs},
      {"depth", "", "also save depth images", ""},
      {"depth-mm", "", "also save depth as 16-bit PNGs in millimetres", ""},
      cli::integer_option("every", "N", "only every N-th record of the type", "1", 1, 1000000000),
      {"video", "FILE", "write the frames as one video, FILE.mp4 or FILE.gif, instead of PNG files", ""},
      cli::real_option("fps", "F", "video frames per second", "2", 0.01, 1000),
      {"camera", "NAME", "the camera a video shows", "front"},
      {"attention", "DIR", "show qte-select's pictures from DIR beside each video frame", ""},
      cli::integer_option("height", "PX", "video frame height; every panel is scaled to it", "256", 16, 4096),
  };
  u.examples = {
      {"sim-step --task lift_numbered_block --image-size 256x256 < /dev/null | stream-png --dir frames/",
       "look at the first observation of an episode"},
      {"stream-png --depth --every 10 --dir demo_frames demos.rec", "every 10th frame of saved demos"},
      {"sim-step --task pick_and_lift < fifo | qte-select --checkpoint ckpt.rec --png q/ | tee ep.rec | plan-path > fifo; "
       "stream-png --video ep.mp4 --attention q/ ep.rec",
       "an episode of the agent, with what it attended to at each step"},
  };
  u.see_also = {"sim-step(1)", "qte-select(1)", "obs-pack(1)", "stream-dump(1)", "qte-stream(5)"};
  return u;
}

namespace {

void save_pngs(const stream::Record& record, const OutputDirectory& dir, bool depth, bool depth_mm) {
  for (const auto& field : record.fields()) {
    const std::string path = dir.path(indexed_name(record.position.record_index, field.name()));
    if (stream::ends_with(field.name(), fields::per_camera::rgb))
      render::save_rgb_png(path + ".png", video::image_field(record, field, false));
    if (!stream::ends_with(field.name(), fields::per_camera::depth) || !(depth || depth_mm)) continue;
    const cv::Mat metres = video::image_field(record, field, true);
    if (depth) render::save_depth_png(path + ".png", metres);
    if (depth_mm) {
      const std::vector<uint16_t> mm = voxels::depth_in_mm(metres.ptr<float>(), metres.total());
      render::save_mm_png(path + "_mm.png", cv::Mat(metres.rows, metres.cols, CV_16UC1, const_cast<uint16_t*>(mm.data())));
    }
  }
}

}  // namespace

static void run(const cli::Arguments& args) {
  const std::vector<std::string> files = args.inputs();
  const std::string dir = args.text("dir"), type = args.text("type");
  const int64_t every = args.integer("every");
  if (args.has("attention") && !std::filesystem::is_directory(args.text("attention")))
    throw UsageError("--attention " + args.text("attention") + ": no such directory (qte-select --png DIR writes the pictures)");
  std::unique_ptr<video::EpisodeVideo> video;
  std::unique_ptr<OutputDirectory> pictures;
  if (args.has("video")) {
    if (type != record_type::obs) throw UsageError("--video shows observations: --type obs");
    video = std::make_unique<video::EpisodeVideo>(args.text("video"), args.real("fps"), args.text("camera"),
                                                  args.text("attention"), static_cast<int>(args.integer("height")));
  } else {
    pictures = std::make_unique<OutputDirectory>(dir);
  }
  if (args.has("attention") && !video) throw UsageError("--attention goes with --video");
  int64_t seen = 0;
  for (const auto& file : files) {
    stream::RecordReader reader(file);
    while (auto record = reader.next()) {
      if (record->type() != type) continue;
      const bool shown = seen++ % every == 0;
      if (video) video->add(*record, shown);
      else if (shown) save_pngs(*record, *pictures, args.flag("depth"), args.flag("depth-mm"));
    }
  }
  if (video) video->close();
  if (pictures) pictures->commit();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
