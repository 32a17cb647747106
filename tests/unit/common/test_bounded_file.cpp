#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <thread>
#include <unordered_set>

#include "common/bounded_file.hpp"
#include "common/error.hpp"

using namespace qte;

namespace {

std::string temp_dir() {
  char pattern[] = "/tmp/qte_bounded_XXXXXX";
  return ::mkdtemp(pattern);
}

void write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Every character clean_text keeps, encoded from its code point (the encoder, not a decoder).
const std::unordered_set<std::string>& kept_characters() {
  static const std::unordered_set<std::string> kept = [] {
    std::unordered_set<std::string> set;
    for (uint32_t c = 0x20; c <= 0x10ffff; ++c) {
      if (c == 0x7f || (c >= 0xd800 && c <= 0xdfff)) continue;
      std::string s;
      if (c < 0x80) s = {char(c)};
      else if (c < 0x800) s = {char(0xc0 | c >> 6), char(0x80 | (c & 0x3f))};
      else if (c < 0x10000) s = {char(0xe0 | c >> 12), char(0x80 | (c >> 6 & 0x3f)), char(0x80 | (c & 0x3f))};
      else s = {char(0xf0 | c >> 18), char(0x80 | (c >> 12 & 0x3f)), char(0x80 | (c >> 6 & 0x3f)), char(0x80 | (c & 0x3f))};
      set.insert(s);
    }
    return set;
  }();
  return kept;
}

// The reference: at each place a whole character of the set (UTF-8 is prefix-free: at most one
// length matches) is kept, anything else is one '?' a byte; cut before the limit is passed.
std::string reference_clean(const std::string& text, std::size_t limit) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    std::size_t length = 0;
    for (std::size_t l = 1; l <= 4 && i + l <= text.size() && !length; ++l)
      if (kept_characters().count(text.substr(i, l))) length = l;
    const std::string piece = length ? text.substr(i, length) : "?";
    if (out.size() + piece.size() > limit) break;
    out += piece;
    i += length ? length : 1;
  }
  return out;
}

}  // namespace

TEST(CleanText, EveryStringOfOneOrTwoBytesAsTheReferenceSays) {
  for (int a = 0; a < 256; ++a) {
    const std::string one{char(a)};
    ASSERT_EQ(clean_text(one, 200), reference_clean(one, 200)) << "byte " << a;
    for (int b = 0; b < 256; ++b) {
      const std::string two{char(a), char(b)};
      ASSERT_EQ(clean_text(two, 200), reference_clean(two, 200)) << "bytes " << a << " " << b;
    }
  }
}

TEST(CleanText, RandomHighByteStringsAndCutsAsTheReferenceSays) {
  std::mt19937 random(7);
  for (int n = 0; n < 200000; ++n) {
    std::string text(1 + random() % 12, '\0');
    for (char& c : text) c = char(random() % 3 ? 0x80 + random() % 0x80 : random() % 0x100);
    const std::size_t limit = random() % 14;
    ASSERT_EQ(clean_text(text, limit), reference_clean(text, limit)) << "case " << n;
  }
  // Every kept character survives whole, and text already clean is left as it is.
  for (const std::string& c : kept_characters()) ASSERT_EQ(clean_text("a" + c, 8), "a" + c);
  EXPECT_EQ(clean_text("collision \xe2\x80\x94 code 22\t\n", 200), "collision \xe2\x80\x94 code 22??");
  EXPECT_EQ(clean_text("ab\xe2\x80\x94", 4), "ab");  // not a cut character
}

TEST(ReadRegularFile, RefusesFifosDevicesDirectoriesAndTooMuchWithoutWaiting) {
  const std::string dir = temp_dir();
  write(dir + "/answer", "0,1,2\n");
  EXPECT_EQ(read_regular_file(dir + "/answer", 6, "an answer"), "0,1,2\n");
  EXPECT_NE(error_of([&] { read_regular_file(dir + "/answer", 5, "an answer"); }).find("larger than 5 bytes"),
            std::string::npos);
  ASSERT_EQ(::mkfifo((dir + "/fifo").c_str(), 0600), 0);  // nobody writes: opening must not wait
  EXPECT_NE(error_of([&] { read_regular_file(dir + "/fifo", 100, "an answer"); }).find("a FIFO, expected a regular file"),
            std::string::npos);
  ASSERT_EQ(::symlink("/dev/zero", (dir + "/zero").c_str()), 0);
  EXPECT_NE(error_of([&] { read_regular_file(dir + "/zero", 100, "an answer"); }).find("a device"), std::string::npos);
  EXPECT_NE(error_of([&] { read_regular_file(dir, 100, "an answer"); }).find("a directory"), std::string::npos);
  EXPECT_NE(error_of([&] { read_regular_file(dir + "/none", 100, "an answer"); }).find("none: cannot open an answer"),
            std::string::npos);
}

TEST(BoundedLines, ReadsFilesAndFifosALineAtATimeWithinTheirLimits) {
  const std::string dir = temp_dir();
  write(dir + "/lines", "success\r\n\n# note\nfailure dropped");
  BoundedLines lines(dir + "/lines", 16, 1000, "outcomes");
  std::string line;
  std::vector<std::string> got;
  while (lines.next(line)) got.push_back(std::to_string(lines.line_number()) + ":" + line);
  EXPECT_EQ(got, (std::vector<std::string>{"1:success", "2:", "3:# note", "4:failure dropped"}));

  write(dir + "/long", "ok\n" + std::string(17, 'x') + "\n");
  BoundedLines long_lines(dir + "/long", 16, 1000, "outcomes");
  ASSERT_TRUE(long_lines.next(line));
  EXPECT_NE(error_of([&] { long_lines.next(line); }).find("line 2 is longer than 16 bytes"), std::string::npos);
  BoundedLines zeros("/dev/zero", 4096, 1 << 20, "a joint log");
  EXPECT_NE(error_of([&] { zeros.next(line); }).find("/dev/zero: line 1 is longer than 4 KiB"), std::string::npos);
  BoundedLines total(dir + "/lines", 16, 10, "outcomes");
  EXPECT_NE(error_of([&] { while (total.next(line)) {} }).find("larger than 10 bytes"), std::string::npos);
  EXPECT_NE(error_of([&] { BoundedLines(dir, 16, 10, "outcomes"); }).find("a directory, expected a file"),
            std::string::npos);

  // A FIFO: a script's outcomes as it writes them.
  ASSERT_EQ(::mkfifo((dir + "/fifo").c_str(), 0600), 0);
  std::thread writer([&] { write(dir + "/fifo", "continue\nsuccess\n"); });
  BoundedLines fifo(dir + "/fifo", 16, 1000, "outcomes");
  got.clear();
  while (fifo.next(line)) got.push_back(line);
  writer.join();
  EXPECT_EQ(got, (std::vector<std::string>{"continue", "success"}));
}
