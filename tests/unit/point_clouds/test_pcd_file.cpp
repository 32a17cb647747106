#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <sys/resource.h>
#include <unistd.h>

#include "common/error.hpp"
#include "point_clouds/pcd_file.hpp"

using namespace qte;

namespace {

voxels::CameraCloud small_camera() {
  voxels::CameraCloud c;
  c.camera = "front";
  c.width = 4, c.height = 3;
  for (int i = 0; i < 12; ++i) {
    const bool none = i == 5;
    c.cloud.xyz.insert(c.cloud.xyz.end(), {none ? NAN : 0.1f * i, none ? NAN : -0.03f * i, none ? NAN : 0.7f + 0.001f * i});
    c.cloud.rgb.insert(c.cloud.rgb.end(), {uint8_t(20 * i), uint8_t(255 - i), uint8_t(i)});
  }
  return c;
}

std::string temp_path(const char* name) { return ::testing::TempDir() + name; }

}  // namespace

// What we write, PCL reads back: the same points bit for bit, colours, and the image's layout.
TEST(PcdFile, PclLoadsTheSamePointsColoursAndLayout) {
  const voxels::CameraCloud c = small_camera();
  const std::string path = temp_path("camera.pcd");
  point_clouds::write_pcd(path, c);
  pcl::PointCloud<pcl::PointXYZRGB> loaded;
  ASSERT_EQ(pcl::io::loadPCDFile(path, loaded), 0);
  EXPECT_EQ(loaded.width, 4u);
  EXPECT_EQ(loaded.height, 3u);
  EXPECT_FALSE(loaded.is_dense);
  ASSERT_EQ(loaded.size(), 12u);
  for (int i = 0; i < 12; ++i) {
    const auto& p = loaded[i];
    if (i == 5) {
      EXPECT_TRUE(std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z));
    } else {
      EXPECT_EQ(std::memcmp(&p.x, &c.cloud.xyz[3 * i], 4), 0);
      EXPECT_EQ(p.y, c.cloud.xyz[3 * i + 1]);
      EXPECT_EQ(p.z, c.cloud.xyz[3 * i + 2]);
    }
    EXPECT_EQ(p.r, c.cloud.rgb[3 * i]);
    EXPECT_EQ(p.g, c.cloud.rgb[3 * i + 1]);
    EXPECT_EQ(p.b, c.cloud.rgb[3 * i + 2]);
  }
  const voxels::CameraCloud back = point_clouds::read_pcd(path);
  EXPECT_EQ(back.width, 4);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.cloud.rgb, c.cloud.rgb);
  for (std::size_t i = 0; i < c.cloud.xyz.size(); ++i)
    EXPECT_TRUE(back.cloud.xyz[i] == c.cloud.xyz[i] || (std::isnan(back.cloud.xyz[i]) && std::isnan(c.cloud.xyz[i])));
  std::remove(path.c_str());
}

TEST(PcdFile, AnUnorganizedCloudWithoutColourReadsAsOneRowOfWhite) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back({0.1f, 0.2f, 0.3f});
  cloud.push_back({0.4f, 0.5f, 0.6f});
  const std::string path = temp_path("plain.pcd");
  ASSERT_EQ(pcl::io::savePCDFileASCII(path, cloud), 0);
  const voxels::CameraCloud back = point_clouds::read_pcd(path);
  EXPECT_EQ(back.height, 1);
  EXPECT_EQ(back.width, 2);
  EXPECT_EQ(back.cloud.xyz, (std::vector<float>{0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}));
  EXPECT_EQ(back.cloud.rgb, std::vector<uint8_t>(6, 255));
  std::remove(path.c_str());
}

