// Reads a record file that other processes are appending to (keyframe --append, stream-cat
// --append: whole records under a lock, but a reader may still see the tail of one being
// written). poll() returns the complete records added since the last call and leaves a
// partly written record for the next call; damage is a StreamError as anywhere else.
#pragma once

#include <string>
#include <vector>

#include "stream/reader.hpp"

namespace qte::replay {

class GrowingStream {
 public:
  explicit GrowingStream(std::string path, stream::ReadOptions options = {});
  ~GrowingStream();
  GrowingStream(const GrowingStream&) = delete;
  GrowingStream& operator=(const GrowingStream&) = delete;

  std::vector<stream::Record> poll();
  uint64_t byte_offset() const { return position_.byte_offset; }

 private:
  int fd_ = -1;
  stream::ReadOptions options_;
  StreamPosition position_;
};

}  // namespace qte::replay
