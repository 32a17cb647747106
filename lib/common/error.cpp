#include "common/error.hpp"

#include <cerrno>
#include <cstring>

namespace qte {

std::string StreamPosition::describe() const {
  return (source == "-" ? std::string("<stdin>") : source) + ": record " +
         std::to_string(record_index) + " at byte " + std::to_string(byte_offset);
}

StreamError::StreamError(const StreamPosition& where, const std::string& what_expected)
    : Error(where.describe() + ": " + what_expected), where_(where) {}

void throw_system_error(const std::string& what) {
  throw Error(what + ": " + std::strerror(errno));
}

}  // namespace qte
