#include "common/standard_streams.hpp"

#include <fcntl.h>

#include <cerrno>

namespace qte {

namespace {
bool g_input_closed = false;
}

void reopen_closed_standard_streams() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) >= 0 || errno != EBADF) continue;
    if (fd == 0) g_input_closed = true;
    // open() takes the lowest free number, which is this one: the ones below are open.
    ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
  }
}

bool standard_input_was_closed() { return g_input_closed; }

}  // namespace qte
