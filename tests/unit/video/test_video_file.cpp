// Videos read back by their own kind's decoders: OpenCV for MP4 (frame count, size, content),
// giflib for GIFs (frames, size, delays, colours within the 256-colour palette's error).
#include <gif_lib.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "common/error.hpp"
#include "video/episode_video.hpp"
#include "video/video_file.hpp"

#include <sys/stat.h>

using namespace qte;

namespace {

// Frame i: a colour ramp with a white square that moves right.
cv::Mat frame(int i, int w = 96, int h = 64) {
  cv::Mat rgb(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar(2 * x), uchar(3 * y), uchar(40 * i));
  cv::rectangle(rgb, cv::Rect(8 * i, 20, 16, 16), cv::Scalar(255, 255, 255), cv::FILLED);
  return rgb;
}

std::string temp(const char* name) { return ::testing::TempDir() + name; }

bool exists(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (f) std::fclose(f);
  return f != nullptr;
}

}  // namespace

TEST(VideoFile, Mp4ReadsBackWithItsFramesSizeAndPictures) {
  const std::string path = temp("episode.mp4");
  {
    video::VideoFile v(path, 5);
    for (int i = 0; i < 6; ++i) v.add(frame(i));
    EXPECT_FALSE(exists(path));  // not under its name before close()
    v.close();
  }
  cv::VideoCapture in(path);
  ASSERT_TRUE(in.isOpened());
  EXPECT_EQ(in.get(cv::CAP_PROP_FRAME_WIDTH), 96);
  EXPECT_EQ(in.get(cv::CAP_PROP_FRAME_HEIGHT), 64);
  int frames = 0;
  for (cv::Mat bgr; in.read(bgr); ++frames) {
    cv::Mat rgb;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    cv::Mat difference;
    cv::absdiff(rgb, frame(frames), difference);
    EXPECT_LT(cv::mean(difference)[0] + cv::mean(difference)[1] + cv::mean(difference)[2], 15.0) << "frame " << frames;
  }
  EXPECT_EQ(frames, 6);
  std::remove(path.c_str());
}

TEST(VideoFile, GifReadsBackWithFramesDelaysAndColours) {
  const std::string path = temp("episode.gif");
  {
    video::VideoFile v(path, 4);
    for (int i = 0; i < 3; ++i) v.add(frame(i));
    v.close();
  }
  int error = 0;
  GifFileType* gif = DGifOpenFileName(path.c_str(), &error);
  ASSERT_NE(gif, nullptr);
  ASSERT_EQ(DGifSlurp(gif), GIF_OK);
  EXPECT_EQ(gif->SWidth, 96);
  EXPECT_EQ(gif->SHeight, 64);
  ASSERT_EQ(gif->ImageCount, 3);
  for (int i = 0; i < 3; ++i) {
    const SavedImage& image = gif->SavedImages[i];
    GraphicsControlBlock timing;
    ASSERT_EQ(DGifSavedExtensionToGCB(gif, i, &timing), GIF_OK);
    EXPECT_EQ(timing.DelayTime, 25);  // 4 frames per second
    const ColorMapObject* map = image.ImageDesc.ColorMap;
    ASSERT_NE(map, nullptr);
    const cv::Mat want = frame(i);
    double error_sum = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 96; ++x) {
        const GifColorType c = map->Colors[image.RasterBits[y * 96 + x]];
        const cv::Vec3b w = want.at<cv::Vec3b>(y, x);
        error_sum += std::abs(c.Red - w[0]) + std::abs(c.Green - w[1]) + std::abs(c.Blue - w[2]);
      }
    EXPECT_LT(error_sum / (64 * 96 * 3), 6.0) << "frame " << i;
  }
  DGifCloseFile(gif, &error);
  std::remove(path.c_str());
}

