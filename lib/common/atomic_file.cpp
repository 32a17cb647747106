#include "common/atomic_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>

#include <atomic>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <vector>

#include "common/error.hpp"

namespace qte {
namespace {

// Temporary files and staging directories of this process, removed by the signal handler.
// Fixed-size table of C strings because a handler may only call async-signal-safe functions.
enum TempKind : int { kFree = 0, kFile, kStagingDirectory, kCreatedDirectory };
constexpr int kMaxTempFiles = 64;
char g_temp_paths[kMaxTempFiles][4096];
volatile sig_atomic_t g_temp_kind[kMaxTempFiles];
std::mutex g_mutex;
std::once_flag g_handlers_installed;

// Unlinks the files of a staging directory and the directory, with system calls only.
void remove_staging_directory_in_handler(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    alignas(8) char buffer[4096];
    long n;
    while ((n = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer)) > 0)
      for (long at = 0; at < n;) {
        const auto* entry = reinterpret_cast<const struct dirent64*>(buffer + at);
        const char* name = entry->d_name;
        if (!(name[0] == '.' && (name[1] == 0 || (name[1] == '.' && name[2] == 0)))) ::unlinkat(fd, name, 0);
        at += entry->d_reclen;
      }
    ::close(fd);
  }
  ::rmdir(path);
}

// The file write_on_fatal_signal() asked for, written first.
char g_note_path[4096];
char g_note_text[256];
volatile sig_atomic_t g_note_set = 0;

// The hook call_on_fatal_signal() asked for, called first.
void (*volatile g_hook)() = nullptr;

void remove_temp_files_and_die(int signal_number) {
  if (g_hook) g_hook();
  if (g_note_set) {
    const int fd = ::open(g_note_path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd >= 0) {
      const ssize_t ignored = ::write(fd, g_note_text, std::strlen(g_note_text));
      (void)ignored;
      ::close(fd);
    }
  }
  for (int kind : {kFile, kStagingDirectory, kCreatedDirectory})  // a directory empties before it goes
    for (int i = 0; i < kMaxTempFiles; ++i) {
      if (g_temp_kind[i] != kind) continue;
      if (kind == kFile) ::unlink(g_temp_paths[i]);
      else if (kind == kStagingDirectory) remove_staging_directory_in_handler(g_temp_paths[i]);
      else ::rmdir(g_temp_paths[i]);
    }
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

int register_temp(const std::string& path, TempKind kind = kFile) {
  std::call_once(g_handlers_installed, install_handlers);
  std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kMaxTempFiles; ++i)
    if (g_temp_kind[i] == kFree && path.size() < sizeof g_temp_paths[i]) {
      std::memcpy(g_temp_paths[i], path.c_str(), path.size() + 1);
      std::atomic_signal_fence(std::memory_order_release);  // the path before the handler may see it
      g_temp_kind[i] = kind;
      return i;
    }
  return -1;  // still correct, only not cleaned up on a signal
}

void unregister_temp(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kMaxTempFiles; ++i)
    if (g_temp_kind[i] != kFree && path == g_temp_paths[i]) g_temp_kind[i] = kFree;
}
}  // namespace

void write_on_fatal_signal(const std::string& path, const std::string& text) {
  if (path.size() >= sizeof g_note_path || text.size() >= sizeof g_note_text)
    throw Error(path + ": too long a name for a file written on a signal");
  std::call_once(g_handlers_installed, install_handlers);
  g_note_set = 0;
  std::memcpy(g_note_path, path.c_str(), path.size() + 1);
  std::memcpy(g_note_text, text.c_str(), text.size() + 1);
  g_note_set = 1;
}

void call_on_fatal_signal(void (*hook)()) {
  std::call_once(g_handlers_installed, install_handlers);
  g_hook = hook;
}

RemovedOnSignal::RemovedOnSignal(std::string path) : path_(std::move(path)) { register_temp(path_); }
RemovedOnSignal::~RemovedOnSignal() { unregister_temp(path_); }

namespace {

// The file a chain of symbolic links ends at (the path itself when it is no link).
std::string follow_symlinks(const std::string& path) {
  std::filesystem::path p(path);
  for (int hops = 0; hops < 40; ++hops) {
    std::error_code error;
    if (!std::filesystem::is_symlink(std::filesystem::symlink_status(p, error))) return p.string();
    const std::filesystem::path target = std::filesystem::read_symlink(p, error);
    if (error) throw_system_error("cannot read the symbolic link " + p.string());
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  throw Error(path + ": too many levels of symbolic links (expected a file to write)");
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
    if (std::filesystem::remove_all(entry.path(), error) > 0) ++removed;  // a file or a staging directory
  }
  return removed;
}

AtomicOutputFile::AtomicOutputFile(std::string path)
    : path_(std::move(path)),
      target_path_(follow_symlinks(path_)),
      temp_path_(target_path_ + ".tmp." + std::to_string(::getpid())) {
  const std::filesystem::path p(target_path_);
  remove_stale_temporaries(p.parent_path().string(), p.filename().string());
  struct stat info {};
  if (::stat(target_path_.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
    fd_ = ::open(target_path_.c_str(), O_WRONLY | O_CLOEXEC);
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
  if (::rename(temp_path_.c_str(), target_path_.c_str()) != 0) {
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

bool make_output_directory(const std::string& path) {
  if (::mkdir(path.c_str(), 0755) == 0) return true;
  if (errno != EEXIST) throw_system_error("cannot create directory " + path);
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw Error(path + ": exists and is not a directory (expected an output directory)");
  return false;
}

namespace {
const char kStagingName[] = ".qte-staging";
}

OutputDirectory::OutputDirectory(std::string dir)
    : dir_(std::move(dir)), staging_(dir_ + "/" + kStagingName + ".tmp." + std::to_string(::getpid())) {
  created_dir_ = make_output_directory(dir_);
  if (created_dir_) register_temp(dir_, kCreatedDirectory);
  remove_stale_temporaries(dir_, kStagingName);
  register_temp(staging_, kStagingDirectory);
  if (::mkdir(staging_.c_str(), 0755) != 0 && errno != EEXIST) {
    const int saved = errno;
    unregister_temp(staging_);
    if (created_dir_) unregister_temp(dir_), ::rmdir(dir_.c_str());
    errno = saved;
    throw_system_error("cannot create a staging directory in " + dir_);
  }
}

OutputDirectory::~OutputDirectory() {
  if (committed_) return;
  std::error_code ignored;
  std::filesystem::remove_all(staging_, ignored);
  unregister_temp(staging_);
  if (created_dir_) {
    ::rmdir(dir_.c_str());  // only when empty: a file put there by someone else stays
    unregister_temp(dir_);
  }
}

void OutputDirectory::write_file(const std::string& name, const void* data, std::size_t n) {
  write_file_atomically(path(name), data, n);
}

void OutputDirectory::commit() {
  if (committed_) return;
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(staging_, error))
    names.push_back(entry.path().filename().string());
  if (error) throw_system_error("cannot read the staging directory " + staging_);
  std::sort(names.begin(), names.end());
  for (const std::string& name : names)
    if (::rename(path(name).c_str(), (dir_ + "/" + name).c_str()) != 0)
      throw_system_error("cannot move " + path(name) + " into " + dir_);
  if (::rmdir(staging_.c_str()) != 0) throw_system_error("cannot remove the staging directory " + staging_);
  unregister_temp(staging_);
  if (created_dir_) unregister_temp(dir_);
  committed_ = true;
}

}  // namespace qte
