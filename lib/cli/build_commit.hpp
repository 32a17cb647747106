// The commit the toolkit was built from (`git describe --always --dirty` of the source tree,
// "unknown" outside a checkout), for --version: learn.sh records it with every run.
#pragma once

namespace qte::cli {
const char* build_commit();
}
