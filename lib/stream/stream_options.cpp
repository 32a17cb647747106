#include "stream/stream_options.hpp"

#include <cstdint>

namespace qte::stream {

std::vector<cli::OptionSpec> append_options() {
  return {
      {"append", "", "append to --output instead of replacing it (a growing replay file)", ""},
      {"repair", "",
       "with --append: cut a torn last record (left by a killed writer) off --output instead of refusing to "
       "append behind it",
       ""},
  };
}

WriteOptions write_options_from(const cli::Arguments& args, std::vector<std::string> inputs) {
  WriteOptions options;
  if (args.flag("append")) options.mode = WriteMode::append;
  options.repair = args.flag("repair");
  options.inputs = std::move(inputs);
  return options;
}

cli::OptionSpec max_record_bytes_option() {
  return {"max-record-bytes", "N", "treat a record payload or decompressed field larger than N bytes as damage",
          cli::default_text(static_cast<int64_t>(ReadOptions{}.max_record_bytes))};
}

ReadOptions read_options_from(const cli::Arguments& args) {
  ReadOptions options;
  options.max_record_bytes = static_cast<uint64_t>(args.integer("max-record-bytes", 1, INT64_MAX));
  return options;
}

}  // namespace qte::stream
