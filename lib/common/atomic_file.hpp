// Output files appear whole or not at all: bytes go to "<path>.tmp.<pid>", which commit()
// renames to <path>. A destructor without commit(), SIGINT, SIGTERM or SIGHUP removes the
// temporary file, so a failed or interrupted tool never leaves a half file under the final name.
// A path that exists and is not a regular file (/dev/null, a FIFO, a terminal) is written
// directly: renaming over it would replace the device or pipe with a file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace qte {

class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t n);
  // fsync, then rename over the final name. After this the file is complete on disk.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string temp_path_;
  int fd_ = -1;
};

// Writes all of `data` to `fd` (retrying on EINTR and short writes). Throws BrokenPipe on
// EPIPE, Error otherwise; `what` names the destination in the message.
void write_all(int fd, const void* data, std::size_t n, const std::string& what);

// Removes what a killed writer left: files in `dir` named <name>.tmp.<pid> whose process is
// gone, for <name> `name` (or any name when `name` is empty). A SIGKILL gives no chance to
// clean up, so the next program writing there does. Returns how many it removed.
int remove_stale_temporaries(const std::string& dir, const std::string& name = "");

// Creates the directory `path` where output files go, unless it exists (parents are not made).
// Throws Error naming it otherwise.
void make_output_directory(const std::string& path);

// Convenience: the whole file at once, atomically.
void write_file_atomically(const std::string& path, const void* data, std::size_t n);

}  // namespace qte
