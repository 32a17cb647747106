// Camera frames as PNG: what OpenCV writes reads back, and damaged or oversized files give one
// Error naming the file and nothing on stderr (neither libpng's nor OpenCV's messages).
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "camera_recordings/png_frames.hpp"
#include "common/error.hpp"
#include "test_support.hpp"

using namespace qte;
using camera_recordings::read_colour_png;
using camera_recordings::read_depth_png;

namespace {

std::string chunk(const std::string& type, const std::string& data) {
  std::string out;
  const uint32_t n = static_cast<uint32_t>(data.size());
  for (int s = 24; s >= 0; s -= 8) out += char(n >> s);
  const std::string body = type + data;
  const uint32_t crc = static_cast<uint32_t>(::crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size()));
  out += body;
  for (int s = 24; s >= 0; s -= 8) out += char(crc >> s);
  return out;
}

std::string big_endian(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }

// A PNG of the given header whose image data is `raw` (filter bytes included) deflated, with
// `extra` chunks before it.
std::string png_bytes(uint32_t width, uint32_t height, int bit_depth, int colour_type, const std::string& raw,
                      const std::string& extra = "") {
  std::string ihdr = big_endian(width) + big_endian(height);
  ihdr += {char(bit_depth), char(colour_type), 0, 0, 0};
  uLongf size = ::compressBound(raw.size());
  std::string packed(size, '\0');
  ::compress(reinterpret_cast<Bytef*>(packed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()), raw.size());
  packed.resize(size);
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + extra + chunk("IDAT", packed) + chunk("IEND", "");
}

std::string write_file(const std::string& dir, const std::string& name, const std::string& bytes) {
  const std::string path = dir + "/" + name;
  FILE* f = std::fopen(path.c_str(), "wb");
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  return path;
}

// The Error read gives, stderr checked empty while it ran.
template <typename Read>
std::string error_of(const Read& read, const std::string& path) {
  std::string error;
  ::testing::internal::CaptureStderr();
  try {
    read(path);
  } catch (const Error& e) {
    error = e.what();
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << path;
  EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  return error;
}

}  // namespace

TEST(PngFrames, ColourAndDepthWrittenByOpenCvReadBackAsTheyWere) {
  const std::string dir = test_support::temp_dir("png_frames");
  cv::Mat bgr(5, 7, CV_8UC3), depth(5, 7, CV_16UC1);
  for (int v = 0; v < 5; ++v)
    for (int u = 0; u < 7; ++u) {
      bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(uint8_t(30 * u), uint8_t(50 * v), uint8_t(u + v));
      depth.at<uint16_t>(v, u) = uint16_t(1000 * v + 77 * u + 65000 * (u == 6 && v == 4));
    }
  ASSERT_TRUE(cv::imwrite(dir + "/c.png", bgr));
  ASSERT_TRUE(cv::imwrite(dir + "/d.png", depth));
  EXPECT_EQ(cv::norm(read_colour_png(dir + "/c.png"), bgr, cv::NORM_INF), 0);
  const cv::Mat d = read_depth_png(dir + "/d.png");
  ASSERT_EQ(d.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(d, depth, cv::NORM_INF), 0);
  // Greyscale and RGBA colour images: as imread(IMREAD_COLOR) gives them.
  cv::Mat grey(3, 4, CV_8UC1, cv::Scalar(9)), bgra(3, 4, CV_8UC4, cv::Scalar(1, 2, 3, 128));
  ASSERT_TRUE(cv::imwrite(dir + "/g.png", grey));
  ASSERT_TRUE(cv::imwrite(dir + "/a.png", bgra));
  // A palette with transparency (tRNS): libpng expands it to RGBA, the alpha dropped as well.
  const std::string palette = png_bytes(2, 1, 8, 3, std::string("\0\0\1", 3),
                                        chunk("PLTE", std::string("\xff\0\0\0\x80\xff", 6)) + chunk("tRNS", std::string("\x40", 1)));
  write_file(dir, "p.png", palette);
  for (const char* name : {"/g.png", "/a.png", "/p.png"})
    EXPECT_EQ(cv::norm(read_colour_png(dir + name), cv::imread(dir + name, cv::IMREAD_COLOR), cv::NORM_INF), 0) << name;
}

// The header's size is checked before a pixel is decoded: no OpenCV assertion, no allocation.
TEST(PngFrames, AnOversizedHeaderIsOneLineNamingTheFile) {
  const std::string dir = test_support::temp_dir("png_frames");
  const std::string colour = write_file(dir, "huge.png", png_bytes(100000, 100000, 8, 2, std::string(301, '\0')));
  EXPECT_NE(error_of(read_colour_png, colour).find("PNG of 100000 x 100000 pixels, expected at most 32768 on a side"),
            std::string::npos);
  const std::string depth = write_file(dir, "huge_depth.png", png_bytes(20000, 20000, 16, 0, std::string(301, '\0')));
  EXPECT_NE(error_of(read_depth_png, depth).find("PNG of 20000 x 20000 pixels, expected at most 32768 on a side and 50000000 in all"),
            std::string::npos);
}

TEST(PngFrames, DamagedAndWrongFilesAreOneLineAndLibpngStaysQuiet) {
  const std::string dir = test_support::temp_dir("png_frames");
  const std::string pixels = std::string("\0\x10\x10\x10\x10\x10\x10", 7);
  const std::string truncated = write_file(dir, "truncated.png", png_bytes(2, 2, 8, 2, std::string(3, '\0')));
  EXPECT_NE(error_of(read_colour_png, truncated).find("damaged PNG (Not enough image data), expected a whole PNG image"),
            std::string::npos);
  std::string bad_crc = png_bytes(2, 2, 8, 2, pixels + pixels);
  bad_crc[29] ^= 1;  // the IHDR's CRC
  EXPECT_NE(error_of(read_colour_png, write_file(dir, "crc.png", bad_crc)).find("damaged PNG"), std::string::npos);
  const std::string cut = png_bytes(2, 2, 8, 2, pixels + pixels);
  EXPECT_NE(error_of(read_colour_png, write_file(dir, "cut.png", cut.substr(0, cut.size() - 20))).find("damaged PNG"),
            std::string::npos);
  EXPECT_NE(error_of(read_colour_png, write_file(dir, "text.png", "hello, not a picture\n")).find("not a PNG file"),
            std::string::npos);
  EXPECT_NE(error_of(read_depth_png, write_file(dir, "rgb.png", png_bytes(2, 2, 8, 2, pixels + pixels)))
                .find("8-bit RGB PNG, expected a 16-bit single-channel (greyscale) depth image"),
            std::string::npos);
  // An ancillary chunk libpng warns about (a too short iCCP): read, and nothing printed.
  const std::string warned = write_file(dir, "warned.png", png_bytes(2, 2, 8, 2, pixels + pixels, chunk("iCCP", std::string("a\0\0junk", 7))));
  ::testing::internal::CaptureStderr();
  const cv::Mat image = read_colour_png(warned);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(image.at<cv::Vec3b>(1, 1), cv::Vec3b(16, 16, 16));
}