TEST(VideoFile, NothingIsLeftWhenNotClosedAndBadInputIsRefused) {
  const std::string path = temp("abandoned.mp4");
  {
    video::VideoFile v(path, 5);
    v.add(frame(0));
    EXPECT_THROW(v.add(frame(1, 48, 32)), Error);  // another size
  }
  EXPECT_FALSE(exists(path));
  EXPECT_THROW(video::VideoFile(temp("x.avi"), 5), Error);
  EXPECT_THROW(video::VideoFile(temp("x.mp4"), 0), Error);
  video::VideoFile empty(temp("empty.gif"), 5);
  EXPECT_THROW(empty.close(), Error);
}

TEST(VideoFile, SideBySideScalesEveryPanelToOneHeight) {
  const cv::Mat camera = frame(0);                           // 96 x 64
  const cv::Mat picture(16, 16, CV_8UC3, cv::Scalar(1, 2, 3));  // a small attention picture
  const cv::Mat out = video::side_by_side(camera, {picture, picture}, 128);
  EXPECT_EQ(out.rows, 128);
  EXPECT_EQ(out.cols, 192 + 128 + 128);
  EXPECT_EQ(out.at<cv::Vec3b>(5, 192 + 3), cv::Vec3b(1, 2, 3));
  EXPECT_EQ(out.at<cv::Vec3b>(0, 0), camera.at<cv::Vec3b>(0, 0));
}

namespace {

stream::Record observation(int step, bool terminal, uint8_t grey) {
  stream::Record obs("obs");
  obs.set<uint8_t>("front.rgb", {8, 8, 3}, std::vector<uint8_t>(8 * 8 * 3, grey));
  obs.set_scalar<int32_t>("step", step);
  obs.set_scalar<uint8_t>("terminal", terminal);
  return obs;
}

// Which action's picture the attention panel of each GIF frame shows (action n's is red 60 * (n + 1);
// the palette may round it by a few levels).
std::vector<int> panel_actions(const std::string& path) {
  int error = 0;
  GifFileType* gif = DGifOpenFileName(path.c_str(), &error);
  EXPECT_NE(gif, nullptr);
  if (!gif) return {};
  EXPECT_EQ(DGifSlurp(gif), GIF_OK);
  std::vector<int> reds;
  for (int i = 0; i < gif->ImageCount; ++i) {
    const SavedImage& image = gif->SavedImages[i];
    const int red = image.ImageDesc.ColorMap->Colors[image.RasterBits[4 * gif->SWidth + 12]].Red;  // row 4, column 12: the panel
    reds.push_back((red + 30) / 60 - 1);
  }
  DGifCloseFile(gif, &error);
  return reds;
}

}  // namespace

// qte-select acts on the last observation of each step: the frames of a motion (sim-step
// --every-step) show the action they carry out, the acted-on frame its own new action.
TEST(EpisodeVideo, EachFrameShowsTheActionChosenOnItOrBeingCarriedOut) {
  const std::string dir = temp("attention");
  ::mkdir(dir.c_str(), 0755);
  for (int n = 0; n < 2; ++n) {
    char name[64];
    std::snprintf(name, sizeof name, "/%06d.depth0.png", n);
    cv::imwrite(dir + name, cv::Mat(8, 8, CV_8UC3, cv::Scalar(0, 0, 60 * (n + 1))));  // BGR: red
  }
  const std::string every_step = temp("every_step.gif");
  video::EpisodeVideo v(every_step, 10, "front", dir, 8);
  for (const auto& [step, terminal] : std::vector<std::pair<int, bool>>{{0, false}, {1, false}, {1, false}, {1, false}, {2, false}, {2, true}})
    v.add(observation(step, terminal, 100));
  v.close();
  EXPECT_EQ(panel_actions(every_step), (std::vector<int>{0, 0, 0, 1, 1, 1}));

  const std::string keyframes = temp("keyframes.gif");
  video::EpisodeVideo k(keyframes, 10, "front", dir, 8);
  k.add(observation(0, false, 100));
  k.add(observation(1, false, 100), /*shown=*/false);  // counted, not shown (--every)
  k.add(observation(2, true, 100));
  k.close();
  EXPECT_EQ(panel_actions(keyframes), (std::vector<int>{0, 1}));
}
