// The joint log: rows of 7 joint angles (rad) and the gripper opening (m); every cell a finite
// number, a bad one named by line and column, a row of nan never taken for a header.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "camera_recordings/camera_recordings.hpp"
#include "common/error.hpp"
#include "test_support.hpp"

using namespace qte;

namespace {

std::string csv_file(const std::string& text) {
  static int n = 0;
  const std::string path = test_support::temp_dir("joint_csv") + "/joints" + std::to_string(n++) + ".csv";
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(text.c_str(), f);
  std::fclose(f);
  return path;
}

std::string csv_error(const std::string& path) {
  try {
    camera_recordings::read_joint_csv(path, test_support::xarm());
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.what();
  }
  return "";
}

}  // namespace

TEST(JointCsv, AHeaderThenRowsReadAsStates) {
  const auto states = camera_recordings::read_joint_csv(
      csv_file("j1,j2,j3,j4,j5,j6,j7,gripper_m\n0,0.1,0,0.2,0,0.3,0,0.04\r\n# a comment\n0,0,0,0,0,0,0\n"), test_support::xarm());
  ASSERT_EQ(states.size(), 2u);
  EXPECT_DOUBLE_EQ(states[0].joints[5], 0.3);
  EXPECT_DOUBLE_EQ(states[0].gripper_opening_m, 0.04);
  EXPECT_DOUBLE_EQ(states[1].gripper_opening_m, test_support::xarm().max_finger_opening_m());
}

// "nan" reads as a number, so a first row of them is data (it used to pass for a header and
// leave "0 rows"); every non-finite or unparsable cell is named by line and column.
TEST(JointCsv, NonFiniteOrUnparsableCellsAreNamedByLineAndColumn) {
  const std::string nan_row = csv_file("nan,nan,nan,nan,nan,nan,nan\n0,0,0,0,0,0,0\n");
  EXPECT_EQ(csv_error(nan_row), nan_row + ": line 1: column 1 is 'nan', expected a finite number (7 joint angles in "
                                          "radians, then optionally the gripper opening in metres)");
  EXPECT_NE(csv_error(csv_file("j1,j2,j3,j4,j5,j6,j7\n0,0,inf,0,0,0,0\n")).find(": line 2: column 3 is 'inf', expected a finite number"),
            std::string::npos);
  EXPECT_NE(csv_error(csv_file("0,0,0,0,0,0,0\n0,0,0,0,1e999,0,0\n")).find(": line 2: column 5 is '1e999'"), std::string::npos);
  EXPECT_NE(csv_error(csv_file("0,0,0,0,0,0,0\n0,0,0,0,0,0,x\n")).find(": line 2: column 7 is 'x'"), std::string::npos);
  EXPECT_NE(csv_error(csv_file("0,0,0,0,0,0,0,\n")).find(": line 1: column 8 is empty"), std::string::npos);
  EXPECT_NE(csv_error(csv_file("0,0,,0,0,0,0\n")).find(": line 1: column 3 is empty"), std::string::npos);
  EXPECT_NE(csv_error(csv_file("0,0,0,0,0,0\n")).find(": line 1: 6 columns, expected 7 or 8"), std::string::npos);
  EXPECT_NE(csv_error(csv_file("j1,j2,j3,j4,j5,j6,j7\n")).find(": no rows, expected one row per frame"), std::string::npos);
  EXPECT_NE(csv_error(csv_file("")).find(": no rows"), std::string::npos);
}
