// Options of record-stream readers and writers that several programs share, declared once:
// --append and --repair for the writers of a growing replay (stream-cat, stream-pack,
// keyframe), --max-record-bytes for the readers that take damage bounds from the user, and
// --no-points for the programs that write observations.
#pragma once

#include <string>
#include <vector>

#include "cli/command.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

namespace qte::cli {

std::vector<OptionSpec> append_options();  // --append, --repair
// `inputs`: the files the program reads, which an append must not write into.
stream::WriteOptions write_options_from(const Arguments& args, std::vector<std::string> inputs);

OptionSpec max_record_bytes_option();  // --max-record-bytes, ReadOptions' default
stream::ReadOptions read_options_from(const Arguments& args);

// --no-points: leave <camera>.points out of the observations a program writes (sim-step,
// obs-pack, robot-step); readers rebuild them from depth.
OptionSpec no_points_option();

}  // namespace qte::cli
