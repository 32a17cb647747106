#include "common/bounded_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include "common/error.hpp"

namespace qte {

namespace {

std::string bytes_text(uint64_t bytes) {
  if (bytes >= (1u << 20) && bytes % (1u << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

std::string read_regular_file(const std::string& path, std::size_t limit_bytes, const std::string& what) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; fstat then refuses it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw_system_error(path + ": cannot open " + what);
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0) throw_system_error(path + ": cannot read " + what);
  if (!S_ISREG(info.st_mode)) throw Error(path + ": " + kind_of(info.st_mode) + ", expected a regular file (" + what + ")");
  std::string text;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw_system_error(path + ": cannot read " + what);
    if (n == 0) return text;
    if (text.size() + static_cast<std::size_t>(n) > limit_bytes)
      throw Error(path + ": larger than " + bytes_text(limit_bytes) + ", the most read as " + what);
    text.append(buffer, static_cast<std::size_t>(n));
  }
}

BoundedLines::BoundedLines(std::string path, std::size_t line_limit_bytes, uint64_t total_limit_bytes, std::string what)
    : path_(std::move(path)), what_(std::move(what)), line_limit_(line_limit_bytes), total_limit_(total_limit_bytes) {
  struct stat info {};
  if (::stat(path_.c_str(), &info) == 0 && S_ISDIR(info.st_mode))
    throw Error(path_ + ": a directory, expected a file (" + what_ + ")");
  file_.reset(std::fopen(path_.c_str(), "rb"));
  if (!file_) throw_system_error(path_ + ": cannot open " + what_);
}

bool BoundedLines::next(std::string& line) {
  line.clear();
  int c = 0;
  bool any = false;
  while ((c = std::getc(file_.get())) != EOF) {
    any = true;
    if (++total_ > total_limit_)
      throw Error(path_ + ": larger than " + bytes_text(total_limit_) + ", the most read as " + what_);
    if (c == '\n') break;
    if (line.size() == line_limit_)
      throw Error(path_ + ": line " + std::to_string(line_number_ + 1) + " is longer than " + bytes_text(line_limit_) +
                  ", the most read as a line of " + what_);
    line.push_back(static_cast<char>(c));
  }
  if (std::ferror(file_.get())) throw_system_error(path_ + ": cannot read " + what_);
  if (!any) return false;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  line_number_ += 1;
  return true;
}

std::string clean_text(const std::string& text, std::size_t limit_bytes) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    // The length of a valid UTF-8 sequence starting here (0: not one), without overlongs and
    // surrogates, as RFC 3629 says.
    std::size_t length = 0;
    if (c >= 0x20 && c < 0x7f) length = 1;
    else if (c >= 0xc2 && c <= 0xdf) length = 2;
    else if (c >= 0xe0 && c <= 0xef) length = 3;
    else if (c >= 0xf0 && c <= 0xf4) length = 4;
    bool valid = length > 0 && i + length <= text.size();
    for (std::size_t k = 1; valid && k < length; ++k)
      valid = (static_cast<unsigned char>(text[i + k]) & 0xc0) == 0x80;
    if (valid && length >= 3) {
      const unsigned char second = static_cast<unsigned char>(text[i + 1]);
      if ((c == 0xe0 && second < 0xa0) || (c == 0xed && second >= 0xa0) || (c == 0xf0 && second < 0x90) ||
          (c == 0xf4 && second >= 0x90))
        valid = false;
    }
    if (!valid) length = 1;
    if (out.size() + length > limit_bytes) break;
    if (valid) out.append(text, i, length);
    else out.push_back('?');
    i += length;
  }
  return out;
}

}  // namespace qte
