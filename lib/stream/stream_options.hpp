// Options of record-stream readers and writers that several programs share, declared once:
// --append and --repair for the writers of a growing replay (stream-cat, stream-pack,
// keyframe), --max-record-bytes for the readers that take damage bounds from the user.
#pragma once

#include <string>
#include <vector>

#include "cli/command.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

namespace qte::stream {

std::vector<cli::OptionSpec> append_options();  // --append, --repair
// `inputs`: the files the program reads, which an append must not write into.
WriteOptions write_options_from(const cli::Arguments& args, std::vector<std::string> inputs);

cli::OptionSpec max_record_bytes_option();  // --max-record-bytes, ReadOptions' default
ReadOptions read_options_from(const cli::Arguments& args);

}  // namespace qte::stream
