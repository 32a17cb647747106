// stream-png: save the camera images of a stream as PNG files a person can look at.
#include <sys/stat.h>

#include <cstdio>
#include <opencv2/core.hpp>

#include "cli/command.hpp"
#include "render/camera.hpp"
#include "stream/reader.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "stream-png";
  u.summary = "save the images of a record stream as PNG files";
  u.description = {
      "Reads record streams and writes every image field as a PNG into DIR: uint8 fields of "
      "shape [H, W, 3] named *.rgb as colour images, and with --depth float32 [H, W] fields "
      "named *.depth as colour-mapped depth (near warm, far cool, no return black). Files are "
      "named <record index>.<field>.png (index zero-padded to 6 digits) and written atomically.",
  };
  u.arguments = {{"FILE", "record streams; '-' or absent is standard input", true, true}};
  u.options = {
      {"dir", "DIR", "where the PNG files go (created if missing)", "."},
      {"type", "T", "only records of type T", "obs"},
      {"depth", "", "also save depth images", ""},
      {"every", "N", "only every N-th record of the type", "1"},
  };
  u.examples = {
      {"sim-step --task lift_numbered_block --image-size 256x256 < /dev/null | stream-png --dir frames/",
       "look at the first observation of an episode"},
      {"stream-png --depth --every 10 --dir demo_frames demos.rec", "every 10th frame of saved demos"},
  };
  u.see_also = {"sim-step(1)", "stream-dump(1)", "qte-stream(5)"};
  return u;
}

static void run(const cli::Arguments& args) {
  std::vector<std::string> files = args.positional();
  if (files.empty()) files.push_back("-");
  const std::string dir = args.text("dir"), type = args.text("type");
  const int64_t every = args.integer("every", 1, 1000000000);
  if (every < 1) throw UsageError("--every must be at least 1");
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) throw_system_error("cannot create directory " + dir);
  int64_t seen = 0;
  for (const auto& file : files) {
    stream::RecordReader reader(file);
    while (auto record = reader.next()) {
      if (record->type() != type || seen++ % every != 0) continue;
      char index[16];
      std::snprintf(index, sizeof index, "%06llu", static_cast<unsigned long long>(record->position.record_index));
      for (const auto& field : record->fields()) {
        const auto& shape = field.shape();
        const std::string path = dir + "/" + index + "." + field.name() + ".png";
        const bool rgb = stream::ends_with(field.name(), ".rgb");
        const bool depth = args.flag("depth") && stream::ends_with(field.name(), ".depth");
        // An image field that is not one, or empty, is the input's fault: name the record.
        if (rgb && !(field.dtype() == stream::DType::u8 && shape.size() == 3 && shape[2] == 3))
          record->fail(field.name(), "an RGB image (uint8, height x width x 3)");
        if (depth && !(field.dtype() == stream::DType::f32 && shape.size() == 2))
          record->fail(field.name(), "a depth image (float32, height x width)");
        if ((rgb || depth) && (shape[0] == 0 || shape[1] == 0)) record->fail(field.name(), "a non-empty image");
        if (rgb) {
          const cv::Mat rgb(static_cast<int>(shape[0]), static_cast<int>(shape[1]), CV_8UC3,
                            const_cast<uint8_t*>(field.bytes()));
          render::save_rgb_png(path, rgb);
        } else if (depth) {
          const cv::Mat depth(static_cast<int>(shape[0]), static_cast<int>(shape[1]), CV_32FC1,
                              const_cast<uint8_t*>(field.bytes()));
          render::save_depth_png(path, depth);
        }
      }
    }
  }
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