TEST(PcdFile, ANonPcdFileIsAnErrorNamingIt) {
  const std::string path = temp_path("not.pcd");
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs("hello\n", f);
  std::fclose(f);
  try {
    point_clouds::read_pcd(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::remove(path.c_str());
}

namespace {

// A .pcd file of `header` lines (DATA last) and `data`; its path.
std::string pcd_file(const char* name, const std::string& header, const std::string& data) {
  const std::string path = temp_path(name);
  FILE* f = std::fopen(path.c_str(), "wb");
  std::fwrite(header.data(), 1, header.size(), f);
  std::fwrite(data.data(), 1, data.size(), f);
  std::fclose(f);
  return path;
}

std::string xyz_header(const std::string& size_type, uint64_t width, uint64_t height, uint64_t points,
                       const std::string& data) {
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n" + size_type + "COUNT 1 1 1\nWIDTH " +
         std::to_string(width) + "\nHEIGHT " + std::to_string(height) + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
         std::to_string(points) + "\nDATA " + data + "\n";
}

const std::string kFloats = "SIZE 4 4 4\nTYPE F F F\n";

// The one-line error read_pcd gives for the file, or "" when it reads.
std::string pcd_error(const std::string& path) {
  try {
    point_clouds::read_pcd(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// The reader's error for a file, checked to be one line that starts with the file's name.
void expect_refused(const std::string& path, const std::string& words) {
  const std::string error = pcd_error(path);
  EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
  EXPECT_NE(error.find(words), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  std::remove(path.c_str());
}

// Address space the process may still take: what it has now and `extra_bytes` more. The
// previous limit comes back when this goes out of scope.
class AddressSpaceLimit {
 public:
  explicit AddressSpaceLimit(uint64_t extra_bytes) {
    ::getrlimit(RLIMIT_AS, &saved_);
    long pages = 0;
    FILE* f = std::fopen("/proc/self/statm", "r");
    if (f && std::fscanf(f, "%ld", &pages) == 1) {
      rlimit lower = saved_;
      lower.rlim_cur = static_cast<rlim_t>(pages) * ::sysconf(_SC_PAGESIZE) + extra_bytes;
      ::setrlimit(RLIMIT_AS, &lower);
    }
    if (f) std::fclose(f);
  }
  ~AddressSpaceLimit() { ::setrlimit(RLIMIT_AS, &saved_); }

 private:
  rlimit saved_{};
};

}  // namespace

// The header is checked against the file before anything is allocated: 200-byte files claiming
// 10^9 or 4 x 10^7 points are refused within 256 MB of address space, naming what was expected.
TEST(PcdFile, AHeaderClaimingMorePointsThanTheFileHoldsIsRefusedBeforeAllocating) {
  const std::string data(200, '\0');
  const std::string huge = pcd_file("huge.pcd", xyz_header(kFloats, 1000000000, 1, 1000000000, "binary"), data);
  const std::string binary = pcd_file("large.pcd", xyz_header(kFloats, 40000000, 1, 40000000, "binary"), data);
  const std::string ascii = pcd_file("large_ascii.pcd", xyz_header(kFloats, 40000000, 1, 40000000, "ascii"), "1 2 3\n");
  {
    const AddressSpaceLimit limit(256 << 20);
    expect_refused(huge, "POINTS 1000000000, expected at most 50000000");
    expect_refused(binary, "POINTS 40000000 of 12 bytes need 480000000 bytes of binary data, the file has 200");
    expect_refused(ascii, "POINTS 40000000 of 3 values cannot fit in the 6 bytes of ASCII data");
  }
  const std::string compressed = pcd_file("huge_lzf.pcd", xyz_header(kFloats, 40000000, 1, 40000000, "binary_compressed"),
                                          std::string("\x10\0\0\0\x00\x38\x9c\x1c", 8) + std::string(16, 'a'));
  {
    const AddressSpaceLimit limit(256 << 20);
    expect_refused(compressed, "binary_compressed data: 16 compressed bytes cannot unpack to 480000000");
  }
}

TEST(PcdFile, WidthTimesHeightMustMakePointsWithoutOverflow) {
  expect_refused(pcd_file("wh.pcd", xyz_header(kFloats, 2, 2, 3, "binary"), std::string(48, '\0')),
                 "WIDTH 2 x HEIGHT 2 does not make POINTS 3, expected them to agree");
  // 65536 x 65536 is 0 in 32 bits.
  expect_refused(pcd_file("wrap.pcd", xyz_header(kFloats, 65536, 65536, 1, "binary"), std::string(12, '\0')),
                 "WIDTH 65536 x HEIGHT 65536 does not make POINTS 1");
  expect_refused(pcd_file("zero.pcd", xyz_header(kFloats, 0, 1, 0, "binary"), ""), "POINTS 0, expected a cloud of at least one point");
  expect_refused(pcd_file("many.pcd", xyz_header(kFloats, 60000000, 1, 60000000, "binary"), ""),
                 "POINTS 60000000, expected at most 50000000");
  expect_refused(pcd_file("short.pcd", xyz_header(kFloats, 2, 1, 2, "binary"), std::string(20, '\0')),
                 "POINTS 2 of 12 bytes need 24 bytes of binary data, the file has 20");
}

// x, y, z of another size or type would be read as 4-byte floats and give wrong points.
TEST(PcdFile, CoordinatesMustBeFourByteFloatsAndColourFourPackedBytes) {
  expect_refused(pcd_file("double.pcd", xyz_header("SIZE 8 8 8\nTYPE F F F\n", 2, 1, 2, "binary"), std::string(48, '\0')),
                 "field x is TYPE F SIZE 8 COUNT 1, expected a 4-byte float (TYPE F SIZE 4 COUNT 1)");
  expect_refused(pcd_file("int.pcd", xyz_header("SIZE 4 4 4\nTYPE F I F\n", 2, 1, 2, "binary"), std::string(24, '\0')),
                 "field y is TYPE I SIZE 4 COUNT 1, expected a 4-byte float");
  expect_refused(pcd_file("f2.pcd", xyz_header("SIZE 4 4 2\nTYPE F F F\n", 2, 1, 2, "binary"), std::string(24, '\0')),
                 "field z is TYPE F SIZE 2 COUNT 1, expected SIZE 4 or 8 for TYPE F");
  expect_refused(pcd_file("noz.pcd", "FIELDS x y w\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n",
                          std::string(12, '\0')),
                 "no field x, y or z");
  expect_refused(pcd_file("rgb2.pcd", "FIELDS x y z rgb\nSIZE 4 4 4 2\nTYPE F F F U\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n",
                          std::string(14, '\0')),
                 "field rgb is TYPE U SIZE 2 COUNT 1, expected 8-bit colour packed in 4 bytes");
  expect_refused(pcd_file("count.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n",
                          std::string(12, '\0')),
                 "3 FIELDS with 3 SIZE, 3 TYPE and 2 COUNT values, expected one of each per field");
  expect_refused(pcd_file("twice.pcd", "FIELDS x y z\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n",
                          std::string(12, '\0')),
                 "header line 2: FIELDS appears twice");
  expect_refused(pcd_file("nodata.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n", ""),
                 "not a .pcd point cloud");
}

// ASCII data is read strictly: one whole number of the field's type per value, POINTS lines.
TEST(PcdFile, MalformedAsciiDataIsRefusedNamingTheLineAndValue) {
  const std::string header = xyz_header(kFloats, 2, 1, 2, "ascii");
  expect_refused(pcd_file("a1.pcd", header, "1 2 3\n4 5 x\n"), "data line 2: value 3 (field z) is 'x', expected a 4-byte float");
  expect_refused(pcd_file("a2.pcd", header, "1 2 3\n4 5 6 7\n"), "data line 2: 4 values, expected 3");
  expect_refused(pcd_file("a3.pcd", header, "1.000000 2.000000 3.000000\n"), "1 data lines, expected POINTS 2");
  expect_refused(pcd_file("a4.pcd", header, "1 2 3\n4 5 6\n7 8 9\n"), "data line 3: more data lines than POINTS 2");
  expect_refused(pcd_file("a5.pcd", header, "1 2 3\n4 5 6e\n"), "value 3 (field z) is '6e'");
  expect_refused(pcd_file("a6.pcd", header, "1 2 3\n4 5 1e39\n"), "is '1e39', expected a 4-byte float");
  expect_refused(pcd_file("a7.pcd", header, "1 2 3\n\n4 5 6\n"), "data line 2: 0 values, expected 3");
  const std::string with_u8 = "FIELDS x y z label\nSIZE 4 4 4 1\nTYPE F F F U\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n";
  expect_refused(pcd_file("a8.pcd", with_u8, "1 2 3 256\n"), "value 4 (field label) is '256', expected an unsigned 1-byte integer");
  expect_refused(pcd_file("a9.pcd", with_u8, "1 2 3 -1\n"), "is '-1', expected an unsigned 1-byte integer");
  // What is well formed reads, NaN included, blank lines after the last point allowed.
  const std::string path = pcd_file("a10.pcd", with_u8, "0.5 -2 nan 255\n\n");
  const voxels::CameraCloud c = point_clouds::read_pcd(path);
  ASSERT_EQ(c.cloud.xyz.size(), 3u);
  EXPECT_TRUE(std::isnan(c.cloud.xyz[0]) && std::isnan(c.cloud.xyz[2]));
  std::remove(path.c_str());
}

TEST(PcdFile, CompressedSizesMustAgreeWithTheHeaderAndTheFile) {
  const std::string header = xyz_header(kFloats, 2, 1, 2, "binary_compressed");
  const auto sizes = [](uint32_t compressed, uint32_t uncompressed) {
    std::string s(8, '\0');
    std::memcpy(&s[0], &compressed, 4);
    std::memcpy(&s[4], &uncompressed, 4);
    return s;
  };
  expect_refused(pcd_file("c1.pcd", header, sizes(10, 25) + std::string(10, 'a')), "unpacks to 25 bytes, expected 24");
  expect_refused(pcd_file("c2.pcd", header, sizes(1000, 24) + std::string(10, 'a')), "1000 compressed bytes claimed, the file has 10");
  expect_refused(pcd_file("c3.pcd", header, sizes(10, 24) + std::string(10, '\xff')), "damaged LZF data");
  expect_refused(pcd_file("c4.pcd", header, "abc"), "the file ends before its two sizes");
}

// PCL's other encodings of a coloured cloud read back as what was saved.
TEST(PcdFile, PclsAsciiAndCompressedColourCloudsReadBack) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud(3, 2);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = 0.25f * i, cloud[i].y = -1.5f + i, cloud[i].z = 0.75f + 0.001f * i;
    cloud[i].r = uint8_t(40 * i), cloud[i].g = uint8_t(255 - i), cloud[i].b = uint8_t(7 * i + 1);
  }
  for (const bool compressed : {false, true}) {
    const std::string path = temp_path(compressed ? "lzf.pcd" : "ascii_rgb.pcd");
    ASSERT_EQ(compressed ? pcl::io::savePCDFileBinaryCompressed(path, cloud) : pcl::io::savePCDFileASCII(path, cloud), 0);
    const voxels::CameraCloud back = point_clouds::read_pcd(path);
    EXPECT_EQ(back.width, 3);
    EXPECT_EQ(back.height, 2);
    ASSERT_EQ(back.cloud.xyz.size(), 18u);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      EXPECT_EQ(back.cloud.xyz[3 * i], cloud[i].x);
      EXPECT_EQ(back.cloud.xyz[3 * i + 1], cloud[i].y);
      EXPECT_EQ(back.cloud.xyz[3 * i + 2], cloud[i].z);
      EXPECT_EQ(back.cloud.rgb[3 * i], cloud[i].r);
      EXPECT_EQ(back.cloud.rgb[3 * i + 1], cloud[i].g);
      EXPECT_EQ(back.cloud.rgb[3 * i + 2], cloud[i].b);
    }
    std::remove(path.c_str());
  }
}
