// stream-png: save the camera images of a stream as PNG files, or an episode as a video.
#include <sys/stat.h>

#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli/command.hpp"
#include "render/camera.hpp"
#include "stream/reader.hpp"
#include "video/video_file.hpp"
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
      "zero-padded to 6 digits) and written atomically.",
      "With --video FILE.mp4 (or FILE.gif, an animated GIF for web pages) the camera's images "
      "become the frames of one video instead, at --fps. With --attention DIR, the pictures "
      "qte-select --png DIR saved for its actions (DIR/<n>.depth<d>.png, n from 0) are shown "
      "beside the camera: on the observation the action was chosen on and, in a stream of every "
      "control step (sim-step --every-step, replaying the episode's trajectories), on the frames "
      "of the motion that carries it out. qte-select acts on the last observation of each step "
      "that is not terminal; before the first action there is black.",
  };
  u.arguments = {{"FILE", "record streams; '-' or absent is standard input", true, true}};
  u.options = {
      {"dir", "DIR", "where the PNG files go (created if missing)", "."},
      {"type", "T", "only records of type T", "obs"},
      {"depth", "", "also save depth images", ""},
      {"depth-mm", "", "also save depth as 16-bit PNGs in millimetres", ""},
      {"every", "N", "only every N-th record of the type", "1"},
      {"video", "FILE", "write the frames as one video, FILE.mp4 or FILE.gif, instead of PNG files", ""},
      {"fps", "F", "video frames per second", "2"},
      {"camera", "NAME", "the camera a video shows", "front"},
      {"attention", "DIR", "show qte-select's pictures from DIR beside each video frame", ""},
      {"height", "PX", "video frame height; every panel is scaled to it", "256"},
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

// An image field that is not one, or empty, is the input's fault: name the record.
cv::Mat image_of(const stream::Record& record, const stream::Field& field, bool depth) {
  const auto& shape = field.shape();
  if (!depth && !(field.dtype() == stream::DType::u8 && shape.size() == 3 && shape[2] == 3))
    record.fail(field.name(), "an RGB image (uint8, height x width x 3)");
  if (depth && !(field.dtype() == stream::DType::f32 && shape.size() == 2))
    record.fail(field.name(), "a depth image (float32, height x width)");
  if (shape[0] == 0 || shape[1] == 0) record.fail(field.name(), "a non-empty image");
  return cv::Mat(static_cast<int>(shape[0]), static_cast<int>(shape[1]), depth ? CV_32FC1 : CV_8UC3,
                 const_cast<uint8_t*>(field.bytes()));
}

void save_pngs(const stream::Record& record, const std::string& dir, bool depth, bool depth_mm) {
  char index[16];
  std::snprintf(index, sizeof index, "%06llu", static_cast<unsigned long long>(record.position.record_index));
  for (const auto& field : record.fields()) {
    const std::string path = dir + "/" + index + "." + field.name();
    if (stream::ends_with(field.name(), ".rgb")) render::save_rgb_png(path + ".png", image_of(record, field, false));
    if (!stream::ends_with(field.name(), ".depth") || !(depth || depth_mm)) continue;
    const cv::Mat metres = image_of(record, field, true);
    if (depth) render::save_depth_png(path + ".png", metres);
    if (depth_mm) {
      const std::vector<uint16_t> mm = voxels::depth_in_mm(metres.ptr<float>(), metres.total());
      render::save_mm_png(path + "_mm.png", cv::Mat(metres.rows, metres.cols, CV_16UC1, const_cast<uint16_t*>(mm.data())));
    }
  }
}

// The pictures qte-select saved for action n, or black panels of their size once they ran out.
std::vector<cv::Mat> attention_pictures(const std::string& dir, int64_t action, std::vector<cv::Size>& sizes) {
  std::vector<cv::Mat> pictures;
  for (int d = 0;; ++d) {
    char name[64];
    std::snprintf(name, sizeof name, "/%06lld.depth%d.png", static_cast<long long>(action), d);
    struct stat st;
    if (action < 0 || ::stat((dir + name).c_str(), &st) != 0) break;  // no such picture (OpenCV would warn)
    cv::Mat bgr = cv::imread(dir + name, cv::IMREAD_COLOR);
    if (bgr.empty()) throw Error(dir + name + ": not a readable picture");
    cv::cvtColor(bgr, bgr, cv::COLOR_BGR2RGB);
    pictures.push_back(bgr);
  }
  if (!pictures.empty()) sizes.clear();
  for (const cv::Mat& p : pictures) sizes.push_back(p.size());
  if (pictures.empty())
    for (const cv::Size& s : sizes) pictures.emplace_back(s, CV_8UC3, cv::Scalar(0, 0, 0));
  return pictures;
}

}  // namespace

