// Episodes as video files a person plays: MP4 (OpenCV's FFmpeg writer, MPEG-4 part 2) or an
// animated GIF (giflib, a 256-colour palette per frame, looping) for READMEs. Frames go to a
// file beside the final name, renamed when complete: a failed or killed run leaves no half video.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace cv {
class VideoWriter;
}

namespace qte::video {

class VideoFile {
 public:
  // The kind follows the extension (.mp4 or .gif); Error otherwise.
  VideoFile(std::string path, double fps);
  ~VideoFile();
  VideoFile(const VideoFile&) = delete;
  VideoFile& operator=(const VideoFile&) = delete;

  // An RGB frame (CV_8UC3); every frame must have the size of the first.
  void add(const cv::Mat& rgb);
  // Finishes the file and gives it its name. Throws Error when no frame was added.
  void close();
  int frames() const { return frames_; }

 private:
  struct Gif;
  std::string path_, temp_path_;
  double fps_;
  int frames_ = 0;
  cv::Size size_;
  std::unique_ptr<cv::VideoWriter> mp4_;
  std::unique_ptr<Gif> gif_;
};

// One video frame: the camera image beside pictures (attention grids, ...), each scaled to
// `height` pixels high (nearest neighbour, so voxels stay sharp), on a black strip.
cv::Mat side_by_side(const cv::Mat& camera_rgb, const std::vector<cv::Mat>& pictures_rgb, int height);

}  // namespace qte::video
