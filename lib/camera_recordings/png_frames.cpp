#include "camera_recordings/png_frames.hpp"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <memory>
#include <vector>

#include "common/error.hpp"

namespace qte::camera_recordings {

namespace {

// libpng reports through these: an error is kept for our message and ends the read (longjmp
// back into guarded()), a warning is dropped (the user sees one line from us, not libpng's).
struct PngErrors {
  char message[160] = "";
};

void on_error(png_structp png, png_const_charp message) {
  auto* errors = static_cast<PngErrors*>(png_get_error_ptr(png));
  std::snprintf(errors->message, sizeof errors->message, "%s", message);
  for (char* c = errors->message; *c; ++c)
    if (*c < 0x20 || *c > 0x7e) *c = '?';
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}

// Runs libpng calls; false when libpng reported an error. Nothing with a destructor lives in
// the frames libpng's longjmp skips (this one after setjmp, `step` and libpng's own).
template <typename Step>
bool guarded(png_structp png, const Step& step) {
  if (setjmp(png_jmpbuf(png))) return false;
  step();
  return true;
}

struct ReadStructs {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~ReadStructs() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

struct FileCloser {
  void operator()(FILE* f) const { std::fclose(f); }
};

enum class PngKind { colour, depth };

const char* colour_type_name(int type) {
  switch (type) {
    case PNG_COLOR_TYPE_GRAY: return "greyscale";
    case PNG_COLOR_TYPE_GRAY_ALPHA: return "greyscale+alpha";
    case PNG_COLOR_TYPE_PALETTE: return "palette";
    case PNG_COLOR_TYPE_RGB: return "RGB";
    case PNG_COLOR_TYPE_RGB_ALPHA: return "RGBA";
    default: return "unknown colour type";
  }
}

// The transformations that give 8-bit BGR from any PNG (what imread(IMREAD_COLOR) gives).
void to_bgr(png_structp png, int bit_depth, int colour_type) {
  if (bit_depth == 16) png_set_strip_16(png);
  if (colour_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (!(colour_type & PNG_COLOR_MASK_COLOR)) {
    if (bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    png_set_gray_to_rgb(png);
  }
  png_set_strip_alpha(png);  // also the alpha a palette's or grey's tRNS chunk expands to
  png_set_bgr(png);
}

cv::Mat read_png(const std::string& path, PngKind kind) {
  std::unique_ptr<FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw_system_error("cannot open " + path);
  png_byte signature[8] = {};
  if (std::fread(signature, 1, sizeof signature, file.get()) != sizeof signature || png_sig_cmp(signature, 0, sizeof signature))
    throw Error(path + ": not a PNG file, expected a PNG image");
  PngErrors errors;
  ReadStructs s;
  s.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &errors, on_error, on_warning);
  if (s.png) s.info = png_create_info_struct(s.png);
  if (!s.info) throw Error(path + ": out of memory starting libpng");
  const auto damaged = [&] { return Error(path + ": damaged PNG (" + errors.message + "), expected a whole PNG image"); };
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, colour_type = 0;
  if (!guarded(s.png, [&] {
        png_init_io(s.png, file.get());
        png_set_sig_bytes(s.png, sizeof signature);
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
        // Checksums not enforced in the fuzz build, as the stream's, so mutations reach the decoder.
        png_set_crc_action(s.png, PNG_CRC_QUIET_USE, PNG_CRC_QUIET_USE);
#endif
        png_read_info(s.png, s.info);
        png_get_IHDR(s.png, s.info, &width, &height, &bit_depth, &colour_type, nullptr, nullptr, nullptr);
      }))
    throw damaged();
  // The header's size, checked before a pixel is decoded or a byte allocated for them.
  if (width > kMaxPngSide || height > kMaxPngSide || uint64_t(width) * height > kMaxPngPixels)
    throw Error(path + ": PNG of " + std::to_string(width) + " x " + std::to_string(height) + " pixels, expected at most " +
                std::to_string(kMaxPngSide) + " on a side and " + std::to_string(kMaxPngPixels) + " in all");
  if (kind == PngKind::depth && (colour_type != PNG_COLOR_TYPE_GRAY || bit_depth != 16))
    throw Error(path + ": " + std::to_string(bit_depth) + "-bit " + colour_type_name(colour_type) +
                " PNG, expected a 16-bit single-channel (greyscale) depth image");
  const int mat_type = kind == PngKind::depth ? CV_16UC1 : CV_8UC3;
  const std::size_t row_bytes = static_cast<std::size_t>(width) * (kind == PngKind::depth ? 2 : 3);
  std::size_t decoded_row_bytes = 0;
  if (!guarded(s.png, [&] {
        if (kind == PngKind::depth) png_set_swap(s.png);  // PNG's 16-bit samples are big-endian, ours little
        else to_bgr(s.png, bit_depth, colour_type);
        png_set_interlace_handling(s.png);
        png_read_update_info(s.png, s.info);
        decoded_row_bytes = png_get_rowbytes(s.png, s.info);
      }))
    throw damaged();
  if (decoded_row_bytes != row_bytes)
    throw Error(path + ": " + std::to_string(bit_depth) + "-bit " + colour_type_name(colour_type) +
                " PNG that libpng cannot convert, expected a colour or greyscale image");
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), mat_type);
  std::vector<png_bytep> rows(height);
  for (png_uint_32 r = 0; r < height; ++r) rows[r] = image.ptr(static_cast<int>(r));
  if (!guarded(s.png, [&] {
        png_read_image(s.png, rows.data());
        png_read_end(s.png, nullptr);
      }))
    throw damaged();
  return image;
}

}  // namespace

cv::Mat read_colour_png(const std::string& path) { return read_png(path, PngKind::colour); }

cv::Mat read_depth_png(const std::string& path) { return read_png(path, PngKind::depth); }

}  // namespace qte::camera_recordings
