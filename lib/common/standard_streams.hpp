// Standard input, output and error that a caller closed: were they left closed, the next file a
// tool opens would take their number, and an outcomes file be read as the record stream or a
// checkpoint written as standard output. Each is opened on /dev/null instead, and a reader of
// standard input is told it was closed.
#pragma once

namespace qte {

void reopen_closed_standard_streams();  // once, first thing in a tool
bool standard_input_was_closed();

}  // namespace qte
