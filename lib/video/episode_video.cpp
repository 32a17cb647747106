#include "video/episode_video.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.hpp"
#include "common/indexed_name.hpp"
#include "stream/field_names.hpp"

namespace qte::video {

cv::Mat image_field(const stream::Record& record, const stream::Field& field, bool depth) {
  const auto& shape = field.shape();
  if (!depth && !(field.dtype() == stream::DType::u8 && shape.size() == 3 && shape[2] == 3))
    record.fail(field.name(), "an RGB image (uint8, height x width x 3)");
  if (depth && !(field.dtype() == stream::DType::f32 && shape.size() == 2))
    record.fail(field.name(), "a depth image (float32, height x width)");
  if (shape[0] == 0 || shape[1] == 0) record.fail(field.name(), "a non-empty image");
  return cv::Mat(static_cast<int>(shape[0]), static_cast<int>(shape[1]), depth ? CV_32FC1 : CV_8UC3,
                 const_cast<uint8_t*>(field.bytes()));
}

EpisodeVideo::EpisodeVideo(const std::string& path, double fps, const std::string& camera, std::string attention_dir,
                           int height)
    : file_(path, fps),
      camera_(camera + fields::per_camera::rgb),
      attention_dir_(std::move(attention_dir)),
      height_(height) {}

// qte-select acts on the last observation of each step: with sim-step --every-step the frames
// during a motion share the step of the observation that ends it, so only the next
// observation tells whether this one was acted on. Frames therefore go out one behind.
void EpisodeVideo::add(const stream::Record& obs, bool shown) {
  Frame next{shown ? image_field(obs, obs.field(camera_), false).clone() : cv::Mat(),
             obs.has(fields::step) ? obs.scalar<int32_t>(fields::step) : -1,
             obs.has(fields::terminal) && obs.scalar<uint8_t>(fields::terminal) != 0, true};
  if (pending_.valid) write(pending_, next.step != pending_.step || pending_.step < 0);
  pending_ = std::move(next);
}

void EpisodeVideo::close() {
  if (pending_.valid) write(pending_, true);
  pending_ = Frame{};
  file_.close();
}

// A frame shows the pictures of the action chosen on it or, during a motion, of the action
// being carried out.
void EpisodeVideo::write(const Frame& frame, bool acted_on) {
  if (acted_on && !frame.terminal) action_ = actions_++;
  if (frame.image.empty()) return;
  file_.add(side_by_side(frame.image, attention_dir_.empty() ? std::vector<cv::Mat>{} : attention_pictures(), height_));
}

// DIR/<action>.depth<d>.png as qte-select --png names them; black panels of their size before
// the first action.
std::vector<cv::Mat> EpisodeVideo::attention_pictures() {
  std::vector<cv::Mat> pictures;
  for (int d = 0; action_ >= 0; ++d) {
    const std::string path =
        attention_dir_ + "/" + indexed_name(static_cast<uint64_t>(action_), "depth" + std::to_string(d) + ".png");
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) break;  // no deeper picture (asking OpenCV would warn)
    cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
    if (bgr.empty()) throw Error(path + ": not a readable picture");
    cv::cvtColor(bgr, bgr, cv::COLOR_BGR2RGB);
    pictures.push_back(bgr);
  }
  if (!pictures.empty()) picture_sizes_.clear();
  for (const cv::Mat& p : pictures) picture_sizes_.push_back(p.size());
  if (pictures.empty())
    for (const cv::Size& s : picture_sizes_) pictures.emplace_back(s, CV_8UC3, cv::Scalar(0, 0, 0));
  return pictures;
}

}  // namespace qte::video
