#include "cli/stream_options.hpp"

#include <cstdint>

namespace qte::cli {

std::vector<OptionSpec> append_options() {
  return {
      {"append", "", "append to --output instead of replacing it (a growing replay file)", ""},
      {"repair", "",
       "with --append: cut a torn last record (left by a killed writer) off --output instead of refusing to "
       "append behind it",
       ""},
  };
}

stream::WriteOptions write_options_from(const Arguments& args, std::vector<std::string> inputs) {
  stream::WriteOptions options;
  if (args.flag("append")) options.mode = stream::WriteMode::append;
  options.repair = args.flag("repair");
  options.inputs = std::move(inputs);
  return options;
}

OptionSpec max_record_bytes_option() {
  return cli::integer_option("max-record-bytes", "N",
                             "treat a record payload or decompressed field larger than N bytes as damage",
                             default_text(static_cast<int64_t>(stream::ReadOptions{}.max_record_bytes)), 1, INT64_MAX);
}

stream::ReadOptions read_options_from(const Arguments& args) {
  stream::ReadOptions options;
  options.max_record_bytes = static_cast<uint64_t>(args.integer("max-record-bytes"));
  return options;
}

OptionSpec no_points_option() {
  return {"no-points", "",
          "leave the world-frame point clouds (<camera>.points) out of the observations written (readers rebuild them "
          "from depth; smaller files)",
          ""};
}

}  // namespace qte::cli
