// stream-cat: concatenate, filter and validate record streams.
#include <memory>
#include <optional>
#include <vector>

#include "cli/command.hpp"
#include "stream/record_filter.hpp"
#include "cli/stream_options.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "stream-cat";
  u.summary = "concatenate, filter and check record streams";
  u.description = {
      "Reads record streams in order and writes their records to one stream, checking every "
      "record on the way (a damaged input stops with one line naming file, record and byte "
      "offset; the output file is then not created). Records can be filtered by type and "
      "counted. With --append the records are added to the end of an existing file, one whole "
      "record at a time under a lock, which is how several actors feed one replay file. The file "
      "appended to must be a record stream ending in a whole record and none of the inputs; "
      "otherwise nothing is written and one line says where it stops being one (a torn last "
      "record, left by a killed writer, is cut off with --repair).",
  };
  u.arguments = {cli::input_files()};
  u.options = {
      {"type", "T", "keep only records of type T", "", true},
      {"exclude", "T", "drop records of type T", "", true},
      {"where", "NAME=VALUE",
       "keep only records whose scalar or text field NAME equals VALUE (numbers compare as numbers)", "", true},
      cli::integer_option("head", "N", "stop after N records have been written; -1 for no limit", "-1", -1,
                          INT64_MAX),
      cli::max_record_bytes_option(),
  };
  u.add_options(cli::append_options());
  u.options.push_back(cli::output_file());
  u.examples = {
      {"stream-cat ep1.rec ep2.rec --output all.rec", "join two files into one (atomically)"},
      {"stream-cat --type transition --append --output replay.rec < episode.rec",
       "add an episode's transitions to a growing replay file"},
      {"stream-cat --head 1 demos.rec | stream-dump", "look at the first record only"},
      {"stream-cat --type obs --where frame=0 demos.rec > starts.rec", "the first observation of every demonstration"},
  };
  u.see_also = {"qte-stream(5)", "stream-dump(1)", "stream-pack(1)"};
  return u;
}

static void run(const cli::Arguments& args) {
  const std::vector<std::string> files = args.inputs();
  const auto keep = args.all("type"), drop = args.all("exclude");
  stream::RecordFilter filter(
      {{keep.begin(), keep.end()}, {drop.begin(), drop.end()}, args.assignments("where"), args.integer("head")});
  const stream::ReadOptions read_options = cli::read_options_from(args);
  const stream::WriteOptions write_options = cli::write_options_from(args, files);
  std::size_t next_file = 0;
  std::unique_ptr<stream::RecordReader> reader;
  // The inputs one after another, each opened when the one before has ended.
  const auto next = [&]() -> std::optional<stream::Record> {
    while (true) {
      if (reader)
        if (auto record = reader->next()) return record;
      if (next_file == files.size()) return std::nullopt;
      reader = std::make_unique<stream::RecordReader>(files[next_file++], read_options);
    }
  };
  if (write_options.mode == stream::WriteMode::append && args.text("output") != "-") {
    // All or nothing: the inputs are read whole (and so checked) before the first record is
    // appended, so a damaged input leaves the file as it was.
    std::vector<stream::Record> held;
    stream::run_stage(filter, next, [&](const stream::Record& r) { held.push_back(r); });
    stream::RecordWriter writer(args.text("output"), write_options);
    for (const stream::Record& r : held) writer.write(r);
    writer.close();
    return;
  }
  stream::RecordWriter writer(args.text("output"), write_options);
  stream::run_stage(filter, next, [&](const stream::Record& r) { writer.write(r); });
  writer.close();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
