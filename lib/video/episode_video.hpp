// An episode as a video: the observations' camera images, with the pictures qte-select --png
// saved for each action beside the frames it was chosen on and carried out in.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stream/record.hpp"
#include "video/video_file.hpp"

namespace qte::video {

// A record's image field viewed as a cv::Mat (no copy): uint8 [H, W, 3] RGB, or with `depth`
// float32 [H, W] metres. A field that is not one, or is empty, fails naming the record.
cv::Mat image_field(const stream::Record& record, const stream::Field& field, bool depth);

class EpisodeVideo {
 public:
  // `attention_dir` empty: the camera alone. `height`: every panel is scaled to it.
  EpisodeVideo(const std::string& path, double fps, const std::string& camera, std::string attention_dir, int height);

  // The next observation; `shown` false counts it without a frame (stream-png --every).
  void add(const stream::Record& obs, bool shown = true);
  void close();

 private:
  struct Frame {
    cv::Mat image;  // empty when not shown
    int32_t step = -1;
    bool terminal = false, valid = false;
  };
  void write(const Frame& frame, bool acted_on);
  std::vector<cv::Mat> attention_pictures();

  VideoFile file_;
  std::string camera_, attention_dir_;
  int height_;
  Frame pending_;                         // frames go out one observation behind, see add()
  int64_t actions_ = 0, action_ = -1;     // actions seen; the one the current frame shows
  std::vector<cv::Size> picture_sizes_;   // for the black panels before the first action
};

}  // namespace qte::video
