#include "video/video_file.hpp"

#include <gif_lib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "common/error.hpp"
#include "stream/record.hpp"

namespace qte::video {

struct VideoFile::Gif {
  GifFileType* file = nullptr;
  ~Gif() {
    int error = 0;
    if (file) EGifCloseFile(file, &error);
  }
};

namespace {

void gif_check(int status, GifFileType* file, const std::string& path) {
  if (status != GIF_OK) throw Error("cannot write " + path + ": " + GifErrorString(file ? file->Error : 0));
}

// Loop for ever (the Netscape application extension every browser honours).
void put_loop_extension(GifFileType* gif, const std::string& path) {
  static const unsigned char app[] = "NETSCAPE2.0";
  static const unsigned char loop[] = {1, 0, 0};
  gif_check(EGifPutExtensionLeader(gif, APPLICATION_EXT_FUNC_CODE), gif, path);
  gif_check(EGifPutExtensionBlock(gif, 11, app), gif, path);
  gif_check(EGifPutExtensionBlock(gif, 3, loop), gif, path);
  gif_check(EGifPutExtensionTrailer(gif), gif, path);
}

}  // namespace

VideoFile::VideoFile(std::string path, double fps) : path_(std::move(path)), fps_(fps) {
  if (!(fps > 0 && fps <= 1000)) throw Error("video frame rate must be in (0, 1000], got " + std::to_string(fps));
  const bool gif = stream::ends_with(path_, ".gif"), mp4 = stream::ends_with(path_, ".mp4");
  if (!gif && !mp4) throw Error(path_ + ": a video's name must end in .mp4 or .gif");
  // The temporary keeps the extension: OpenCV picks its container by it.
  temp_path_ = path_ + ".tmp." + std::to_string(::getpid()) + (gif ? ".gif" : ".mp4");
  if (gif) gif_ = std::make_unique<Gif>();
}

VideoFile::~VideoFile() {
  mp4_.reset();
  gif_.reset();
  if (!temp_path_.empty()) std::remove(temp_path_.c_str());
}

void VideoFile::add(const cv::Mat& rgb) {
  if (rgb.type() != CV_8UC3 || rgb.empty()) throw Error(path_ + ": video frames must be RGB images");
  if (frames_ == 0) {
    size_ = rgb.size();
    if (gif_) {
      int error = 0;
      gif_->file = EGifOpenFileName(temp_path_.c_str(), false, &error);
      if (!gif_->file) throw Error("cannot write " + path_ + ": " + GifErrorString(error));
      EGifSetGifVersion(gif_->file, true);
      gif_check(EGifPutScreenDesc(gif_->file, size_.width, size_.height, 8, 0, nullptr), gif_->file, path_);
      put_loop_extension(gif_->file, path_);
    } else {
      mp4_ = std::make_unique<cv::VideoWriter>(temp_path_, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps_, size_);
      if (!mp4_->isOpened()) throw Error("cannot write " + path_ + ": OpenCV has no MP4 writer here");
    }
  } else if (rgb.size() != size_) {
    throw Error(path_ + ": every frame must be " + std::to_string(size_.width) + "x" + std::to_string(size_.height));
  }
  if (mp4_) {
    cv::Mat bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    mp4_->write(bgr);
  } else {
    const int w = size_.width, h = size_.height;
    std::vector<GifByteType> r(w * h), g(w * h), b(w * h), indices(w * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const cv::Vec3b p = rgb.at<cv::Vec3b>(y, x);
        r[y * w + x] = p[0], g[y * w + x] = p[1], b[y * w + x] = p[2];
      }
    int colours = 256;
    std::vector<GifColorType> palette(256);
    if (GifQuantizeBuffer(w, h, &colours, r.data(), g.data(), b.data(), indices.data(), palette.data()) != GIF_OK)
      throw Error("cannot write " + path_ + ": colour quantisation failed");
    ColorMapObject* map = GifMakeMapObject(256, palette.data());
    GraphicsControlBlock timing{};
    timing.DelayTime = std::max(1, static_cast<int>(std::lround(100.0 / fps_)));  // centiseconds
    timing.TransparentColor = NO_TRANSPARENT_COLOR;
    GifByteType extension[4];
    const std::size_t length = EGifGCBToExtension(&timing, extension);
    const int put = EGifPutExtension(gif_->file, GRAPHICS_EXT_FUNC_CODE, static_cast<int>(length), extension);
    const int desc = put == GIF_OK ? EGifPutImageDesc(gif_->file, 0, 0, w, h, false, map) : put;
    GifFreeMapObject(map);
    gif_check(desc, gif_->file, path_);
    for (int y = 0; y < h; ++y) gif_check(EGifPutLine(gif_->file, &indices[y * w], w), gif_->file, path_);
  }
  frames_ += 1;
}

void VideoFile::close() {
  if (frames_ == 0) throw Error(path_ + ": no frames to write");
  if (mp4_) {
    mp4_->release();
    mp4_.reset();
  } else {
    int error = 0;
    const int status = EGifCloseFile(gif_->file, &error);
    gif_->file = nullptr;
    if (status != GIF_OK) throw Error("cannot write " + path_ + ": " + GifErrorString(error));
  }
  // giflib creates its file for the owner alone; give it the mode any new file gets.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::chmod(temp_path_.c_str(), 0666 & ~mask);
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) throw_system_error("cannot rename " + temp_path_ + " to " + path_);
  temp_path_.clear();
}

cv::Mat side_by_side(const cv::Mat& camera_rgb, const std::vector<cv::Mat>& pictures_rgb, int height) {
  std::vector<cv::Mat> panels{camera_rgb};
  panels.insert(panels.end(), pictures_rgb.begin(), pictures_rgb.end());
  for (cv::Mat& p : panels) {
    cv::Mat scaled;
    const int width = std::max(1, static_cast<int>(std::lround(double(p.cols) * height / std::max(1, p.rows))));
    cv::resize(p, scaled, cv::Size(width, height), 0, 0, cv::INTER_NEAREST);
    p = scaled;
  }
  cv::Mat out;
  cv::hconcat(panels, out);
  // Codecs work on 2x2 blocks: an even size plays everywhere.
  cv::Mat even(out.rows + out.rows % 2, out.cols + out.cols % 2, CV_8UC3, cv::Scalar(0, 0, 0));
  out.copyTo(even(cv::Rect(0, 0, out.cols, out.rows)));
  return even;
}

}  // namespace qte::video
