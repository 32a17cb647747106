#include "common/png_file.hpp"

#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.hpp"
#include "common/error.hpp"

namespace qte {

std::vector<uint8_t> encode_png(const cv::Mat& image, const std::string& what) {
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", image, png)) throw Error("cannot encode " + what + " as PNG");
  return png;
}

void write_png(const std::string& path, const cv::Mat& image) {
  const std::vector<uint8_t> png = encode_png(image, path);
  write_file_atomically(path, png.data(), png.size());
}

}  // namespace qte
