#include "common/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>

#include "common/error.hpp"

namespace qte {
namespace {

// Temporary files of this process, unlinked by the signal handler. Fixed-size table of
// C strings because a handler may only call async-signal-safe functions.
constexpr int kMaxTempFiles = 64;
char g_temp_paths[kMaxTempFiles][4096];
volatile sig_atomic_t g_temp_used[kMaxTempFiles];
std::mutex g_mutex;
std::once_flag g_handlers_installed;

void remove_temp_files_and_die(int signal_number) {
  for (int i = 0; i < kMaxTempFiles; ++i)
    if (g_temp_used[i]) ::unlink(g_temp_paths[i]);
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

void install_handlers() {
  for (int s : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = remove_temp_files_and_die;
    sigemptyset(&action.sa_mask);
    ::sigaction(s, &action, nullptr);
  }
}

int register_temp(const std::string& path) {
  std::call_once(g_handlers_installed, install_handlers);
  std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kMaxTempFiles; ++i)
    if (!g_temp_used[i] && path.size() < sizeof g_temp_paths[i]) {
      std::memcpy(g_temp_paths[i], path.c_str(), path.size() + 1);
      g_temp_used[i] = 1;
      return i;
    }
  return -1;  // still correct, only not cleaned up on a signal
}

void unregister_temp(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kMaxTempFiles; ++i)
    if (g_temp_used[i] && path == g_temp_paths[i]) g_temp_used[i] = 0;
}

}  // namespace

void write_all(int fd, const void* data, std::size_t n, const std::string& what) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (n > 0) {
    const ssize_t put = ::write(fd, p, n);
    if (put < 0) {
      if (errno == EINTR) continue;
      if (errno == EPIPE) throw BrokenPipe();
      throw_system_error("cannot write " + what);
    }
    p += put;
    n -= static_cast<std::size_t>(put);
  }
}

int remove_stale_temporaries(const std::string& dir, const std::string& name) {
  std::error_code error;
  int removed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.empty() ? "." : dir, error)) {
    const std::string file = entry.path().filename().string();
    const std::size_t tmp = file.rfind(".tmp.");
    if (tmp == std::string::npos || tmp == 0 || (!name.empty() && file.compare(0, tmp, name) != 0) ||
        (!name.empty() && tmp != name.size()))
      continue;
    const std::string digits = file.substr(tmp + 5);
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;  // its writer may still be at work
    if (std::filesystem::remove(entry.path(), error)) ++removed;
  }
  return removed;
}

AtomicOutputFile::AtomicOutputFile(std::string path)
    : path_(std::move(path)), temp_path_(path_ + ".tmp." + std::to_string(::getpid())) {
  const std::filesystem::path p(path_);
  remove_stale_temporaries(p.parent_path().string(), p.filename().string());
  struct stat info {};
  if (::stat(path_.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) throw_system_error("cannot open " + path_);
    temp_path_.clear();  // written in place
    return;
  }
  register_temp(temp_path_);
  fd_ = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    unregister_temp(temp_path_);
    throw_system_error("cannot create " + path_ + " (as " + temp_path_ + ")");
  }
}

AtomicOutputFile::~AtomicOutputFile() {
  if (fd_ >= 0) {
    ::close(fd_);
    if (!temp_path_.empty()) {
      ::unlink(temp_path_.c_str());
      unregister_temp(temp_path_);
    }
  }
}

void AtomicOutputFile::write(const void* data, std::size_t n) {
  if (fd_ < 0) throw Error("write to " + path_ + " after it was committed");
  write_all(fd_, data, n, path_);
}

void AtomicOutputFile::commit() {
  if (fd_ < 0) return;
  if (temp_path_.empty()) {  // a device or pipe: nothing to sync or rename
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) throw_system_error("cannot close " + path_);
    return;
  }
  if (::fsync(fd_) != 0 && errno != EINVAL) throw_system_error("cannot sync " + path_);
  if (::close(fd_) != 0) {
    fd_ = -1;
    ::unlink(temp_path_.c_str());
    unregister_temp(temp_path_);
    throw_system_error("cannot close " + path_);
  }
  fd_ = -1;
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temp_path_.c_str());
    unregister_temp(temp_path_);
    errno = saved;
    throw_system_error("cannot rename " + temp_path_ + " to " + path_);
  }
  unregister_temp(temp_path_);
}

void write_file_atomically(const std::string& path, const void* data, std::size_t n) {
  AtomicOutputFile file(path);
  file.write(data, n);
  file.commit();
}

void make_output_directory(const std::string& path) {
  if (::mkdir(path.c_str(), 0755) == 0) return;
  if (errno != EEXIST) throw_system_error("cannot create directory " + path);
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw Error(path + ": exists and is not a directory (expected an output directory)");
}

}  // namespace qte