namespace {

// The frames of a video, one observation behind the stream: qte-select acts on the last
// observation of each step (with sim-step --every-step the frames during a motion share the
// step of the observation that ends it), and only the next observation tells which that is.
class EpisodeVideo {
 public:
  EpisodeVideo(const cli::Arguments& args)
      : file_(args.text("video"), args.real("fps", 0.01, 1000)),
        camera_(args.text("camera") + ".rgb"),
        attention_(args.text("attention")),
        height_(static_cast<int>(args.integer("height", 16, 4096))) {}

  void add(const stream::Record& obs, bool shown) {
    Frame next{shown ? image_of(obs, obs.field(camera_), false).clone() : cv::Mat(),
               obs.has("step") ? obs.scalar<int32_t>("step") : -1,
               obs.has("terminal") && obs.scalar<uint8_t>("terminal") != 0, true};
    if (pending_.valid) write(pending_, next.step != pending_.step || pending_.step < 0);
    pending_ = std::move(next);
  }

  void close() {
    if (pending_.valid) write(pending_, true);
    file_.close();
  }

 private:
  struct Frame {
    cv::Mat image;  // empty when --every skips it
    int32_t step = -1;
    bool terminal = false, valid = false;
  };

  // Each frame shows the pictures of the action chosen on it or, during a motion, of the action
  // being carried out.
  void write(const Frame& frame, bool acted_on) {
    if (acted_on && !frame.terminal) action_ = actions_++;
    if (frame.image.empty()) return;
    const std::vector<cv::Mat> pictures =
        attention_.empty() ? std::vector<cv::Mat>{} : attention_pictures(attention_, action_, picture_sizes_);
    file_.add(video::side_by_side(frame.image, pictures, height_));
  }

  video::VideoFile file_;
  std::string camera_, attention_;
  int height_;
  Frame pending_;
  int64_t actions_ = 0, action_ = -1;
  std::vector<cv::Size> picture_sizes_;
};

}  // namespace

static void run(const cli::Arguments& args) {
  std::vector<std::string> files = args.positional();
  if (files.empty()) files.push_back("-");
  const std::string dir = args.text("dir"), type = args.text("type");
  const int64_t every = args.integer("every", 1, 1000000000);
  std::unique_ptr<EpisodeVideo> video;
  if (args.has("video")) {
    if (type != "obs") throw UsageError("--video shows observations: --type obs");
    video = std::make_unique<EpisodeVideo>(args);
  } else if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) {
    throw_system_error("cannot create directory " + dir);
  }
  if (args.has("attention") && !video) throw UsageError("--attention goes with --video");
  int64_t seen = 0;
  for (const auto& file : files) {
    stream::RecordReader reader(file);
    while (auto record = reader.next()) {
      if (record->type() != type) continue;
      const bool shown = seen++ % every == 0;
      if (video) video->add(*record, shown);
      else if (shown) save_pngs(*record, dir, args.flag("depth"), args.flag("depth-mm"));
    }
  }
  if (video) video->close();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
