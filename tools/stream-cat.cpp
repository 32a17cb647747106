// stream-cat: concatenate, filter and validate record streams.
#include <cmath>
#include <set>

#include "cli/command.hpp"
#include "stream/inspect.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

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
      {"append", "", "append to --output instead of replacing it", ""},
      {"repair", "", "with --append: cut a torn last record (left by a killed writer) off --output instead of refusing to append behind it", ""},
      {"type", "T", "keep only records of type T", "", true},
      {"exclude", "T", "drop records of type T", "", true},
      {"where", "NAME=VALUE", "keep only records whose scalar or text field NAME equals VALUE (numbers compare as numbers)", "", true},
      {"head", "N", "stop after N records have been written; -1 for no limit", "-1"},
      {"max-record-bytes", "N", "treat a record payload or decompressed field larger than N bytes as damage",
       std::to_string(uint64_t(4) << 30)},
  };
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

namespace {

// --where NAME=VALUE: a scalar field equal to the number VALUE, or a text field equal to VALUE.
struct Condition {
  std::string name, value;
  bool holds(const stream::Record& record) const {
    const stream::Field* field = record.find(name);
    if (field == nullptr) return false;
    if (field->dtype() == stream::DType::str) return record.string(name) == value;
    if (field->element_count() != 1) return false;
    char* end = nullptr;
    const double wanted = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0') return false;
    return stream::element_as_double(*field, 0) == wanted;
  }
};

}  // namespace

static void run(const cli::Arguments& args) {
  const std::vector<std::string> files = args.inputs();
  const auto keep = args.all("type"), drop = args.all("exclude");
  const std::set<std::string> keep_types(keep.begin(), keep.end()),
      drop_types(drop.begin(), drop.end());
  const int64_t head = args.integer("head", -1, 1000000000000000);
  std::vector<Condition> conditions;
  for (const std::string& where : args.all("where")) {
    const auto eq = where.find('=');
    if (eq == std::string::npos || eq == 0) throw UsageError("--where expects NAME=VALUE, got '" + where + "'");
    conditions.push_back({where.substr(0, eq), where.substr(eq + 1)});
  }
  stream::ReadOptions read_options;
  read_options.max_record_bytes = static_cast<uint64_t>(args.integer("max-record-bytes", 1, INT64_MAX));
  stream::WriteOptions write_options;
  if (args.flag("append")) write_options.mode = stream::WriteMode::append;
  write_options.repair = args.flag("repair");
  write_options.inputs = files;
  stream::RecordWriter writer(args.text("output"), write_options);
  for (const std::string& file : files) {
    stream::RecordReader reader(file, read_options);
    while (head < 0 || static_cast<int64_t>(writer.records_written()) < head) {
      auto record = reader.next();
      if (!record) break;
      if (!keep_types.empty() && !keep_types.count(record->type())) continue;
      if (drop_types.count(record->type())) continue;
      bool wanted = true;
      for (const Condition& c : conditions) wanted = wanted && c.holds(*record);
      if (!wanted) continue;
      writer.write(*record);
    }
  }
  writer.close();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
